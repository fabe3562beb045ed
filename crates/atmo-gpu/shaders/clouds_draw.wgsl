// Drawing the cloud (clouds 2.2): each particle a screen-parallel Gaussian billboard,
// drawn back to front with E_k = S_k + T_k E_{k-1} (5) as premultiplied "over"
// blending, S_k = a_k tau_k p(omega, l) I_k / 4 pi (6) with I_k looked up per pixel in
// the 3-D intensity buffer (trilinear in ln Gamma), as atmo::clouds::render does.

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
    // Sky light scattered by the droplets, RGB radiance.
    ambient: vec4<f32>,
    // The air between the eye and the cloud: transmittance and in-scattered light, RGB.
    haze_transmittance: vec4<f32>,
    haze_inscatter: vec4<f32>,
    width: u32,
    height: u32,
    pad0: u32,
    pad1: u32,
}

@group(0) @binding(0) var<uniform> params: DrawParams;
@group(0) @binding(1) var<uniform> frame: BufferFrame;
@group(0) @binding(2) var<storage, read> particles: array<GpuParticle>;
// Particle indices, farthest first.
@group(0) @binding(3) var<storage, read> order: array<u32>;
// ln Gamma at voxel centres, [x][z][y].
@group(0) @binding(4) var<storage, read> log_gamma: array<f32>;

struct Billboard {
    @builtin(position) clip: vec4<f32>,
    // Centre and radius on the screen (pixels), and camera depth (m).
    @location(0) @interpolate(flat) screen: vec4<f32>,
    // a p(omega, l) E_sun and a E_ambient for this particle.
    @location(1) @interpolate(flat) lit: vec3<f32>,
    @location(2) @interpolate(flat) ambient: vec3<f32>,
    // radius, density.
    @location(3) @interpolate(flat) blob: vec2<f32>,
}

fn phase(c: f32) -> f32 {
    return phase_function(u32(params.to_sun.w), params.sun.w, c);
}

@vertex
fn vertex(@builtin(vertex_index) v: u32, @builtin(instance_index) i: u32) -> Billboard {
    let p = particles[order[i]];
    let centre = p.position_radius.xyz;
    let d = centre - params.position.xyz;
    let z = dot(d, params.forward.xyz);
    let focal = params.position.w;
    let w = f32(params.width);
    let h = f32(params.height);
    let sx = dot(d, params.right.xyz) / z * focal + 0.5 * w;
    let sy = -dot(d, params.up.xyz) / z * focal + 0.5 * h;
    let sr = p.position_radius.w / z * focal;
    // Two triangles over the square around the footprint.
    let corner = array<vec2<f32>, 6>(
        vec2(-1.0, -1.0), vec2(1.0, -1.0), vec2(1.0, 1.0),
        vec2(-1.0, -1.0), vec2(1.0, 1.0), vec2(-1.0, 1.0),
    )[v];
    let px = sx + corner.x * sr;
    let py = sy + corner.y * sr;
    var out: Billboard;
    out.clip = vec4<f32>(2.0 * px / w - 1.0, 1.0 - 2.0 * py / h, 0.5, 1.0);
    out.screen = vec4<f32>(sx, sy, sr, z);
    // The phase at the particle's centre: the angle changes little over it.
    let view = normalize(d);
    out.lit = p.albedo * phase(dot(params.to_sun.xyz, view)) * params.sun.xyz;
    out.ambient = p.albedo * params.ambient.xyz;
    out.blob = vec2<f32>(p.position_radius.w, p.density);
    return out;
}

fn cell(x: u32, z: u32, y: u32) -> f32 {
    let n = frame.resolution;
    return log_gamma[(x * n + z) * n + y];
}

// Gamma at grid coordinates g (voxel centres at integers): ln Gamma trilinear, clamped
// to the grid, 1 on the sun's side of it.
fn gamma(g: vec3<f32>) -> f32 {
    if g.y < -0.5 {
        return 1.0;
    }
    let n = frame.resolution;
    let last = f32(n - 1u);
    let c = clamp(g, vec3<f32>(0.0), vec3<f32>(last));
    let top = n - 2u;
    let i = min(vec3<u32>(c), vec3<u32>(top));
    let f = c - vec3<f32>(i);
    let a = mix(cell(i.x, i.z, i.y), cell(i.x, i.z, i.y + 1u), f.y);
    let b = mix(cell(i.x + 1u, i.z, i.y), cell(i.x + 1u, i.z, i.y + 1u), f.y);
    let c0 = mix(cell(i.x, i.z + 1u, i.y), cell(i.x, i.z + 1u, i.y + 1u), f.y);
    let d = mix(cell(i.x + 1u, i.z + 1u, i.y), cell(i.x + 1u, i.z + 1u, i.y + 1u), f.y);
    return exp(mix(mix(a, b, f.x), mix(c0, d, f.x), f.z));
}

@fragment
fn fragment(b: Billboard) -> @location(0) vec4<f32> {
    // The pixel's centre, in pixels.
    let pixel = b.clip.xy;
    let z = b.screen.w;
    let metres_per_pixel = z / params.position.w;
    let dx = (pixel.x - b.screen.x) * metres_per_pixel;
    let dy = (pixel.y - b.screen.y) * metres_per_pixel;
    let b2 = dx * dx + dy * dy;
    let radius = b.blob.x;
    if b2 >= radius * radius {
        discard;
    }
    let s = radius / 3.0;
    let column = b.blob.y * s * sqrt(2.0 * PI);
    let tau = column * exp(-b2 / (2.0 * s * s));
    // The point the pixel shows on the billboard, in the buffer's grid.
    let w = f32(params.width);
    let h = f32(params.height);
    let ray = params.forward.xyz + (2.0 * pixel.x / w - 1.0) * params.forward.w * params.right.xyz
        + (1.0 - 2.0 * pixel.y / h) * params.right.w * params.up.xyz;
    let world = params.position.xyz + ray * z;
    let g = (to_buffer(frame, world) - frame.min.xyz) / frame.voxel.xyz - vec3<f32>(0.5);
    let source = tau * (b.lit * gamma(g) + b.ambient);
    // Premultiplied: colour + (1 - alpha) x what is behind, alpha = 1 - T_k; hazed, the
    // colour seen through the air plus the air's light where the particle hides what is
    // behind (summed over the particles, the CPU's haze exactly).
    let alpha = 1.0 - exp(-tau);
    return vec4<f32>(params.haze_transmittance.xyz * source + alpha * params.haze_inscatter.xyz, alpha);
}
