// The skylight map of a sun by the shell method (sky 3): for each view direction of a
// grid, the sum over its ray's shell crossings of the light map x phase map x density
// map x attenuation map, sky (3), plus the scattered light of the orders below through
// the moments of the scattered light maps, sky (11), and the sunlit ground at the end of
// the ray. The sun-independent maps come from atmo::sky::export::ModelArrays; this is
// ScatteringMaps::radiance operation for operation, one invocation per direction.

// Mirrors atmo_gpu::sky::ShellParams.
struct ShellParams {
    // sin and cos of the sun's elevation.
    sun: vec4<f32>,
    // Grid: lowest and highest elevation (rad), azimuths, elevations.
    grid: vec4<f32>,
    bottom: f32,
    top: f32,
    sun_radius: f32,
    ground_albedo: f32,
    lanes: u32,
    // 1 with orders above the first.
    multiple: u32,
    shells: u32,
    light_entries: u32,
    mu_size: u32,
    r_size: u32,
    sun_bins: u32,
    sun_bins_a: f32,
    rayleigh_kind: u32,
    rayleigh_g: f32,
    mie_kind: u32,
    mie_g: f32,
    // Where each region starts in `data`, in vec4s.
    rays_at: u32,
    samples_at: u32,
    rayleigh_at: u32,
    mie_at: u32,
    ground_at: u32,
    shells_at: u32,
    light_at: u32,
    irradiance_at: u32,
    transmittance_at: u32,
    moments_at: u32,
    rgb_at: u32,
    aerosol_at: u32,
    ground_light_at: u32,
    // 1 if aerosols scatter the higher orders (their table is present).
    aerosols: u32,
    pad0: u32,
    pad1: u32,
}

@group(0) @binding(0) var<uniform> params: ShellParams;
// Rays (start bits, end bits, origin radius, ground distance), samples (2 vec4: shell
// bits, between, altitude, distance; mu), the Rayleigh and aerosol maps [sample][lane],
// the ground [ray][lane], shells (radius, mu_low, scale), the light map
// [shell][entry][lane], the irradiance [lane], the transmittance [r][mu][lane], the
// higher orders' moments [shell][bin][moment][lane], the colour matrix [lane][rgb], the
// aerosols' in-scattering [bin][shell][cell][lane] and the ground's irradiance
// [bin][lane].
@group(0) @binding(1) var<storage, read> data: array<vec4<f32>>;
// Out: linear sRGB, [elevation][azimuth][rgb].
@group(0) @binding(2) var<storage, read_write> map: array<f32>;

// MOMENTS (the moments a Rayleigh in-scattering needs), TABLE_MU, TABLE_PHI and
// MAX_LANES come from the prelude (atmo::sky::shells::export).

// The light map of sunlight at shell `shell`, lane `l` (LightMap::sample).
fn light_map(shell: u32, mu_s: f32, l: u32) -> vec4<f32> {
    let s = data[params.shells_at + shell];
    if mu_s <= s.y {
        return vec4<f32>(0.0);
    }
    let x = (mu_s - s.y) * s.z;
    let k = min(u32(x), params.light_entries - 2u);
    let f = x - f32(k);
    let base = params.light_at + (shell * params.light_entries + k) * params.lanes + l;
    let a = data[base];
    return a + (data[base + params.lanes] - a) * f;
}

