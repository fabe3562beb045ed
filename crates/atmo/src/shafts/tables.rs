//! The two tables of shafts (6): `g(alpha, s, t) = F(alpha) h(s, t)` split into a 1-D
//! table of the phase `F` over the scattering angle and a 2-D table of the attenuation
//! `h` over the light's and the eye's distances, built once a frame and looked up with
//! linear interpolation (what the paper's texture units did).
//!
//! Two choices differ from the paper, both for accuracy in float buffers:
//! - `F` is tabulated over `sin(alpha/2)` in [0, 1] rather than `alpha`: as even in
//!   `alpha` near 0 (where forward peaks are), and no arc-cosine at lookup.
//! - The table holds `s^2 h = sigma_s exp(-sigma_t (s + t))` and the lookup divides by
//!   `s^2` exactly: linear interpolation of `1/s^2` errs by tens of percent near the
//!   lamp, where the beam is brightest. Inside a haze box `s` and `t` in the exponent
//!   are the lengths inside the haze.

use std::sync::Arc;

use rayon::prelude::*;

use super::haze::Haze;
use super::photometry::Symmetry;
use super::spotlight::{Profile, Spotlight};
use crate::fast::fast_atan2;

/// `F(alpha)`, the haze's phase function in 1/sr, tabulated.
#[derive(Debug, Clone)]
pub struct PhaseTable {
    /// `F` at `sin(alpha/2) = k / (SIZE - 1)`, 1/sr.
    pub values: Vec<f32>,
}

impl PhaseTable {
    /// Entries of the table.
    pub const SIZE: usize = 1024;

    /// The table of `haze`'s phase function.
    pub fn new(haze: &Haze) -> PhaseTable {
        let values = (0..Self::SIZE)
            .map(|k| {
                let half_sin = k as f32 / (Self::SIZE - 1) as f32;
                // cos alpha = 1 - 2 sin^2(alpha/2)
                haze.phase.eval_f32(1.0 - 2.0 * half_sin * half_sin)
            })
            .collect();
        PhaseTable { values }
    }

    /// `F` at the scattering angle whose cosine is `cos_alpha`.
    #[inline]
    pub fn get(&self, cos_alpha: f32) -> f32 {
        let half_sin = (0.5 * (1.0 - cos_alpha)).clamp(0.0, 1.0).sqrt();
        lerp_1d(&self.values, half_sin * (Self::SIZE - 1) as f32)
    }
}

#[inline(always)]
fn lerp_1d(values: &[f32], x: f32) -> f32 {
    let i = (x as i32).clamp(0, values.len() as i32 - 2) as usize;
    let f = x - i as f32;
    values[i] + f * (values[i + 1] - values[i])
}

/// A spotlight's profile as the paper's light map (shafts 4.1; named `IntensityMap`
/// here, as the sky's light map is another thing), tabulated over `q = u^2 + v^2` in
/// [0, 1] (the square of the off-axis tangent over the field's) and,
/// for a measured profile that is not rotationally symmetric, over the half-plane
/// angle `C`: looked up at every sub-sample where the exact profile needs square roots
/// and arc-tangents (and for a measured one a search through the file's angles). A
/// beam's table starts at its edge (inside it the profile is 1); a measured one's at
/// the axis. The gobo, if any, stays an image.
#[derive(Debug, Clone, PartialEq)]
pub struct IntensityMap {
    /// `rows` rows of [`IntensityMap::SIZE`] entries: row `r` is the half-plane at
    /// `C = 360 r / rows` degrees, entry `k` the profile at `q = q_beam + k / scale`.
    pub values: Arc<[f32]>,
    /// Rows: 1 for a profile the same in every half-plane.
    pub rows: usize,
    /// Below this `q` the profile is 1 (inside a beam; 0 for a measured profile).
    pub q_beam: f32,
    /// Table entries per unit of `q`.
    pub scale: f32,
}

impl IntensityMap {
    /// Entries along `q` in each row.
    pub const SIZE: usize = 1024;

    /// Rows over `C` of a measured profile without rotational symmetry: 2.5 degrees
    /// apart, finer than the 5 to 22.5 degree planes photometric files measure.
    pub const MEASURED_ROWS: usize = 144;

    /// A table of nothing, for a light's map before it is built.
    pub(crate) fn empty() -> IntensityMap {
        IntensityMap {
            values: Arc::new([]),
            rows: 0,
            q_beam: 0.0,
            scale: 0.0,
        }
    }

