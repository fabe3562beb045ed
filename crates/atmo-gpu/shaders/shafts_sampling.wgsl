// Light shafts (shafts 4): the sample and sub-sample planes, shafts (5)-(9)
// (atmo::shafts::planes). Part of every shafts pass.

// --- the sample planes (atmo::shafts::planes, shafts (5)-(9)) ---

// Where the ray from `eye` along the unit `dir` enters the haze box, m (0 without one).
fn haze_entry(eye: vec3<f32>, dir: vec3<f32>) -> f32 {
    if params.haze_box != 0u {
        let span = clip_box(params.haze_min.xyz, params.haze_max.xyz, eye, safe_recip(dir), 0.0, NO_HIT);
        if span.x <= span.y {
            return span.x;
        }
    }
    return 0.0;
}

// A slab passes near the lamp when its length along the ray is more than NEAR_LAMP times
// its centre's distance from the lamp; there its light is summed at points evenly spaced
// in the scattering angle, at most ANGLE_STEP radians apart (SamplePlanes::near_slabs;
// the constants come from the prelude).
fn near_lamp(s2: f32, slab: f32) -> bool {
    return s2 * (NEAR_LAMP * NEAR_LAMP) < slab * slab;
}

// J_i g_i dz |r| / m I_l (without the sub-pixel weight) of plane `plane` of light `k`
// along sub-pixel ray `q` of pixel (x, y): the sub-samples of the plane's slice
// averaged (shafts (9)), times g at the plane (shafts (6)).
fn plane_term(k: u32, plane: u32, q: u32, x: u32, y: u32) -> vec3<f32> {
    let l = lights[k];
    let pa = PLANES_AT + 12u * k;
    let z_near = derived[pa + 7u];
    let z_far = derived[pa + 11u];
    let n = params.planes;
    let m = params.sub_planes;
    let dz = (z_far - z_near) / f32(n);
    if !(dz > 0.0) {
        return vec3<f32>(0.0);
    }
    let sub = dz / f32(m);
    let o = subpixel(q);
    let ray = camera_ray(f32(x) + o.x, f32(y) + o.y);
    let len = length(ray);
    let dir = ray / len;
    let eye = params.position.xyz;
    let end = ends[q * params.width * params.height + y * params.width + x];
    let box_min = vec3<f32>(derived[pa + 4u], derived[pa + 5u], derived[pa + 6u]);
    let box_max = vec3<f32>(derived[pa + 8u], derived[pa + 9u], derived[pa + 10u]);
    // Where the ray is in the lit volume's box before the surface, as camera depths: a
    // slice outside it has nothing to add (the per-sample tests below would all fail).
    let span = clip_box(box_min, box_max, eye, safe_recip(dir), 0.0, end) / len;
    if span.x > span.y || span.y < z_near + f32(plane) * dz || span.x > z_near + f32(plane + 1u) * dz {
        return vec3<f32>(0.0);
    }
    let origin = vec3<f32>(derived[pa], derived[pa + 1u], derived[pa + 2u]);
    let step = light_dir(l, ray);
    // A slab near the lamp: points evenly spaced in the scattering angle instead. (On
    // llvmpipe this block costs every fragment a quarter more, taken or not; one loop
    // body for both kinds of slab, with the near one's `g` under an `if`, cost more.)
    // The slab's centre: its camera depth and its point in the light's space.
    let dc = z_near + (f32(plane) + 0.5) * dz;
    let centre = origin + dc * step;
    let s2 = dot(centre, centre);
    if near_lamp(s2, dz * len) {
        let entry = haze_entry(eye, dir);
        let z0 = z_near + f32(plane) * dz;
        var sum = vec3<f32>(0.0);
        let d_near = -dot(origin, step) / (len * len);
        let foot = origin + d_near * step;
        let b = max(length(foot), 1e-6);
        let a0 = atan2(b, -(z0 - d_near) * len);
        let a1 = atan2(b, -(z0 + dz - d_near) * len);
        let count = u32(clamp(ceil((a1 - a0) / ANGLE_STEP), 1.0, MAX_ANGLE_SAMPLES));
        let d_angle = (a1 - a0) / f32(count);
        for (var j = 0u; j < count; j++) {
            let a = a0 + (f32(j) + 0.5) * d_angle;
            let sn = sin(a);
            let cs = cos(a);
            let tau = -b * cs / sn;
            let d = d_near + tau / len;
            let p = eye + d * ray;
            if d * len >= end || d >= z_far || any(p < box_min) || any(p > box_max) || !in_haze(p) {
                continue;
            }
            let local = foot + tau * (step / len);
            let lz = max(local.z, 1e-6);
            let scale = 1.0 / (l.position.w * lz);
            let u = local.x * scale;
            let v = local.y * scale;
            let weight = f32(lit_at(k, u, v, lz)) * light_map(l, u, v);
            if weight == 0.0 {
                continue;
            }
            var lit = vec3<f32>(weight);
            if l.gobo != GOBO_NONE {
                lit = weight * gobo_sample(l, u, v);
            }
            var s_haze = b / sn;
            if derived[pa + 3u] == 0.0 {
                s_haze = length_inside(l.position.xyz, p);
            }
            sum += lit * phase_f(cs) * attenuation(s_haze, max(d * len - entry, 0.0));
        }
        return l.intensity.xyz * sum * (d_angle / b);
    }
    let offset = interleaved_offset(x, y);
    let inv_tan = 1.0 / l.position.w;
    var j_sum = vec3<f32>(0.0);
    for (var j = 0u; j < m; j++) {
        let kk = plane * m + j;
        let d = z_near + (f32(kk) + offset) * sub;
        let t = d * len;
        let p = eye + t * dir;
        // The lit stretch: in front of the surface, in the lit volume's box, in the haze.
        if t >= end || d >= z_far || any(p < box_min) || any(p > box_max) || !in_haze(p) {
            continue;
        }
        let lz = max(origin.z + d * step.z, 1e-6);
        let scale = inv_tan / lz;
        let u = (origin.x + d * step.x) * scale;
        let v = (origin.y + d * step.y) * scale;
        let weight = f32(lit_at(k, u, v, lz)) * light_map(l, u, v);
        if l.gobo == GOBO_NONE {
            j_sum.x += weight;
        } else if weight > 0.0 {
            j_sum += weight * gobo_sample(l, u, v);
        }
    }
    if all(j_sum == vec3<f32>(0.0)) {
        return vec3<f32>(0.0);
    }
    if l.gobo == GOBO_NONE {
        j_sum = vec3<f32>(j_sum.x);
    }
    // g of shafts (6) at the plane, at the slab's centre.
    let inv_s = 1.0 / sqrt(s2);
    let cos_alpha = -dot(centre, step) * inv_s / len;
    var s_haze = s2 * inv_s;
    if derived[pa + 3u] == 0.0 {
        s_haze = length_inside(l.position.xyz, eye + dc * ray);
    }
    let t_haze = max(dc * len - haze_entry(eye, dir), 0.0);
    let g = phase_f(cos_alpha) * attenuation(s_haze, t_haze) * inv_s * inv_s;
    return l.intensity.xyz * j_sum * g * (dz * len / f32(m));
}
