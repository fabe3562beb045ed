//! The cloud's shadow on what lies beneath it (atmo's addition; the paper lights only
//! the cloud): the optical depth of the whole cloud along each of the sun's rays, kept
//! as a 2-D map across the light, which is what an engine projects onto its terrain as
//! a shadow map; and the sunlight that reaches a point beneath the cloud, the part that
//! crosses it unscattered and the part its droplets scatter on, forward and out of its
//! underside.
//!
//! The map is filled from the particles, not from the intensity buffer, so it is the
//! same whichever device holds the buffer: each particle adds its faded Gaussian column
//! ([`Particle::faded_column`], the billboards' own) at every texel centre it covers.
//! The whole column is what a point past the cloud's far side sees; for a point inside
//! the cloud the buffer is the one to ask.

use glam::{Mat3, Vec2, Vec3, Vec4};
use rayon::prelude::*;

use super::buffer::LightFrame;
use super::particles::Particle;
use crate::atmosphere::optical_depth::column_densities;
use crate::atmosphere::spectrum::SpectrumToRgb;
use crate::atmosphere::Atmosphere;
use crate::error::{check_range, Result};
use crate::image::Frame;
use crate::view::{Camera, Sun};

/// The optical depth of the cloud along the sun's rays, on a square grid across them.
#[derive(Debug, Clone)]
pub struct CloudShadow {
    /// Texels along each side.
    pub resolution: usize,
    /// World to light axes: rows `x`, the light's travel, `z` (as the intensity
    /// buffer's, [`LightFrame`]).
    pub light_from_world: Mat3,
    /// Light-axis coordinates `(x, z)` of the map's smallest corner, m.
    pub min: Vec2,
    /// A texel's size along `x` and `z`, m.
    pub texel: Vec2,
    /// The whole cloud's optical depth along the ray through each texel centre,
    /// row-major `[z][x]`.
    pub depth: Vec<f32>,
}

/// The share of the sunlight a cloud takes out of the sun's beam that reaches the
/// ground within its shadow, scattered forward and down: what lights a cloud's shadow
/// besides the sky. Fitted to the path tracer's irradiance on the ground 1.5 km beneath
/// a 1 km cumulus (sun 25 deg high from three sides; tests/clouds_light.rs holds it
/// there): the light the cloud scatters spreads over some kilometres of ground, so
/// its shadow keeps only a fiftieth of it, and the glow around the shadow (about 1 %
/// of the sun's irradiance there) is left out. A cloud nearer the ground keeps more.
pub const SCATTERED_DOWN: f32 = 0.02;

impl CloudShadow {
    /// The map of `particles` lit from `to_sun` (toward the sun, any length),
    /// `resolution` texels a side over the cloud's extent across the light.
    pub fn new(particles: &[Particle], to_sun: Vec3, resolution: usize) -> Result<CloudShadow> {
        check_range("shadow.resolution", resolution as f64, 4.0, 8192.0)?;
        let frame = LightFrame::new(particles, to_sun, 0.0)?;
        let across = |p: &Particle| {
            let c = frame.from_world * p.position;
            Vec2::new(c.x, c.z)
        };
        // Every footprint, and a clear texel around them.
        let (min, max) = particles.iter().fold(
            (Vec2::splat(f32::INFINITY), Vec2::splat(f32::NEG_INFINITY)),
            |(lo, hi), p| (lo.min(across(p) - p.reach()), hi.max(across(p) + p.reach())),
        );
        let texel = (max - min).max(Vec2::splat(1e-3)) / (resolution as f32 - 2.0).max(1.0);
        let min = min - texel;
        let n = resolution;
        // Each particle's centre across the light, the texel range it covers, its
        // Gaussian's exponent per m^2, `-1 / 2s^2`, and its factor along `x` at each
        // texel centre there (the blob is separable: `exp(-b^2 / 2s^2)` is the product
        // of the factors along `x` and `z`).
        let footprints: Vec<(Vec2, [usize; 4], f32, Vec<f32>)> = particles
            .par_iter()
            .map(|p| {
                let c = across(p);
                let reach = Vec2::splat(p.reach());
                // Texel centres `min + (i + 1/2) texel` within the reach.
                let lo = ((c - reach - min) / texel - 0.5).ceil().max(Vec2::ZERO);
                let hi = ((c + reach - min) / texel - 0.5).floor() + 1.0;
                let hi = hi.min(Vec2::splat(n as f32)).max(lo);
                let range = [lo.x as usize, hi.x as usize, lo.y as usize, hi.y as usize];
                let k = -0.5 / (p.sigma() * p.sigma());
                let along_x = (range[0]..range[1])
                    .map(|ix| {
                        let dx = min.x + (ix as f32 + 0.5) * texel.x - c.x;
                        (k * dx * dx).exp()
                    })
                    .collect();
                (c, range, k, along_x)
            })
            .collect();
        // The particles touching each row, in particle order (so the sums do not depend
        // on the thread count).
        let mut rows: Vec<Vec<u32>> = vec![Vec::new(); n];
        for (k, (_, [_, _, z0, z1], _, _)) in footprints.iter().enumerate() {
            for row in &mut rows[*z0..*z1] {
                row.push(k as u32);
            }
        }
        let mut depth = vec![0.0f32; n * n];
        depth
            .par_chunks_mut(n)
            .zip(rows)
            .enumerate()
            .for_each(|(iz, (line, touching))| {
                let z = min.y + (iz as f32 + 0.5) * texel.y;
                for k in touching {
                    let (c, [x0, x1, _, _], exponent, along_x) = &footprints[k as usize];
                    let (scale, floor) = particles[k as usize].faded_column_parts();
                    let along_z = (exponent * (z - c.y) * (z - c.y)).exp();
                    for (tau, g) in line[*x0..*x1].iter_mut().zip(along_x) {
                        *tau += (scale * (g * along_z - floor)).max(0.0);
                    }
                }
            });
        Ok(CloudShadow {
            resolution,
            light_from_world: frame.from_world,
            min,
            texel,
            depth,
        })
    }

