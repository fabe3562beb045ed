// A linear HDR picture shown on a display target: times the exposure, tone-mapped and,
// for a target that does not encode sRGB itself, sRGB-encoded, as atmo::image::Display
// does for PNG files. One full-screen triangle (screen.wgsl); pixels outside the
// picture are left.

// Mirrors atmo_gpu::display::DisplayParams.
struct DisplayParams {
    // The target's pixel where the picture's (0, 0) is.
    corner: vec2<f32>,
    exposure: f32,
    // A TONE_* code.
    tone: u32,
    // 1: sRGB-encode here (the target is linear-stored, e.g. Bgra8Unorm).
    encode: u32,
    pad0: u32,
    pad1: u32,
    pad2: u32,
}

@group(0) @binding(0) var<uniform> params: DisplayParams;
// Linear radiance, RGBA f32 (unfilterable: read texel by texel).
@group(0) @binding(1) var picture: texture_2d<f32>;

@fragment
fn fragment(@builtin(position) position: vec4<f32>) -> @location(0) vec4<f32> {
    let texel = picture_texel(position, params.corner);
    if !in_picture(texel, vec2<i32>(textureDimensions(picture))) {
        discard;
    }
    let rgb = textureLoad(picture, texel, 0).rgb * params.exposure;
    var out = vec3<f32>(tone_map(params.tone, rgb.r), tone_map(params.tone, rgb.g), tone_map(params.tone, rgb.b));
    if params.encode != 0u {
        out = vec3<f32>(srgb_encode(out.r), srgb_encode(out.g), srgb_encode(out.b));
    }
    return vec4<f32>(out, 1.0);
}
