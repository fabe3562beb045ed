// Drawing the cloud (clouds 2.2): each particle a screen-parallel Gaussian billboard,
// drawn back to front with E_k = S_k + T_k E_{k-1} (5) as premultiplied "over"
// blending, S_k the light the blob sends along each pixel's own ray (its column faded
// at its cut, the sunlight read at its three emission nodes, integrated over its depth,
// the phase for the ray), as atmo::clouds::render does. The orders past the first by
// the octaves go to a second target, scaled afterwards by the cloud's depth on the ray;
// by the transfer table, with the single-scattered light, the depth toward the eye read
// from a second buffer lit from the eye (the depth in front of a blob on its pixel, the
// CPU's, is not known to billboards blended in hardware); by the transfer solve, with
// the single-scattered light, its light toward the eye read at the emission nodes' mean
// place (clouds_solve.wgsl made it).

// Mirrors atmo_gpu::clouds::DrawParams.
struct DrawParams {
    // Camera position (m); w: focal length in pixels.
    position: vec4<f32>,
    // Unit view axis; w: tan of half the horizontal field.
    forward: vec4<f32>,
    // Unit right; w: tan of half the vertical field.
    right: vec4<f32>,
    up: vec4<f32>,
    // Unit vector to the sun; w: the phase function's PHASE_* code.
    to_sun: vec4<f32>,
    // Sunlight at the cloud, RGB; w: the phase function's parameter.
    sun: vec4<f32>,
    // The sky's light the droplets scatter toward the eye: nine spherical harmonics,
    // RGB (atmo::clouds::SkyLight, its order).
    sky: array<vec4<f32>, 9>,
    // The sky's light inside the cloud from above and below against outside
    // (atmo::clouds::SkyDimming), RGB; sky_above.w: the extrapolation length.
    sky_above: vec4<f32>,
    sky_below: vec4<f32>,
    // The air between the eye and the cloud: transmittance and in-scattered light, RGB.
    haze_transmittance: vec4<f32>,
    haze_inscatter: vec4<f32>,
    // atmo::clouds::Octaves: attenuation, contribution, eccentricity, depth scale.
    octaves: vec4<f32>,
    // The slab's diffuse light (Octaves::diffuse): weight, extrapolation length.
    diffuse: vec4<f32>,
    width: u32,
    height: u32,
    octave_count: u32,
    // Where the grid lit from the eye starts in `log_gamma`, and its scale across its
    // rays (atmo_gpu::clouds::seen_from).
    eye_base: u32,
    eye_scale: f32,
    pad1: u32,
    pad2: u32,
    pad3: u32,
    // The transfer solve's grid: cell (0, 0, 0)'s centre (m), w the cells' side (m);
    // the cells along x, y and z.
    solve_centre: vec4<f32>,
    solve_dims: vec4<u32>,
}

@group(0) @binding(0) var<uniform> params: DrawParams;
@group(0) @binding(1) var<uniform> frame: BufferFrame;
@group(0) @binding(2) var<storage, read> particles: array<GpuParticle>;
// Particle indices, farthest first.
@group(0) @binding(3) var<storage, read> order: array<u32>;
// ln Gamma at voxel centres, [x][z][y]: the sun's grid, then (with the table) the
// eye's at params.eye_base.
@group(0) @binding(4) var<storage, read> log_gamma: array<f32>;
// The grid lit from the eye along each pixel's ray: of the particles as seen from the
// eye, where a pixel's ray is the line (eye_scale (r . right), eye_scale (r . up), z),
// z its depth along the view axis.
@group(0) @binding(5) var<uniform> eye: BufferFrame;
// The transfer table's values, [thickness][sun][out][cosine][eye]
// (atmo::clouds::TransferTable).
@group(0) @binding(6) var<storage, read> table: array<f32>;
// The transfer solve's light toward the eye per cell, [x][y][z], per unit scattering
// coefficient: the sun's (1/sr per unit sun irradiance) and the sky's (RGB).
@group(0) @binding(7) var<storage, read> solved: array<vec4<f32>>;
// The caller's scene in front of which the cloud is seen: each pixel's depth along the
// view axis, m (CloudsPass::scene_depth; one texel of f32::MAX without a scene).
@group(0) @binding(8) var scene_depth: texture_2d<f32>;

// How the orders past the first are drawn: `shade`'s modes.
const BY_OCTAVES: u32 = 0u;
const BY_TABLE: u32 = 1u;
const BY_SOLVE: u32 = 2u;

