// The sample planes (shafts 4.2-4.3): per light, plane and sub-pixel ray, one
// screen-parallel quad (a triangle over the whole screen) whose fragments add
// J_i g_i dz |r| / m I_l, blended additively. The sub-sample planes of each slice are
// averaged inside the fragment (the same sum as the paper's texture of sub-planes
// multiplied in, without its two extra passes per plane).

struct Plane {
    @builtin(position) clip: vec4<f32>,
    // Light, plane, sub-pixel ray.
    @location(0) @interpolate(flat) which: vec3<u32>,
}

@vertex
fn vertex(@builtin(vertex_index) v: u32, @builtin(instance_index) i: u32) -> Plane {
    let rays = params.supersampling * params.supersampling;
    let per_light = params.planes * rays;
    var out: Plane;
    let xy = vec2<f32>(f32((v << 1u) & 2u), f32(v & 2u));
    out.clip = vec4<f32>(xy * 2.0 - 1.0, 0.5, 1.0);
    out.which = vec3<u32>(i / per_light, (i % per_light) / rays, i % rays);
    return out;
}

@fragment
fn fragment(p: Plane) -> @location(0) vec4<f32> {
    let term = plane_term(p.which.x, p.which.y, p.which.z, u32(p.clip.x), u32(p.clip.y));
    if all(term == vec3<f32>(0.0)) {
        discard;
    }
    return vec4<f32>(term * params.up.w, 0.0);
}
