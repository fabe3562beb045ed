// The aerial perspective at a point of the picture (`uv` in [0, 1]^2 across it) at a
// distance `d` m, from atmo's froxels (atmo_gpu::sky::AerialTextures, written by
// GpuAerial::prepare): its transmittance and the radiance scattered in before it, in
// the froxels' units. A surface of radiance L there is seen as T L + S. The slices lie
// at far (k / n)^2 (atmo::sky::aerial::quadratic_slices), so the slice coordinate is
// sqrt(d / far) n; nearer than the first slice the light fades toward no air at all.
// Sampling f32 textures linearly needs the device's FLOAT32_FILTERABLE.

struct AerialLight {
    transmittance: vec3<f32>,
    inscatter: vec3<f32>,
}

fn aerial_light(
    transmittance: texture_3d<f32>,
    inscatter: texture_3d<f32>,
    linear: sampler,
    uv: vec2<f32>,
    d: f32,
    far: f32,
    slices: f32,
) -> AerialLight {
    let k = sqrt(d / far) * slices;
    let at = vec3<f32>(uv, (k - 0.5) / slices);
    let near = clamp(k, 0.0, 1.0);
    let t = mix(vec3<f32>(1.0), textureSampleLevel(transmittance, linear, at, 0.0).rgb, near);
    let s = textureSampleLevel(inscatter, linear, at, 0.0).rgb * near;
    return AerialLight(t, s);
}