struct Billboard {
    @builtin(position) clip: vec4<f32>,
    // Centre (m, world) and standard deviation (m).
    @location(0) @interpolate(flat) centre: vec4<f32>,
    // Albedo times sunlight; the albedo.
    @location(1) @interpolate(flat) sun: vec3<f32>,
    @location(2) @interpolate(flat) albedo: f32,
    @location(3) @interpolate(flat) density: f32,
    // The sky's light at the particle against outside the cloud, RGB.
    @location(4) @interpolate(flat) sky_inside: vec3<f32>,
    // The particle's depth out of the cloud (CloudDepths::out), and its slices of the
    // transfer table by the cloud's thickness through it (transfer::Slices): the lower
    // slice's node and the upper's weight.
    @location(5) @interpolate(flat) out_depth: f32,
    @location(6) @interpolate(flat) slices: vec2<f32>,
}

struct Colours {
    // The picture, and the higher octaves' light apart (alpha alike in both).
    @location(0) picture: vec4<f32>,
    @location(1) higher: vec4<f32>,
}

fn phase(c: f32) -> f32 {
    return phase_function(u32(params.to_sun.w), params.sun.w, c);
}

// The sky's light scattered toward the eye along the unit ray d (SkyLight::along).
fn sky_along(d: vec3<f32>) -> vec3<f32> {
    let basis = array<f32, 9>(
        0.282095,
        0.488603 * d.y,
        0.488603 * d.z,
        0.488603 * d.x,
        1.092548 * d.x * d.y,
        1.092548 * d.y * d.z,
        0.315392 * (3.0 * d.z * d.z - 1.0),
        1.092548 * d.x * d.z,
        0.546274 * (d.x * d.x - d.y * d.y),
    );
    var sum = vec3<f32>(0.0);
    for (var k = 0u; k < 9u; k++) {
        sum += basis[k] * params.sky[k].xyz;
    }
    return sum;
}

@vertex
fn vertex(@builtin(vertex_index) v: u32, @builtin(instance_index) i: u32) -> Billboard {
    let p = particles[order[i]];
    let centre = p.position_radius.xyz;
    let s = p.position_radius.w / 3.0;
    let d = centre - params.position.xyz;
    let z = dot(d, params.forward.xyz);
    let focal = params.position.w;
    let w = f32(params.width);
    let h = f32(params.height);
    let tx = dot(d, params.right.xyz) / z;
    let ty = dot(d, params.up.xyz) / z;
    let sx = tx * focal + 0.5 * w;
    let sy = -ty * focal + 0.5 * h;
    // The reach's radius at its distance, widened off the axis (the CPU's footprint).
    let r = FOOTPRINT * s;
    let sr = r / sqrt(z * z - r * r) * focal * (1.0 + tx * tx + ty * ty);
    // Two triangles over the square around the footprint.
    let corner = array<vec2<f32>, 6>(
        vec2(-1.0, -1.0), vec2(1.0, -1.0), vec2(1.0, 1.0),
        vec2(-1.0, -1.0), vec2(1.0, 1.0), vec2(-1.0, 1.0),
    )[v];
    let px = sx + corner.x * sr;
    let py = sy + corner.y * sr;
    var out: Billboard;
    out.clip = vec4<f32>(2.0 * px / w - 1.0, 1.0 - 2.0 * py / h, 0.5, 1.0);
    out.centre = vec4<f32>(centre, s);
    out.sun = p.albedo * params.sun.xyz;
    out.albedo = p.albedo;
    out.density = p.density;
    out.out_depth = p.out_depth;
    out.slices = hat(p.thickness, TRANSFER_THICKNESS, TRANSFER_THICKNESS_COUNT);
    // SkyDimming::top_share and SkyDimming::at: the two-stream profile down the vertical.
    let e = params.sky_above.w;
    let top = clamp((p.sky_column - p.sky_depth + e) / (p.sky_column + 2.0 * e), 0.0, 1.0);
    out.sky_inside = params.sky_below.xyz + (params.sky_above.xyz - params.sky_below.xyz) * top;
    return out;
}

