// The same sums as shafts_planes.wgsl in one compute pass: each pixel loops over its
// sub-pixel rays, the lights and their planes, adding to the surfaces' radiance.

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= params.width || id.y >= params.height {
        return;
    }
    var sum = vec3<f32>(0.0);
    for (var q = 0u; q < params.supersampling * params.supersampling; q++) {
        for (var k = 0u; k < params.lights; k++) {
            for (var i = 0u; i < params.planes; i++) {
                sum += plane_term(k, i, q, id.x, id.y);
            }
        }
    }
    let at = id.y * params.width + id.x;
    out[at] = vec4<f32>(out[at].xyz + sum * params.up.w, out[at].w);
}
