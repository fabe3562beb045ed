//! The baseline light pass: Harris and Lastra's, as clouds 2.1 describes it. The
//! particles are sorted along the light; a 2-D buffer seen from the sun starts at full
//! sunlight; each particle in turn reads the light arriving at its centre, `I_k`, then
//! is drawn into the buffer with `B <- g_k + T_k B` (3)-(4), where
//! `g_k = a_k tau_k p(l, l) I_k / 4 pi` and `T_k = exp(-tau_k)` at each texel of its
//! footprint. Each particle ends with one light value (a GPU needed a read-back per
//! particle for it; here it is a memory read).

use glam::Vec3;

use super::buffer::LightFrame;
use super::particles::Particle;
use crate::error::{check_range, Result};

/// `I_k / I_0` for each particle, in the particles' order: the sunlight reaching its
/// centre. `to_sun` points toward the sun; `resolution` is the side of the square
/// buffer seen from the sun; `forward` is `p(l, l) / 4 pi` as in
/// [`super::buffer::IntensityBuffer::new`].
pub fn light_per_particle(
    particles: &[Particle],
    to_sun: Vec3,
    resolution: usize,
    forward: f32,
) -> Result<Vec<f32>> {
    check_range("buffer.resolution", resolution as f64, 2.0, 8192.0)?;
    // The view from the sun: x and z across the light, y along it (as the 3-D buffer).
    let frame = LightFrame::new(particles, to_sun, forward)?;
    let local: Vec<Vec3> = particles
        .iter()
        .map(|p| frame.from_world * p.position)
        .collect();
    let (lo, hi) = (frame.min, frame.max);
    let n = resolution;
    let (tx, tz) = ((hi.x - lo.x) / n as f32, (hi.z - lo.z) / n as f32);
    let mut buffer = vec![1.0f32; n * n];
    // Sun-side particles first.
    let mut order: Vec<usize> = (0..particles.len()).collect();
    order.sort_by(|&a, &b| local[a].y.total_cmp(&local[b].y).then(a.cmp(&b)));
    let mut light_at = vec![0.0f32; particles.len()];
    for k in order {
        let (p, c) = (&particles[k], local[k]);
        // Read: bilinear at the centre (texel centres at +1/2).
        let (gx, gz) = ((c.x - lo.x) / tx - 0.5, (c.z - lo.z) / tz - 0.5);
        let (i, j) = (
            gx.floor().clamp(0.0, (n - 2) as f32),
            gz.floor().clamp(0.0, (n - 2) as f32),
        );
        let (fx, fz) = ((gx - i).clamp(0.0, 1.0), (gz - j).clamp(0.0, 1.0));
        let (i, j) = (i as usize, j as usize);
        let at = |i: usize, j: usize| buffer[j * n + i];
        let read = (at(i, j) * (1.0 - fx) + at(i + 1, j) * fx) * (1.0 - fz)
            + (at(i, j + 1) * (1.0 - fx) + at(i + 1, j + 1) * fx) * fz;
        light_at[k] = read;
        // Draw: B <- g + T B over the footprint.
        let index =
            |v: f32, lo: f32, t: f32| ((v - lo) / t - 0.5).ceil().clamp(0.0, n as f32) as usize;
        let (i0, i1) = (
            index(c.x - p.radius, lo.x, tx),
            index(c.x + p.radius, lo.x, tx),
        );
        let (j0, j1) = (
            index(c.z - p.radius, lo.z, tz),
            index(c.z + p.radius, lo.z, tz),
        );
        for jj in j0..j1 {
            let dz = lo.z + (jj as f32 + 0.5) * tz - c.z;
            for ii in i0..i1 {
                let dx = lo.x + (ii as f32 + 0.5) * tx - c.x;
                let b = ((dx * dx + dz * dz) as f64).sqrt();
                let tau = p.column(b, f64::NEG_INFINITY, f64::INFINITY) as f32;
                if tau > 0.0 {
                    let texel = &mut buffer[jj * n + ii];
                    *texel = p.albedo * tau * forward * read + (-tau).exp() * *texel;
                }
            }
        }
    }
    Ok(light_at)
}
