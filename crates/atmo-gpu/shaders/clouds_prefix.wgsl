// The second half of the light pass: each column along the light summed (exactly, in
// integers), turning increments into ln Gamma at every voxel centre, written back as
// f32 in place.

@group(0) @binding(0) var<uniform> frame: BufferFrame;
// In: fixed-point increments; out: ln Gamma as f32 bits. [x][z][y].
@group(0) @binding(1) var<storage, read_write> cells: array<i32>;

@compute @workgroup_size(64)
fn main(
    @builtin(workgroup_id) group: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    let n = frame.resolution;
    let column = flat_index(group, groups, local);
    if column >= n * n {
        return;
    }
    var sum = 0;
    for (var i = column * n; i < (column + 1u) * n; i++) {
        // Held above -2^14 rather than wrapping: Gamma is e^-16384 = 0 all the same.
        sum = max(sum, -1073741824) + cells[i];
        cells[i] = bitcast<i32>(f32(sum) / FIXED_SCALE);
    }
}
