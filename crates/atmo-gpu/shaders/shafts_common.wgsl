// Light shafts by sample planes (shafts 4): what every pass shares. Translates
// atmo::shafts (objects, spotlight, shadow_map, tables, surface, planes) operation for
// operation, so that the GPU's picture can be held to the CPU's pixel by pixel.
// Prepended to each shafts_*.wgsl pass.

// Mirrors atmo_gpu::shafts::ShaftsParams.
struct ShaftsParams {
    // Camera position (m); w: far plane (m).
    position: vec4<f32>,
    // Unit view axis; w: tan of half the horizontal field.
    forward: vec4<f32>,
    // Unit right; w: tan of half the vertical field.
    right: vec4<f32>,
    // Unit up; w: 1 / supersampling^2, the weight of one sub-pixel ray.
    up: vec4<f32>,
    // The haze box (if haze_box is 1); w: extinction sigma_t (1/m), scattering (1/m).
    haze_min: vec4<f32>,
    haze_max: vec4<f32>,
    width: u32,
    height: u32,
    supersampling: u32,
    lights: u32,
    planes: u32,
    sub_planes: u32,
    shadow_size: u32,
    haze_box: u32,
    objects: u32,
    // Where the BVH nodes and the triangles start in `geometry`, in vec4s.
    nodes_at: u32,
    triangles_at: u32,
    // Entries of the phase table F (over sin(alpha/2)) and of each light map.
    phase_size: u32,
    light_map_size: u32,
    attenuation_size: u32,
    // The camera's light index for the plane pass's instances is in the vertex stage.
    pad0: u32,
    pad1: u32,
}

// Mirrors atmo_gpu::shafts::GpuLight.
struct GpuLight {
    // Lamp position (m); w: tan(field / 2).
    position: vec4<f32>,
    // Rows of world to light space; w of x: q below which the profile is 1; w of y: light
    // map entries per unit q; w of z: tan(beam / 2).
    x_axis: vec4<f32>,
    y_axis: vec4<f32>,
    z_axis: vec4<f32>,
    // Intensity (cd or W/sr, RGB); w: beam half angle (rad).
    intensity: vec4<f32>,
    field_half: f32,
    // 0 linear, 1 smooth, 2 measured (the light map is the profile).
    falloff: u32,
    // 0 none, 1 nearest, 2 bilinear.
    gobo: u32,
    gobo_at: u32,
    gobo_width: u32,
    gobo_height: u32,
    // The objects that can meet this light's field cone: indices at `cone_at` in
    // `geometry` (as u32 bits), `cone_count` of them.
    cone_at: u32,
    cone_count: u32,
    // The light's map is rows map_row .. map_row + map_rows of light_maps, over C.
    map_row: u32,
    map_rows: u32,
    // The gobo's turn (Gobo::rotation) as its cosine and sine.
    gobo_cos: f32,
    gobo_sin: f32,
}

@group(0) @binding(0) var<uniform> params: ShaftsParams;
@group(0) @binding(1) var<storage, read> lights: array<GpuLight>;
// Objects (4 vec4 each: a, b, c, albedo with the kind's bits in w), BVH nodes (2 vec4:
// min with start bits, max with count bits), triangles (3 vec4: a, b - a, c - a), the
// per-light object lists and the gobo texels, one after the other.
@group(0) @binding(2) var<storage, read> geometry: array<vec4<f32>>;
// F over sin(alpha/2) (one row), and each light's profile over q (one row a light).
@group(0) @binding(3) var phase_table: texture_2d<f32>;
@group(0) @binding(4) var light_maps: texture_2d<f32>;
// Bindings 5 to 9 (depth, extents, derived, ends, out) are declared by
// shafts_writable.wgsl for the compute passes and shafts_readable.wgsl for the planes.
// s^2 h(s, t) of shafts (6) over (s, t), made each frame by shafts_attenuation.wgsl.
@group(0) @binding(10) var attenuation_table: texture_2d<f32>;

const RAY_EPSILON: f32 = 1e-4;
const NO_HIT: f32 = 3.4e38;
const FRAC_1_PI: f32 = 0.31830988;

