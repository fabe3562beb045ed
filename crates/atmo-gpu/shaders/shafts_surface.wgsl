// The first term of shafts (1): the surface each sub-pixel ray meets, lit by the
// spotlights through their (filtered) shadow maps and dimmed by the haze
// (surface::first_hit, surface_radiance); and where each ray ends, for the planes.

// Radiance the eye receives from a surface point (surface_radiance).
fn surface_radiance(p: vec3<f32>, normal: vec3<f32>, albedo: vec3<f32>) -> vec3<f32> {
    let extinction = params.haze_min.w;
    var sum = vec3<f32>(0.0);
    for (var k = 0u; k < params.lights; k++) {
        let l = lights[k];
        let to_lamp = l.position.xyz - p;
        let s = length(to_lamp);
        let c = dot(normal, to_lamp) / s;
        if c <= 0.0 {
            continue;
        }
        let local = to_light(l, p);
        let intensity = intensity_toward(l, local);
        if all(intensity == vec3<f32>(0.0)) {
            continue;
        }
        var v = visibility(k, l.position.w, local, light_dir(l, normal));
        // Where the filter straddles a shadow's edge, a shadow ray decides.
        if v > 0.0 && v < 1.0 {
            v = shadow_ray(l, p, normal);
        }
        if v <= 0.0 {
            continue;
        }
        let attenuation = exp(-extinction * length_inside(l.position.xyz, p));
        sum += intensity * (v * c * attenuation / (s * s));
    }
    if all(sum == vec3<f32>(0.0)) {
        return sum;
    }
    let to_eye = exp(-extinction * length_inside(params.position.xyz, p));
    return albedo * FRAC_1_PI * sum * to_eye;
}

// 1 when nothing lies between the surface point (lifted 0.1 mm off it) and the lamp,
// else 0 (surface::shadow_ray).
fn shadow_ray(l: GpuLight, p: vec3<f32>, normal: vec3<f32>) -> f32 {
    let origin = p + normal * 1e-4;
    let to_lamp = l.position.xyz - origin;
    let s = length(to_lamp);
    var best: Hit;
    best.t = s;
    for (var i = 0u; i < params.objects; i++) {
        // A head's body holds its lamp: it casts no shadow.
        if (bitcast<u32>(geometry[4u * i + 3u].w) & OBJECT_NO_SHADOW) == 0u {
            intersect(i, origin, to_lamp / s, &best);
        }
    }
    return f32(best.t >= s);
}

// The length of the ray from `eye` along unit `dir` to `t` (which may be infinite)
// inside the haze.
fn inside_along(eye: vec3<f32>, dir: vec3<f32>, t: f32) -> f32 {
    if params.haze_box == 0u {
        return t;
    }
    let span = clip_box(params.haze_min.xyz, params.haze_max.xyz, eye, safe_recip(dir), 0.0, t);
    return max(span.y - span.x, 0.0);
}

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let w = params.width;
    let h = params.height;
    if id.x >= w || id.y >= h {
        return;
    }
    let eye = params.position.xyz;
    let far = params.position.w;
    var sum = vec3<f32>(0.0);
    var through = 0.0;
    for (var q = 0u; q < params.supersampling * params.supersampling; q++) {
        let o = subpixel(q);
        let ray = camera_ray(f32(id.x) + o.x, f32(id.y) + o.y);
        let len = length(ray);
        let dir = ray / len;
        var best: Hit;
        best.t = far * len;
        for (var i = 0u; i < params.objects; i++) {
            intersect(i, eye, dir, &best);
        }
        if params.surfaces == 0u {
            through += exp(-params.haze_min.w * inside_along(eye, dir, best.t));
        } else if best.t < far * len {
            let normal = select(best.normal, -best.normal, dot(best.normal, dir) > 0.0);
            sum += surface_radiance(eye + best.t * dir, normal, best.albedo);
        }
        ends[q * w * h + id.y * w + id.x] = best.t;
    }
    let alpha = select(through * params.up.w, 1.0, params.surfaces != 0u);
    out[id.y * w + id.x] = vec4<f32>(sum * params.up.w, alpha);
}
