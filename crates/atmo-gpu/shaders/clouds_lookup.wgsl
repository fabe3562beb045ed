// Reading an intensity buffer (atmo::clouds::buffer::IntensityBuffer's lookups), for
// the passes that read one: the pass declares `frame` (its BufferFrame) and `log_gamma`
// (ln Gamma at voxel centres, [x][z][y]).

fn cell(x: u32, z: u32, y: u32) -> f32 {
    let n = frame.resolution;
    return log_gamma[(x * n + z) * n + y];
}

// ln Gamma at grid coordinates g (voxel centres at integers), trilinear, clamped to
// the grid, 0 on the sun's side of it: IntensityBuffer::sample_log_grid.
fn log_gamma_at(g: vec3<f32>) -> f32 {
    if g.y < -0.5 {
        return 0.0;
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
    return mix(mix(a, b, f.x), mix(c0, d, f.x), f.z);
}

// The whole cloud's optical depth along the light through grid coordinates g: -ln
// Gamma at the grid's far end, bilinear across the light
// (IntensityBuffer::column_depth_grid).
fn column_depth_at(g: vec3<f32>) -> f32 {
    return -log_gamma_at(vec3<f32>(g.x, f32(frame.resolution - 1u), g.z));
}