    /// The table of `light`'s profile ([`Spotlight::profile_at`]).
    pub fn new(light: &Spotlight) -> IntensityMap {
        let (q_beam, rows) = match &light.profile {
            Profile::Beam { .. } => {
                let ratio = light.tan_beam() / light.tan_field();
                (ratio * ratio, 1)
            }
            Profile::Measured(p) if p.symmetry == Symmetry::Rotational => (0.0, 1),
            Profile::Measured(_) => (0.0, Self::MEASURED_ROWS),
        };
        let step = (1.0 - q_beam) / (Self::SIZE - 1) as f32;
        let values = (0..rows * Self::SIZE)
            .map(|i| {
                let (r, k) = (i / Self::SIZE, i % Self::SIZE);
                let q = (q_beam + k as f32 * step).min(1.0 - 1e-7);
                let c = std::f32::consts::TAU * r as f32 / rows as f32;
                light.profile_at(q.sqrt() * c.cos(), q.sqrt() * c.sin())
            })
            .collect();
        IntensityMap {
            values,
            rows,
            q_beam,
            scale: 1.0 / step.max(1e-12),
        }
    }

    /// The profile at the light-space projection `(u, v)`: 0 from `q = 1` on.
    #[inline(always)]
    pub fn get(&self, u: f32, v: f32) -> f32 {
        let q = u * u + v * v;
        if q < self.q_beam {
            1.0
        } else if q >= 1.0 {
            0.0
        } else {
            let x = (q - self.q_beam) * self.scale;
            let row = |r: usize| &self.values[r * Self::SIZE..(r + 1) * Self::SIZE];
            if self.rows == 1 {
                return lerp_1d(row(0), x);
            }
            // Between the rows on either side of the half-plane's C.
            let rows = self.rows as f32;
            let t = fast_atan2(v, u) * (rows / std::f32::consts::TAU);
            let t = if t < 0.0 { t + rows } else { t };
            let r = (t as usize).min(self.rows - 1);
            let f = t - r as f32;
            let (a, b) = (lerp_1d(row(r), x), lerp_1d(row((r + 1) % self.rows), x));
            a + f * (b - a)
        }
    }
}

/// `s^2 h(s, t)` of shafts (6) over `s` in `[0, s_max]` and `t` in `[0, t_max]`, m.
#[derive(Debug, Clone)]
pub struct AttenuationTable {
    values: Vec<f32>,
    s_scale: f32,
    t_scale: f32,
}

impl AttenuationTable {
    /// Samples along each axis.
    pub const SIZE: usize = 256;

    /// The table of `haze` up to `s_max` and `t_max` (beyond them the last entries hold).
    pub fn new(haze: &Haze, s_max: f32, t_max: f32) -> AttenuationTable {
        let n = Self::SIZE;
        let step = |max: f32| max.max(1e-3) / (n - 1) as f32;
        let (ds, dt) = (step(s_max), step(t_max));
        // Made a frame (its extent follows the lit volume): over both cores.
        let values = (0..n * n)
            .into_par_iter()
            .map(|k| {
                let (j, i) = (k / n, k % n);
                haze.scattering() * (-haze.extinction * (i as f32 * ds + j as f32 * dt)).exp()
            })
            .collect();
        AttenuationTable {
            values,
            s_scale: 1.0 / ds,
            t_scale: 1.0 / dt,
        }
    }