// --- rays against the objects (atmo::shafts::objects) ---

struct Hit {
    t: f32,
    normal: vec3<f32>,
    albedo: vec3<f32>,
}

// 1 / d with zero components made huge but finite (WGSL leaves 1/0 undefined).
fn safe_recip(d: vec3<f32>) -> vec3<f32> {
    let tiny = abs(d) < vec3<f32>(1e-30);
    return select(1.0 / d, select(vec3<f32>(-1e30), vec3<f32>(1e30), d >= vec3<f32>(0.0)), tiny);
}

// The slab interval [t0, t1] of a box within [t_min, t_max], or t0 > t1.
fn clip_box(lo: vec3<f32>, hi: vec3<f32>, origin: vec3<f32>, inv: vec3<f32>, t_min: f32, t_max: f32) -> vec2<f32> {
    let a = (lo - origin) * inv;
    let b = (hi - origin) * inv;
    let n = min(a, b);
    let f = max(a, b);
    return vec2<f32>(max(max(max(n.x, n.y), n.z), t_min), min(min(min(f.x, f.y), f.z), t_max));
}

// (t, a, b) of a ray against the parallelogram corner + a edge_a + b edge_b; t = NO_HIT
// when parallel.
fn parallelogram(origin: vec3<f32>, dir: vec3<f32>, corner: vec3<f32>, edge_a: vec3<f32>, edge_b: vec3<f32>) -> vec3<f32> {
    let p = cross(dir, edge_b);
    let det = dot(edge_a, p);
    if abs(det) < 1e-12 {
        return vec3<f32>(NO_HIT, -1.0, -1.0);
    }
    let inv = 1.0 / det;
    let s = origin - corner;
    let a = dot(s, p) * inv;
    let q = cross(s, edge_a);
    let b = dot(dir, q) * inv;
    let t = dot(edge_b, q) * inv;
    return vec3<f32>(t, a, b);
}

fn valid(t: f32, t_max: f32) -> bool {
    return t > RAY_EPSILON && t < t_max;
}

// The nearest hit of object `k` closer than best.t, into best.
fn intersect(k: u32, origin: vec3<f32>, dir: vec3<f32>, best: ptr<function, Hit>) {
    let a = geometry[4u * k];
    let b = geometry[4u * k + 1u];
    let c = geometry[4u * k + 2u];
    let albedo = geometry[4u * k + 3u];
    let kind = bitcast<u32>(albedo.w);
    let t_max = (*best).t;
    var t = NO_HIT;
    var normal = vec3<f32>(0.0);
    if kind == OBJECT_PLANE {
        // Plane: a point, b normal.
        t = dot(a.xyz - origin, b.xyz) / dot(b.xyz, dir);
        normal = b.xyz;
    } else if kind == OBJECT_RECT {
        // Rectangle: a corner, b and c edges.
        let h = parallelogram(origin, dir, a.xyz, b.xyz, c.xyz);
        if h.y >= 0.0 && h.y <= 1.0 && h.z >= 0.0 && h.z <= 1.0 {
            t = h.x;
            normal = normalize(cross(b.xyz, c.xyz));
        }
    } else if kind == OBJECT_SPHERE {
        // Sphere: a centre and radius.
        let oc = origin - a.xyz;
        let bb = dot(oc, dir);
        let cc = dot(oc, oc) - a.w * a.w;
        let disc = bb * bb - cc;
        if disc >= 0.0 {
            let root = sqrt(disc);
            t = select(-bb + root, -bb - root, valid(-bb - root, t_max));
            normal = (origin + t * dir - a.xyz) / a.w;
        }
    } else if kind == OBJECT_BOX {
        // Box: a min, b max.
        let span = clip_box(a.xyz, b.xyz, origin, safe_recip(dir), -NO_HIT, t_max);
        if span.x <= span.y {
            t = select(span.y, span.x, valid(span.x, t_max));
            let p = origin + t * dir;
            let d = (p - 0.5 * (a.xyz + b.xyz)) / (0.5 * (b.xyz - a.xyz));
            let m = abs(d);
            if m.x >= m.y && m.x >= m.z {
                normal = vec3<f32>(sign(d.x), 0.0, 0.0);
            } else if m.y >= m.z {
                normal = vec3<f32>(0.0, sign(d.y), 0.0);
            } else {
                normal = vec3<f32>(0.0, 0.0, sign(d.z));
            }
        }
    } else {
        // Mesh: its BVH's root at node a.x, its triangles from a.y (as u32 bits).
        mesh_hit(bitcast<u32>(a.x), bitcast<u32>(a.y), origin, dir, albedo.xyz, best);
        return;
    }
    if valid(t, t_max) {
        (*best).t = t;
        (*best).normal = normal;
        (*best).albedo = albedo.xyz;
    }
}