// Sunlight at altitude h (between shells), exactly as LightMap::sample_at: the
// transmittance table to the top, times the visible part of the disc and the irradiance.
fn sunlight(h: f32, mu_s: f32, l: u32) -> vec4<f32> {
    let b = params.bottom;
    let r = b + h;
    let rho = sqrt(max(h * (2.0 * b + h), 0.0));
    let cos_h = -rho / r;
    let half_width = b / r * params.sun_radius;
    let visible = clamp((mu_s - cos_h + half_width) / (2.0 * half_width), 0.0, 1.0);
    if visible == 0.0 {
        return vec4<f32>(0.0);
    }
    // TransmittanceTable::coords, with r^2 - b^2 and top^2 - r^2 from altitudes.
    let top = params.top;
    let big_h = sqrt((top - b) * (top + b));
    let mu = max(mu_s, cos_h);
    let disc = ((top - b) - h) * (top + r) + r * r * mu * mu;
    let d = max(-r * mu + sqrt(max(disc, 0.0)), 0.0);
    let d_min = top - r;
    let d_max = rho + big_h;
    var x_mu = 0.0;
    if d_max > d_min {
        x_mu = (d - d_min) / (d_max - d_min);
    }
    let x = clamp(x_mu, 0.0, 1.0) * f32(params.mu_size - 1u);
    let y = clamp(rho / big_h, 0.0, 1.0) * f32(params.r_size - 1u);
    let i = min(u32(x), params.mu_size - 2u);
    let j = min(u32(y), params.r_size - 2u);
    let fx = x - f32(i);
    let fy = y - f32(j);
    let at = params.transmittance_at;
    let n = params.lanes;
    let v00 = data[at + (j * params.mu_size + i) * n + l];
    let v10 = data[at + (j * params.mu_size + i + 1u) * n + l];
    let v01 = data[at + ((j + 1u) * params.mu_size + i) * n + l];
    let v11 = data[at + ((j + 1u) * params.mu_size + i + 1u) * n + l];
    let lo = v00 + (v10 - v00) * fx;
    let hi = v01 + (v11 - v01) * fx;
    return (lo + (hi - lo) * fy) * visible * data[params.irradiance_at + l];
}

// The ray's direction in the local frame of a sample (maps::local_direction).
fn local_direction(mu: f32, mu_s: f32, nu: f32) -> vec3<f32> {
    let sin_d = sqrt(max(1.0 - mu * mu, 0.0));
    let sin_s = sqrt(max(1.0 - mu_s * mu_s, 0.0));
    var cos_phi = 1.0;
    if sin_d * sin_s > 1e-9 {
        cos_phi = clamp((nu - mu * mu_s) / (sin_d * sin_s), -1.0, 1.0);
    }
    let sin_phi = sqrt(max(1.0 - cos_phi * cos_phi, 0.0));
    return vec3<f32>(sin_d * cos_phi, sin_d * sin_phi, mu);
}

// The sun bin below mu_s and the fraction toward the next (SunBins::lerp).
fn sun_bin(mu_s: f32) -> vec2<f32> {
    let a = params.sun_bins_a;
    let m = min(abs(mu_s), 1.0);
    let x = (-a + sqrt(a * a + 4.0 * (1.0 - a) * m)) / (2.0 * (1.0 - a));
    let coordinate = 0.5 * (select(-x, x, mu_s >= 0.0) + 1.0) * f32(params.sun_bins - 1u);
    let b = min(u32(coordinate), params.sun_bins - 2u);
    return vec2<f32>(f32(b), coordinate - f32(b));
}

// Rayleigh in-scattering of the higher orders' light at `shell` toward local direction
// d, from its five moments (ScatteredLightMap::inscatter).
fn inscatter(shell: u32, mu_s: f32, d: vec3<f32>, l: u32) -> vec4<f32> {
    let bin = sun_bin(mu_s);
    let b = u32(bin.x);
    let f = bin.y;
    let k = 3.0 / (16.0 * PI);
    let g = array<f32, 5>(k, k * d.x * d.x, k * d.y * d.y, k * d.z * d.z, 2.0 * k * d.x * d.z);
    let n = params.lanes;
    let at = params.moments_at + (shell * params.sun_bins + b) * MOMENTS * n;
    var out = vec4<f32>(0.0);
    for (var i = 0u; i < MOMENTS; i++) {
        let m0 = data[at + i * n + l];
        let m1 = data[at + MOMENTS * n + i * n + l];
        out += g[i] * (m0 + (m1 - m0) * f);
    }
    return out;
}

