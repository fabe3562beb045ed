// The panel's layer (premultiplied alpha, the window's size) put over the frame texel
// for texel: screen.wgsl's triangle covering the target, cut to the panel by a scissor
// rectangle.

@group(0) @binding(0) var layer: texture_2d<f32>;

@fragment
fn fragment(@builtin(position) position: vec4<f32>) -> @location(0) vec4<f32> {
    return textureLoad(layer, vec2<i32>(floor(position.xy)), 0);
}