fn mesh_hit(root: u32, tris: u32, origin: vec3<f32>, dir: vec3<f32>, albedo: vec3<f32>, best: ptr<function, Hit>) {
    let inv = safe_recip(dir);
    var stack: array<u32, 64>;
    var top = 1u;
    stack[0] = 0u;
    while top > 0u {
        top -= 1u;
        let index = stack[top];
        let lo = geometry[params.nodes_at + 2u * (root + index)];
        let hi = geometry[params.nodes_at + 2u * (root + index) + 1u];
        let span = clip_box(lo.xyz, hi.xyz, origin, inv, 0.0, (*best).t);
        if span.x > span.y {
            continue;
        }
        let start = bitcast<u32>(lo.w);
        let count = bitcast<u32>(hi.w);
        if count == 0u {
            stack[top] = index + 1u;
            stack[top + 1u] = start;
            top += 2u;
            continue;
        }
        for (var i = start; i < start + count; i++) {
            let at = params.triangles_at + 3u * (tris + i);
            let t0 = geometry[at].xyz;
            let e1 = geometry[at + 1u].xyz;
            let e2 = geometry[at + 2u].xyz;
            let h = parallelogram(origin, dir, t0, e1, e2);
            if h.x > RAY_EPSILON && h.x < (*best).t && h.y >= 0.0 && h.z >= 0.0 && h.y + h.z <= 1.0 {
                (*best).t = h.x;
                (*best).normal = normalize(cross(e1, e2));
                (*best).albedo = albedo;
            }
        }
    }
}

// --- bilinear lookups ---

// The texel at or left of and above the point `x` (texel coordinates with centres at
// +0.5, as the CPU's), and the weights toward the next column and row.
struct Bilinear {
    at: vec2<i32>,
    w: vec2<f32>,
}

fn bilinear(x: vec2<f32>) -> Bilinear {
    let f = x - vec2<f32>(0.5);
    let i = floor(f);
    return Bilinear(vec2<i32>(i), f - i);
}

// The four texels (this, right, below, below right) weighed by w.
fn weigh(c00: vec3<f32>, c10: vec3<f32>, c01: vec3<f32>, c11: vec3<f32>, w: vec2<f32>) -> vec3<f32> {
    return (c00 * (1.0 - w.x) + c10 * w.x) * (1.0 - w.y) + (c01 * (1.0 - w.x) + c11 * w.x) * w.y;
}

// --- the spotlight (atmo::shafts::spotlight) ---

fn to_light(l: GpuLight, p: vec3<f32>) -> vec3<f32> {
    let d = p - l.position.xyz;
    return vec3<f32>(dot(l.x_axis.xyz, d), dot(l.y_axis.xyz, d), dot(l.z_axis.xyz, d));
}

fn light_dir(l: GpuLight, v: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(dot(l.x_axis.xyz, v), dot(l.y_axis.xyz, v), dot(l.z_axis.xyz, v));
}

// World direction of light-space (u tan_field, v tan_field, 1).
fn world_direction(l: GpuLight, u: f32, v: f32) -> vec3<f32> {
    let tf = l.position.w;
    return l.x_axis.xyz * (u * tf) + l.y_axis.xyz * (v * tf) + l.z_axis.xyz;
}