    /// `s^2 h(s, t)`, 1/m, from the in-haze lengths `s_haze` and `t_haze`; the caller
    /// divides by the lamp's distance squared.
    #[inline]
    pub fn get(&self, s_haze: f32, t_haze: f32) -> f32 {
        let n = Self::SIZE;
        let last = (n - 1) as f32;
        let x = (s_haze * self.s_scale).clamp(0.0, last);
        let y = (t_haze * self.t_scale).clamp(0.0, last);
        let (i, j) = (
            (x as i32).min(n as i32 - 2) as usize,
            (y as i32).min(n as i32 - 2) as usize,
        );
        let (a, b) = (x - i as f32, y - j as f32);
        let row = |j: usize| &self.values[j * n + i..j * n + i + 2];
        let (r0, r1) = (row(j), row(j + 1));
        (r0[0] + a * (r0[1] - r0[0])) * (1.0 - b) + (r1[0] + a * (r1[1] - r1[0])) * b
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::atmosphere::phase::PhaseFunction;

    #[test]
    fn the_intensity_map_matches_the_exact_profile() {
        use crate::shafts::spotlight::{light_frame, Falloff};
        for falloff in [Falloff::Linear, Falloff::Smooth] {
            let light = Spotlight::new(
                glam::Vec3::ZERO,
                light_frame(glam::Vec3::Z, glam::Vec3::Y).unwrap(),
                glam::Vec3::ONE,
                20f32.to_radians(),
                crate::shafts::spotlight::Profile::Beam {
                    beam_half: 12f32.to_radians(),
                    falloff,
                },
                None,
            );
            let map = &light.intensity_map;
            for k in 0..=2000 {
                let r = k as f32 / 1900.0;
                let want = light.profile_at(r, 0.0);
                assert!(
                    (map.get(r, 0.0) - want).abs() < 2e-4,
                    "{falloff:?} {r}: {} {want}",
                    map.get(r, 0.0)
                );
            }
        }
    }

    #[test]
    fn a_measured_intensity_map_matches_the_exact_profile_in_every_half_plane() {
        use crate::shafts::photometry::Photometry;
        use crate::shafts::spotlight::light_frame;
        // An oval: 30 degrees wide along C = 0, 15 along C = 90, planes 10 degrees apart
        // over the whole circle; smooth in gamma.
        let vertical: Vec<f32> = (0..=16).map(|k| 2.5 * k as f32).collect();
        let horizontal: Vec<f32> = (0..36).map(|k| 10.0 * k as f32).collect();
        let candela = horizontal
            .iter()
            .flat_map(|c| {
                let a = c.to_radians();
                let width = 1.0 / ((a.cos() / 30.0).hypot(a.sin() / 15.0));
                vertical
                    .iter()
                    .map(move |g| 5000.0 * (1.0 - (g / width).powi(2)).max(0.0).powi(2))
            })
            .collect();
        let photometry = Photometry {
            vertical,
            horizontal,
            candela,
            symmetry: crate::shafts::photometry::Symmetry::Full,
        };
        let light = Spotlight::new(
            glam::Vec3::ZERO,
            light_frame(glam::Vec3::Z, glam::Vec3::Y).unwrap(),
            glam::Vec3::splat(5000.0),
            photometry.reach().to_radians(),
            Profile::Measured(Arc::new(photometry)),
            None,
        );
        let map = &light.intensity_map;
        assert_eq!(map.rows, IntensityMap::MEASURED_ROWS);
        // The profile peaks at 1 on the axis; 10 degrees off it (tan 0.176) it is
        // lower along C = 90 than along C = 0.
        let t = 10f32.to_radians().tan() / light.tan_field();
        assert!((light.profile_at(0.0, 0.0) - 1.0).abs() < 1e-6);
        assert!(light.profile_at(0.0, t) < 0.5 * light.profile_at(t, 0.0));
        let mut worst = 0.0f32;
        for i in 0..=120 {
            for j in 0..=120 {
                let (u, v) = (i as f32 / 60.0 - 1.0, j as f32 / 60.0 - 1.0);
                worst = worst.max((map.get(u, v) - light.profile_at(u, v)).abs());
            }
        }
        // Rows 2.5 degrees apart over planes 10 apart: within 1 % of the peak.
        assert!(worst < 0.01, "{worst}");
    }

    #[test]
    fn tables_match_the_functions_they_hold() {
        for phase in [
            PhaseFunction::PaperHaze { exponent: 16.0 },
            PhaseFunction::HenyeyGreenstein { g: 0.8 },
        ] {
            let haze = Haze {
                extinction: 0.05,
                albedo: 0.8,
                phase,
                bounds: None,
            };
            let f = PhaseTable::new(&haze);
            for k in 0..=1000 {
                let c = -1.0 + k as f32 / 500.0;
                let want = phase.eval_f32(c);
                assert!(
                    (f.get(c) - want).abs() <= 2e-3 * want,
                    "{phase:?} {c} {} {want}",
                    f.get(c)
                );
            }
            let h = AttenuationTable::new(&haze, 40.0, 60.0);
            for (s, t) in [(0.05, 0.0), (1.0, 3.3), (17.2, 41.9), (40.0, 60.0)] {
                let want = 0.04 * (-0.05f32 * (s + t)).exp() / (s * s);
                assert!(
                    (h.get(s, t) / (s * s) - want).abs() <= 5e-5 * want,
                    "{s} {t}"
                );
            }
        }
    }
}