    /// Unit vector toward the sun the map was made for.
    pub fn to_sun(&self) -> Vec3 {
        -self.light_from_world.row(1)
    }

    /// The map's texel coordinates of the world point `p` (texel `(i, j)`'s centre at
    /// `(i, j)`): where the sun's ray through `p` crosses the map.
    #[inline]
    pub fn texel_coordinates(&self, p: Vec3) -> Vec2 {
        let l = self.light_from_world * p;
        (Vec2::new(l.x, l.z) - self.min) / self.texel - Vec2::splat(0.5)
    }

    /// The map's texture coordinates of a world point as two affine rows:
    /// `u = rows[0] . (p, 1)`, `v = rows[1] . (p, 1)`, in [0, 1] over the map (`u`
    /// along its rows' texels, `v` down its rows; texel centres at `(i + 1/2) / n`).
    /// What an engine's shader projects its terrain with, sampling the map's texture
    /// (e.g. `atmo_gpu::clouds::shadow_texture`) with a linear filter for the optical
    /// depth; the same as [`CloudShadow::depth_at`] on the map.
    pub fn uv_rows(&self) -> [Vec4; 2] {
        let size = self.texel * self.resolution as f32;
        let (x, z) = (self.light_from_world.row(0), self.light_from_world.row(2));
        [
            (x / size.x).extend(-self.min.x / size.x),
            (z / size.y).extend(-self.min.y / size.y),
        ]
    }

    /// The cloud's optical depth on the sun's ray through `p` (a point beyond the
    /// cloud's far side: beneath it), bilinear between texel centres; 0 off the map.
    pub fn depth_at(&self, p: Vec3) -> f32 {
        let n = self.resolution;
        let g = self.texel_coordinates(p);
        let last = (n - 1) as f32;
        // Off the map by more than half a texel: no cloud (the edge texels are clear:
        // the map reaches past every footprint).
        if g.x < -0.5 || g.y < -0.5 || g.x > last + 0.5 || g.y > last + 0.5 {
            return 0.0;
        }
        let g = g.clamp(Vec2::ZERO, Vec2::splat(last));
        let (ix, iz) = ((g.x as usize).min(n - 2), (g.y as usize).min(n - 2));
        let (fx, fz) = (g.x - ix as f32, g.y - iz as f32);
        let at = |x: usize, z: usize| self.depth[z * n + x];
        let near = at(ix, iz) + fx * (at(ix + 1, iz) - at(ix, iz));
        let far = at(ix, iz + 1) + fx * (at(ix + 1, iz + 1) - at(ix, iz + 1));
        near + fz * (far - near)
    }

    /// The share of the sun's irradiance (on a surface facing the sun) that reaches the
    /// point `p` beneath the cloud: what crosses it unscattered, `exp(-tau)`, and
    /// [`SCATTERED_DOWN`] of what it takes out of the beam.
    pub fn sunlight(&self, p: Vec3) -> f32 {
        let direct = (-self.depth_at(p)).exp();
        direct + SCATTERED_DOWN * (1.0 - direct)
    }
}

