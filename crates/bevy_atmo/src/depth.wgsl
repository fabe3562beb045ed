// The scene's depth for atmo's clouds: each pixel of the viewport's depth along the
// view axis, m, from Bevy's reversed-z depth buffer (its nearest sample with MSAA), and
// f32's largest where nothing is (the far plane). atmo_gpu::clouds::CloudsPass reads it.
//
// Variants are made by bevy_atmo::cloud_pass::depth_source: the depth buffer's type
// (texture_depth_2d or texture_depth_multisampled_2d) and how `z` is read from it.

struct DepthParams {
    // Bevy's view_from_clip: a pixel's depth back to its view-space position.
    view_from_clip: mat4x4<f32>,
    // The viewport: its corner in the depth buffer and its size, pixels.
    viewport: vec4<f32>,
}

@group(0) @binding(0) var<uniform> params: DepthParams;
@group(0) @binding(1) var depth: DEPTH_TEXTURE;

// A triangle covering the target.
@vertex
fn vertex(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let uv = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    return vec4<f32>(uv * 2.0 - 1.0, 0.0, 1.0);
}

@fragment
fn fragment(@builtin(position) position: vec4<f32>) -> @location(0) vec4<f32> {
    let texel = vec2<i32>(position.xy + params.viewport.xy);
    NEAREST
    // Reversed z: the far plane is 0.
    if z <= 0.0 {
        return vec4<f32>(3.4028235e38, 0.0, 0.0, 0.0);
    }
    let ndc = vec2<f32>(2.0 * position.x / params.viewport.z - 1.0, 1.0 - 2.0 * position.y / params.viewport.w);
    let at_view = params.view_from_clip * vec4<f32>(ndc, z, 1.0);
    return vec4<f32>(-at_view.z / at_view.w, 0.0, 0.0, 0.0);
}