// The beam profile at (u, v), exactly (Spotlight::profile_at); a measured one from
// its light map.
fn profile_at(l: GpuLight, u: f32, v: f32) -> f32 {
    let q = u * u + v * v;
    if q >= 1.0 {
        return 0.0;
    }
    if l.falloff == FALLOFF_MEASURED {
        return light_map(l, u, v);
    }
    let tf = l.position.w;
    let tb = l.z_axis.w;
    let r2 = q * tf * tf;
    if r2 <= tb * tb {
        return 1.0;
    }
    let beam_half = l.intensity.w;
    let x = clamp((l.field_half - fast_atan(sqrt(r2))) / (l.field_half - beam_half), 0.0, 1.0);
    return select(x, x * x * (3.0 - 2.0 * x), l.falloff == FALLOFF_SMOOTH);
}

fn gobo_texel(l: GpuLight, i: i32, j: i32) -> vec3<f32> {
    let w = i32(l.gobo_width);
    let h = i32(l.gobo_height);
    return geometry[l.gobo_at + u32(clamp(j, 0, h - 1) * w + clamp(i, 0, w - 1))].xyz;
}

// The gobo's colour at (u, v), the image turned (Gobo::sample).
fn gobo_sample(l: GpuLight, u_turned: f32, v_turned: f32) -> vec3<f32> {
    let u = l.gobo_cos * u_turned + l.gobo_sin * v_turned;
    let v = l.gobo_cos * v_turned - l.gobo_sin * u_turned;
    let x = 0.5 * (u + 1.0) * f32(l.gobo_width);
    let y = 0.5 * (1.0 - v) * f32(l.gobo_height);
    if l.gobo == GOBO_NEAREST {
        return gobo_texel(l, i32(floor(x)), i32(floor(y)));
    }
    let c = bilinear(vec2<f32>(x, y));
    return weigh(gobo_texel(l, c.at.x, c.at.y), gobo_texel(l, c.at.x + 1, c.at.y),
        gobo_texel(l, c.at.x, c.at.y + 1), gobo_texel(l, c.at.x + 1, c.at.y + 1), c.w);
}

// I_l toward the light-space point `local` (Spotlight::intensity_toward).
fn intensity_toward(l: GpuLight, local: vec3<f32>) -> vec3<f32> {
    if local.z <= 0.0 {
        return vec3<f32>(0.0);
    }
    let scale = 1.0 / (local.z * l.position.w);
    let u = local.x * scale;
    let v = local.y * scale;
    let profile = profile_at(l, u, v);
    if l.gobo != GOBO_NONE && profile > 0.0 {
        return l.intensity.xyz * profile * gobo_sample(l, u, v);
    }
    return l.intensity.xyz * profile;
}

// --- shadow maps (atmo::shafts::shadow_map) ---

fn shadow_depth(light: u32, i: i32, j: i32) -> f32 {
    let n = i32(params.shadow_size);
    let ii = clamp(i, 0, n - 1);
    let jj = clamp(j, 0, n - 1);
    return depth[(light * params.shadow_size + u32(jj)) * params.shadow_size + u32(ii)];
}

// H: whether the point at light-space depth z projecting to (u, v) is lit.
fn lit_at(light: u32, u: f32, v: f32, z: f32) -> bool {
    let half = 0.5 * f32(params.shadow_size);
    return z < shadow_depth(light, i32(half + u * half), i32(half - v * half));
}

// Whether texel (i, j) of light `light` lets the light reach the receiver whose plane
// is normal . x = plane (light space), at depth `own` where the texel's ray misses it.
fn texel_lit(light: u32, tan_field: f32, i: i32, j: i32, normal: vec3<f32>, plane: f32, own: f32) -> f32 {
    let n = i32(params.shadow_size);
    let ii = clamp(i, 0, n - 1);
    let jj = clamp(j, 0, n - 1);
    let texel = 2.0 / f32(params.shadow_size);
    let ray = vec3<f32>((f32(ii) + 0.5) * texel - 1.0, 1.0 - (f32(jj) + 0.5) * texel, 0.0) * tan_field
        + vec3<f32>(0.0, 0.0, 1.0);
    let facing = dot(normal, ray);
    let z = select(own, plane / facing, facing < 0.0 && plane < 0.0);
    return f32(z * (1.0 - RECEIVER_BIAS) < shadow_depth(light, ii, jj));
}

