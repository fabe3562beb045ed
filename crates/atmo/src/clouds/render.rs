//! Drawing a cloud (clouds 2.2): each particle a camera-facing Gaussian billboard,
//! composited with `E_k = S_k + T_k E_{k-1}` (5) and
//! `S_k = a_k tau_k p(omega, l) I_k / 4 pi` (6). The paper draws back to front; the same
//! sum taken front to back, `E += T_acc S_k`, `T_acc *= T_k`, lets a pixel stop once
//! almost nothing gets through it (a thousandth), which in a thick cloud is after a few
//! layers of the many behind. Unlike Harris's per-particle `I_k`, the
//! sunlight at every pixel of a billboard is looked up in the 3-D intensity buffer at the
//! point the pixel shows (trilinear), the quality gain of clouds 3.3: detail finer than
//! a particle.

use std::f32::consts::PI;

use glam::Vec3;
use rayon::prelude::*;

use super::buffer::IntensityBuffer;
use super::particles::Particle;
use crate::atmosphere::phase::PhaseFunction;
use crate::error::Result;
use crate::image::Frame;
use crate::view::Camera;

/// How the cloud is lit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Lighting {
    /// Unit vector toward the sun.
    pub to_sun: Vec3,
    /// Sunlight arriving at the cloud, RGB (irradiance in any units: pixels come out in
    /// the same per steradian).
    pub sun: Vec3,
    /// Light from the sky scattered by the droplets, RGB radiance, the same everywhere
    /// (it keeps the undersides from black; the paper has none).
    pub ambient: Vec3,
    /// The droplets' phase function (clouds (6)'s `p`), e.g.
    /// [`PhaseFunction::CloudMie`].
    pub phase: PhaseFunction,
    /// The air between the eye and the cloud.
    pub haze: Haze,
}

/// The atmosphere between the eye and the cloud (its aerial perspective,
/// [`crate::sky::aerial`]), one value for the whole cloud at its distance: the cloud's
/// light reaches the eye times `transmittance`, and the air in front of it adds
/// `inscatter` where the cloud hides what is behind (RGB).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Haze {
    pub transmittance: Vec3,
    pub inscatter: Vec3,
}

impl Haze {
    /// No air between the eye and the cloud.
    pub const CLEAR: Haze = Haze {
        transmittance: Vec3::ONE,
        inscatter: Vec3::ZERO,
    };
}

/// Rows drawn together by one thread.
const BAND: usize = 8;

/// Columns of a block whose opacity is tracked, to skip particles hidden behind it.
const BLOCK: usize = 16;

