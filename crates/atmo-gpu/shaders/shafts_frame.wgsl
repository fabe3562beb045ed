// The shafts' picture drawn into a caller's colour target: one full-screen triangle (screen.wgsl),
// each fragment the pixel of the frame under it (linear radiance, as the composite left
// it in the frame buffer) times the exposure, its alpha 1 or (the haze alone) the haze's
// transmittance to the pixel's surface. Pixels outside the frame are left.

// Mirrors atmo_gpu::shafts::ShaftsFrameParams.
struct ShaftsFrameParams {
    // The target's pixel where the frame's (0, 0) is.
    corner: vec2<f32>,
    exposure: f32,
    width: u32,
    height: u32,
    pad0: u32,
    pad1: u32,
    pad2: u32,
}

@group(0) @binding(0) var<uniform> params: ShaftsFrameParams;
// The frame, row after row from the top, RGBA.
@group(0) @binding(1) var<storage, read> frame: array<vec4<f32>>;

@fragment
fn fragment(@builtin(position) position: vec4<f32>) -> @location(0) vec4<f32> {
    let p = picture_texel(position, params.corner);
    if !in_picture(p, vec2<i32>(i32(params.width), i32(params.height))) {
        discard;
    }
    let pixel = frame[u32(p.y) * params.width + u32(p.x)];
    return vec4<f32>(pixel.rgb * params.exposure, pixel.a);
}
