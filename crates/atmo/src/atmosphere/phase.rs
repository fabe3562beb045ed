//! Phase functions: the angular distribution of scattered light, for every method.
//!
//! Each function takes `cos_theta`, the cosine of the scattering angle between the
//! direction light travelled before and after scattering (1 = straight on), and returns
//! a density in 1/sr normalised so that its integral over the sphere is 1. The sky paper
//! writes the same quantity as `beta(alpha) / (4 pi)` (sky (10)); the shafts paper as
//! `F(alpha) / K` up to a constant (shafts (4)); the clouds paper as `p(omega, l)`
//! (clouds (6)). The sky evaluates in f64 ([`PhaseFunction::eval`]), shafts and clouds in
//! f32 ([`PhaseFunction::eval_f32`]); both come from one formula each.

use serde::Deserialize;
use std::ops::{Add, Div, Mul, Sub};

use crate::error::{check_range, Result};

/// Rayleigh's phase is `RAYLEIGH_NORM (1 + cos^2)`, 1/sr: `3 / (16 pi)`.
pub const RAYLEIGH_NORM: f64 = 3.0 / (16.0 * std::f64::consts::PI);

/// A phase function of one kind of particle.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(tag = "kind", rename_all = "kebab-case", deny_unknown_fields)]
pub enum PhaseFunction {
    /// Rayleigh scattering by molecules, sky (A-1): `3/4 (1 + cos^2)`, normalised.
    Rayleigh,
    /// The sky paper's aerosol phase, sky (A-4): `a (1 + 50 cos^6(alpha/2))` with
    /// `a = 1 / (54 pi)` so that it integrates to 1.
    PaperMie,
    /// The shafts paper's haze, shafts (4): `1 + 9 cos^n(alpha/2)`, normalised; the paper
    /// takes `n = 16`.
    PaperHaze { exponent: f64 },
    /// Henyey-Greenstein with asymmetry `g` in (-1, 1).
    HenyeyGreenstein { g: f64 },
    /// Cornette-Shanks with asymmetry `g` in (-1, 1): Henyey-Greenstein with a
    /// Rayleigh-like factor, closer to measured aerosol phase functions.
    CornetteShanks { g: f64 },
    /// A Mie-like cloud phase: a strong forward Henyey-Greenstein lobe (g = 0.8) and a
    /// weak backward one (g = -0.3), weighted 0.75 : 0.25 (after the two-lobe fits used
    /// in games since Nishita 1996): the silver lining and a faint glory side.
    CloudMie,
}

/// The arithmetic the formulas need, so that each is written once for f32 and f64.
trait Real:
    Copy
    + PartialOrd
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
{
    fn of(x: f64) -> Self;
    fn sqrt(self) -> Self;
    fn powf(self, e: Self) -> Self;
}

impl Real for f32 {
    fn of(x: f64) -> Self {
        x as f32
    }
    fn sqrt(self) -> Self {
        f32::sqrt(self)
    }
    fn powf(self, e: Self) -> Self {
        f32::powf(self, e)
    }
}

impl Real for f64 {
    fn of(x: f64) -> Self {
        x
    }
    fn sqrt(self) -> Self {
        f64::sqrt(self)
    }
    fn powf(self, e: Self) -> Self {
        f64::powf(self, e)
    }
}

/// Henyey-Greenstein with asymmetry `g`, 1/sr.
#[inline]
fn henyey_greenstein<R: Real>(g: R, c: R) -> R {
    let one = R::of(1.0);
    let denom = one + g * g - R::of(2.0) * g * c;
    (one - g * g) / (R::of(4.0 * std::f64::consts::PI) * denom * denom.sqrt())
}

impl PhaseFunction {
    #[inline]
    fn value<R: Real>(&self, c: R) -> R {
        use std::f64::consts::PI;
        let one = R::of(1.0);
        match *self {
            PhaseFunction::Rayleigh => R::of(RAYLEIGH_NORM) * (one + c * c),
            PhaseFunction::PaperMie => {
                // cos^2(alpha/2) = (1 + cos alpha) / 2
                let half = R::of(0.5) * (one + c);
                (one + R::of(50.0) * half * half * half) / R::of(54.0 * PI)
            }
            PhaseFunction::PaperHaze { exponent } => {
                // The integral of cos^n(alpha/2) over the sphere is 4 pi * 2 / (n + 2).
                let half = R::of(0.5) * (one + c);
                let half = if half > R::of(0.0) { half } else { R::of(0.0) };
                let n = R::of(exponent);
                let norm = R::of(4.0 * PI) * (one + R::of(18.0) / (n + R::of(2.0)));
                (one + R::of(9.0) * half.powf(R::of(0.5) * n)) / norm
            }
            PhaseFunction::HenyeyGreenstein { g } => henyey_greenstein(R::of(g), c),
            PhaseFunction::CornetteShanks { g } => {
                let g = R::of(g);
                let denom = one + g * g - R::of(2.0) * g * c;
                R::of(3.0 / (8.0 * PI)) * (one - g * g) * (one + c * c)
                    / ((R::of(2.0) + g * g) * denom * denom.sqrt())
            }
            PhaseFunction::CloudMie => {
                R::of(0.75) * henyey_greenstein(R::of(0.8), c)
                    + R::of(0.25) * henyey_greenstein(R::of(-0.3), c)
            }
        }
    }

