// Light shafts (shafts 4): rays against the scene's objects, as atmo::shafts::objects
// and atmo::geometry. Part of every shafts pass (after shafts_common.wgsl).

// --- rays against the objects (atmo::shafts::objects) ---

struct Hit {
    t: f32,
    normal: vec3<f32>,
    albedo: vec3<f32>,
}

// 1 / d with zero components made huge but finite (WGSL leaves 1/0 undefined).
fn safe_recip(d: vec3<f32>) -> vec3<f32> {
    let tiny = abs(d) < vec3<f32>(1e-30);
    return select(1.0 / d, select(vec3<f32>(-1e30), vec3<f32>(1e30), d >= vec3<f32>(0.0)), tiny);
}

// The slab interval [t0, t1] of a box within [t_min, t_max], or t0 > t1.
fn clip_box(lo: vec3<f32>, hi: vec3<f32>, origin: vec3<f32>, inv: vec3<f32>, t_min: f32, t_max: f32) -> vec2<f32> {
    let a = (lo - origin) * inv;
    let b = (hi - origin) * inv;
    let n = min(a, b);
    let f = max(a, b);
    return vec2<f32>(max(max(max(n.x, n.y), n.z), t_min), min(min(min(f.x, f.y), f.z), t_max));
}

// (t, a, b) of a ray against the parallelogram corner + a edge_a + b edge_b; t = NO_HIT
// when parallel.
fn parallelogram(origin: vec3<f32>, dir: vec3<f32>, corner: vec3<f32>, edge_a: vec3<f32>, edge_b: vec3<f32>) -> vec3<f32> {
    let p = cross(dir, edge_b);
    let det = dot(edge_a, p);
    if abs(det) < 1e-12 {
        return vec3<f32>(NO_HIT, -1.0, -1.0);
    }
    let inv = 1.0 / det;
    let s = origin - corner;
    let a = dot(s, p) * inv;
    let q = cross(s, edge_a);
    let b = dot(dir, q) * inv;
    let t = dot(edge_b, q) * inv;
    return vec3<f32>(t, a, b);
}

fn valid(t: f32, t_max: f32) -> bool {
    return t > RAY_EPSILON && t < t_max;
}

// The nearest hit of object `k` closer than best.t, into best.
fn intersect(k: u32, origin: vec3<f32>, dir: vec3<f32>, best: ptr<function, Hit>) {
    let a = geometry[4u * k];
    let b = geometry[4u * k + 1u];
    let c = geometry[4u * k + 2u];
    let albedo = geometry[4u * k + 3u];
    let kind = bitcast<u32>(albedo.w) & ~OBJECT_NO_SHADOW;
    let t_max = (*best).t;
    var t = NO_HIT;
    var normal = vec3<f32>(0.0);
    if kind == OBJECT_PLANE {
        // Plane: a point, b normal.
        t = dot(a.xyz - origin, b.xyz) / dot(b.xyz, dir);
        normal = b.xyz;
    } else if kind == OBJECT_RECT {
        // Rectangle: a corner, b and c edges.
        let h = parallelogram(origin, dir, a.xyz, b.xyz, c.xyz);
        if h.y >= 0.0 && h.y <= 1.0 && h.z >= 0.0 && h.z <= 1.0 {
            t = h.x;
            normal = normalize(cross(b.xyz, c.xyz));
        }
    } else if kind == OBJECT_SPHERE {
        // Sphere: a centre and radius; the stable intersection of geometry.rs
        // (Haines et al.: the discriminant from the closest approach, the near root
        // as c / q).
        let f = origin - a.xyz;
        let bb = -dot(f, dir);
        let closest = f + bb * dir;
        let disc = a.w * a.w - dot(closest, closest);
        if disc >= 0.0 {
            let cc = dot(f, f) - a.w * a.w;
            let q = bb + select(-1.0, 1.0, bb >= 0.0) * sqrt(disc);
            let t0 = select(cc / q, 0.0, q == 0.0);
            let near = min(t0, q);
            let far = max(t0, q);
            t = select(far, near, valid(near, t_max));
            normal = normalize(origin + t * dir - a.xyz);
        }
    } else if kind == OBJECT_BOX {
        // Box: a min, b max.
        let span = clip_box(a.xyz, b.xyz, origin, safe_recip(dir), -NO_HIT, t_max);
        if span.x <= span.y {
            t = select(span.y, span.x, valid(span.x, t_max));
            let p = origin + t * dir;
            let d = (p - 0.5 * (a.xyz + b.xyz)) / (0.5 * (b.xyz - a.xyz));
            let m = abs(d);
            if m.x >= m.y && m.x >= m.z {
                normal = vec3<f32>(sign(d.x), 0.0, 0.0);
            } else if m.y >= m.z {
                normal = vec3<f32>(0.0, sign(d.y), 0.0);
            } else {
                normal = vec3<f32>(0.0, 0.0, sign(d.z));
            }
        }
    } else {
        // Mesh: its BVH's root at node a.x, its triangles from a.y (as u32 bits).
        mesh_hit(bitcast<u32>(a.x), bitcast<u32>(a.y), origin, dir, albedo.xyz, best);
        return;
    }
    if valid(t, t_max) {
        (*best).t = t;
        (*best).normal = normal;
        (*best).albedo = albedo.xyz;
    }
}

fn mesh_hit(root: u32, tris: u32, origin: vec3<f32>, dir: vec3<f32>, albedo: vec3<f32>, best: ptr<function, Hit>) {
    let inv = safe_recip(dir);
    var stack: array<u32, 64>;
    var top = 1u;
    stack[0] = 0u;
    while top > 0u {
        top -= 1u;
        let index = stack[top];
        let lo = geometry[params.nodes_at + 2u * (root + index)];
        let hi = geometry[params.nodes_at + 2u * (root + index) + 1u];
        let span = clip_box(lo.xyz, hi.xyz, origin, inv, 0.0, (*best).t);
        if span.x > span.y {
            continue;
        }
        let start = bitcast<u32>(lo.w);
        let count = bitcast<u32>(hi.w);
        if count == 0u {
            stack[top] = index + 1u;
            stack[top + 1u] = start;
            top += 2u;
            continue;
        }
        for (var i = start; i < start + count; i++) {
            let at = params.triangles_at + 3u * (tris + i);
            let t0 = geometry[at].xyz;
            let e1 = geometry[at + 1u].xyz;
            let e2 = geometry[at + 2u].xyz;
            let h = parallelogram(origin, dir, t0, e1, e2);
            if h.x > RAY_EPSILON && h.x < (*best).t && h.y >= 0.0 && h.z >= 0.0 && h.y + h.z <= 1.0 {
                (*best).t = h.x;
                (*best).normal = normalize(cross(e1, e2));
                (*best).albedo = albedo;
            }
        }
    }
}
