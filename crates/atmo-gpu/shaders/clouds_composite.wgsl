// The cloud drawn into a caller's colour target: one full-screen triangle (screen.wgsl),
// each fragment the billboards' picture under it plus its higher octaves scaled by
// `1 - through^k` (atmo::clouds::octaves::Octaves::higher_share), times the exposure,
// with the cloud's coverage as alpha: blended "over" what the caller drew behind
// (premultiplied: colour + (1 - alpha) behind). Pixels outside the picture are left.

// Mirrors atmo_gpu::clouds::CompositeParams.
struct CompositeParams {
    // The target's pixel where the picture's (0, 0) is.
    corner: vec2<f32>,
    exposure: f32,
    // The octaves' depth scale k.
    depth_scale: f32,
    // 1: add the higher octaves (more than one octave), 0: single scattering.
    higher: u32,
    pad0: u32,
    pad1: u32,
    pad2: u32,
}

@group(0) @binding(0) var<uniform> params: CompositeParams;
// The billboards over nothing: premultiplied radiance, alpha the coverage.
@group(0) @binding(1) var picture: texture_2d<f32>;
// The higher octaves' light apart, alpha the coverage.
@group(0) @binding(2) var higher_octaves: texture_2d<f32>;

@fragment
fn fragment(@builtin(position) position: vec4<f32>) -> @location(0) vec4<f32> {
    let texel = picture_texel(position, params.corner);
    if !in_picture(texel, vec2<i32>(textureDimensions(picture))) {
        discard;
    }
    let cloud = textureLoad(picture, texel, 0);
    var rgb = cloud.rgb;
    if params.higher != 0u {
        let h = textureLoad(higher_octaves, texel, 0);
        let through = max(1.0 - h.a, OPAQUE);
        rgb += (1.0 - exp(params.depth_scale * log(through))) * h.rgb;
    }
    return vec4<f32>(rgb * params.exposure, cloud.a);
}