    /// The phase function's value in 1/sr for the scattering-angle cosine `cos_theta`.
    #[inline]
    pub fn eval(&self, cos_theta: f64) -> f64 {
        self.value(cos_theta)
    }

    /// The phase function's Legendre moment of order `l`, `chi_l = 2 pi integral p(c)
    /// P_l(c) dc` (1 for `l = 0`, the mean cosine `g` for `l = 1`; `g^l` for
    /// Henyey-Greenstein): what the transfer solve's delta-Eddington scaling reads of the
    /// phase ([`crate::clouds::diffusion`]).
    pub fn legendre_moment(&self, l: u32) -> f64 {
        self.legendre_moments(l)[l as usize]
    }

    /// The moments `chi_0` to `chi_last` ([`PhaseFunction::legendre_moment`]) in one
    /// pass over the quadrature.
    pub fn legendre_moments(&self, last: u32) -> Vec<f64> {
        let mut sums = vec![0.0; last as usize + 1];
        crate::quadrature::gauss_legendre(-1.0, 1.0, 2000, |c, w| {
            let weight = w * self.eval(c);
            for (sum, p) in sums
                .iter_mut()
                .zip(crate::quadrature::legendre(c, last as usize))
            {
                *sum += weight * p;
            }
        });
        sums.iter()
            .map(|s| 2.0 * std::f64::consts::PI * s)
            .collect()
    }

    /// [`PhaseFunction::eval`] in f32, for the per-sample paths of shafts and clouds.
    #[inline]
    pub fn eval_f32(&self, cos_theta: f32) -> f32 {
        self.value(cos_theta)
    }

