//! The haze: a homogeneous medium (shafts 3: "the density of particles is constant"),
//! filling all space or an axis-aligned box with vacuum outside.
//!
//! The paper writes the medium as a density `rho`, an extinction cross-section `kappa`
//! and a phase `F(alpha) = K (1 + 9 cos^16(alpha/2))` (4) whose scale `K` the user picks.
//! atmo uses the physical pair: extinction `sigma_t = rho kappa` (1/m) and the
//! single-scattering albedo `omega`, with a phase function `p` normalised over the sphere
//! (1/sr). Then `rho F(alpha) = omega sigma_t p(alpha)`; for the paper's phase,
//! `p = (1 + 9 cos^16(alpha/2)) / (8 pi)` and `omega = 8 pi K / kappa`.

use glam::Vec3;

use crate::atmosphere::phase::PhaseFunction;
use crate::geometry::Aabb;

/// The haze of a scene.
#[derive(Debug, Clone, PartialEq)]
pub struct Haze {
    /// Extinction coefficient `sigma_t = rho kappa`, 1/m.
    pub extinction: f32,
    /// Single-scattering albedo `omega` in [0, 1]: scattering over extinction.
    pub albedo: f32,
    /// Phase function of the haze's particles (the paper's is
    /// [`PhaseFunction::PaperHaze`]).
    pub phase: PhaseFunction,
    /// Where the haze is; `None` fills all space.
    pub bounds: Option<Aabb>,
}

impl Haze {
    /// Scattering coefficient `sigma_s = omega sigma_t`, 1/m.
    pub fn scattering(&self) -> f32 {
        self.albedo * self.extinction
    }

    /// The length, m, of the segment `a -> b` that lies in the haze: the path the
    /// attenuation `exp(-sigma_t l)` of shafts (3) acts along.
    #[inline]
    pub fn length_inside(&self, a: Vec3, b: Vec3) -> f32 {
        let d = b - a;
        match &self.bounds {
            None => d.length(),
            Some(aabb) => aabb
                .clip(a, d.recip(), 0.0, 1.0)
                .map_or(0.0, |(t0, t1)| (t1 - t0) * d.length()),
        }
    }

    /// How far from `eye` the haze can send light to it, m: to the farthest corner of
    /// its box, or, where it fills all space, 20 of its mean free paths (a transmittance
    /// of 2e-9: nothing beyond shows); infinite in clear air.
    pub fn reach(&self, eye: Vec3) -> f32 {
        match self.bounds {
            Some(b) => b
                .corners()
                .into_iter()
                .map(|c| c.distance(eye))
                .fold(0.0, f32::max),
            None => 20.0 / self.extinction,
        }
    }

    /// The part `[t0, t1]` of `[t_min, t_max]` where the ray `origin + t dir` is in the
    /// haze.
    #[inline]
    pub fn clip(&self, origin: Vec3, dir: Vec3, t_min: f32, t_max: f32) -> Option<(f32, f32)> {
        match &self.bounds {
            None => (t_min <= t_max).then_some((t_min, t_max)),
            Some(aabb) => aabb.clip(origin, dir.recip(), t_min, t_max),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_haze_box_limits_the_attenuating_path() {
        let mut haze = Haze {
            extinction: 0.1,
            albedo: 1.0,
            phase: PhaseFunction::PaperHaze { exponent: 16.0 },
            bounds: None,
        };
        let (a, b) = (Vec3::new(-5.0, 0.5, 0.5), Vec3::new(5.0, 0.5, 0.5));
        assert!((haze.length_inside(a, b) - 10.0).abs() < 1e-5);
        haze.bounds = Some(Aabb {
            min: Vec3::ZERO,
            max: Vec3::ONE,
        });
        assert!((haze.length_inside(a, b) - 1.0).abs() < 1e-5);
        assert!((haze.length_inside(b, a) - 1.0).abs() < 1e-5);
        assert_eq!(haze.length_inside(a, Vec3::new(-1.0, 0.5, 0.5)), 0.0);
        let inside = Vec3::splat(0.5);
        assert!((haze.length_inside(inside, b) - 0.5).abs() < 1e-5);
        assert_eq!(haze.clip(a, Vec3::X, 0.0, 100.0), Some((5.0, 6.0)));
    }
}