// The aerosols' in-scattering of the higher orders' light at `shell` toward local
// direction d: trilinear in the table (ScatteredLightMap::inscatter).
fn aerosol_inscatter(shell: u32, mu_s: f32, d: vec3<f32>, l: u32) -> vec4<f32> {
    let bin = sun_bin(mu_s);
    let b = u32(bin.x);
    let f = bin.y;
    let x = clamp(d.z + 1.0, 0.0, 2.0) * 0.5 * f32(TABLE_MU - 1u);
    let i = min(u32(x), TABLE_MU - 2u);
    let fx = x - f32(i);
    let y = clamp(atan2(d.y, d.x), 0.0, PI) / PI * f32(TABLE_PHI - 1u);
    let j = min(u32(y), TABLE_PHI - 2u);
    let fy = y - f32(j);
    let cells = array<u32, 4>(i * TABLE_PHI + j, i * TABLE_PHI + j + 1u, (i + 1u) * TABLE_PHI + j, (i + 1u) * TABLE_PHI + j + 1u);
    let weights = array<f32, 4>((1.0 - fx) * (1.0 - fy), (1.0 - fx) * fy, fx * (1.0 - fy), fx * fy);
    let n = params.lanes;
    var out = vec4<f32>(0.0);
    let cells_n = TABLE_MU * TABLE_PHI;
    for (var c = 0u; c < 4u; c++) {
        let at = params.aerosol_at + ((b * params.shells + shell) * cells_n + cells[c]) * n + l;
        let v0 = data[at];
        let v1 = data[at + params.shells * cells_n * n];
        out += weights[c] * (v0 + (v1 - v0) * f);
    }
    return out;
}

// The irradiance the higher orders' light puts on the ground, sun at mu_s there.
fn ground_light(mu_s: f32, l: u32) -> vec4<f32> {
    let bin = sun_bin(mu_s);
    let at = params.ground_light_at + u32(bin.x) * params.lanes + l;
    let e0 = data[at];
    return e0 + (data[at + params.lanes] - e0) * bin.y;
}

// The light each species scatters toward a ray's origin per unit weight at a sample
// (lane l): sunlight x phase for order 1, and the higher orders' light scattered again
// (ScatteringMaps::sources_along).
struct Sources {
    r: vec4<f32>,
    m: vec4<f32>,
}

// A sample of a ray: its shell, fraction between it and the next, altitude (m), the
// sun's zenith cosine there, and the ray's local direction (higher orders only).
struct Sample {
    shell: u32,
    between: f32,
    altitude: f32,
    mu_s: f32,
    d: vec3<f32>,
}

// The sample of records `a` (shell bits, between, altitude, distance) and zenith cosine
// `mu`, on a ray with origin radius x sun zenith cosine `r0_mu_s` at cosine `nu` to the
// sun.
fn sample_at(a: vec4<f32>, mu: f32, r0_mu_s: f32, nu: f32) -> Sample {
    let mu_s = clamp((r0_mu_s + a.w * nu) / (params.bottom + a.z), -1.0, 1.0);
    var d = vec3<f32>(0.0);
    if params.multiple == 1u {
        d = local_direction(mu, mu_s, nu);
    }
    return Sample(bitcast<u32>(a.x), a.y, a.z, mu_s, d);
}

