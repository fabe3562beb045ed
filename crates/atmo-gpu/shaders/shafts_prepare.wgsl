// After the shadow maps: each light's planes (the camera-depth range of its lit volume,
// clipped to the haze box, SamplePlanes::prepare), and the scales of the attenuation
// table up to the largest distances the planes reach (AttenuationTable::new).

fn decode(u: u32) -> f32 {
    return bitcast<f32>(select(~u, u & 0x7fffffffu, (u & 0x80000000u) != 0u));
}

fn extent(k: u32, i: u32) -> f32 {
    return decode(atomicLoad(&extents[10u * k + i]));
}

@compute @workgroup_size(1)
fn planes() {
    let eye = params.position.xyz;
    let forward = params.forward.xyz;
    let far = params.position.w;
    var s_max = 0.0;
    var t_max = 0.0;
    for (var k = 0u; k < params.lights; k++) {
        let l = lights[k];
        let lamp = l.position.xyz;
        let lamp_z = dot(lamp - eye, forward);
        var lo = min(extent(k, 0u), lamp_z);
        var hi = max(extent(k, 1u), lamp_z);
        s_max = max(s_max, sqrt(extent(k, 2u)));
        t_max = max(t_max, sqrt(extent(k, 3u)));
        let box_min = min(vec3<f32>(extent(k, 4u), extent(k, 5u), extent(k, 6u)), lamp);
        let box_max = max(vec3<f32>(extent(k, 7u), extent(k, 8u), extent(k, 9u)), lamp);
        if params.haze_box != 0u {
            var bl = NO_HIT;
            var bh = -NO_HIT;
            for (var c = 0u; c < 8u; c++) {
                let corner = select(params.haze_min.xyz, params.haze_max.xyz,
                    vec3<bool>((c & 1u) != 0u, (c & 2u) != 0u, (c & 4u) != 0u));
                let z = dot(corner - eye, forward);
                bl = min(bl, z);
                bh = max(bh, z);
            }
            lo = max(lo, bl);
            hi = min(hi, bh);
        }
        let p = PLANES_AT + 12u * k;
        let local = to_light(l, eye);
        derived[p] = local.x;
        derived[p + 1u] = local.y;
        derived[p + 2u] = local.z;
        derived[p + 3u] = f32(in_haze(lamp));
        derived[p + 4u] = box_min.x;
        derived[p + 5u] = box_min.y;
        derived[p + 6u] = box_min.z;
        derived[p + 7u] = max(lo, 1e-3);
        derived[p + 8u] = box_max.x;
        derived[p + 9u] = box_max.y;
        derived[p + 10u] = box_max.z;
        derived[p + 11u] = min(hi, far);
    }
    // The longest camera ray per unit depth: to the image's corners.
    let corner = sqrt(1.0 + params.forward.w * params.forward.w + params.right.w * params.right.w);
    t_max = min(t_max, far * corner);
    let n = f32(params.attenuation_size - 1u);
    let ds = max(s_max, 1e-3) / n;
    let dt = max(t_max, 1e-3) / n;
    let at = scales_at();
    derived[at] = 1.0 / ds;
    derived[at + 1u] = 1.0 / dt;
    derived[at + 2u] = ds;
    derived[at + 3u] = dt;
}
