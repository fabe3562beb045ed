//! The sky's light on a cloud (its ambient term): the sky's radiance as nine spherical
//! harmonics ([`crate::sky::lighting`]'s basis and order), scattered toward the eye by
//! the droplets' phase function.
//!
//! A droplet seen along the unit ray `r` sends toward the eye
//! `integral L(w) p(w . r) dw` of the sky's radiance `L`: with the sun behind the eye a
//! cloud's forward lobe looks at the sky behind the droplet, so a cloud seen from above
//! scatters the dark ground's light more than the sky's. By Funk and Hecke a function of
//! the angle to `r` scales each band `l` of the harmonics by its Legendre moment
//! `lambda_l = 2 pi integral p(mu) P_l(mu) d mu` (`lambda_0 = 1`, `lambda_1` the mean
//! cosine): the light is `sum_lm lambda_l L_lm Y_lm(r)`. Nine harmonics keep the phase
//! function's tilt, not the sharpness of its forward peak.
//!
//! The sky's light scattered more than once follows the octaves ([`Octaves`]): octave
//! `i` brings `b^i` of the light with the phase softened to `c^i` of its shape, so the
//! sum of the orders scales bands 1 and 2 by `lambda_l sum b^i c^i / sum b^i` and keeps
//! the sphere's mean (band 0) as its total, the isotropic term atmo used before (which
//! the path tracer holds within 10 % in the mean, docs/clouds.md).
//!
//! Inside the cloud the sky's light of every order is dimmed as the slab's diffuse light
//! of the sun ([`Octaves`]' module doc) is: the cloud along the vertical through a
//! droplet is a slab of optical depth `T`, the droplet at the depth `tau` below its top,
//! and the two-stream profile without absorption carries the light that enters from
//! above and from below linearly across it,
//!
//! ```text
//! J(tau) = E_above / pi * (T - tau + e) / (T + 2 e) + E_below / pi * (tau + e) / (T + 2 e)
//! ```
//!
//! `E_above`, `E_below` the sky's irradiance on a horizontal surface facing up and down
//! (the diffusion's sources at its faces), `e` the slab's extrapolation length. A sky of
//! the same radiance all round gives `J` = that radiance everywhere; a sky above a dark
//! ground lights the top twice the sphere's mean and the base little. The droplets'
//! light is the harmonics' times `J` over the sphere's mean ([`SkyDimming`]), with
//! `tau` and `T` at each particle's centre ([`vertical_depths`]). Against the path
//! tracer (a sky above a dark ground, two clouds seen from above, level and below) the
//! views' means are off by 8 % on average and 12 % at worst where they were 12 % and
//! 22 %, their thirds by 12 % where they were 18 % (docs/clouds.md). With single
//! scattering the light is not dimmed (the paper's constant ambient term).

use glam::Vec3;

use super::buffer::{IntensityBuffer, Splat};
use super::diffusion::{directions, DIRECTIONS};
use super::octaves::Octaves;
use super::particles::Particle;
use crate::atmosphere::PhaseFunction;
use crate::error::Result;
use crate::image::Frame;
use crate::sky::lighting::{cell_means, irradiance, project_equirect, sh_basis, SH_BAND, SH_Y00};

/// The sky's radiance, W m^-2 sr^-1 (or the picture's units), per linear-sRGB channel,
/// twice: as nine real spherical harmonics in [`crate::sky::lighting`]'s order (the
/// billboards' light of the sky, its tilt and its dimming), and as its mean over each
/// cell of the sphere about the transfer solve's directions (what the solve carries into
/// the cloud: nine harmonics of a sky over a dark ground ring into light from up to 48
/// deg below the horizon, which the droplets at a thick cloud's base scattered toward
/// the eye 20-60 % too bright).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SkyLight {
    pub harmonics: [Vec3; 9],
    /// Entry `i`: the radiance travelling along the solve's direction `i`
    /// ([`directions`]), i.e. seen looking the opposite way, averaged over the cell of
    /// the sphere nearest that direction.
    around: [Vec3; DIRECTIONS],
}