// Percentage-closer filtered visibility of a light-space point against its plane
// (ShadowMap::visibility).
fn visibility(light: u32, tan_field: f32, local: vec3<f32>, normal: vec3<f32>) -> f32 {
    let size = f32(params.shadow_size);
    let scale = 0.5 * size / (local.z * tan_field);
    let c = bilinear(vec2<f32>(0.5 * size + local.x * scale, 0.5 * size - local.y * scale));
    let plane = dot(normal, local);
    let lit = vec4<f32>(
        texel_lit(light, tan_field, c.at.x, c.at.y, normal, plane, local.z),
        texel_lit(light, tan_field, c.at.x + 1, c.at.y, normal, plane, local.z),
        texel_lit(light, tan_field, c.at.x, c.at.y + 1, normal, plane, local.z),
        texel_lit(light, tan_field, c.at.x + 1, c.at.y + 1, normal, plane, local.z),
    );
    return weigh(vec3<f32>(lit.x), vec3<f32>(lit.y), vec3<f32>(lit.z), vec3<f32>(lit.w), c.w).x;
}

// --- the haze (atmo::shafts::haze) ---

// The length of the segment a-b inside the haze, m.
fn length_inside(a: vec3<f32>, b: vec3<f32>) -> f32 {
    let d = b - a;
    if params.haze_box == 0u {
        return length(d);
    }
    let span = clip_box(params.haze_min.xyz, params.haze_max.xyz, a, safe_recip(d), 0.0, 1.0);
    if span.x > span.y {
        return 0.0;
    }
    return (span.y - span.x) * length(d);
}

fn in_haze(p: vec3<f32>) -> bool {
    return params.haze_box == 0u || (all(p >= params.haze_min.xyz) && all(p <= params.haze_max.xyz));
}

// --- the tables (atmo::shafts::tables) ---

fn lerp_row(table: texture_2d<f32>, row: i32, size: u32, x: f32) -> f32 {
    let i = clamp(i32(x), 0, i32(size) - 2);
    let f = x - f32(i);
    let a = textureLoad(table, vec2<i32>(i, row), 0).x;
    let b = textureLoad(table, vec2<i32>(i + 1, row), 0).x;
    return a + f * (b - a);
}

// F at the scattering angle whose cosine is c.
fn phase_f(c: f32) -> f32 {
    let half_sin = sqrt(clamp(0.5 * (1.0 - c), 0.0, 1.0));
    return lerp_row(phase_table, 0, params.phase_size, half_sin * f32(params.phase_size - 1u));
}

// The light map of light l at (u, v) (LightMap::get).
fn light_map(l: GpuLight, u: f32, v: f32) -> f32 {
    let q = u * u + v * v;
    if q < l.x_axis.w {
        return 1.0;
    }
    if q >= 1.0 {
        return 0.0;
    }
    let x = (q - l.x_axis.w) * l.y_axis.w;
    let row = i32(l.map_row);
    if l.map_rows == 1u {
        return lerp_row(light_maps, row, params.light_map_size, x);
    }
    // Between the rows on either side of the half-plane's C.
    let rows = f32(l.map_rows);
    var t = fast_atan2(v, u) * (rows / (2.0 * PI));
    t = select(t, t + rows, t < 0.0);
    let r = min(u32(t), l.map_rows - 1u);
    let f = t - f32(r);
    let a = lerp_row(light_maps, row + i32(r), params.light_map_size, x);
    let b = lerp_row(light_maps, row + i32((r + 1u) % l.map_rows), params.light_map_size, x);
    return a + f * (b - a);
}

const PLANES_AT: u32 = 0u;

fn scales_at() -> u32 {
    return 12u * params.lights;
}

