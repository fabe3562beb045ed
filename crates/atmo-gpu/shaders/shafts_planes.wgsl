// The sample planes (shafts 4.2-4.3): per light, plane and sub-pixel ray, one
// screen-parallel quad over the screen rectangle of the light's lit volume, whose
// fragments add J_i g_i dz |r| / m I_l, blended additively. The sub-sample planes of each slice are
// averaged inside the fragment (the same sum as the paper's texture of sub-planes
// multiplied in, without its two extra passes per plane).

struct Plane {
    @builtin(position) clip: vec4<f32>,
    // Light, plane, sub-pixel ray.
    @location(0) @interpolate(flat) which: vec3<u32>,
}

// The screen rectangle (normalised device coordinates, min and max) that holds the
// box of light k's lit volume: its corners projected, or the whole screen when one is
// behind the eye. Pixels outside it get nothing from the light (plane_term skips
// sub-samples outside the box), so the quad covers only what can be lit.
fn lit_rectangle(k: u32) -> vec4<f32> {
    let pa = PLANES_AT + 12u * k;
    let lo = vec3<f32>(derived[pa + 4u], derived[pa + 5u], derived[pa + 6u]);
    let hi = vec3<f32>(derived[pa + 8u], derived[pa + 9u], derived[pa + 10u]);
    var rect = vec4<f32>(1.0, 1.0, -1.0, -1.0);
    for (var c = 0u; c < 8u; c++) {
        let corner = select(lo, hi, vec3<bool>((c & 1u) != 0u, (c & 2u) != 0u, (c & 4u) != 0u));
        let d = corner - params.position.xyz;
        let z = dot(d, params.forward.xyz);
        if z <= 1e-3 {
            return vec4<f32>(-1.0, -1.0, 1.0, 1.0);
        }
        let p = vec2<f32>(dot(d, params.right.xyz) / (z * params.forward.w),
            dot(d, params.up.xyz) / (z * params.right.w));
        rect = vec4<f32>(min(rect.xy, p), max(rect.zw, p));
    }
    // A pixel's margin against rounding, then clipped to the screen.
    let margin = 2.0 / vec2<f32>(f32(params.width), f32(params.height));
    return clamp(rect + vec4<f32>(-margin, margin), vec4<f32>(-1.0), vec4<f32>(1.0));
}

@vertex
fn vertex(@builtin(vertex_index) v: u32, @builtin(instance_index) i: u32) -> Plane {
    let rays = params.supersampling * params.supersampling;
    let per_light = params.planes * rays;
    let k = i / per_light;
    let rect = lit_rectangle(k);
    let corner = array<vec2<u32>, 6>(
        vec2(0u, 1u), vec2(2u, 1u), vec2(2u, 3u), vec2(0u, 1u), vec2(2u, 3u), vec2(0u, 3u),
    )[v];
    var out: Plane;
    out.clip = vec4<f32>(rect[corner.x], rect[corner.y], 0.5, 1.0);
    out.which = vec3<u32>(k, (i % per_light) / rays, i % rays);
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