/// [`SH_Y00`] in f32.
const Y00: f32 = SH_Y00 as f32;

impl SkyLight {
    /// No light from the sky.
    pub const NONE: SkyLight = SkyLight {
        harmonics: [Vec3::ZERO; 9],
        around: [Vec3::ZERO; DIRECTIONS],
    };

    /// Radiance `rgb` from every direction alike.
    pub fn uniform(rgb: Vec3) -> SkyLight {
        let mut harmonics = [Vec3::ZERO; 9];
        harmonics[0] = rgb / Y00;
        SkyLight {
            harmonics,
            around: [rgb; DIRECTIONS],
        }
    }

    /// From harmonics as [`crate::sky::lighting::project_equirect`] gives them, where
    /// the sky itself is not at hand: the solve's directions read the harmonics, their
    /// ringing kept from going below 0 ([`SkyLight::from_map`] is truer).
    pub fn from_harmonics(sh: &[[f64; 3]; 9]) -> SkyLight {
        let harmonics = sh.map(|c| Vec3::new(c[0] as f32, c[1] as f32, c[2] as f32));
        let mut sky = SkyLight {
            harmonics,
            around: [Vec3::ZERO; DIRECTIONS],
        };
        let directions = directions();
        sky.around = std::array::from_fn(|i| sky.along(-directions[i]).max(Vec3::ZERO));
        sky
    }

    /// From an equirectangular radiance map (`envmap`'s conventions, width twice the
    /// height; the sky above, the ground below): its harmonics, and each of the solve's
    /// directions the mean of the pixels nearest it, weighted by their solid angles (a
    /// direction no pixel's centre falls nearest, in a map coarser than the lattice,
    /// reads the pixel it points at).
    pub fn from_map(map: &Frame) -> SkyLight {
        // The light travelling along `w` is seen looking along `-w`.
        let looking: Vec<Vec3> = directions().iter().map(|w| -*w).collect();
        let means = cell_means(map, &looking);
        SkyLight {
            around: std::array::from_fn(|i| means[i]),
            ..SkyLight::from_harmonics(&project_equirect(map))
        }
    }

    /// The radiance travelling along each of the transfer solve's directions
    /// ([`directions`], in its order): what it carries into the cloud from outside.
    pub fn around(&self) -> &[Vec3; DIRECTIONS] {
        &self.around
    }

    /// The radiance averaged over the sphere, `(1 / 4 pi) integral L dw`.
    pub fn mean(&self) -> Vec3 {
        self.harmonics[0] * Y00
    }

    /// The harmonics of the light that droplets with `phase` scatter toward the eye,
    /// every order of `octaves` summed (see the module's doc): each band scaled by the
    /// phase's Legendre moment and the octaves' softening. Evaluated along a ray by
    /// [`SkyLight::along`]; the solve's directions are kept as they are (the solve
    /// scatters them by the phase itself).
    pub fn scattered(&self, phase: PhaseFunction, octaves: &Octaves) -> SkyLight {
        let lambda = legendre_moments(phase);
        let tilt = octaves.phase_share();
        let mut harmonics = self.harmonics;
        for (h, band) in harmonics.iter_mut().zip(SH_BAND) {
            if band > 0 {
                *h *= tilt * lambda[band];
            }
        }
        SkyLight { harmonics, ..*self }
    }

    /// The radiance these harmonics give in the unit direction `d`.
    #[inline]
    pub fn along(&self, d: Vec3) -> Vec3 {
        self.harmonics
            .iter()
            .zip(sh_basis(d))
            .fold(Vec3::ZERO, |sum, (h, b)| sum + b as f32 * *h)
    }