// s^2 h(s, t) from the in-haze lengths (AttenuationTable::get).
fn attenuation(s_haze: f32, t_haze: f32) -> f32 {
    let n = params.attenuation_size;
    let at = scales_at();
    let last = f32(n - 1u);
    let x = clamp(s_haze * derived[at], 0.0, last);
    let y = clamp(t_haze * derived[at + 1u], 0.0, last);
    let i = min(i32(x), i32(n) - 2);
    let j = min(i32(y), i32(n) - 2);
    let a = x - f32(i);
    let b = y - f32(j);
    let r00 = textureLoad(attenuation_table, vec2<i32>(i, j), 0).x;
    let r01 = textureLoad(attenuation_table, vec2<i32>(i + 1, j), 0).x;
    let r10 = textureLoad(attenuation_table, vec2<i32>(i, j + 1), 0).x;
    let r11 = textureLoad(attenuation_table, vec2<i32>(i + 1, j + 1), 0).x;
    return (r00 + a * (r01 - r00)) * (1.0 - b) + (r10 + a * (r11 - r10)) * b;
}

// --- the camera (atmo::shafts::camera) ---

// The ray through image point (x, y) in pixels, unit length along the view axis.
fn camera_ray(x: f32, y: f32) -> vec3<f32> {
    let sx = (2.0 * x / f32(params.width) - 1.0) * params.forward.w;
    let sy = (1.0 - 2.0 * y / f32(params.height)) * params.right.w;
    return params.forward.xyz + sx * params.right.xyz + sy * params.up.xyz;
}

// Offset of sub-pixel ray q from its pixel's top-left corner.
fn subpixel(q: u32) -> vec2<f32> {
    let k = params.supersampling;
    return vec2<f32>((f32(q % k) + 0.5) / f32(k), (f32(q / k) + 0.5) / f32(k));
}

// --- the sample planes (atmo::shafts::planes, shafts (5)-(9)) ---

// Where the ray from `eye` along the unit `dir` enters the haze box, m (0 without one).
fn haze_entry(eye: vec3<f32>, dir: vec3<f32>) -> f32 {
    if params.haze_box != 0u {
        let span = clip_box(params.haze_min.xyz, params.haze_max.xyz, eye, safe_recip(dir), 0.0, NO_HIT);
        if span.x <= span.y {
            return span.x;
        }
    }
    return 0.0;
}

// A slab passes near the lamp when its length along the ray is more than NEAR_LAMP times
// its centre's distance from the lamp; there its light is summed at points evenly spaced
// in the scattering angle, at most ANGLE_STEP radians apart (SamplePlanes::near_slabs;
// the constants come from the prelude).
fn near_lamp(s2: f32, slab: f32) -> bool {
    return s2 * (NEAR_LAMP * NEAR_LAMP) < slab * slab;
}

