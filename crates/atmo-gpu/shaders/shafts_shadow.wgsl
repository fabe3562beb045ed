// Shadow maps (shafts 4.1), one ray through each texel centre (ShadowMap::new), and the
// extents of each light's lit volume from where those rays end (SamplePlanes::prepare):
// min and max by atomics on order-preserving encodings of the floats.

// A float as a u32 whose unsigned order is the float's order.
fn encode(f: f32) -> u32 {
    let b = bitcast<u32>(f);
    return select(b | 0x80000000u, ~b, (b & 0x80000000u) != 0u);
}

// Whether the texel centred at (u, v) touches the unit disc (the field cone).
fn touches_disc(u: f32, v: f32) -> bool {
    let half = 1.0 / f32(params.shadow_size);
    let du = max(abs(u) - half, 0.0);
    let dv = max(abs(v) - half, 0.0);
    return du * du + dv * dv <= 1.0;
}

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = params.shadow_size;
    if id.x >= size || id.y >= size {
        return;
    }
    let k = id.z;
    let l = lights[k];
    let v = 1.0 - 2.0 * (f32(id.y) + 0.5) / f32(size);
    let u = 2.0 * (f32(id.x) + 0.5) / f32(size) - 1.0;
    var d = NO_HIT;
    if touches_disc(u, v) {
        let dir = world_direction(l, u, v);
        let len = length(dir);
        var best: Hit;
        best.t = NO_HIT;
        for (var i = 0u; i < l.cone_count; i++) {
            let object = bitcast<u32>(geometry[l.cone_at + i / 4u][i % 4u]);
            intersect(object, l.position.xyz, dir / len, &best);
        }
        if best.t < NO_HIT {
            // The direction has light-space z = 1: depth is distance / length.
            d = best.t / len;
        }
        // Where the texel's ray ends, for the lit volume (ShadowMap::ray_ends).
        let eye = params.position.xyz;
        let reach = params.position.w * 2.0 + length(l.position.xyz - eye);
        let left = world_direction(l, -1.0, v);
        let right = world_direction(l, 1.0, v);
        let end = l.position.xyz + min(d, reach) * (left + (right - left) * (0.5 * (u + 1.0)));
        let z = dot(end - eye, params.forward.xyz);
        let s = end - l.position.xyz;
        let t = end - eye;
        let e = 10u * k;
        atomicMin(&extents[e], encode(z));
        atomicMax(&extents[e + 1u], encode(z));
        atomicMax(&extents[e + 2u], encode(dot(s, s)));
        atomicMax(&extents[e + 3u], encode(dot(t, t)));
        for (var c = 0u; c < 3u; c++) {
            atomicMin(&extents[e + 4u + c], encode(end[c]));
            atomicMax(&extents[e + 7u + c], encode(end[c]));
        }
    }
    depth[(k * size + id.y) * size + id.x] = d;
}
