// Reading an intensity buffer (atmo::clouds::buffer::IntensityBuffer's lookups), for
// the passes that read one: the pass declares `frame` (its BufferFrame) and `log_gamma`
// (ln Gamma at voxel centres, [x][z][y]; the draw's holds a second grid after the
// sun's, lit from the eye).

// The value at voxel (x, z, y) of the n^3 grid starting at `base` in `log_gamma`.
fn cell(base: u32, n: u32, x: u32, z: u32, y: u32) -> f32 {
    return log_gamma[base + (x * n + z) * n + y];
}

// ln Gamma at grid coordinates g (voxel centres at integers) of the grid `f` starting
// at `base`, trilinear, clamped to the grid, 0 on the light's side of it
// (IntensityBuffer::sample_log_grid); and its slope along the light per voxel
// (IntensityBuffer::extinction times -voxel.y).
fn log_gamma_and_slope_in(f: BufferFrame, base: u32, g: vec3<f32>) -> vec2<f32> {
    if g.y < -0.5 {
        return vec2<f32>(0.0);
    }
    let n = f.resolution;
    let last = f32(n - 1u);
    let c = clamp(g, vec3<f32>(0.0), vec3<f32>(last));
    let top = n - 2u;
    let i = min(vec3<u32>(c), vec3<u32>(top));
    let w = c - vec3<f32>(i);
    // Each corner across the light: its two values along it.
    let a = vec2<f32>(cell(base, n, i.x, i.z, i.y), cell(base, n, i.x, i.z, i.y + 1u));
    let b = vec2<f32>(cell(base, n, i.x + 1u, i.z, i.y), cell(base, n, i.x + 1u, i.z, i.y + 1u));
    let c0 = vec2<f32>(cell(base, n, i.x, i.z + 1u, i.y), cell(base, n, i.x, i.z + 1u, i.y + 1u));
    let d = vec2<f32>(
        cell(base, n, i.x + 1u, i.z + 1u, i.y),
        cell(base, n, i.x + 1u, i.z + 1u, i.y + 1u),
    );
    let across = mix(mix(a, b, w.x), mix(c0, d, w.x), w.z);
    return vec2<f32>(mix(across.x, across.y, w.y), across.y - across.x);
}

// ln Gamma alone.
fn log_gamma_in(f: BufferFrame, base: u32, g: vec3<f32>) -> f32 {
    return log_gamma_and_slope_in(f, base, g).x;
}

// ln Gamma of the pass's own grid (`frame`, at the start of `log_gamma`).
fn log_gamma_at(g: vec3<f32>) -> f32 {
    return log_gamma_in(frame, 0u, g);
}

// Grid coordinates of the world point p in the grid of `f`.
fn grid_of(f: BufferFrame, p: vec3<f32>) -> vec3<f32> {
    return (to_buffer(f, p) - f.min.xyz) / f.voxel.xyz - vec3<f32>(0.5);
}

// The whole cloud's optical depth along the light through grid coordinates g: -ln
// Gamma at the grid's far end, bilinear across the light
// (IntensityBuffer::column_depth_grid).
fn column_depth_at(g: vec3<f32>) -> f32 {
    return -log_gamma_at(vec3<f32>(g.x, f32(frame.resolution - 1u), g.z));
}