// The lower of the nodes around v of `edges` (the first `count`) and the upper's
// weight, held at the end nodes: atmo::clouds::transfer's hat_lanes.
fn hat(v: f32, edges: array<f32, TRANSFER_NODES>, count: u32) -> vec2<f32> {
    var e = edges;
    var node = 0u;
    for (var i = 1u; i + 1u < count; i++) {
        if v >= e[i] {
            node = i;
        }
    }
    let share = clamp((v - e[node]) / (e[node + 1u] - e[node]), 0.0, 1.0);
    return vec2<f32>(f32(node), share);
}

// TransferTable::at: the table multilinear between its nodes, `slices` the particle's
// (the lower slice's node and the upper's weight).
fn transfer(slices: vec2<f32>, to_sun: f32, out: f32, cosine: f32, to_eye: f32) -> f32 {
    let s = hat(to_sun, TRANSFER_SUN, TRANSFER_SUN_COUNT);
    let o = hat(out, TRANSFER_OUT, TRANSFER_OUT_COUNT);
    let c = hat(cosine, TRANSFER_COSINE, TRANSFER_COSINE_COUNT);
    let e = hat(to_eye, TRANSFER_EYE, TRANSFER_EYE_COUNT);
    let share = vec4<f32>(s.y, o.y, c.y, e.y);
    let strides = vec4<u32>(
        TRANSFER_OUT_COUNT * TRANSFER_COSINE_COUNT * TRANSFER_EYE_COUNT,
        TRANSFER_COSINE_COUNT * TRANSFER_EYE_COUNT,
        TRANSFER_EYE_COUNT,
        1u,
    );
    let slice = TRANSFER_SUN_COUNT * strides.x;
    let base = u32(slices.x) * slice + dot(vec4<u32>(u32(s.x), u32(o.x), u32(c.x), u32(e.x)), strides);
    var sum = vec2<f32>(0.0);
    for (var k = 0u; k < 16u; k++) {
        let upper = (vec4<u32>(k) >> vec4<u32>(3u, 2u, 1u, 0u)) & vec4<u32>(1u);
        let w = select(vec4<f32>(1.0) - share, share, upper == vec4<u32>(1u));
        let at = base + dot(upper, strides);
        sum += w.x * w.y * w.z * w.w * vec2<f32>(table[at], table[at + slice]);
    }
    return mix(sum.x, sum.y, slices.y);
}

// Particle::faded_column: the column at squared distance b2 from the centre, faded to
// zero at the cut.
fn faded_column(b2: f32, s: f32, density: f32) -> f32 {
    let x = b2 / (2.0 * s * s);
    let cut = 0.5 * FOOTPRINT * FOOTPRINT;
    if x >= cut {
        return 0.0;
    }
    return density * s * sqrt(2.0 * PI) * FADE_SCALE * (exp(-x) - exp(-cut));
}

// atmo::clouds::particles::erf_inverse (Giles 2010).
fn erf_inverse(x: f32) -> f32 {
    var w = -log((1.0 - x) * (1.0 + x));
    var p: f32;
    if w < 5.0 {
        w = w - 2.5;
        p = 2.81022636e-08;
        p = 3.43273939e-07 + p * w;
        p = -3.5233877e-06 + p * w;
        p = -4.39150654e-06 + p * w;
        p = 0.00021858087 + p * w;
        p = -0.00125372503 + p * w;
        p = -0.00417768164 + p * w;
        p = 0.246640727 + p * w;
        p = 1.50140941 + p * w;
    } else {
        w = sqrt(w) - 3.0;
        p = -0.000200214257;
        p = 0.000100950558 + p * w;
        p = 0.00134934322 + p * w;
        p = -0.00367342844 + p * w;
        p = 0.00573950773 + p * w;
        p = -0.0076224613 + p * w;
        p = 0.00943887047 + p * w;
        p = 1.00167406 + p * w;
        p = 2.83297682 + p * w;
    }
    return p * x;
}

// atmo::clouds::particles::emission_nodes: (u, l) at the Gauss-Legendre node `node`
// of the absorbed fraction, the blob's column `tau` absorbing `absorbed`.
fn emission_node(tau: f32, absorbed: f32, node: f32) -> vec2<f32> {
    // ln(1 - v) for small v without losing it (log1p is not in WGSL).
    let v = absorbed * node;
    var u = -log(1.0 - v);
    if v < 1e-4 {
        u = v * (1.0 + 0.5 * v);
    }
    var q = node;
    if tau > 1e-6 {
        q = u / tau;
    }
    return vec2<f32>(u, sqrt(2.0) * erf_inverse(clamp(2.0 * q - 1.0, -0.999999, 0.999999)));
}