    /// How the droplets' light from this sky is dimmed inside the cloud with every order
    /// of `octaves` (the module's doc): not at all with single scattering (no slab's
    /// diffuse light, [`Octaves::diffuse`] 0) or a sky of no light.
    pub fn dimming(&self, octaves: &Octaves) -> SkyDimming {
        let mean = self.mean();
        if octaves.diffuse <= 0.0 || mean.max_element() <= 0.0 {
            return SkyDimming::NONE;
        }
        let sh = self.harmonics.map(|h| [h.x as f64, h.y as f64, h.z as f64]);
        // The irradiance over pi, per channel against the sphere's mean radiance (1 for
        // a channel without light); the harmonics' ringing kept from going below 0.
        let ratio = |normal: Vec3| {
            let e = irradiance(&sh, normal).map(|e| (e / std::f64::consts::PI).max(0.0) as f32);
            Vec3::from_array(std::array::from_fn(|c| {
                if mean[c] > 0.0 {
                    e[c] / mean[c]
                } else {
                    1.0
                }
            }))
        };
        SkyDimming {
            above: ratio(Vec3::Y),
            below: ratio(-Vec3::Y),
            extrapolation: octaves.extrapolation,
        }
    }
}

/// The sky's light inside the cloud against outside it, per linear-sRGB channel
/// ([`SkyLight::dimming`]): `above + (below - above) (1 - top)` at a droplet whose share
/// of the light from above is `top` ([`SkyDimming::top_share`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SkyDimming {
    /// The irradiance from above over pi, against the sky's mean radiance.
    pub above: Vec3,
    /// The same from below.
    pub below: Vec3,
    /// The slab's extrapolation length `e`, optical depths ([`Octaves::extrapolation`]).
    pub extrapolation: f32,
}

impl SkyDimming {
    /// The light not dimmed: as much from above as from below, so no profile changes it.
    pub const NONE: SkyDimming = SkyDimming {
        above: Vec3::ONE,
        below: Vec3::ONE,
        extrapolation: 1.0,
    };

    /// Whether the light is the same at every depth (no [`vertical_depths`] needed).
    pub fn is_flat(&self) -> bool {
        (self.above - self.below).abs().max_element() < 1e-6
    }

    /// The share of the light from above at optical depth `tau` below the top of a
    /// vertical of the cloud's whole depth `column` (from [`vertical_depths`]):
    /// `(T - tau + e) / (T + 2 e)`, the two-stream profile; the rest is from below.
    #[inline]
    pub fn top_share(&self, [tau, column]: [f32; 2]) -> f32 {
        let e = self.extrapolation;
        ((column - tau + e) / (column + 2.0 * e)).clamp(0.0, 1.0)
    }

    /// The light at a droplet whose share from above is `top`, against outside.
    #[inline]
    pub fn at(&self, top: f32) -> Vec3 {
        self.below + (self.above - self.below) * top
    }
}

/// The resolution of the buffer [`vertical_depths`] reads: the depths are taken at the
/// particles' centres and the profile is linear in them, so a coarse grid does (on the
/// test's clouds the sky's light moves by under 0.1 % between 32^3 and 128^3).
pub const VERTICAL_RESOLUTION: usize = 64;

/// Each particle's optical depth below the cloud's top, down the vertical through its
/// centre, and the whole cloud's optical depth along that vertical: `[tau, T]` for
/// [`SkyDimming::top_share`]. Read from an [`IntensityBuffer`] lit from the zenith with
/// no forward scattering (its `Gamma` is then the transmittance from the top), so the
/// sky's depths come from the same machinery as the sun's.
pub fn vertical_depths(particles: &[Particle]) -> Result<Vec<[f32; 2]>> {
    depths_along(particles, Vec3::Y)
}

