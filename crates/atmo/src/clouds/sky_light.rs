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
//! the path tracer holds within 10 % in the mean, docs/clouds.md). The sky's light is
//! not dimmed inside the cloud: a droplet deep in it sees the sky through the cloud.

use glam::Vec3;

use super::octaves::Octaves;
use crate::atmosphere::PhaseFunction;
use crate::sky::lighting::{sh_basis, SH_BAND, SH_Y00};

/// The sky's radiance as nine real spherical harmonics per linear-sRGB channel, in
/// [`crate::sky::lighting`]'s order, W m^-2 sr^-1 (or the picture's units).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SkyLight {
    pub harmonics: [Vec3; 9],
}

/// [`SH_Y00`] in f32.
const Y00: f32 = SH_Y00 as f32;

impl SkyLight {
    /// No light from the sky.
    pub const NONE: SkyLight = SkyLight {
        harmonics: [Vec3::ZERO; 9],
    };

    /// Radiance `rgb` from every direction alike.
    pub fn uniform(rgb: Vec3) -> SkyLight {
        let mut harmonics = [Vec3::ZERO; 9];
        harmonics[0] = rgb / Y00;
        SkyLight { harmonics }
    }

    /// From harmonics as [`crate::sky::lighting::project_equirect`] gives them.
    pub fn from_harmonics(sh: &[[f64; 3]; 9]) -> SkyLight {
        SkyLight {
            harmonics: sh.map(|c| Vec3::new(c[0] as f32, c[1] as f32, c[2] as f32)),
        }
    }

    /// The radiance averaged over the sphere, `(1 / 4 pi) integral L dw`.
    pub fn mean(&self) -> Vec3 {
        self.harmonics[0] * Y00
    }

    /// The harmonics of the light that droplets with `phase` scatter toward the eye,
    /// every order of `octaves` summed (see the module's doc): each band scaled by the
    /// phase's Legendre moment and the octaves' softening. Evaluated along a ray by
    /// [`SkyLight::along`].
    pub fn scattered(&self, phase: PhaseFunction, octaves: &Octaves) -> SkyLight {
        let lambda = legendre_moments(phase);
        let tilt = octaves.phase_share();
        let mut harmonics = self.harmonics;
        for (h, band) in harmonics.iter_mut().zip(SH_BAND) {
            if band > 0 {
                *h *= tilt * lambda[band];
            }
        }
        SkyLight { harmonics }
    }

    /// The radiance these harmonics give in the unit direction `d`.
    #[inline]
    pub fn along(&self, d: Vec3) -> Vec3 {
        self.harmonics
            .iter()
            .zip(sh_basis(d))
            .fold(Vec3::ZERO, |sum, (h, b)| sum + b as f32 * *h)
    }
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
}