/// Draws `particles` lit through `buffer` over `background` (same size as the camera's
/// image, or black); an error for a fisheye camera.
pub fn render(
    particles: &[Particle],
    buffer: &IntensityBuffer,
    camera: &Camera,
    light: &Lighting,
    background: Option<&Frame>,
) -> Result<Frame> {
    let (w, h) = (camera.width as usize, camera.height as usize);
    let (_, tan_half_height) = camera.pinhole("the clouds' billboards")?;
    let focal = 0.5 * h as f32 / tan_half_height;
    // Front to back: nearest first (see the module doc).
    let depth: Vec<f32> = particles.iter().map(|p| camera.depth(p.position)).collect();
    let mut order: Vec<usize> = (0..particles.len())
        .filter(|&k| depth[k] > particles[k].radius)
        .collect();
    order.sort_by(|&a, &b| depth[a].total_cmp(&depth[b]).then(a.cmp(&b)));
    // Each particle's footprint on the screen: centre and radius in pixels.
    let footprint: Vec<(f32, f32, f32)> = order
        .iter()
        .map(|&k| {
            let d = particles[k].position - camera.position;
            let z = depth[k];
            let sx = d.dot(camera.right) / z * focal + 0.5 * w as f32;
            let sy = -d.dot(camera.up) / z * focal + 0.5 * h as f32;
            (sx, sy, particles[k].radius / z * focal)
        })
        .collect();
    let mut frame = Frame::new(camera.width, camera.height);
    frame
        .pixels
        .par_chunks_mut(BAND * w)
        .enumerate()
        .for_each(|(band, pixels)| {
            let (y0, y1) = (band * BAND, (band * BAND + pixels.len() / w) as f32);
            // What still gets through each pixel of the band from behind.
            let mut through = vec![1.0f32; pixels.len()];
            // Blocks of BLOCK columns across the band: whether one of their pixels still
            // lets light through, kept up to date lazily (`dirty` after a particle).
            let blocks = w.div_ceil(BLOCK);
            let (mut open, mut dirty) = (vec![true; blocks], vec![false; blocks]);
            let rows_in_band = pixels.len() / w;
            for (&k, &(sx, sy, sr)) in order.iter().zip(&footprint) {
                if sy + sr < y0 as f32 || sy - sr > y1 || sx + sr < 0.0 || sx - sr > w as f32 {
                    continue;
                }
                // Behind pixels that are all finished: nothing to draw.
                let b0 = (sx - sr).max(0.0) as usize / BLOCK;
                let b1 = ((sx + sr).max(0.0) as usize / BLOCK).min(blocks - 1);
                let mut any_open = false;
                for b in b0..=b1 {
                    if dirty[b] {
                        let cols = b * BLOCK..((b + 1) * BLOCK).min(w);
                        open[b] = (0..rows_in_band).any(|r| {
                            through[r * w + cols.start..r * w + cols.end]
                                .iter()
                                .any(|t| *t >= OPAQUE)
                        });
                        dirty[b] = false;
                    }
                    any_open |= open[b];
                }
                if !any_open {
                    continue;
                }
                dirty[b0..=b1].iter_mut().for_each(|d| *d = true);
                let p = &particles[k];
                let z = depth[k];
                let s = p.sigma();
                let inv_2s2 = 1.0 / (2.0 * s * s);
                let column = p.density * s * (2.0 * PI).sqrt();
                // The phase at the particle's centre: the angle changes little over it.
                let view = (p.position - camera.position).normalize();
                let phase = light.phase.eval_f32(light.to_sun.dot(view));
                let lit = p.albedo * phase * light.sun;
                let ambient = p.albedo * light.ambient;
                let metres_per_pixel = z / focal;
                let rows = ((sy - sr).floor().max(y0 as f32) as usize)
                    ..((sy + sr).ceil().min(y1) as usize);
                let cols = ((sx - sr).floor().max(0.0) as usize)
                    ..((sx + sr).ceil().min(w as f32) as usize);
                // The billboard's points are affine in the pixel: so are their grid
                // coordinates in the buffer.
                let grid_at = |x: f32, y: f32| {
                    buffer.grid_coordinates(camera.position + camera.ray(x, y) * z)
                };
                let origin = grid_at(0.5, 0.5);
                let (step_x, step_y) = (grid_at(1.5, 0.5) - origin, grid_at(0.5, 1.5) - origin);
                for y in rows {
                    let dy = (y as f32 + 0.5 - sy) * metres_per_pixel;
                    for x in cols.clone() {
                        let i = (y - band * BAND) * w + x;
                        if through[i] < OPAQUE {
                            continue;
                        }
                        let dx = (x as f32 + 0.5 - sx) * metres_per_pixel;
                        let b2 = dx * dx + dy * dy;
                        if b2 >= p.radius * p.radius {
                            continue;
                        }
                        // The column through the blob at this pixel, and the point it shows.
                        let tau = column * (-b2 * inv_2s2).exp();
                        let gamma =
                            buffer.sample_grid(origin + x as f32 * step_x + y as f32 * step_y);
                        let source = tau * (lit * gamma + ambient);
                        pixels[i] += through[i] * source;
                        through[i] *= (-tau).exp();
                    }
                }
            }
            // The haze in front of the cloud, then what shows through it.
            let haze = light.haze;
            for (e, t) in pixels.iter_mut().zip(&through) {
                *e = haze.transmittance * *e + (1.0 - *t) * haze.inscatter;
            }
            if let Some(background) = background {
                let behind = &background.pixels[band * BAND * w..band * BAND * w + pixels.len()];
                for ((e, t), b) in pixels.iter_mut().zip(&through).zip(behind) {
                    *e += *t * *b;
                }
            }
        });
    Ok(frame)
}

/// A pixel that lets less than this through from behind is finished: the particles
/// still to come would change it by less than 0.1 %.
const OPAQUE: f32 = 1e-3;
