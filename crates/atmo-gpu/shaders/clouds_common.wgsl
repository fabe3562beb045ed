// What the clouds' passes share: the particle record and the light pass's frame.
// Prepended to clouds_light.wgsl, clouds_prefix.wgsl and clouds_draw.wgsl.

// Mirrors atmo_gpu::clouds::GpuParticle.
struct GpuParticle {
    // Centre (m) and radius (m, three standard deviations).
    position_radius: vec4<f32>,
    // Extinction coefficient at the centre, 1/m.
    density: f32,
    albedo: f32,
    // The optical depth above the centre and the cloud's whole depth on that vertical
    // (atmo::clouds::sky_light::vertical_depths; 0 until the sky's light needs them).
    sky_depth: f32,
    sky_column: f32,
    // The least optical depth from the centre out of the cloud along the six axes
    // (atmo::clouds::CloudDepths::out, the transfer table's tau_out; made the least of
    // itself and each pass's along an axis, the largest f32 before).
    out_depth: f32,
    // The cloud's greatest optical depth through the centre along the three axes
    // (atmo::clouds::CloudDepths::thickness; made with out_depth, 0 before).
    thickness: f32,
    pad1: u32,
    pad2: u32,
}

// Mirrors atmo_gpu::clouds::BufferFrame: world to buffer axes (rows x, y along the
// light, z), the grid's smallest corner and voxel size in buffer axes (m).
struct BufferFrame {
    x_axis: vec4<f32>,
    y_axis: vec4<f32>,
    z_axis: vec4<f32>,
    min: vec4<f32>,
    voxel: vec4<f32>,
    resolution: u32,
    particles: u32,
    // Splat::Pieces (1) or Splat::Whole (0).
    pieces: u32,
    // p(l, l) / 4 pi as f32 bits.
    forward_bits: u32,
}

// ln Gamma is accumulated in fixed point, 2^-16 a step: integer sums are exact and
// independent of order, so the buffer does not depend on which particle lands first.
const FIXED_SCALE: f32 = 65536.0;

fn to_buffer(f: BufferFrame, p: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(dot(f.x_axis.xyz, p), dot(f.y_axis.xyz, p), dot(f.z_axis.xyz, p));
}

// Invocation index of a 1-D dispatch spread over (x, y) workgroups of 64.
fn flat_index(group: vec3<u32>, groups: vec3<u32>, local: u32) -> u32 {
    return (group.y * groups.x + group.x) * 64u + local;
}
