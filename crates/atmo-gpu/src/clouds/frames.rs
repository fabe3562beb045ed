//! Where the light passes lie: the sun's grid, and the particles carried into the
//! space where the camera's rays are parallel for the grid lit from the eye.

use super::*;

/// The frame of a light pass of `particles` lit from `to_sun` into a `resolution`^3
/// grid.
pub(super) fn frame_of(
    particles: &[Particle],
    to_sun: Vec3,
    forward: f32,
    splat: Splat,
    resolution: u32,
) -> Result<BufferFrame, GpuError> {
    let light = LightFrame::new(particles, to_sun, forward)?;
    let voxel = (light.max - light.min) / resolution as f32;
    let row = |v: Vec3| [v.x, v.y, v.z, 0.0];
    let m = light.from_world;
    Ok(BufferFrame {
        x_axis: row(m.row(0)),
        y_axis: row(m.row(1)),
        z_axis: row(m.row(2)),
        min: row(light.min),
        voxel: row(voxel),
        resolution,
        particles: particles.len() as u32,
        pieces: (splat == Splat::Pieces) as u32,
        forward_bits: forward.to_bits(),
    })
}

/// The particles as seen from `camera`, in a space where its rays are parallel (to -z):
/// a point `d` from the eye goes to `(s (d . right) / z, s (d . up) / z, z)`, `z = d .
/// forward`, `s` the depth of the particles' mean (returned). Each particle keeps its
/// column along every ray: its radius across is scaled by `s / z` at its centre and its
/// density by `z / s` (only its spread along the ray, now `s / z` of its own, is not
/// kept). The light pass of these lit from -z is the optical depth toward the eye along
/// each pixel's own ray, where a pass lit along one direction from the eye reads, near
/// a blob, the depth in front of its neighbours (a blob-sized mottle wherever the rays
/// leave that direction). Particles not wholly in front of the eye weigh nothing.
pub(super) fn seen_from(particles: &[Particle], camera: &Camera) -> (Vec<Particle>, f32) {
    let centre = particles.iter().map(|p| p.position).sum::<Vec3>() / particles.len() as f32;
    let s = camera.depth(centre).max(1.0);
    let warped = particles
        .iter()
        .map(|p| {
            let d = p.position - camera.position;
            let z = d.dot(camera.forward);
            if z <= p.reach() {
                return Particle {
                    position: Vec3::new(0.0, 0.0, s),
                    density: 0.0,
                    ..*p
                };
            }
            Particle {
                position: Vec3::new(s * d.dot(camera.right) / z, s * d.dot(camera.up) / z, z),
                radius: p.radius * s / z,
                density: p.density * z / s,
                albedo: p.albedo,
            }
        })
        .collect();
    (warped, s)
}

/// The `n`^3 grid of f32 starting `offset` bytes into `cells`.
pub(super) fn grid(cells: &wgpu::Buffer, offset: u64, n: u32) -> wgpu::BufferBinding<'_> {
    wgpu::BufferBinding {
        buffer: cells,
        offset,
        size: std::num::NonZeroU64::new((n as u64).pow(3) * 4),
    }
}
