// The table s^2 h(s, t) = sigma_s exp(-sigma_t (s + t)) of shafts (6), written into a
// texture each frame over the distances shafts_prepare.wgsl found
// (AttenuationTable::new); the planes read it as the paper's texture of h.

@group(0) @binding(11) var attenuation_out: texture_storage_2d<r32float, write>;

@compute @workgroup_size(16, 16)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let n = params.attenuation_size;
    if id.x >= n || id.y >= n {
        return;
    }
    let at = scales_at();
    let ds = derived[at + 2u];
    let dt = derived[at + 3u];
    let value = params.haze_max.w * exp(-params.haze_min.w * (f32(id.x) * ds + f32(id.y) * dt));
    textureStore(attenuation_out, vec2<i32>(id.xy), vec4<f32>(value, 0.0, 0.0, 0.0));
}
