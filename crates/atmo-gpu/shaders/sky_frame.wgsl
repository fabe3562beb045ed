// A picture of the sky: each pixel's direction looked up bilinearly in the skylight
// map (sky 4.2), black below the table's horizon, plus the sun's disc. Follows
// atmo::sky::frame (SkyPicture::render) operation for operation.

// Mirrors atmo_gpu::sky::SkyFrameParams.
struct SkyFrameParams {
    // Perspective: direction of pixel (x, y) = origin + (x + 1/2) right - (y + 1/2) up.
    origin: vec4<f32>,
    right: vec4<f32>,
    up: vec4<f32>,
    // xyz: unit vector to the sun; w: cosine of its angular radius.
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
    pad: u32,
}

@group(0) @binding(0) var<uniform> params: SkyFrameParams;
// The skylight map, [elevation][azimuth][channel].
@group(0) @binding(1) var<storage, read> map: array<f32>;
// Out: linear sRGB radiance per pixel, rows top to bottom.
@group(0) @binding(2) var<storage, read_write> frame: array<vec4<f32>>;

const HALF_PI: f32 = 1.5707963;

fn texel(at: u32) -> vec3<f32> {
    return vec3<f32>(map[3u * at], map[3u * at + 1u], map[3u * at + 2u]);
}

// Bilinear at (azimuth from the sun in [0, pi], elevation), rad, clamped to the grid.
fn sample(azimuth: f32, elevation: f32) -> vec3<f32> {
    let g = params.lookup;
    let x = clamp(azimuth * g.x, 0.0, g.w);
    let y = clamp((elevation - g.y) * g.z, 0.0, params.y_last);
    let i = min(u32(x), params.azimuths - 2u);
    let j = min(u32(y), u32(params.y_last) - 1u);
    let fx = x - f32(i);
    let fy = y - f32(j);
    let at = j * params.azimuths + i;
    let lo = mix(texel(at), texel(at + 1u), fx);
    let hi = mix(texel(at + params.azimuths), texel(at + params.azimuths + 1u), fx);
    return mix(lo, hi, fy);
}

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= params.width || id.y >= params.height {
        return;
    }
    let p = vec2<f32>(f32(id.x) + 0.5, f32(id.y) + 0.5);
    var d: vec3<f32>;
    var rgb = vec3<f32>(0.0);
    if params.fisheye != 0u {
        let q = (params.sun_horizontal.zw - p) / params.radius;
        let rho = length(q);
        if rho > 1.0 {
            frame[id.y * params.width + id.x] = vec4<f32>(0.0, 0.0, 0.0, 1.0);
            return;
        }
        let zenith = rho * HALF_PI;
        var horizontal = vec2<f32>(0.0, 1.0);
        if rho > 0.0 {
            horizontal = q / rho;
        }
        d = vec3<f32>(horizontal * sin(zenith), cos(zenith));
    } else {
        d = params.origin.xyz + p.x * params.right.xyz - p.y * params.up.xyz;
    }
    let horizontal = sqrt(d.x * d.x + d.y * d.y);
    let len = sqrt(horizontal * horizontal + d.z * d.z);
    let elevation = HALF_PI - acos(clamp(d.z / len, -1.0, 1.0));
    // The azimuth from the sun's, folded into [0, pi]; straight up, any will do.
    var c = 1.0;
    if horizontal > 1e-6 * len {
        c = clamp(dot(d.xy, params.sun_horizontal.xy) / horizontal, -1.0, 1.0);
    }
    if elevation >= params.ground_below {
        rgb = sample(acos(c), elevation);
    }
    if params.sun_rgb.w != 0.0 && dot(d, params.sun_direction.xyz) / len >= params.sun_direction.w {
        rgb += params.sun_rgb.xyz;
    }
    frame[id.y * params.width + id.x] = vec4<f32>(rgb, 1.0);
}
