//! Phase functions: the angular distribution of scattered light.
//!
//! Each function takes `cos_theta`, the cosine of the scattering angle between the
//! direction light travelled before and after scattering (1 = straight on), and returns
//! a density in 1/sr normalised so that its integral over the sphere is 1. The paper's
//! sky (10) writes the same quantity as `beta(alpha) / (4 pi)`.

use serde::Deserialize;
use std::f64::consts::PI;

use crate::error::{check_range, Result};

/// A phase function of one kind of particle.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(tag = "kind", rename_all = "kebab-case", deny_unknown_fields)]
pub enum PhaseFunction {
    /// Rayleigh scattering by molecules, sky (A-1): `3/4 (1 + cos^2)`, normalised.
    Rayleigh,
    /// The paper's aerosol phase, sky (A-4): `a (1 + 50 cos^6(alpha/2))` with
    /// `a = 1 / (54 pi)` so that it integrates to 1.
    PaperMie,
    /// Henyey-Greenstein with asymmetry `g` in (-1, 1).
    HenyeyGreenstein { g: f64 },
    /// Cornette-Shanks with asymmetry `g` in (-1, 1): Henyey-Greenstein with a
    /// Rayleigh-like factor, closer to measured aerosol phase functions.
    CornetteShanks { g: f64 },
}

impl PhaseFunction {
    /// The phase function's value in 1/sr for the scattering-angle cosine `cos_theta`.
    #[inline]
    pub fn eval(&self, cos_theta: f64) -> f64 {
        match *self {
            PhaseFunction::Rayleigh => 3.0 / (16.0 * PI) * (1.0 + cos_theta * cos_theta),
            PhaseFunction::PaperMie => {
                // cos^2(alpha/2) = (1 + cos alpha) / 2
                let half = 0.5 * (1.0 + cos_theta);
                (1.0 + 50.0 * half * half * half) / (54.0 * PI)
            }
            PhaseFunction::HenyeyGreenstein { g } => {
                let denom = 1.0 + g * g - 2.0 * g * cos_theta;
                (1.0 - g * g) / (4.0 * PI * denom * denom.sqrt())
            }
            PhaseFunction::CornetteShanks { g } => {
                let denom = 1.0 + g * g - 2.0 * g * cos_theta;
                3.0 / (8.0 * PI) * (1.0 - g * g) * (1.0 + cos_theta * cos_theta)
                    / ((2.0 + g * g) * denom * denom.sqrt())
            }
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
            PhaseFunction::HenyeyGreenstein { g } => {
                format!(r#"{{ kind = "henyey-greenstein", g = {g:?} }}"#)
            }
            PhaseFunction::CornetteShanks { g } => {
                format!(r#"{{ kind = "cornette-shanks", g = {g:?} }}"#)
            }
        }
    }

    /// Checks the asymmetry parameter, naming `field` when it is out of range.
    pub fn validate(&self, field: &str) -> Result<()> {
        match *self {
            PhaseFunction::HenyeyGreenstein { g } | PhaseFunction::CornetteShanks { g } => {
                check_range(&format!("{field}.g"), g, -0.999, 0.999)
            }
            _ => Ok(()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::quadrature::gauss_legendre;

    fn sphere_integral(p: &PhaseFunction) -> f64 {
        // Integral over the sphere = 2 pi * integral over cos in [-1, 1].
        let mut sum = 0.0;
        gauss_legendre(-1.0, 1.0, 2000, |c, w| sum += w * p.eval(c));
        2.0 * PI * sum
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
    fn out_of_range_asymmetry_is_refused() {
        let err = PhaseFunction::HenyeyGreenstein { g: 1.0 }
            .validate("mie.phase")
            .unwrap_err();
        assert!(err.to_string().contains("mie.phase.g"), "{err}");
    }
}