/// [`vertical_depths`] along any unit `axis`: each particle's optical depth from the
/// side `axis` points to, and the whole cloud's along the line through its centre.
pub(crate) fn depths_along(particles: &[Particle], axis: Vec3) -> Result<Vec<[f32; 2]>> {
    let buffer = IntensityBuffer::new(particles, axis, VERTICAL_RESOLUTION, 0.0, Splat::Pieces)?;
    Ok(particles
        .iter()
        .map(|p| {
            let g = buffer.grid_coordinates(p.position);
            [-buffer.sample_log_grid(g), buffer.column_depth_grid(g)]
        })
        .collect())
}

/// `lambda_l = 2 pi integral_-1^1 p(mu) P_l(mu) d mu` for `l` = 0, 1, 2, by the midpoint
/// rule on 16,384 intervals (0.11 ms on one core of the 2-core VM; the cloud's forward lobe,
/// g = 0.8, is smooth at that: the moments agree with the exact ones of a
/// Henyey-Greenstein, `g^l`, within 2e-6).
pub fn legendre_moments(phase: PhaseFunction) -> [f32; 3] {
    const STEPS: usize = 16_384;
    let h = 2.0 / STEPS as f64;
    let mut moments = [0.0f64; 3];
    for k in 0..STEPS {
        let mu = -1.0 + (k as f64 + 0.5) * h;
        let w = 2.0 * std::f64::consts::PI * phase.eval(mu) * h;
        moments[0] += w;
        moments[1] += w * mu;
        moments[2] += w * 0.5 * (3.0 * mu * mu - 1.0);
    }
    moments.map(|m| m as f32)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `integral f(w) dw` over the sphere by a latitude-longitude midpoint rule.
    fn over_sphere(f: impl Fn(Vec3) -> f64) -> f64 {
        let (rows, cols) = (400, 800);
        let mut sum = 0.0;
        for i in 0..rows {
            let theta = std::f64::consts::PI * (i as f64 + 0.5) / rows as f64;
            for j in 0..cols {
                let phi = 2.0 * std::f64::consts::PI * (j as f64 + 0.5) / cols as f64;
                let w = Vec3::new(
                    (theta.sin() * phi.cos()) as f32,
                    theta.cos() as f32,
                    (theta.sin() * phi.sin()) as f32,
                );
                sum += f(w) * theta.sin();
            }
        }
        sum * (std::f64::consts::PI / rows as f64) * (2.0 * std::f64::consts::PI / cols as f64)
    }

    #[test]
    fn legendre_moments_of_henyey_greenstein_are_powers_of_g() {
        for g in [0.0, 0.3, -0.5, 0.8] {
            let m = legendre_moments(PhaseFunction::HenyeyGreenstein { g });
            for (l, m) in m.into_iter().enumerate() {
                let want = (g as f32).powi(l as i32);
                assert!((m - want).abs() < 2e-6, "g {g}, l {l}: {m} vs {want}");
            }
        }
    }

    #[test]
    fn the_scattered_sky_is_the_phase_weighted_integral_of_the_sky() {
        // A sky within the nine harmonics (brighter above, a band along x and z), so
        // the convolution is exact: against the integral of L(w) p(w . r) over the
        // sphere, for single scattering and rays up, down and aslant.
        let sky_at = |w: Vec3| 1.0 + 0.6 * w.y + 0.3 * w.x * w.z + 0.2 * (w.x * w.x - w.y * w.y);
        let mut sh = [[0.0f64; 3]; 9];
        for (k, s) in sh.iter_mut().enumerate() {
            let c = over_sphere(|w| sky_at(w) as f64 * sh_basis(w)[k]);
            *s = [c, 0.5 * c, 0.25 * c];
        }
        let sky = SkyLight::from_harmonics(&sh);
        for w in [Vec3::Y, -Vec3::Y, Vec3::new(0.3, -0.5, 0.8).normalize()] {
            assert!((sky.along(w).x - sky_at(w)).abs() < 1e-3, "{w}");
        }
        assert!((sky.mean().x - 1.0).abs() < 1e-3, "the sky's mean is 1");
        let phase = PhaseFunction::HenyeyGreenstein { g: 0.5 };
        let scattered = sky.scattered(phase, &Octaves::SINGLE);
        for r in [Vec3::Y, -Vec3::Y, Vec3::new(-0.6, -0.3, 0.74).normalize()] {
            let want = over_sphere(|w| sky_at(w) as f64 * phase.eval(w.dot(r) as f64));
            let got = scattered.along(r);
            assert!((got.x as f64 - want).abs() < 2e-3, "{r}: {got} vs {want}");
            assert!((got.z as f64 - 0.25 * want).abs() < 1e-3);
        }
        // Isotropic droplets see the sphere's mean whichever way they are seen.
        let isotropic = sky.scattered(PhaseFunction::HenyeyGreenstein { g: 0.0 }, &Octaves::SINGLE);
        assert!((isotropic.along(Vec3::Y) - sky.mean()).abs().max_element() < 1e-5);
    }

    #[test]
    fn the_octaves_soften_the_tilt_and_keep_the_mean() {
        let sky = SkyLight::from_harmonics(&{
            let mut sh = [[0.0; 3]; 9];
            sh[0] = [2.0; 3];
            sh[1] = [1.0; 3];
            sh
        });
        let phase = PhaseFunction::CloudMie;
        let single = sky.scattered(phase, &Octaves::SINGLE);
        let every = sky.scattered(phase, &Octaves::MULTIPLE);
        let o = Octaves::MULTIPLE;
        let (b, c) = (o.contribution, o.eccentricity);
        let sum = |x: f32| (0..o.count as i32).map(|i| x.powi(i)).sum::<f32>();
        let share = sum(b * c) / sum(b);
        assert_eq!(single.harmonics[0], every.harmonics[0]);
        assert!((every.harmonics[1].x / single.harmonics[1].x - share).abs() < 1e-6);
        // Seen from above (the ray down) the droplets' forward lobe looks at the dark
        // below: less light than the mean; from below, more.
        assert!(single.along(-Vec3::Y).x < every.along(-Vec3::Y).x);
        assert!(every.along(-Vec3::Y).x < sky.mean().x);
        assert!(every.along(Vec3::Y).x > sky.mean().x);
        assert_eq!(SkyLight::uniform(Vec3::ONE).mean(), Vec3::ONE);
    }

    #[test]
    fn the_solves_directions_keep_the_skys_horizon_where_harmonics_ring() {
        // A sky of 1 over the upper hemisphere and none below, as a map: every
        // direction of the solve arriving from more than a cell's width (15 deg) above
        // the horizon carries 1 and from as far below 0, their mean the sky's (0.5);
        // its nine harmonics carried light up from below the horizon.
        let hemisphere = |rows: u32| {
            let mut map = Frame::new(2 * rows, rows);
            map.pixels[..(2 * rows * rows / 2) as usize].fill(Vec3::ONE);
            map
        };
        let directions = directions();
        for rows in [32, 4] {
            let sky = SkyLight::from_map(&hemisphere(rows));
            let mut sum = 0.0;
            for (w, l) in directions.iter().zip(sky.around()) {
                let elevation = (-w.y).asin().to_degrees();
                if elevation > 15.0 {
                    assert_eq!(*l, Vec3::ONE, "{rows} rows, from {elevation} deg");
                } else if elevation < -15.0 {
                    assert_eq!(*l, Vec3::ZERO, "{rows} rows, from {elevation} deg");
                }
                sum += l.x;
            }
            let mean = sum / DIRECTIONS as f32;
            assert!((mean - 0.5).abs() < 0.03, "{rows} rows: the mean {mean}");
            // The same harmonics as by themselves.
            let map = hemisphere(rows);
            let by_harmonics = SkyLight::from_harmonics(&project_equirect(&map));
            assert_eq!(sky.harmonics, by_harmonics.harmonics);
        }
        let ringing = SkyLight::from_harmonics(&project_equirect(&hemisphere(32)));
        let below = directions
            .iter()
            .zip(ringing.around())
            .filter(|(w, _)| w.y > 0.26)
            .map(|(_, l)| l.x)
            .fold(0.0f32, f32::max);
        assert!(below > 0.05, "the harmonics' light from below: {below}");
        // A sky alike all round is that light along every direction, every way.
        let grey = Vec3::new(0.2, 0.3, 0.5);
        let mut map = Frame::new(8, 4);
        map.pixels.fill(grey);
        for sky in [SkyLight::uniform(grey), SkyLight::from_map(&map)] {
            for l in sky.around() {
                assert!((*l - grey).abs().max_element() < 1e-6, "{l}");
            }
        }
    }

    #[test]
    fn the_sky_inside_the_cloud_comes_from_above_and_below_by_the_profile() {
        // A sky of the same light all round is the same at every depth; a sky of 1 over
        // the upper hemisphere and none below lights the top twice its mean (0.5) and
        // the base from nothing (to the nine harmonics' precision).
        let every = Octaves::MULTIPLE;
        assert!(SkyLight::uniform(Vec3::new(0.2, 0.3, 0.5))
            .dimming(&every)
            .is_flat());
        assert_eq!(SkyLight::NONE.dimming(&every), SkyDimming::NONE);
        let above = {
            let mut map = crate::image::Frame::new(64, 32);
            map.pixels[..64 * 16].fill(Vec3::ONE);
            SkyLight::from_harmonics(&crate::sky::lighting::project_equirect(&map))
        };
        assert_eq!(above.dimming(&Octaves::SINGLE), SkyDimming::NONE);
        let d = above.dimming(&every);
        assert!(
            (d.above - Vec3::splat(2.0)).abs().max_element() < 0.03,
            "{d:?}"
        );
        assert!(d.below.max_element() < 0.03, "{d:?}");
        assert_eq!(d.extrapolation, every.extrapolation);
        // The profile: at the top (T + e) / (T + 2e), at the base e / (T + 2e), half
        // and half where there is no cloud; linear between.
        let (t, e) = (10.0, every.extrapolation);
        assert!((d.top_share([0.0, t]) - (t + e) / (t + 2.0 * e)).abs() < 1e-6);
        assert!((d.top_share([t, t]) - e / (t + 2.0 * e)).abs() < 1e-6);
        assert_eq!(d.top_share([0.0, 0.0]), 0.5);
        let mid = d.top_share([0.5 * t, t]);
        assert!((mid - 0.5 * (d.top_share([0.0, t]) + d.top_share([t, t]))).abs() < 1e-6);
        assert!((d.at(1.0) - d.above).abs().max_element() < 1e-6);
        assert!((d.at(0.0) - d.below).abs().max_element() < 1e-6);
    }

    #[test]
    fn vertical_depths_are_counted_from_the_top() {
        // Two particles one above the other: the upper one's centre under half its own
        // column, the lower one's under the upper's whole column and half its own; the
        // vertical through each holds both.
        let particle = |y: f32| Particle {
            position: Vec3::new(0.0, y, 0.0),
            radius: 90.0,
            density: 0.02,
            albedo: 1.0,
        };
        let column = 0.02 * 30.0 * (2.0 * std::f32::consts::PI).sqrt();
        let depths = vertical_depths(&[particle(1600.0), particle(1300.0)]).unwrap();
        let near = |got: f32, want: f32| (got - want).abs() < 0.01 * want;
        assert!(
            near(depths[0][0], 0.5 * column),
            "{depths:?} against {column}"
        );
        assert!(near(depths[1][0], 1.5 * column), "{depths:?}");
        assert!(near(depths[0][1], 2.0 * column) && near(depths[1][1], 2.0 * column));
    }
}