    /// Every kind's name and code, as the GPU's phase function reads them (atmo-gpu
    /// writes them into its shaders as `PHASE_<NAME>` constants).
    pub const CODES: [(&'static str, u32); 6] = [
        ("RAYLEIGH", 0),
        ("PAPER_MIE", 1),
        ("HENYEY_GREENSTEIN", 2),
        ("CORNETTE_SHANKS", 3),
        ("PAPER_HAZE", 4),
        ("CLOUD_MIE", 5),
    ];

    /// This function's code in [`PhaseFunction::CODES`] and its one parameter (`g`, the
    /// exponent, or 0).
    pub fn code(&self) -> (u32, f64) {
        match *self {
            PhaseFunction::Rayleigh => (0, 0.0),
            PhaseFunction::PaperMie => (1, 0.0),
            PhaseFunction::HenyeyGreenstein { g } => (2, g),
            PhaseFunction::CornetteShanks { g } => (3, g),
            PhaseFunction::PaperHaze { exponent } => (4, exponent),
            PhaseFunction::CloudMie => (5, 0.0),
        }
    }

    /// True when the phase is `a + b cos^2`, whose integral against any radiance field
    /// reduces exactly to five moments of that field (see `sky::light_map`).
    pub fn is_rayleigh(&self) -> bool {
        matches!(self, PhaseFunction::Rayleigh)
    }

    /// The inline TOML table that deserializes to this function.
    pub fn to_toml(&self) -> String {
        match *self {
            PhaseFunction::Rayleigh => r#"{ kind = "rayleigh" }"#.into(),
            PhaseFunction::PaperMie => r#"{ kind = "paper-mie" }"#.into(),
            PhaseFunction::PaperHaze { exponent } => {
                format!(r#"{{ kind = "paper-haze", exponent = {exponent:?} }}"#)
            }
            PhaseFunction::HenyeyGreenstein { g } => {
                format!(r#"{{ kind = "henyey-greenstein", g = {g:?} }}"#)
            }
            PhaseFunction::CornetteShanks { g } => {
                format!(r#"{{ kind = "cornette-shanks", g = {g:?} }}"#)
            }
            PhaseFunction::CloudMie => r#"{ kind = "cloud-mie" }"#.into(),
        }
    }

    /// Checks the parameters (`g` in [-0.999, 0.999], the exponent in [0, 1000]),
    /// naming `field` when one is out of range.
    pub fn validate(&self, field: &str) -> Result<()> {
        match *self {
            PhaseFunction::HenyeyGreenstein { g } | PhaseFunction::CornetteShanks { g } => {
                check_range(&format!("{field}.g"), g, -0.999, 0.999)
            }
            PhaseFunction::PaperHaze { exponent } => {
                check_range(&format!("{field}.exponent"), exponent, 0.0, 1000.0)
            }
            _ => Ok(()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::quadrature::gauss_legendre;
    use std::f64::consts::PI;

    fn sphere_integral(p: &PhaseFunction) -> f64 {
        // Integral over the sphere = 2 pi * integral over cos in [-1, 1].
        let mut sum = 0.0;
        gauss_legendre(-1.0, 1.0, 2000, |c, w| sum += w * p.eval(c));
        2.0 * PI * sum
    }

    #[test]
    fn legendre_moments_of_henyey_greenstein_are_powers_of_g() {
        let hg = PhaseFunction::HenyeyGreenstein { g: 0.6 };
        for l in 0..4 {
            assert!(
                (hg.legendre_moment(l) - 0.6f64.powi(l as i32)).abs() < 1e-6,
                "{l}"
            );
        }
        // The cloud's two lobes: 0.75 g1^l + 0.25 g2^l.
        let cloud = PhaseFunction::CloudMie;
        assert!((cloud.legendre_moment(1) - 0.525).abs() < 1e-6);
        assert!((cloud.legendre_moment(2) - 0.5025).abs() < 1e-6);
    }

    #[test]
    fn every_phase_function_integrates_to_one() {
        for p in [
            PhaseFunction::Rayleigh,
            PhaseFunction::PaperMie,
            PhaseFunction::HenyeyGreenstein { g: 0.8 },
            PhaseFunction::HenyeyGreenstein { g: -0.3 },
            PhaseFunction::CornetteShanks { g: 0.8 },
            PhaseFunction::CornetteShanks { g: 0.0 },
            PhaseFunction::PaperHaze { exponent: 16.0 },
            PhaseFunction::PaperHaze { exponent: 4.0 },
            PhaseFunction::CloudMie,
        ] {
            let total = sphere_integral(&p);
            assert!((total - 1.0).abs() < 1e-6, "{p:?} integrates to {total}");
        }
    }

    #[test]
    fn forward_peaked_aerosols_and_symmetric_rayleigh() {
        let r = PhaseFunction::Rayleigh;
        assert!((r.eval(0.3) - r.eval(-0.3)).abs() < 1e-15);
        for p in [
            PhaseFunction::PaperMie,
            PhaseFunction::CornetteShanks { g: 0.76 },
        ] {
            assert!(p.eval(1.0) > 10.0 * p.eval(-1.0), "{p:?}");
        }
    }

    #[test]
    fn f32_and_f64_agree_and_the_papers_haze_has_its_ratio_of_ten() {
        for p in [
            PhaseFunction::Rayleigh,
            PhaseFunction::PaperMie,
            PhaseFunction::PaperHaze { exponent: 16.0 },
            PhaseFunction::HenyeyGreenstein { g: 0.6 },
            PhaseFunction::CornetteShanks { g: 0.76 },
            PhaseFunction::CloudMie,
        ] {
            for c in [-1.0, -0.4, 0.0, 0.7, 0.999, 1.0] {
                let (a, b) = (p.eval(c), p.eval_f32(c as f32) as f64);
                assert!((a - b).abs() <= 1e-5 * a, "{p:?} at {c}: {a} vs {b}");
            }
        }
        let haze = PhaseFunction::PaperHaze { exponent: 16.0 };
        assert!((haze.eval(1.0) / haze.eval(-1.0) - 10.0).abs() < 1e-9);
        assert!((haze.eval(1.0) - 10.0 / (8.0 * PI)).abs() < 1e-12);
        let k = PhaseFunction::Rayleigh.eval(0.0);
        assert_eq!(k, RAYLEIGH_NORM);
    }

    #[test]
    fn out_of_range_asymmetry_is_refused() {
        let err = PhaseFunction::HenyeyGreenstein { g: 1.0 }
            .validate("mie.phase")
            .unwrap_err();
        assert!(err.to_string().contains("mie.phase.g"), "{err}");
    }
}