/// The ground beneath a cloud as a picture shows it (the plane `y = 0` of the world
/// frame), lit by the sun through the cloud's shadow.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ground {
    /// The radiance the ground sends to the eye from its unshadowed sunlight at each
    /// distance: `albedo / pi * sun * mu_s` through the air between, RGB, sampled at
    /// [`Ground::distances_m`].
    pub sunlit: [Vec3; GROUND_DISTANCES],
    /// The radiance to paint the ground with where the cloud does not shadow it (its
    /// sunlight and its other light), or `None` to keep the picture's own ground (the
    /// sky module's) and take the shadowed sunlight out of it.
    pub paint: Option<Vec3>,
}

/// Distances at which [`Ground::sunlit`] is given: geometric from 10 m to 200 km.
pub const GROUND_DISTANCES: usize = 32;
/// The nearest and the farthest of them, m.
const NEAREST_M: f32 = 10.0;
const FARTHEST_M: f32 = 200_000.0;

impl Ground {
    /// The distances of [`Ground::sunlit`]'s samples, m.
    pub fn distances_m() -> [f32; GROUND_DISTANCES] {
        let ratio = FARTHEST_M / NEAREST_M;
        std::array::from_fn(|k| NEAREST_M * ratio.powf(k as f32 / (GROUND_DISTANCES - 1) as f32))
    }

    /// A ground of reflectance `albedo` lit by `sun` (irradiance facing the sun) from
    /// `to_sun`, seen through clear air, painted with the ambient radiance `ambient`
    /// reflected besides.
    pub fn painted(albedo: f32, sun: Vec3, to_sun: Vec3, ambient: Vec3) -> Ground {
        let sunlit = albedo / std::f32::consts::PI * sun * to_sun.y.max(0.0);
        Ground {
            sunlit: [sunlit; GROUND_DISTANCES],
            paint: Some(sunlit + albedo * ambient),
        }
    }

    /// The ground of `atmosphere` (its `ground_albedo`) as the sky module draws it, seen
    /// from `eye_altitude_m` with the sun at `sun`: the sun's irradiance at the ground
    /// reflected toward the eye through the air, taking the air between as flat (the
    /// slant column to a point `d` m away is `d / h` times the vertical column below the
    /// eye, exact but for the Earth's curvature: a few tenths of a percent at 20 km).
    /// The picture's own ground is kept (`paint` is `None`).
    pub fn seen_through(atmosphere: &Atmosphere, eye_altitude_m: f64, sun: Sun) -> Ground {
        let n = atmosphere.channels();
        let sunlight = atmosphere.direct_sunlight(0.0, sun.elevation());
        let reflected =
            atmosphere.ground_albedo / std::f64::consts::PI * sun.elevation().sin().max(0.0);
        let h = eye_altitude_m.max(1.0);
        let r = atmosphere.bottom_radius_m;
        let vertical = column_densities(atmosphere, r, 1.0, 0.0, h, 8);
        let colour = SpectrumToRgb::for_atmosphere(atmosphere);
        let distances = Ground::distances_m();
        let sunlit = std::array::from_fn(|k| {
            let slant = distances[k] as f64 / h;
            let radiance: Vec<f32> = (0..n)
                .map(|c| {
                    let tau = slant * atmosphere.optical_depth(&vertical, c);
                    (reflected * sunlight[c] * (-tau).exp()) as f32
                })
                .collect();
            Vec3::from(colour.rgb(&radiance))
        });
        Ground {
            sunlit,
            paint: None,
        }
    }

    /// [`Ground::sunlit`] at `distance` m, linear in the logarithm between samples.
    fn sunlit_at(&self, distance: f32) -> Vec3 {
        let last = (GROUND_DISTANCES - 1) as f32;
        let x = (distance / NEAREST_M).max(1.0).ln() / (FARTHEST_M / NEAREST_M).ln();
        let x = (x * last).min(last);
        let k = (x as usize).min(GROUND_DISTANCES - 2);
        self.sunlit[k].lerp(self.sunlit[k + 1], x - k as f32)
    }
}

