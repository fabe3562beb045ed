// A triangle covering the whole target, for passes that draw a picture pixel by pixel,
// and where a fragment falls in the picture.
@vertex
fn vertex(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let uv = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    return vec4<f32>(uv * 2.0 - 1.0, 0.0, 1.0);
}

// The texel of a picture placed with its (0, 0) at the target's pixel `corner` under
// the fragment at `position`.
fn picture_texel(position: vec4<f32>, corner: vec2<f32>) -> vec2<i32> {
    return vec2<i32>(floor(position.xy - corner));
}

// Whether `texel` is inside a picture of `size` texels.
fn in_picture(texel: vec2<i32>, size: vec2<i32>) -> bool {
    return all(texel >= vec2<i32>(0)) && all(texel < size);
}
