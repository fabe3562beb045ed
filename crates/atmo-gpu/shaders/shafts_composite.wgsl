// The planes' sum added to the surfaces' radiance: the picture, in one buffer (its
// alpha, 1 or the haze's transmittance, kept).

@group(0) @binding(0) var planes: texture_2d<f32>;
@group(0) @binding(1) var<storage, read_write> out: array<vec4<f32>>;

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = textureDimensions(planes);
    if id.x >= size.x || id.y >= size.y {
        return;
    }
    let at = id.y * size.x + id.x;
    out[at] = vec4<f32>(out[at].xyz + textureLoad(planes, id.xy, 0).xyz, out[at].w);
}