fn sources_at(at: Sample, phase_r: f32, phase_m: f32, l: u32) -> Sources {
    let shell = at.shell;
    let between = at.between;
    let mu_s = at.mu_s;
    let d = at.d;
    var light: vec4<f32>;
    if between == 0.0 {
        light = light_map(shell, mu_s, l);
    } else {
        light = sunlight(at.altitude, mu_s, l);
    }
    var out = Sources(light * phase_r, light * phase_m);
    if params.multiple == 1u {
        var scattered = inscatter(shell, mu_s, d, l);
        if between > 0.0 {
            scattered += (inscatter(shell + 1u, mu_s, d, l) - scattered) * between;
        }
        out.r += scattered;
        if params.aerosols == 1u {
            var aerosol = aerosol_inscatter(shell, mu_s, d, l);
            if between > 0.0 {
                aerosol += (aerosol_inscatter(shell + 1u, mu_s, d, l) - aerosol) * between;
            }
            out.m += aerosol;
        }
    }
    return out;
}

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let azimuths = u32(params.grid.z);
    let elevations = u32(params.grid.w);
    if id.x >= azimuths || id.y >= elevations {
        return;
    }
    let j = id.y;
    let elevation = params.grid.x + (params.grid.y - params.grid.x) * f32(j) / f32(elevations - 1u);
    let azimuth = PI * f32(id.x) / f32(azimuths - 1u);
    let sin_s = params.sun.x;
    let nu = cos(elevation) * cos(azimuth) * params.sun.y + sin(elevation) * sin_s;
    let ray = data[params.rays_at + j];
    let r0_mu_s = ray.z * sin_s;
    let phase_r = phase_function(params.rayleigh_kind, params.rayleigh_g, nu);
    let phase_m = phase_function(params.mie_kind, params.mie_g, nu);
    let n = params.lanes;
    var total: array<vec4<f32>, MAX_LANES>;
    for (var s = bitcast<u32>(ray.x); s < bitcast<u32>(ray.y); s++) {
        let at = sample_at(data[params.samples_at + 2u * s], data[params.samples_at + 2u * s + 1u].x, r0_mu_s, nu);
        for (var l = 0u; l < n; l++) {
            let source = sources_at(at, phase_r, phase_m, l);
            total[l] += data[params.rayleigh_at + s * n + l] * source.r
                + data[params.mie_at + s * n + l] * source.m;
        }
    }
    // A Lambertian ground at the end of the ray reflects the sunlight and the higher
    // orders' light coming down on it.
    if ray.w >= 0.0 && params.ground_albedo > 0.0 {
        let mu_s = clamp((r0_mu_s + ray.w * nu) / data[params.shells_at].x, -1.0, 1.0);
        for (var l = 0u; l < n; l++) {
            var irradiance = vec4<f32>(0.0);
            if mu_s > 0.0 {
                irradiance = light_map(0u, mu_s, l) * mu_s;
            }
            if params.multiple == 1u {
                irradiance += ground_light(mu_s, l);
            }
            total[l] += irradiance * data[params.ground_at + j * n + l];
        }
    }
    var rgb = vec3<f32>(0.0);
    for (var l = 0u; l < n; l++) {
        for (var c = 0u; c < 4u; c++) {
            let w = data[params.rgb_at + 4u * l + c].xyz;
            rgb += w * total[l][c];
        }
    }
    let at = 3u * (j * azimuths + id.x);
    map[at] = rgb.x;
    map[at + 1u] = rgb.y;
    map[at + 2u] = rgb.z;
}

// The aerial perspective of froxel columns (atmo::sky::aerial::AerialRays::froxels):
// each invocation reads the marked ray of its column's elevation row at the column's
// angle to the sun, as ScatteringMaps::radiance_at_marks does, and writes for each mark
// (slice) the in-scattered radiance and the transmittance as linear sRGB.

// Mirrors atmo_gpu::sky::AerialParams.
struct AerialParams {
    // The solar spectrum's linear sRGB, to turn transmittance into colour.
    white: vec4<f32>,
    // Sine of the sun's elevation.
    sin_sun: f32,
    columns: u32,
    slices: u32,
    // Froxel columns across the picture (the rest are its rows).
    width: u32,
    // Where each region starts in `marked`, in vec4s.
    rows_at: u32,
    samples_at: u32,
    rayleigh_at: u32,
    mie_at: u32,
    marks_at: u32,
    pad1: u32,
    pad2: u32,
    pad3: u32,
}

