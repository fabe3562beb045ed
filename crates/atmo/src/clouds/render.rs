//! Drawing a cloud (clouds 2.2): each particle a camera-facing Gaussian billboard,
//! composited with `E_k = S_k + T_k E_{k-1}` (5). The paper draws back to front; the
//! same sum taken front to back, `E += T_acc S_k`, `T_acc *= T_k`, lets a pixel stop
//! once almost nothing gets through it (a thousandth), which in a thick cloud is after
//! a few layers of the many behind. Unlike Harris's per-particle `I_k`, the sunlight
//! is looked up in the 3-D intensity buffer per pixel (trilinear), the quality gain of
//! clouds 3.3: detail finer than a particle. Where clouds (6) takes
//! `S_k = a_k tau_k p I_k / 4 pi` for a thin particle, each pixel here follows its own
//! ray through the blob and integrates the light the blob sends along it, what it
//! absorbs of its own light included ([`Emission`]), for every octave of
//! [`Octaves`] (docs/clouds.md, "Drawing").

use glam::Vec3;
use rayon::prelude::*;

use super::buffer::IntensityBuffer;
use super::octaves::{Emission, Octaves};
use super::particles::{tabulated_emission_nodes, Particle};
use super::sky_light::SkyLight;
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
    /// The sky's radiance around the cloud (the paper has none), which the droplets
    /// scatter toward the eye by their phase function and every order of
    /// `scattering` ([`SkyLight::scattered`]); [`SkyLight::NONE`] for none.
    pub ambient: SkyLight,
    /// The droplets' phase function (clouds (6)'s `p`), e.g.
    /// [`PhaseFunction::CloudMie`].
    pub phase: PhaseFunction,
    /// Single scattering, or every order by octaves.
    pub scattering: Octaves,
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
        .filter(|&k| depth[k] > particles[k].reach())
        .collect();
    order.sort_by(|&a, &b| depth[a].total_cmp(&depth[b]).then(a.cmp(&b)));
    // Each particle's footprint on the screen: centre and radius in pixels, the radius
    // of its reach seen at its distance, widened off the axis where the perspective
    // stretches it (by 1 / cos^2 of the angle from the axis).
    let footprint: Vec<(f32, f32, f32)> = order
        .iter()
        .map(|&k| {
            let d = particles[k].position - camera.position;
            let z = depth[k];
            let (tx, ty) = (d.dot(camera.right) / z, d.dot(camera.up) / z);
            let r = particles[k].reach();
            let stretch = 1.0 + tx * tx + ty * ty;
            let (sx, sy) = (tx * focal + 0.5 * w as f32, -ty * focal + 0.5 * h as f32);
            (sx, sy, r / (z * z - r * r).sqrt() * focal * stretch)
        })
        .collect();
    // Each pixel's ray (its component along the view axis 1) is affine in the pixel
    // centre: `r = r0 + x rx + y ry`; so is its step in the buffer's grid.
    let r0 = camera.ray(0.5, 0.5);
    let (rx, ry) = (camera.ray(1.5, 0.5) - r0, camera.ray(0.5, 1.5) - r0);
    let (g_eye, g0, gx, gy) = (
        buffer.grid_coordinates(camera.position),
        buffer.grid_step(r0),
        buffer.grid_step(rx),
        buffer.grid_step(ry),
    );
    // Pixel `k`'s unit ray; the phase function for it, the same for every blob it
    // crosses.
    let ray = |k: usize| (r0 + (k % w) as f32 * rx + (k / w) as f32 * ry).normalize();
    let phases: Vec<f32> = (0..w * h)
        .into_par_iter()
        .map(|k| light.phase.eval_f32(light.to_sun.dot(ray(k))))
        .collect();
    // The sky's light the droplets scatter along a ray, taken where a blob was drawn.
    let sky = light.ambient.scattered(light.phase, &light.scattering);
    let octaves = light.scattering.terms();
    let mut frame = Frame::new(camera.width, camera.height);
    frame
        .pixels
        .par_chunks_mut(BAND * w)
        .enumerate()
        .for_each(|(band, pixels)| {
            let (y0, y1) = (band * BAND, (band * BAND + pixels.len() / w) as f32);
            // What still gets through each pixel of the band from behind.
            let mut through = vec![1.0f32; pixels.len()];
            // The higher octaves' light, kept apart until the pixel's depth is known; the
            // share of the sky's light the blobs scatter (albedo times what each takes
            // out of the pixel's ray), to be times the ray's sky light.
            let mut higher = vec![Vec3::ZERO; pixels.len()];
            let mut skylit = vec![0.0f32; pixels.len()];
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
                let s = p.sigma();
                // The centre from the eye; its dot with a pixel's ray, affine in the pixel.
                let d = p.position - camera.position;
                let (d2, d0, dx, dy) = (d.length_squared(), d.dot(r0), d.dot(rx), d.dot(ry));
                let sun = p.albedo * light.sun;
                let rows = ((sy - sr).floor().max(y0 as f32) as usize)
                    ..((sy + sr).ceil().min(y1) as usize);
                let cols = ((sx - sr).floor().max(0.0) as usize)
                    ..((sx + sr).ceil().min(w as f32) as usize);
                for y in rows {
                    let (yf, ray_y) = (y as f32, y as f32 * ry);
                    for x in cols.clone() {
                        let i = (y - band * BAND) * w + x;
                        if through[i] < OPAQUE {
                            continue;
                        }
                        // The pixel's ray, its nearest approach to the centre (at `t`
                        // times the ray) and the column through the blob there.
                        let xf = x as f32;
                        let r = r0 + xf * rx + ray_y;
                        let rr = r.length_squared();
                        let t = (d0 + xf * dx + yf * dy) / rr;
                        let tau = p.faded_column((d2 - t * t * rr).max(0.0));
                        if tau <= 0.0 {
                            continue;
                        }
                        // The sunlight at two depths of the blob along the ray (see
                        // `emission_nodes`), from which Octaves::light integrates what
                        // the blob sends toward the eye, and the cloud's whole depth
                        // along the sun's ray through the nearer; the phase for this ray.
                        let inv_length = rr.sqrt().recip();
                        let g_ray = g0 + xf * gx + yf * gy;
                        let g = g_eye + t * g_ray;
                        let along = (s * inv_length) * g_ray;
                        let [(u0, l0), (u1, l1)] = tabulated_emission_nodes(tau);
                        let near = g + l0 * along;
                        let emission = Emission {
                            tau,
                            u: [u0, u1],
                            log_gamma: [
                                buffer.sample_log_grid(near),
                                buffer.sample_log_grid(g + l1 * along),
                            ],
                            slab: if octaves.needs_slab() {
                                buffer.column_depth_grid(near)
                            } else {
                                0.0
                            },
                        };
                        let phase = phases[band * BAND * w + i];
                        let blob = octaves.light(phase, &emission);
                        pixels[i] += through[i] * blob.single * sun;
                        higher[i] += through[i] * blob.higher * sun;
                        skylit[i] += through[i] * (1.0 - blob.transmitted) * p.albedo;
                        through[i] *= blob.transmitted;
                    }
                }
            }
            // The higher octaves by the cloud's depth on the ray, the sky's light, the
            // haze in front of the cloud, then what shows through it.
            let haze = light.haze;
            for (j, ((e, t), more)) in pixels.iter_mut().zip(&through).zip(&higher).enumerate() {
                *e += light.scattering.higher_share(*t) * *more;
                if skylit[j] > 0.0 {
                    *e += skylit[j] * sky.along(ray(band * BAND * w + j));
                }
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
pub const OPAQUE: f32 = 1e-3;