// 1 - e^-tau, by its series for a thin blob (OctaveTerms::light).
fn absorbed_of(tau: f32) -> f32 {
    if tau < 0.25 {
        return tau * (1.0 - tau / 2.0 * (1.0 - tau / 3.0 * (1.0 - tau / 4.0 * (1.0 - tau / 5.0
            * (1.0 - tau / 6.0)))));
    }
    return 1.0 - exp(-tau);
}

// The transfer solve's light toward the eye at the world point p, trilinear between
// the cells' centres, 0 beyond them (atmo::clouds::diffusion's trilinear).
fn solved_at(p: vec3<f32>) -> vec4<f32> {
    let g = (p - params.solve_centre.xyz) / params.solve_centre.w;
    let n = params.solve_dims.xyz;
    if !(all(g >= vec3<f32>(0.0)) && all(g < vec3<f32>(n - vec3<u32>(1u)))) {
        return vec4<f32>(0.0);
    }
    let i = vec3<u32>(g);
    let f = g - vec3<f32>(i);
    let base = (i.x * n.y + i.y) * n.z + i.z;
    let sx = n.y * n.z;
    let sy = n.z;
    let x0 = mix(
        mix(solved[base], solved[base + 1u], f.z),
        mix(solved[base + sy], solved[base + sy + 1u], f.z),
        f.y,
    );
    let x1 = mix(
        mix(solved[base + sx], solved[base + sx + 1u], f.z),
        mix(solved[base + sx + sy], solved[base + sx + sy + 1u], f.z),
        f.y,
    );
    return mix(x0, x1, f.x);
}

// The orders past the first by the octaves.
@fragment
fn fragment(b: Billboard) -> Colours {
    return shade(b, BY_OCTAVES);
}

// The orders past the first by the transfer table.
@fragment
fn fragment_table(b: Billboard) -> Colours {
    return shade(b, BY_TABLE);
}

// The orders past the first by the transfer solve.
@fragment
fn fragment_solve(b: Billboard) -> Colours {
    return shade(b, BY_SOLVE);
}

