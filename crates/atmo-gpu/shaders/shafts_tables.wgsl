// Light shafts (shafts 4): the haze, the F and h tables of shafts (6) and the
// intensity maps (atmo::shafts::haze, tables), and the camera's rays. Part of every
// shafts pass.

// --- the haze (atmo::shafts::haze) ---

// The length of the segment a-b inside the haze, m.
fn length_inside(a: vec3<f32>, b: vec3<f32>) -> f32 {
    let d = b - a;
    if params.haze_box == 0u {
        return length(d);
    }
    let span = clip_box(params.haze_min.xyz, params.haze_max.xyz, a, safe_recip(d), 0.0, 1.0);
    if span.x > span.y {
        return 0.0;
    }
    return (span.y - span.x) * length(d);
}

fn in_haze(p: vec3<f32>) -> bool {
    return params.haze_box == 0u || (all(p >= params.haze_min.xyz) && all(p <= params.haze_max.xyz));
}

// --- the tables (atmo::shafts::tables) ---

fn lerp_row(table: texture_2d<f32>, row: i32, size: u32, x: f32) -> f32 {
    let i = clamp(i32(x), 0, i32(size) - 2);
    let f = x - f32(i);
    let a = textureLoad(table, vec2<i32>(i, row), 0).x;
    let b = textureLoad(table, vec2<i32>(i + 1, row), 0).x;
    return a + f * (b - a);
}

// F at the scattering angle whose cosine is c.
fn phase_f(c: f32) -> f32 {
    let half_sin = sqrt(clamp(0.5 * (1.0 - c), 0.0, 1.0));
    return lerp_row(phase_table, 0, params.phase_size, half_sin * f32(params.phase_size - 1u));
}

// The light map of light l at (u, v) (LightMap::get).
fn light_map(l: GpuLight, u: f32, v: f32) -> f32 {
    let q = u * u + v * v;
    if q < l.x_axis.w {
        return 1.0;
    }
    if q >= 1.0 {
        return 0.0;
    }
    let x = (q - l.x_axis.w) * l.y_axis.w;
    let row = i32(l.map_row);
    if l.map_rows == 1u {
        return lerp_row(light_maps, row, params.light_map_size, x);
    }
    // Between the rows on either side of the half-plane's C.
    let rows = f32(l.map_rows);
    var t = fast_atan2(v, u) * (rows / (2.0 * PI));
    t = select(t, t + rows, t < 0.0);
    let r = min(u32(t), l.map_rows - 1u);
    let f = t - f32(r);
    let a = lerp_row(light_maps, row + i32(r), params.light_map_size, x);
    let b = lerp_row(light_maps, row + i32((r + 1u) % l.map_rows), params.light_map_size, x);
    return a + f * (b - a);
}

const PLANES_AT: u32 = 0u;

fn scales_at() -> u32 {
    return 12u * params.lights;
}

// s^2 h(s, t) from the in-haze lengths (AttenuationTable::get).
fn attenuation(s_haze: f32, t_haze: f32) -> f32 {
    let n = params.attenuation_size;
    let at = scales_at();
    let last = f32(n - 1u);
    let x = clamp(s_haze * derived[at], 0.0, last);
    let y = clamp(t_haze * derived[at + 1u], 0.0, last);
    let i = min(i32(x), i32(n) - 2);
    let j = min(i32(y), i32(n) - 2);
    let a = x - f32(i);
    let b = y - f32(j);
    let r00 = textureLoad(attenuation_table, vec2<i32>(i, j), 0).x;
    let r01 = textureLoad(attenuation_table, vec2<i32>(i + 1, j), 0).x;
    let r10 = textureLoad(attenuation_table, vec2<i32>(i, j + 1), 0).x;
    let r11 = textureLoad(attenuation_table, vec2<i32>(i + 1, j + 1), 0).x;
    return (r00 + a * (r01 - r00)) * (1.0 - b) + (r10 + a * (r11 - r10)) * b;
}

// --- the camera (atmo::shafts::camera) ---

// The ray through image point (x, y) in pixels, unit length along the view axis.
fn camera_ray(x: f32, y: f32) -> vec3<f32> {
    let sx = (2.0 * x / f32(params.width) - 1.0) * params.forward.w;
    let sy = (1.0 - 2.0 * y / f32(params.height)) * params.right.w;
    return params.forward.xyz + sx * params.right.xyz + sy * params.up.xyz;
}

// Offset of sub-pixel ray q from its pixel's top-left corner.
fn subpixel(q: u32) -> vec2<f32> {
    let k = params.supersampling;
    return vec2<f32>((f32(q % k) + 0.5) / f32(k), (f32(q / k) + 0.5) / f32(k));
}
