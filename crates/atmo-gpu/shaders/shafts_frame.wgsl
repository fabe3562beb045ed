// The shafts' picture drawn into a caller's colour target: one full-screen triangle (screen.wgsl),
// each fragment the pixel of the frame under it (bilinearly between the frame's
// pixels where the frame is shown larger than it is) (linear radiance, as the composite left
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
    // The frame's size on the target, pixels: its own (pixel for pixel), or larger
    // (the frame drawn at a lower resolution, read bilinearly).
    shown: vec2<f32>,
}

@group(0) @binding(0) var<uniform> params: ShaftsFrameParams;
// The frame, row after row from the top, RGBA.
@group(0) @binding(1) var<storage, read> frame: array<vec4<f32>>;

fn texel(x: i32, y: i32) -> vec4<f32> {
    let c = clamp(vec2<i32>(x, y), vec2<i32>(0), vec2<i32>(i32(params.width), i32(params.height)) - 1);
    return frame[u32(c.y) * params.width + u32(c.x)];
}

@fragment
fn fragment(@builtin(position) position: vec4<f32>) -> @location(0) vec4<f32> {
    let on_target = position.xy - params.corner;
    if any(on_target < vec2<f32>(0.0)) || any(on_target >= params.shown) {
        discard;
    }
    // The frame's point under the pixel's centre, in texels from the first's centre.
    let size = vec2<f32>(f32(params.width), f32(params.height));
    let at = on_target * size / params.shown - 0.5;
    let base = floor(at);
    let f = at - base;
    let i = vec2<i32>(base);
    let pixel = mix(mix(texel(i.x, i.y), texel(i.x + 1, i.y), f.x),
        mix(texel(i.x, i.y + 1), texel(i.x + 1, i.y + 1), f.x), f.y);
    return vec4<f32>(pixel.rgb * params.exposure, pixel.a);
}