// A fragment of the billboard `b`, the orders past the first by the octaves, the
// transfer table or the solve (`mode`, a constant of each entry point, so that each
// compiles to its own branch alone).
fn shade(b: Billboard, mode: u32) -> Colours {
    // The pixel's centre, in pixels, and its ray (component 1 along the view axis).
    let pixel = b.clip.xy;
    let w = f32(params.width);
    let h = f32(params.height);
    let r = params.forward.xyz + (2.0 * pixel.x / w - 1.0) * params.forward.w * params.right.xyz
        + (1.0 - 2.0 * pixel.y / h) * params.right.w * params.up.xyz;
    // Its nearest approach to the centre (at t times the ray) and the column there.
    let d = b.centre.xyz - params.position.xyz;
    let rr = dot(r, r);
    let t = dot(d, r) / rr;
    let s = b.centre.w;
    let inv_length = inverseSqrt(rr);
    // Of the column, the part in front of the scene's surface on this pixel: the
    // Gaussian's share before it along the ray (r is 1 along the view axis, so the
    // surface is at t = its depth), 1 in front of the sky.
    let texels = vec2<i32>(textureDimensions(scene_depth)) - vec2<i32>(1);
    let surface = textureLoad(scene_depth, clamp(vec2<i32>(pixel), vec2<i32>(0), texels), 0).r;
    let before = 0.5 + 0.5 * erf(clamp((surface - t) / (sqrt(2.0) * s * inv_length), -8.0, 8.0));
    let tau = faded_column(max(dot(d, d) - t * t * rr, 0.0), s, b.density) * before;
    if tau <= 0.0 {
        discard;
    }
    // The sunlight at the blob's emission nodes along the ray, in the grid, and the
    // cloud's extinction there (the slope of ln Gamma along the light).
    let g_ray = to_buffer(frame, r) / frame.voxel.xyz;
    let g = grid_of(frame, params.position.xyz) + t * g_ray;
    let along = (s * inv_length) * g_ray;
    let alpha = absorbed_of(tau);
    let n0 = emission_node(tau, alpha, EMISSION_FRACTIONS.x);
    let n1 = emission_node(tau, alpha, EMISSION_FRACTIONS.y);
    let n2 = emission_node(tau, alpha, EMISSION_FRACTIONS.z);
    let ls = vec3<f32>(n0.y, n1.y, n2.y);
    let near = g + n0.y * along;
    let r0 = log_gamma_and_slope_in(frame, 0u, near);
    let r1 = log_gamma_and_slope_in(frame, 0u, g + n1.y * along);
    let r2 = log_gamma_and_slope_in(frame, 0u, g + n2.y * along);
    let l = vec3<f32>(r0.x, r1.x, r2.x);
    // The blobs beside (atmo::clouds::render): the others' extinction at each node
    // times its distance from the blob's middle. The GPU does not know the depth in
    // front of the blob, which the CPU bounds this by.
    let own = tau * exp(-0.5 * ls * ls) / sqrt(2.0 * PI);
    let others = max(vec3<f32>(r0.y, r1.y, r2.y) * (-s / frame.voxel.y) - own, vec3<f32>(0.0));
    let dimmed = exp(-others * ls);
    // Octaves::light: single scattering, and the higher octaves apart, by the
    // Gauss-Legendre rule in the blob's absorbed fraction.
    let cosine = dot(params.to_sun.xyz, r) * inv_length;
    let p = phase(cosine);
    let single = p * alpha * dot(EMISSION_WEIGHTS, exp(l) * dimmed);
    var higher = 0.0;
    var weight = 1.0;
    var shape = 1.0;
    var share = 1.0;
    for (var i = 1u; i < params.octave_count; i++) {
        weight *= params.octaves.y;
        shape *= params.octaves.z;
        share *= params.octaves.x;
        let pi = shape * p + (1.0 - shape) / (4.0 * PI);
        higher += weight * pi * alpha * dot(EMISSION_WEIGHTS, exp(share * l) * dimmed);
    }
    // The transfer table's light (atmo::clouds::render) at the emission nodes' mean
    // depths toward the sun and toward the eye, the least of those and the particle's
    // depth out, and the ray's angle.
    var tabled = 0.0;
    if mode == BY_TABLE {
        let across = params.eye_scale * vec2<f32>(dot(r, params.right.xyz), dot(r, params.up.xyz));
        let depths = vec3<f32>(t) + (s * inv_length) * ls;
        let eye_at = vec3<f32>(
            log_gamma_in(eye, params.eye_base, grid_of(eye, vec3<f32>(across, depths.x))),
            log_gamma_in(eye, params.eye_base, grid_of(eye, vec3<f32>(across, depths.y))),
            log_gamma_in(eye, params.eye_base, grid_of(eye, vec3<f32>(across, depths.z))),
        );
        let to_eye = -dot(EMISSION_WEIGHTS, eye_at);
        let to_sun = -dot(EMISSION_WEIGHTS, l);
        tabled = alpha * transfer(b.slices, to_sun, min(min(to_eye, to_sun), b.out_depth), cosine, to_eye);
    }
    // The solve's light toward the eye at the emission nodes' mean place, the sun's
    // and the sky's (every order of it, in place of the sky's light dimmed below).
    var sky = b.sky_inside * sky_along(r * inv_length);
    if mode == BY_SOLVE {
        let at = t + dot(EMISSION_WEIGHTS, ls) * s * inv_length;
        let light = solved_at(params.position.xyz + at * r);
        tabled = alpha * light.x;
        sky = light.yzw;
    }
    // OctaveTerms::light: the slab's diffuse light, the cloud's whole depth along the
    // sun's ray through the nearest node (IntensityBuffer::column_depth_grid).
    if params.diffuse.x > 0.0 {
        let t = column_depth_at(near);
        let e = params.diffuse.y;
        let profile = max((vec3<f32>(t) + l + vec3<f32>(e)) / (t + 2.0 * e), vec3<f32>(0.0));
        higher += params.diffuse.x * dot(EMISSION_WEIGHTS, profile * dimmed) * (1.0 - exp(-t)) * alpha
            / (4.0 * PI);
    }
    // Premultiplied: colour + (1 - alpha) x what is behind, alpha = 1 - T_k; hazed, the
    // colour seen through the air plus the air's light where the particle hides what is
    // behind (summed over the particles, the CPU's haze exactly).
    let haze = params.haze_transmittance.xyz;
    var out: Colours;
    sky *= b.albedo;
    out.picture = vec4<f32>(haze * ((single + tabled) * b.sun + alpha * sky)
        + alpha * params.haze_inscatter.xyz, alpha);
    out.higher = vec4<f32>(haze * higher * b.sun, alpha);
    return out;
}
