// A picture of the sky: each pixel's direction looked up bilinearly in the skylight
// map (sky 4.2), below the horizon in the ground map (a model's) or black (a table's),
// plus the sun's disc; both edges anti-aliased over one pixel. Follows
// atmo::sky::frame (SkyPicture::render) operation for operation.
//
// Drawn as one full-screen triangle at the far plane into the caller's colour target,
// so that a depth test (less-equal, or greater-equal for reversed z) leaves the sky only
// where the caller's depth buffer is still at the far plane.

// Mirrors atmo_gpu::sky::SkyFrameParams.
struct SkyFrameParams {
    // Perspective: direction of pixel (x, y) = origin + (x + 1/2) right - (y + 1/2) up.
    // Fisheye: origin is the view axis, right and up the screen's unit axes.
    origin: vec4<f32>,
    right: vec4<f32>,
    up: vec4<f32>,
    // xyz: unit vector to the sun; w: cosine of its angular radius plus a pixel.
    sun_direction: vec4<f32>,
    // Linear sRGB radiance of the disc; w: 1 to draw it.
    sun_rgb: vec4<f32>,
    // xy: horizontal unit vector toward the sun; zw: the fisheye's centre, pixels.
    sun_horizontal: vec4<f32>,
    // Grid lookup: columns per radian, lowest elevation, rows per radian, last column.
    lookup: vec4<f32>,
    y_last: f32,
    ground_below: f32,
    radius: f32,
    fisheye: u32,
    width: u32,
    height: u32,
    azimuths: u32,
    // The sun's angular radius and a pixel's angle, rad: the disc's and the horizon's
    // edges are smooth over one pixel (atmo::sky::frame's Edges).
    sun_radius: f32,
    pixel: f32,
    // 1 when there is a ground map, its lookup as `lookup`'s, its last row and its
    // azimuths.
    has_ground: u32,
    ground_y_last: f32,
    ground_azimuths: u32,
    ground_lookup: vec4<f32>,
    // The target's pixel that is the picture's (0, 0) (a viewport's corner).
    corner: vec2<f32>,
    // Multiplies the radiance written.
    exposure: f32,
    // The far plane's depth: 1, or 0 for reversed z.
    depth: f32,
}

@group(0) @binding(0) var<uniform> params: SkyFrameParams;
// The skylight map, [elevation][azimuth][channel].
@group(0) @binding(1) var<storage, read> map: array<f32>;
// The ground map, [elevation][azimuth][channel] (unused without one).
@group(0) @binding(2) var<storage, read> ground: array<f32>;

fn texel(is_ground: bool, at: u32) -> vec3<f32> {
    if is_ground {
        return vec3<f32>(ground[3u * at], ground[3u * at + 1u], ground[3u * at + 2u]);
    }
    return vec3<f32>(map[3u * at], map[3u * at + 1u], map[3u * at + 2u]);
}

// Bilinear at (azimuth from the sun in [0, pi], elevation), rad, clamped to the grid
// (the sky's or the ground's), negative values clamped to zero as the CPU stores them.
fn sample(is_ground: bool, azimuth: f32, elevation: f32) -> vec3<f32> {
    var g = params.lookup;
    var y_last = params.y_last;
    var azimuths = params.azimuths;
    if is_ground {
        g = params.ground_lookup;
        y_last = params.ground_y_last;
        azimuths = params.ground_azimuths;
    }
    let x = clamp(azimuth * g.x, 0.0, g.w);
    let y = clamp((elevation - g.y) * g.z, 0.0, y_last);
    let i = min(u32(x), azimuths - 2u);
    let j = min(u32(y), u32(y_last) - 1u);
    let fx = x - f32(i);
    let fy = y - f32(j);
    let at = j * azimuths + i;
    let zero = vec3<f32>(0.0);
    let lo = mix(max(texel(is_ground, at), zero), max(texel(is_ground, at + 1u), zero), fx);
    let hi = mix(max(texel(is_ground, at + azimuths), zero), max(texel(is_ground, at + azimuths + 1u), zero), fx);
    return mix(lo, hi, fy);
}

// A triangle covering the target, at the far plane.
@vertex
fn vertex(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let uv = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    return vec4<f32>(uv * 2.0 - 1.0, params.depth, 1.0);
}

// Linear sRGB radiance times the exposure at the pixel centre `position`.
@fragment
fn fragment(@builtin(position) position: vec4<f32>) -> @location(0) vec4<f32> {
    let p = position.xy - params.corner;
    var d: vec3<f32>;
    var rgb = vec3<f32>(0.0);
    if params.fisheye != 0u {
        let centre = params.sun_horizontal.zw;
        let q = vec2<f32>(p.x - centre.x, centre.y - p.y) / params.radius;
        let rho = length(q);
        if rho > 1.0 {
            // Outside the dome: the target keeps what it has (black when cleared so).
            discard;
        }
        let zenith = rho * HALF_PI;
        var across = vec2<f32>(0.0, 1.0);
        if rho > 0.0 {
            across = q / rho;
        }
        let s = sin(zenith);
        d = cos(zenith) * params.origin.xyz + (s * across.x) * params.right.xyz + (s * across.y) * params.up.xyz;
    } else {
        d = params.origin.xyz + p.x * params.right.xyz - p.y * params.up.xyz;
    }
    let horizontal = sqrt(d.x * d.x + d.y * d.y);
    let len = sqrt(horizontal * horizontal + d.z * d.z);
    let elevation = HALF_PI - fast_acos(d.z / len);
    // The azimuth from the sun's, folded into [0, pi]; straight up, any will do.
    var c = 1.0;
    if horizontal > 1e-6 * len {
        c = (d.x * params.sun_horizontal.x + d.y * params.sun_horizontal.y) / horizontal;
    }
    // The sky's share of the pixel, over one pixel at the horizon; below it the ground
    // map, or black for a table (the application draws its terrain there).
    let sky = clamp((elevation - params.ground_below) / params.pixel + 0.5, 0.0, 1.0);
    let azimuth = fast_acos(c);
    if sky > 0.0 {
        rgb = sky * sample(false, azimuth, elevation);
    }
    if params.has_ground != 0u && sky < 1.0 {
        rgb += (1.0 - sky) * sample(true, azimuth, elevation);
    }
    let sun = params.sun_direction.xyz;
    if params.sun_rgb.w != 0.0 && dot(d, sun) / len >= params.sun_direction.w {
        let angle = asin(min(length(cross(d, sun)) / len, 1.0));
        rgb += params.sun_rgb.xyz * clamp((params.sun_radius - angle) / params.pixel + 0.5, 0.0, 1.0);
    }
    return vec4<f32>(params.exposure * rgb, 1.0);
}