// J_i g_i dz |r| / m I_l (without the sub-pixel weight) of plane `plane` of light `k`
// along sub-pixel ray `q` of pixel (x, y): the sub-samples of the plane's slice
// averaged (shafts (9)), times g at the plane (shafts (6)).
fn plane_term(k: u32, plane: u32, q: u32, x: u32, y: u32) -> vec3<f32> {
    let l = lights[k];
    let pa = PLANES_AT + 12u * k;
    let z_near = derived[pa + 7u];
    let z_far = derived[pa + 11u];
    let n = params.planes;
    let m = params.sub_planes;
    let dz = (z_far - z_near) / f32(n);
    if !(dz > 0.0) {
        return vec3<f32>(0.0);
    }
    let sub = dz / f32(m);
    let o = subpixel(q);
    let ray = camera_ray(f32(x) + o.x, f32(y) + o.y);
    let len = length(ray);
    let dir = ray / len;
    let eye = params.position.xyz;
    let end = ends[q * params.width * params.height + y * params.width + x];
    let box_min = vec3<f32>(derived[pa + 4u], derived[pa + 5u], derived[pa + 6u]);
    let box_max = vec3<f32>(derived[pa + 8u], derived[pa + 9u], derived[pa + 10u]);
    // Where the ray is in the lit volume's box before the surface, as camera depths: a
    // slice outside it has nothing to add (the per-sample tests below would all fail).
    let span = clip_box(box_min, box_max, eye, safe_recip(dir), 0.0, end) / len;
    if span.x > span.y || span.y < z_near + f32(plane) * dz || span.x > z_near + f32(plane + 1u) * dz {
        return vec3<f32>(0.0);
    }
    let origin = vec3<f32>(derived[pa], derived[pa + 1u], derived[pa + 2u]);
    let step = light_dir(l, ray);
    // A slab near the lamp: points evenly spaced in the scattering angle instead. (On
    // llvmpipe this block costs every fragment a quarter more, taken or not; one loop
    // body for both kinds of slab, with the near one's `g` under an `if`, cost more.)
    // The slab's centre: its camera depth and its point in the light's space.
    let dc = z_near + (f32(plane) + 0.5) * dz;
    let centre = origin + dc * step;
    let s2 = dot(centre, centre);
    if near_lamp(s2, dz * len) {
        let entry = haze_entry(eye, dir);
        let z0 = z_near + f32(plane) * dz;
        var sum = vec3<f32>(0.0);
        let d_near = -dot(origin, step) / (len * len);
        let foot = origin + d_near * step;
        let b = max(length(foot), 1e-6);
        let a0 = atan2(b, -(z0 - d_near) * len);
        let a1 = atan2(b, -(z0 + dz - d_near) * len);
        let count = u32(clamp(ceil((a1 - a0) / ANGLE_STEP), 1.0, MAX_ANGLE_SAMPLES));
        let d_angle = (a1 - a0) / f32(count);
        for (var j = 0u; j < count; j++) {
            let a = a0 + (f32(j) + 0.5) * d_angle;
            let sn = sin(a);
            let cs = cos(a);
            let tau = -b * cs / sn;
            let d = d_near + tau / len;
            let p = eye + d * ray;
            if d * len >= end || d >= z_far || any(p < box_min) || any(p > box_max) || !in_haze(p) {
                continue;
            }
            let local = foot + tau * (step / len);
            let lz = max(local.z, 1e-6);
            let scale = 1.0 / (l.position.w * lz);
            let u = local.x * scale;
            let v = local.y * scale;
            let weight = f32(lit_at(k, u, v, lz)) * light_map(l, u, v);
            if weight == 0.0 {
                continue;
            }
            var lit = vec3<f32>(weight);
            if l.gobo != GOBO_NONE {
                lit = weight * gobo_sample(l, u, v);
            }
            var s_haze = b / sn;
            if derived[pa + 3u] == 0.0 {
                s_haze = length_inside(l.position.xyz, p);
            }
            sum += lit * phase_f(cs) * attenuation(s_haze, max(d * len - entry, 0.0));
        }
        return l.intensity.xyz * sum * (d_angle / b);
    }
    let offset = interleaved_offset(x, y);
    let inv_tan = 1.0 / l.position.w;
    var j_sum = vec3<f32>(0.0);
    for (var j = 0u; j < m; j++) {
        let kk = plane * m + j;
        let d = z_near + (f32(kk) + offset) * sub;
        let t = d * len;
        let p = eye + t * dir;
        // The lit stretch: in front of the surface, in the lit volume's box, in the haze.
        if t >= end || d >= z_far || any(p < box_min) || any(p > box_max) || !in_haze(p) {
            continue;
        }
        let lz = max(origin.z + d * step.z, 1e-6);
        let scale = inv_tan / lz;
        let u = (origin.x + d * step.x) * scale;
        let v = (origin.y + d * step.y) * scale;
        let weight = f32(lit_at(k, u, v, lz)) * light_map(l, u, v);
        if l.gobo == GOBO_NONE {
            j_sum.x += weight;
        } else if weight > 0.0 {
            j_sum += weight * gobo_sample(l, u, v);
        }
    }
    if all(j_sum == vec3<f32>(0.0)) {
        return vec3<f32>(0.0);
    }
    if l.gobo == GOBO_NONE {
        j_sum = vec3<f32>(j_sum.x);
    }
    // g of shafts (6) at the plane, at the slab's centre.
    let inv_s = 1.0 / sqrt(s2);
    let cos_alpha = -dot(centre, step) * inv_s / len;
    var s_haze = s2 * inv_s;
    if derived[pa + 3u] == 0.0 {
        s_haze = length_inside(l.position.xyz, eye + dc * ray);
    }
    let t_haze = max(dc * len - haze_entry(eye, dir), 0.0);
    let g = phase_f(cos_alpha) * attenuation(s_haze, t_haze) * inv_s * inv_s;
    return l.intensity.xyz * j_sum * g * (dz * len / f32(m));
}