impl CloudShadow {
    /// Puts the cloud's shadow on the ground `camera` sees in `frame` (a pinhole camera
    /// above the ground): at each pixel whose ray meets the ground at `P`, `d` m away,
    /// the ground's sunlit radiance there is scaled by [`CloudShadow::sunlight`]`(P)`
    /// (painted first, where `ground` paints).
    pub fn shade_ground(&self, frame: &mut Frame, camera: &Camera, ground: &Ground) {
        let eye = camera.position;
        if eye.y <= 0.0 {
            return;
        }
        let w = frame.width as usize;
        frame
            .pixels
            .par_chunks_mut(w)
            .enumerate()
            .for_each(|(y, row)| {
                for (x, pixel) in row.iter_mut().enumerate() {
                    let r = camera.ray(x as f32 + 0.5, y as f32 + 0.5);
                    if r.y >= 0.0 {
                        continue;
                    }
                    let t = -eye.y / r.y;
                    let shadowed = 1.0 - self.sunlight(eye + t * r);
                    if let Some(paint) = ground.paint {
                        *pixel = paint;
                    }
                    if shadowed > 0.0 {
                        *pixel -= shadowed * ground.sunlit_at(t * r.length());
                        *pixel = pixel.max(Vec3::ZERO);
                    }
                }
            });
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::reference::clouds::transmittance;
    use crate::view::Fov;

    fn blobs() -> Vec<Particle> {
        [
            (0.0, 0.0, 0.0, 40.0),
            (60.0, 20.0, -30.0, 25.0),
            (-50.0, -10.0, 40.0, 30.0),
        ]
        .iter()
        .map(|&(x, y, z, radius)| Particle {
            position: Vec3::new(x, 1500.0 + y, z),
            radius,
            density: 0.1,
            albedo: 0.99,
        })
        .collect()
    }

    /// On the ground beneath three blobs, the map's transmittance is the exact one of
    /// their Gaussians: within 2 % in optical depth where the shadow is deep, and
    /// within 0.015 in transmittance in its rim, where the blobs' faded edges
    /// differ from the Gaussians' tails.
    #[test]
    fn the_map_is_the_exact_transmittance_on_the_ground() {
        let particles = blobs();
        let to_sun = Vec3::new(0.3, 0.8, -0.2).normalize();
        let shadow = CloudShadow::new(&particles, to_sun, 256).unwrap();
        assert!((shadow.to_sun() - to_sun).length() < 1e-6);
        // Where the sun's ray through the first blob's centre meets the ground, and
        // points around it.
        let centre = particles[0].position - particles[0].position.y / to_sun.y * to_sun;
        let (mut deepest, mut worst) = (0.0f32, 0.0f32);
        for k in 0..400 {
            let offset = Vec3::new(
                (k % 20) as f32 * 12.0 - 120.0,
                0.0,
                (k / 20) as f32 * 12.0 - 120.0,
            );
            let p = centre + offset;
            let exact = transmittance(&particles, to_sun, p) as f32;
            let mapped = (-shadow.depth_at(p)).exp();
            deepest = deepest.max(shadow.depth_at(p));
            worst = worst.max((mapped - exact).abs());
            if exact < 0.5 {
                assert!(
                    (mapped.ln() / exact.ln() - 1.0).abs() < 0.02,
                    "{p}: {mapped} vs {exact}"
                );
            }
        }
        assert!(worst < 0.015, "{worst}");
        assert!(deepest > 3.0, "the test crosses the shadow: {deepest}");
        // Far from the cloud, no shadow.
        assert_eq!(shadow.depth_at(centre + Vec3::new(5000.0, 0.0, 0.0)), 0.0);
    }

    /// A painted ground is its paint in the open, and keeps only its other light and
    /// the scattered share of its sunlight deep in the shadow.
    #[test]
    fn the_ground_is_dark_in_the_shadow_and_painted_in_the_open() {
        let particles = blobs();
        let to_sun = Vec3::new(0.0, 1.0, 0.0);
        let shadow = CloudShadow::new(&particles, to_sun, 128).unwrap();
        let (ambient, sun) = (Vec3::new(0.02, 0.03, 0.05), Vec3::ONE);
        let ground = Ground::painted(0.3, sun, to_sun, ambient);
        // Straight down from above the first blob, and a wide view around it.
        let eye = Vec3::new(0.0, 1000.0, 0.0);
        let camera =
            Camera::look_at(eye, Vec3::ZERO, Vec3::Z, Fov::Vertical(90.0), (33, 33)).unwrap();
        let mut frame = Frame::new(33, 33);
        shadow.shade_ground(&mut frame, &camera, &ground);
        let paint = ground.paint.unwrap();
        let lit = 0.3 / std::f32::consts::PI * sun;
        let (centre, corner) = (frame.pixels[16 * 33 + 16], frame.pixels[0]);
        let tau = shadow.depth_at(Vec3::ZERO);
        assert!(tau > 3.0, "{tau}");
        let want = 0.3 * ambient + lit * ((-tau).exp() + SCATTERED_DOWN * (1.0 - (-tau).exp()));
        assert!(
            (centre - want).abs().max_element() < 1e-5,
            "{centre} vs {want}"
        );
        assert!(
            (corner - paint).abs().max_element() < 1e-6,
            "{corner} vs {paint}"
        );
        // A camera looking up sees no ground.
        let up = Camera::look_at(eye, eye + Vec3::Y, Vec3::Z, Fov::Vertical(60.0), (8, 8)).unwrap();
        let mut sky = Frame::new(8, 8);
        shadow.shade_ground(&mut sky, &up, &ground);
        assert!(sky.pixels.iter().all(|p| *p == Vec3::ZERO));
    }

    /// The ground seen through the air: the slant column taken as flat is the exact
    /// one along the curved ray within 1 % of its transmittance at 30 km; nearer, the
    /// sunlit ground is the sun's reflection, and it fades with distance.
    #[test]
    fn the_ground_seen_through_the_air_fades_as_the_exact_column_says() {
        let atmosphere = Atmosphere::earth();
        let sun = Sun::from_degrees(30.0, 0.0).unwrap();
        let h = 900.0;
        let ground = Ground::seen_through(&atmosphere, h, sun);
        let near = ground.sunlit_at(10.0);
        let e = atmosphere.direct_sunlight(0.0, sun.elevation());
        let colour = SpectrumToRgb::for_atmosphere(&atmosphere);
        let reflected = (atmosphere.ground_albedo / std::f64::consts::PI * 0.5) as f32;
        let e_rgb = Vec3::from(colour.rgb(&e.iter().map(|v| *v as f32).collect::<Vec<_>>()));
        assert!(
            ((near / (reflected * e_rgb)) - Vec3::ONE)
                .abs()
                .max_element()
                < 2e-3,
            "{near}"
        );
        // The ray from the eye to a point 30 km away on the ground, on the sphere.
        let d = 30_000.0f64;
        let r = atmosphere.bottom_radius_m + h;
        let bottom = atmosphere.bottom_radius_m;
        // mu from the triangle eye, centre, ground point: bottom^2 = r^2 + d^2 + 2 r d mu.
        let mu = (bottom * bottom - r * r - d * d) / (2.0 * r * d);
        let columns = column_densities(&atmosphere, r, mu, 0.0, d, 96);
        let exact: Vec<f32> = (0..atmosphere.channels())
            .map(|c| (-atmosphere.optical_depth(&columns, c)).exp() as f32)
            .collect();
        let far = ground.sunlit_at(d as f32);
        let want: Vec<f32> = e
            .iter()
            .zip(&exact)
            .map(|(e, t)| *e as f32 * t * reflected)
            .collect();
        let want = Vec3::from(colour.rgb(&want));
        assert!(
            ((far / want) - Vec3::ONE).abs().max_element() < 0.01,
            "{far} vs {want}"
        );
        assert!(far.max_element() < 0.9 * near.max_element());
    }

    /// The texture coordinates of a texel centre's world point are the texel's centre.
    #[test]
    fn uv_rows_project_world_points_onto_the_map() {
        let particles = blobs();
        let shadow = CloudShadow::new(&particles, Vec3::new(-0.4, 0.7, 0.2), 64).unwrap();
        let from_light = shadow.light_from_world.transpose();
        let [ru, rv] = shadow.uv_rows();
        for (i, j) in [(0usize, 0usize), (10, 50), (63, 7)] {
            let (x, z) = (
                shadow.min.x + (i as f32 + 0.5) * shadow.texel.x,
                shadow.min.y + (j as f32 + 0.5) * shadow.texel.y,
            );
            // Any point along the sun's ray through the texel centre.
            let p = from_light * Vec3::new(x, 1234.0, z);
            let (u, v) = (ru.dot(p.extend(1.0)), rv.dot(p.extend(1.0)));
            assert!((u - (i as f32 + 0.5) / 64.0).abs() < 1e-5, "{i}: {u}");
            assert!((v - (j as f32 + 0.5) / 64.0).abs() < 1e-5, "{j}: {v}");
            assert!((shadow.depth_at(p) - shadow.depth[j * 64 + i]).abs() < 1e-5);
        }
    }
}
