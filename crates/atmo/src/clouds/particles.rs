//! Cloud particles: Gaussian blobs of water droplets (clouds 2, Fig. 1), each with a
//! centre, a radius, a peak extinction and an albedo.
//!
//! A particle's extinction coefficient at distance `d` from its centre is
//! `sigma(d) = density exp(-d^2 / (2 s^2))` with `s = radius / 3`: at the radius it has
//! fallen to 1.1 % of its peak, and the methods leave out what lies beyond it across a
//! line (the footprints) or along it past three `s` (a 0.13 % tail). Its optical depth
//! along a straight line at distance `b` from the centre, between line coordinates `l0`
//! and `l1` measured from the point nearest the centre, is
//!
//! ```text
//! tau = density exp(-b^2 / (2 s^2)) s sqrt(pi / 2) [erf(l / (s sqrt 2))] from l0 to l1
//! ```
//!
//! ([`Particle::column`]). The Gaussian is separable, `exp(-(x^2 + y^2 + z^2) / 2s^2)`
//! being a product of three 1-D factors, which is what makes the light pass fast.

use glam::Vec3;

/// One particle of a cloud.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Particle {
    /// Centre, m.
    pub position: Vec3,
    /// Radius where the blob is cut off, m (three standard deviations).
    pub radius: f32,
    /// Extinction coefficient at the centre, 1/m.
    pub density: f32,
    /// Single-scattering albedo in [0, 1].
    pub albedo: f32,
}

impl Particle {
    /// The Gaussian's standard deviation `s = radius / 3`, m.
    #[inline]
    pub fn sigma(&self) -> f32 {
        self.radius / 3.0
    }

    /// Extinction coefficient at `p`, 1/m.
    #[inline]
    pub fn extinction_at(&self, p: Vec3) -> f32 {
        let d2 = (p - self.position).length_squared();
        let s = self.sigma();
        self.density * (-d2 / (2.0 * s * s)).exp()
    }

    /// Optical depth along a line passing `b` m from the centre, between the line
    /// coordinates `l0 <= l1` (m, 0 at the point nearest the centre; infinite allowed).
    pub fn column(&self, b: f64, l0: f64, l1: f64) -> f64 {
        if l1 <= l0 {
            return 0.0;
        }
        let s = self.sigma() as f64;
        let k = 1.0 / (s * std::f64::consts::SQRT_2);
        self.density as f64
            * (-b * b / (2.0 * s * s)).exp()
            * s
            * (std::f64::consts::PI / 2.0).sqrt()
            * (erf(l1 * k) - erf(l0 * k))
    }
}

/// The error function, within 1.2e-7 everywhere (Numerical Recipes' `erfcc`, a Chebyshev
/// fit of `erfc`). std has none; a crate for one function is not worth its weight.
pub fn erf(x: f64) -> f64 {
    let z = x.abs();
    let t = 1.0 / (1.0 + 0.5 * z);
    let poly = -z * z - 1.265_512_23
        + t * (1.000_023_68
            + t * (0.374_091_96
                + t * (0.096_784_18
                    + t * (-0.186_288_06
                        + t * (0.278_868_07
                            + t * (-1.135_203_98
                                + t * (1.488_515_87 + t * (-0.822_152_23 + t * 0.170_872_77))))))));
    let erfc = t * poly.exp();
    if x >= 0.0 {
        1.0 - erfc
    } else {
        erfc - 1.0
    }
}

/// `erf(x)` from a table of 4097 values over [0, 4] with linear interpolation, within
/// 2e-7 of [`erf`] (and `1 - erf(4) = 1.5e-8` beyond): the light pass evaluates it tens
/// of millions of times.
#[inline]
pub fn erf_table(x: f32) -> f32 {
    static TABLE: std::sync::OnceLock<Vec<f32>> = std::sync::OnceLock::new();
    const STEPS: f32 = 1024.0;
    let table = TABLE.get_or_init(|| {
        (0..=4096)
            .map(|i| erf(i as f64 / STEPS as f64) as f32)
            .collect()
    });
    let a = (x.abs() * STEPS).min(4095.999);
    let i = a as usize;
    let f = a - i as f32;
    let v = table[i] + f * (table[i + 1] - table[i]);
    if x < 0.0 {
        -v
    } else {
        v
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn erf_matches_known_values() {
        for (x, want) in [
            (0.0, 0.0),
            (0.5, 0.520_499_877_813_046_5),
            (1.0, 0.842_700_792_949_714_9),
            (2.0, 0.995_322_265_018_952_7),
            (-1.0, -0.842_700_792_949_714_9),
            (3.5, 0.999_999_256_901_627_7),
        ] {
            assert!((erf(x) - want).abs() < 2e-7, "{x}: {} vs {want}", erf(x));
        }
    }

    #[test]
    fn the_erf_table_follows_erf() {
        let worst = (-5000..=5000)
            .map(|k| k as f64 * 1e-3)
            .map(|x| (erf_table(x as f32) as f64 - erf(x)).abs())
            .fold(0.0, f64::max);
        assert!(worst < 3e-7, "{worst}");
    }

    #[test]
    fn the_column_is_the_integral_of_the_extinction() {
        let p = Particle {
            position: Vec3::new(1.0, 2.0, 3.0),
            radius: 2.0,
            density: 0.7,
            albedo: 0.9,
        };
        for (b, l0, l1) in [
            (0.0, -5.0, 5.0),
            (0.6, -0.3, 1.2),
            (1.5, -2.0, 0.1),
            (2.5, -1.0, 1.0),
        ] {
            // Midpoint rule along a line through the blob at distance b from the centre.
            let n = 20_000;
            let dl = (l1 - l0) / n as f64;
            let numeric: f64 = (0..n)
                .map(|k| {
                    let l = l0 + (k as f64 + 0.5) * dl;
                    p.extinction_at(p.position + Vec3::new(b as f32, l as f32, 0.0)) as f64 * dl
                })
                .sum();
            let exact = p.column(b, l0, l1);
            assert!(
                (numeric - exact).abs() < 5e-4 * exact.max(1e-3),
                "{b} {l0} {l1}: {numeric} {exact}"
            );
        }
        assert_eq!(p.column(0.5, 1.0, 0.5), 0.0);
    }
}
