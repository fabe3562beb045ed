// Each particle's depths for the sky's light inside the cloud
// (atmo::clouds::sky_light::vertical_depths): the buffer lit from the zenith read at
// the particle's centre, the optical depth above it and the whole column's, written
// into the particle's record.

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
    let g = (to_buffer(frame, particles[k].position_radius.xyz) - frame.min.xyz)
        / frame.voxel.xyz - vec3<f32>(0.5);
    particles[k].sky_depth = -log_gamma_at(g);
    particles[k].sky_column = column_depth_at(g);
}
