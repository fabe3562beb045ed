// Light shafts by sample planes (shafts 4): what every pass shares, translating
// atmo::shafts operation for operation, so that the GPU's picture can be held to the
// CPU's pixel by pixel. This file holds the parameters and the bindings; the rest is in
// shafts_objects, shafts_spotlight, shafts_tables and shafts_sampling.wgsl, each part
// of every shafts pass (atmo_gpu::shafts::COMMON).

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
    // 1: the surfaces' own light is drawn (the picture); 0: the haze alone, over a
    // scene shaded elsewhere, with the haze's transmittance to each pixel's surface in
    // the picture's alpha (GpuShafts::haze_over).
    surfaces: u32,
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
