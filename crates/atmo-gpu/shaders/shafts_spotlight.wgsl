// Light shafts (shafts 4): a spotlight's light at a point, I_l of shafts (2) (bilinear
// lookups, the profile, the gobo) and its shadow, H (atmo::shafts::spotlight,
// shadow_map). Part of every shafts pass.

// --- bilinear lookups ---

// The texel at or left of and above the point `x` (texel coordinates with centres at
// +0.5, as the CPU's), and the weights toward the next column and row.
struct Bilinear {
    at: vec2<i32>,
    w: vec2<f32>,
}

fn bilinear(x: vec2<f32>) -> Bilinear {
    let f = x - vec2<f32>(0.5);
    let i = floor(f);
    return Bilinear(vec2<i32>(i), f - i);
}

// The four texels (this, right, below, below right) weighed by w.
fn weigh(c00: vec3<f32>, c10: vec3<f32>, c01: vec3<f32>, c11: vec3<f32>, w: vec2<f32>) -> vec3<f32> {
    return (c00 * (1.0 - w.x) + c10 * w.x) * (1.0 - w.y) + (c01 * (1.0 - w.x) + c11 * w.x) * w.y;
}

// --- the spotlight (atmo::shafts::spotlight) ---

fn to_light(l: GpuLight, p: vec3<f32>) -> vec3<f32> {
    let d = p - l.position.xyz;
    return vec3<f32>(dot(l.x_axis.xyz, d), dot(l.y_axis.xyz, d), dot(l.z_axis.xyz, d));
}

fn light_dir(l: GpuLight, v: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(dot(l.x_axis.xyz, v), dot(l.y_axis.xyz, v), dot(l.z_axis.xyz, v));
}

// World direction of light-space (u tan_field, v tan_field, 1).
fn world_direction(l: GpuLight, u: f32, v: f32) -> vec3<f32> {
    let tf = l.position.w;
    return l.x_axis.xyz * (u * tf) + l.y_axis.xyz * (v * tf) + l.z_axis.xyz;
}

// The beam profile at (u, v), exactly (Spotlight::profile_at); a measured one from
// its light map.
fn profile_at(l: GpuLight, u: f32, v: f32) -> f32 {
    let q = u * u + v * v;
    if q >= 1.0 {
        return 0.0;
    }
    if l.falloff == FALLOFF_MEASURED {
        return light_map(l, u, v);
    }
    let tf = l.position.w;
    let tb = l.z_axis.w;
    let r2 = q * tf * tf;
    if r2 <= tb * tb {
        return 1.0;
    }
    let beam_half = l.intensity.w;
    let x = clamp((l.field_half - fast_atan(sqrt(r2))) / (l.field_half - beam_half), 0.0, 1.0);
    return select(x, x * x * (3.0 - 2.0 * x), l.falloff == FALLOFF_SMOOTH);
}

fn gobo_texel(l: GpuLight, i: i32, j: i32) -> vec3<f32> {
    let w = i32(l.gobo_width);
    let h = i32(l.gobo_height);
    return geometry[l.gobo_at + u32(clamp(j, 0, h - 1) * w + clamp(i, 0, w - 1))].xyz;
}

// The gobo's colour at (u, v), the image turned (Gobo::sample).
fn gobo_sample(l: GpuLight, u_turned: f32, v_turned: f32) -> vec3<f32> {
    let u = l.gobo_cos * u_turned + l.gobo_sin * v_turned;
    let v = l.gobo_cos * v_turned - l.gobo_sin * u_turned;
    let x = 0.5 * (u + 1.0) * f32(l.gobo_width);
    let y = 0.5 * (1.0 - v) * f32(l.gobo_height);
    if l.gobo == GOBO_NEAREST {
        return gobo_texel(l, i32(floor(x)), i32(floor(y)));
    }
    let c = bilinear(vec2<f32>(x, y));
    return weigh(gobo_texel(l, c.at.x, c.at.y), gobo_texel(l, c.at.x + 1, c.at.y),
        gobo_texel(l, c.at.x, c.at.y + 1), gobo_texel(l, c.at.x + 1, c.at.y + 1), c.w);
}

// I_l toward the light-space point `local` (Spotlight::intensity_toward).
fn intensity_toward(l: GpuLight, local: vec3<f32>) -> vec3<f32> {
    if local.z <= 0.0 {
        return vec3<f32>(0.0);
    }
    let scale = 1.0 / (local.z * l.position.w);
    let u = local.x * scale;
    let v = local.y * scale;
    let profile = profile_at(l, u, v);
    if l.gobo != GOBO_NONE && profile > 0.0 {
        return l.intensity.xyz * profile * gobo_sample(l, u, v);
    }
    return l.intensity.xyz * profile;
}

// --- shadow maps (atmo::shafts::shadow_map) ---

fn shadow_depth(light: u32, i: i32, j: i32) -> f32 {
    let n = i32(params.shadow_size);
    let ii = clamp(i, 0, n - 1);
    let jj = clamp(j, 0, n - 1);
    return depth[(light * params.shadow_size + u32(jj)) * params.shadow_size + u32(ii)];
}

// H: whether the point at light-space depth z projecting to (u, v) is lit.
fn lit_at(light: u32, u: f32, v: f32, z: f32) -> bool {
    let half = 0.5 * f32(params.shadow_size);
    return z < shadow_depth(light, i32(half + u * half), i32(half - v * half));
}

// Whether texel (i, j) of light `light` lets the light reach the receiver whose plane
// is normal . x = plane (light space), at depth `own` where the texel's ray misses it.
fn texel_lit(light: u32, tan_field: f32, i: i32, j: i32, normal: vec3<f32>, plane: f32, own: f32) -> f32 {
    let n = i32(params.shadow_size);
    let ii = clamp(i, 0, n - 1);
    let jj = clamp(j, 0, n - 1);
    let texel = 2.0 / f32(params.shadow_size);
    let ray = vec3<f32>((f32(ii) + 0.5) * texel - 1.0, 1.0 - (f32(jj) + 0.5) * texel, 0.0) * tan_field
        + vec3<f32>(0.0, 0.0, 1.0);
    let facing = dot(normal, ray);
    let z = select(own, plane / facing, facing < 0.0 && plane < 0.0);
    return f32(z * (1.0 - RECEIVER_BIAS) < shadow_depth(light, ii, jj));
}

// Percentage-closer filtered visibility of a light-space point against its plane
// (ShadowMap::visibility).
fn visibility(light: u32, tan_field: f32, local: vec3<f32>, normal: vec3<f32>) -> f32 {
    let size = f32(params.shadow_size);
    let scale = 0.5 * size / (local.z * tan_field);
    let c = bilinear(vec2<f32>(0.5 * size + local.x * scale, 0.5 * size - local.y * scale));
    let plane = dot(normal, local);
    let lit = vec4<f32>(
        texel_lit(light, tan_field, c.at.x, c.at.y, normal, plane, local.z),
        texel_lit(light, tan_field, c.at.x + 1, c.at.y, normal, plane, local.z),
        texel_lit(light, tan_field, c.at.x, c.at.y + 1, normal, plane, local.z),
        texel_lit(light, tan_field, c.at.x + 1, c.at.y + 1, normal, plane, local.z),
    );
    return weigh(vec3<f32>(lit.x), vec3<f32>(lit.y), vec3<f32>(lit.z), vec3<f32>(lit.w), c.w).x;
}
