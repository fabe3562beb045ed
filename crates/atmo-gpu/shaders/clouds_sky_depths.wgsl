// Each particle's depths (atmo::clouds::CloudDepths::of): a buffer lit along an axis
// read at the particle's centre, the optical depth from the lit side and the whole
// column's, written into the particle's record (kept for the sky's light inside the
// cloud from the vertical's pass, which runs last); and the least of its depths out
// from either side, made the least of its own and those of the passes before, and the
// greatest column, its thickness (CloudDepths::thickness).

@group(0) @binding(0) var<uniform> frame: BufferFrame;
@group(0) @binding(1) var<storage, read_write> particles: array<GpuParticle>;
// The zenith's ln Gamma at voxel centres, [x][z][y].
@group(0) @binding(2) var<storage, read> log_gamma: array<f32>;

@compute @workgroup_size(64)
fn main(
    @builtin(workgroup_id) group: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    let k = flat_index(group, groups, local);
    if k >= frame.particles {
        return;
    }
    let g = grid_of(frame, particles[k].position_radius.xyz);
    let depth = -log_gamma_at(g);
    let column = column_depth_at(g);
    particles[k].sky_depth = depth;
    particles[k].sky_column = column;
    let out = min(depth, max(column - depth, 0.0));
    particles[k].out_depth = min(particles[k].out_depth, out);
    particles[k].thickness = max(particles[k].thickness, column);
}