@group(0) @binding(3) var<uniform> aerial: AerialParams;
// Rows (first sample, end sample, origin radius, first mark bits), samples (as the
// sky's), Rayleigh and aerosol weights [sample][lane], marks (sample bits; left
// weights 2 x lanes; transmittance lanes).
@group(0) @binding(4) var<storage, read> marked: array<vec4<f32>>;
// Per column: (row, cosine of the angle to the sun).
@group(0) @binding(5) var<storage, read> columns: array<vec2<f32>>;
// Out: at (column across, column down, slice) the in-scattered radiance and the
// transmittance, linear sRGB.
@group(0) @binding(6) var inscatter_out: texture_storage_3d<rgba32float, write>;
@group(0) @binding(7) var transmittance_out: texture_storage_3d<rgba32float, write>;

// Lane `l` of a spectrum to linear sRGB.
fn lane_rgb(v: vec4<f32>, l: u32) -> vec3<f32> {
    var rgb = vec3<f32>(0.0);
    for (var c = 0u; c < 4u; c++) {
        rgb += data[params.rgb_at + 4u * l + c].xyz * v[c];
    }
    return rgb;
}

@compute @workgroup_size(64)
fn aerial_main(@builtin(global_invocation_id) id: vec3<u32>) {
    let k = id.x;
    if k >= aerial.columns {
        return;
    }
    let column = columns[k];
    let row = u32(column.x);
    let nu = column.y;
    let record = marked[aerial.rows_at + row];
    var m = bitcast<u32>(record.w);
    let m_first = m;
    let m_end = bitcast<u32>(marked[aerial.rows_at + row + 1u].w);
    let r0_mu_s = record.z * aerial.sin_sun;
    let phase_r = phase_function(params.rayleigh_kind, params.rayleigh_g, nu);
    let phase_m = phase_function(params.mie_kind, params.mie_g, nu);
    let n = params.lanes;
    let per_mark = 1u + 3u * n;
    var total: array<vec4<f32>, MAX_LANES>;
    var source_r: array<vec4<f32>, MAX_LANES>;
    var source_m: array<vec4<f32>, MAX_LANES>;
    for (var s = bitcast<u32>(record.x); s < bitcast<u32>(record.y); s++) {
        let sample = sample_at(marked[aerial.samples_at + 2u * s], marked[aerial.samples_at + 2u * s + 1u].x, r0_mu_s, nu);
        for (var l = 0u; l < n; l++) {
            let source = sources_at(sample, phase_r, phase_m, l);
            source_r[l] = source.r;
            source_m[l] = source.m;
        }
        // The marks at this sample: the light so far plus the part of its weights
        // before it.
        loop {
            if m >= m_end {
                break;
            }
            let at = aerial.marks_at + m * per_mark;
            if bitcast<u32>(marked[at].x) != s {
                break;
            }
            var inscattered = vec3<f32>(0.0);
            var through = vec3<f32>(0.0);
            for (var l = 0u; l < n; l++) {
                let here = total[l] + marked[at + 1u + l] * source_r[l] + marked[at + 1u + n + l] * source_m[l];
                inscattered += lane_rgb(here, l);
                through += lane_rgb(marked[at + 1u + 2u * n + l] * data[params.irradiance_at + l], l);
            }
            let froxel = vec3<u32>(k % aerial.width, k / aerial.width, m - m_first);
            let t = through / max(aerial.white.xyz, vec3<f32>(1e-30));
            textureStore(inscatter_out, froxel, vec4<f32>(inscattered, 1.0));
            textureStore(transmittance_out, froxel, vec4<f32>(t, 1.0));
            m++;
        }
        for (var l = 0u; l < n; l++) {
            total[l] += marked[aerial.rayleigh_at + s * n + l] * source_r[l] + marked[aerial.mie_at + s * n + l] * source_m[l];
        }
    }
}
