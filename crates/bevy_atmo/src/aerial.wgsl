// Aerial perspective over the scene: each pixel's surface, at the distance Bevy's depth
// buffer gives, is seen as T L + S (atmo::sky::aerial): the colour target is blended as
// dst * T + S, with T per channel where the device has dual-source blending (else their
// mean). T and S come from atmo's froxels (GpuAerial), read by atmo-gpu's
// `aerial_light`, which bevy_atmo::aerial puts in below the directives.
//
// Variants are made by bevy_atmo::aerial: DEPTH_TEXTURE (texture_depth_2d, or
// texture_depth_multisampled_2d read per sample with MSAA), SAMPLE_INPUT and
// SAMPLE_INDEX, and OUTPUT (one or two blend sources).

DUAL_SOURCE

AERIAL_LIGHT

struct AerialParams {
    // Bevy's view_from_clip: a pixel's depth back to its view-space position.
    view_from_clip: mat4x4<f32>,
    // The viewport: its corner in the target and its size, pixels.
    viewport: vec4<f32>,
    // x: the farthest slice, m; y: the slices; z: luminance per radiance (683 lm/W)
    // times the camera's exposure.
    froxels: vec4<f32>,
}

@group(0) @binding(0) var<uniform> params: AerialParams;
@group(0) @binding(1) var transmittance: texture_3d<f32>;
@group(0) @binding(2) var inscatter: texture_3d<f32>;
@group(0) @binding(3) var linear: sampler;
@group(0) @binding(4) var depth: DEPTH_TEXTURE;

OUTPUT_STRUCT

// A triangle covering the target.
@vertex
fn vertex(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let uv = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    return vec4<f32>(uv * 2.0 - 1.0, 0.0, 1.0);
}

@fragment
fn fragment(@builtin(position) position: vec4<f32> SAMPLE_INPUT) -> Output {
    let z = textureLoad(depth, vec2<i32>(position.xy), SAMPLE_INDEX);
    // Reversed z: the far plane is 0, where the sky is.
    if z <= 0.0 {
        discard;
    }
    let p = position.xy - params.viewport.xy;
    let ndc = vec2<f32>(2.0 * p.x / params.viewport.z - 1.0, 1.0 - 2.0 * p.y / params.viewport.w);
    let at_view = params.view_from_clip * vec4<f32>(ndc, z, 1.0);
    let d = length(at_view.xyz / at_view.w);
    let uv = p / params.viewport.zw;
    let light = aerial_light(transmittance, inscatter, linear, uv, d, params.froxels.x, params.froxels.y);
    let t = light.transmittance;
    let s = light.inscatter * params.froxels.z;
    return OUTPUT;
}
