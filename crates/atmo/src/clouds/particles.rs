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

use super::buffer::FOOTPRINT;
use crate::lanes::{exp_lanes, first, Lanes};

/// `FOOTPRINT^2 / 2`: the Gaussian's exponent at the billboards' cut.
const CUT_EXPONENT: f32 = FOOTPRINT * FOOTPRINT / 2.0;

/// What makes [`Particle::faded_column`]'s integral over its disc the Gaussian's:
/// `1 / (1 - e^-c (1 + c))`, `c = FOOTPRINT^2 / 2` (1.0158 for a cut at 3.5).
pub const FADE_SCALE: f32 = 1.015_832_6;

/// Memory a particle takes in a drawn cloud, bytes: its record and its copies in the
/// light pass, the sorted billboards and the frames' lists. Measured from outside at
/// about 400 (peak resident size over 720,000 more particles); charged at 512.
pub const BYTES_PER_PARTICLE: u64 = 512;

/// Charges `count` particles (from `origin`: a file, or the generator) to the run's
/// memory budget before they are made or read: refused naming them and the count.
pub fn check_count(count: usize, origin: &str) -> crate::Result<()> {
    crate::budget::check(
        &format!("{count} particles ({origin})"),
        count as u64 * BYTES_PER_PARTICLE,
        "the particle count",
    )
}

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

    /// How far across a line of sight the methods reach from the centre, m:
    /// [`FOOTPRINT`] standard deviations (the buffer's footprints, the billboards' fade).
    #[inline]
    pub fn reach(&self) -> f32 {
        FOOTPRINT * self.sigma()
    }

    /// The optical depth of the whole line passing `sqrt(b2)` m from the centre as the
    /// billboards draw it: the Gaussian column cut at [`FOOTPRINT`] standard deviations
    /// and faded to zero there (its value at the cut taken off everywhere, so a blob has
    /// no edge), scaled by [`FADE_SCALE`] so that its integral over the disc, the
    /// particle's extinction cross-section, is the Gaussian's. Zero outside the cut.
    #[inline]
    pub fn faded_column(&self, b2: f32) -> f32 {
        first(self.faded_column_lanes(Lanes::splat(b2)))
    }

    /// [`Particle::faded_column`] of eight lines.
    #[inline(always)]
    pub(crate) fn faded_column_lanes(&self, b2: Lanes) -> Lanes {
        let s = self.sigma();
        let x = b2 * Lanes::splat(1.0 / (2.0 * s * s));
        let (scale, floor) = self.faded_column_parts();
        let column = Lanes::splat(scale) * (exp_lanes(-x) - Lanes::splat(floor));
        x.simd_lt(Lanes::splat(CUT_EXPONENT))
            .select(column, Lanes::ZERO)
    }

    /// [`Particle::faded_column`] as `max(0, scale (g - floor))` with
    /// `g = exp(-b2 / 2 s^2)`: `(scale, floor)`, for a caller that builds `g` from the
    /// Gaussian's separable factors.
    #[inline]
    pub fn faded_column_parts(&self) -> (f32, f32) {
        let axis = self.density * self.sigma() * (2.0 * std::f32::consts::PI).sqrt();
        (axis * FADE_SCALE, (-CUT_EXPONENT).exp())
    }

    /// Optical depth along a line passing `b` m from the centre, between the line
    /// coordinates `l0 <= l1` (m, 0 at the point nearest the centre; infinite allowed).
    pub fn column(&self, b: f64, l0: f64, l1: f64) -> f64 {
        self.line(b * b).depth(l0, l1)
    }

    /// The line passing `sqrt(b2)` m from the centre, for many lookups along it.
    pub fn line(&self, b2: f64) -> Line {
        let s = self.sigma() as f64;
        let peak = self.density as f64 * (-b2 / (2.0 * s * s)).exp();
        Line {
            peak,
            half_depth: peak * s * (std::f64::consts::PI / 2.0).sqrt(),
            scale: 1.0 / (s * std::f64::consts::SQRT_2),
        }
    }
}

/// A line through a particle's Gaussian, `l` m along it from the point nearest the
/// centre: the extinction `peak e^(-(scale l)^2)` and the optical depth
/// `half_depth [erf(scale l)]` between two points (in double precision, for the
/// references).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Line {
    /// The extinction at the point nearest the centre, 1/m.
    pub peak: f64,
    /// Half the optical depth of the whole line.
    pub half_depth: f64,
    /// `1 / (s sqrt 2)`, 1/m.
    pub scale: f64,
}

impl Line {
    /// The extinction `l` m along the line, 1/m.
    #[inline]
    pub fn extinction(&self, l: f64) -> f64 {
        let x = self.scale * l;
        self.peak * (-x * x).exp()
    }

    /// `erf(scale l)`: the optical depth up to `l` is `half_depth` times this plus a
    /// constant.
    #[inline]
    pub fn erf_at(&self, l: f64) -> f64 {
        erf(self.scale * l)
    }

    /// The optical depth between `l0 <= l1` (0 otherwise; infinite allowed).
    #[inline]
    pub fn depth(&self, l0: f64, l1: f64) -> f64 {
        if l1 <= l0 {
            return 0.0;
        }
        self.half_depth * (self.erf_at(l1) - self.erf_at(l0))
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

/// The inverse of `erf` on (-1, 1), within 4e-7 relative (Giles 2010, "Approximating
/// the erfinv function", the single-precision branch).
#[inline]
pub fn erf_inverse(x: f32) -> f32 {
    let w = -((1.0 - x) * (1.0 + x)).ln();
    let p = if w < 5.0 {
        let w = w - 2.5;
        [
            3.432_739_4e-7,
            -3.523_387_7e-6,
            -4.391_506_5e-6,
            2.185_808_7e-4,
            -1.253_725e-3,
            -4.177_681_6e-3,
            0.246_640_73,
            1.501_409_4,
        ]
        .iter()
        .fold(2.810_226_4e-8, |p, c| c + p * w)
    } else {
        let w = w.sqrt() - 3.0;
        [
            1.009_505_6e-4,
            1.349_343_2e-3,
            -3.673_428_4e-3,
            5.739_507_7e-3,
            -7.622_461_3e-3,
            9.438_870_5e-3,
            1.001_674,
            2.832_976_8,
        ]
        .iter()
        .fold(-2.002_142_6e-4, |p, c| c + p * w)
    };
    p * x
}

/// Where a blob's light toward the eye is best sampled along a line through it: the
/// blob sends `integral Gamma e^-u du` over its own optical depth `u` on the line
/// (`0..tau` from the eye's side), which is the mean of `Gamma` over the absorbed
/// fraction `v = 1 - e^-u` times `1 - e^-tau`. The Gauss-Legendre nodes of that mean
/// ([`EMISSION_WEIGHTS`] are their weights), each as its depth `u` and its distance
/// along the line from the point nearest the centre in standard deviations (negative
/// toward the eye), `l = sqrt 2 erfinv(2 u / tau - 1)` since the blob's depth to `l` is
/// `tau (1 + erf(l / sqrt 2)) / 2`. A thin blob's nodes sit at -1.21, 0 and +1.21
/// standard deviations; a thick one's move toward the eye.
///
/// Three nodes, not two: inside a cloud the sunlight along a line through a blob is
/// shaped by its neighbours, and on the 200-particle cloud of `tests/clouds_light.rs`
/// two nodes (with `ln Gamma` taken linear between them, exact for a lone blob) left
/// its single scattering 1-2 % darker than the blob's exact integral, three 0.3-0.6 %
/// (docs/clouds.md, "Drawing").
#[inline]
pub fn emission_nodes(tau: f32) -> [(f32, f32); EMISSION_NODES] {
    let absorbed = -(-tau).exp_m1();
    GAUSS_LEGENDRE.map(|node| {
        let u = -(-absorbed * node).ln_1p();
        let q = if tau > 1e-6 { u / tau } else { node };
        let l =
            std::f32::consts::SQRT_2 * erf_inverse((2.0 * q - 1.0).clamp(-0.999_999, 0.999_999));
        (u, l)
    })
}

/// How many nodes [`emission_nodes`] gives.
pub const EMISSION_NODES: usize = 3;

/// The emission nodes' shares of the absorbed fraction: the three-point Gauss-Legendre
/// nodes on [0, 1], `(1 -+ sqrt(3/5)) / 2` and `1/2`.
pub const GAUSS_LEGENDRE: [f32; EMISSION_NODES] = [0.112_701_66, 0.5, 0.887_298_3];

/// Their weights on [0, 1]: 5/18, 8/18, 5/18.
pub const EMISSION_WEIGHTS: [f32; EMISSION_NODES] = [5.0 / 18.0, 8.0 / 18.0, 5.0 / 18.0];

/// `sum_j w_j f(j)` over the emission nodes' weights ([`EMISSION_WEIGHTS`]), in lanes.
#[inline(always)]
pub(crate) fn weighted_lanes(f: impl Fn(usize) -> Lanes) -> Lanes {
    (0..EMISSION_NODES).fold(Lanes::ZERO, |sum, j| {
        sum + Lanes::splat(EMISSION_WEIGHTS[j]) * f(j)
    })
}

/// [`emission_nodes`] from a table over `sqrt(tau)` (20,000 steps up to a column of
/// 400, the nearest row; within 1e-3 of it, test below): the drawing needs it at every
/// pixel of every billboard, where its logarithms and exponentials cost more than the
/// rest of the pixel.
#[inline]
pub fn tabulated_emission_nodes(tau: f32) -> [(f32, f32); EMISSION_NODES] {
    tabulated_emission_nodes_lanes::<true>(Lanes::splat(tau)).map(|[u, l, _]| (first(u), first(l)))
}

/// [`tabulated_emission_nodes`] of eight columns: each node's `[u, l, phi(l)]`, in
/// lanes, `phi` the standard normal density (the blob's extinction at the node is
/// `tau phi(l) / s`); `u` only with `DEPTHS` (else 0).
///
/// The nearest of many rows rather than between two of fewer: without a gather on the
/// baseline instruction set each value is read lane by lane, and the lerp's second
/// row doubled the reads, a seventh of the frame's instructions (callgrind).
#[inline(always)]
pub(crate) fn tabulated_emission_nodes_lanes<const DEPTHS: bool>(
    tau: Lanes,
) -> [[Lanes; 3]; EMISSION_NODES] {
    const STEPS: usize = 20_000;
    const TOP: f32 = 400.0;
    // Per row the nodes' `l`, then `phi(l)`, then `u / tau`.
    const ROW: usize = 3 * EMISSION_NODES;
    static TABLE: std::sync::OnceLock<Vec<[f32; ROW]>> = std::sync::OnceLock::new();
    let table = TABLE.get_or_init(|| {
        (0..=STEPS)
            .map(|k| {
                let tau = (k as f32 / STEPS as f32 * TOP.sqrt()).powi(2);
                // The depths as fractions of the column (smooth down to 0), and the
                // distances.
                let nodes = emission_nodes(tau);
                std::array::from_fn(|i| {
                    let (u, l) = nodes[i % EMISSION_NODES];
                    match (i / EMISSION_NODES, tau > 0.0) {
                        (0, _) => l,
                        (1, _) => (-0.5 * l * l).exp() / (2.0 * std::f32::consts::PI).sqrt(),
                        (_, true) => u / tau,
                        (_, false) => GAUSS_LEGENDRE[i % EMISSION_NODES],
                    }
                })
            })
            .collect()
    });
    let x = (tau.fast_max(Lanes::ZERO).sqrt() / Lanes::splat(TOP.sqrt())
        * Lanes::splat(STEPS as f32)
        + Lanes::splat(0.5))
    .fast_min(Lanes::splat(STEPS as f32));
    let rows = x.trunc_int().to_array().map(|k| &table[k as usize]);
    let column = |i: usize| Lanes::new(rows.map(|row| row[i]));
    std::array::from_fn(|n| {
        let u = if DEPTHS {
            column(2 * EMISSION_NODES + n) * tau
        } else {
            Lanes::ZERO
        };
        [u, column(n), column(EMISSION_NODES + n)]
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_emission_node_table_follows_the_nodes() {
        let mut worst = 0.0f32;
        for k in 0..20_000 {
            let tau = 1e-4 * 1.0006f32.powi(k);
            if tau > 400.0 {
                break;
            }
            let (exact, table) = (emission_nodes(tau), tabulated_emission_nodes(tau));
            for (e, t) in exact.iter().zip(&table) {
                // Depths relative to the column, distances in standard deviations.
                worst = worst
                    .max((e.0 - t.0).abs() / tau.min(1.0))
                    .max((e.1 - t.1).abs());
            }
        }
        assert!(worst < 1e-3, "{worst}");
    }

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
    fn faded_columns_keep_the_cross_section_and_end_at_zero() {
        let c = CUT_EXPONENT as f64;
        assert!((FADE_SCALE as f64 - 1.0 / (1.0 - (-c).exp() * (1.0 + c))).abs() < 1e-6);
        let p = Particle {
            position: Vec3::ZERO,
            radius: 3.0,
            density: 2.0,
            albedo: 1.0,
        };
        // Ring by ring over the disc: the Gaussian's 2 pi s^2 times the axis's density.
        let steps = 100_000;
        let h = FOOTPRINT / steps as f32;
        let area: f64 = (0..steps)
            .map(|k| {
                let b = (k as f32 + 0.5) * h;
                p.faded_column(b * b) as f64 * 2.0 * std::f64::consts::PI * b as f64 * h as f64
            })
            .sum();
        let want = 2.0 * std::f64::consts::PI * 2.0 * (2.0 * std::f64::consts::PI).sqrt();
        assert!((area / want - 1.0).abs() < 1e-4, "{area} vs {want}");
        let edge = FOOTPRINT * 0.9999;
        assert!(p.faded_column(edge * edge) < 1e-4 && p.faded_column(FOOTPRINT * FOOTPRINT) == 0.0);
    }

    #[test]
    fn erf_inverse_inverts_erf() {
        let worst = (-999..=999)
            .map(|k| k as f64 * 1e-3)
            .map(|x| (erf(erf_inverse(x as f32) as f64) - x).abs())
            .fold(0.0, f64::max);
        assert!(worst < 2e-6, "{worst}");
    }

    #[test]
    fn emission_nodes_split_the_absorbed_light_by_gauss_legendre() {
        // The blob's depth up to each node is the Gauss-Legendre node of the absorbed
        // fraction: 1 - exp(-depth) = node (1 - exp(-tau)).
        let legendre = [0.5 - 0.15f64.sqrt(), 0.5, 0.5 + 0.15f64.sqrt()];
        for tau in [1e-4f32, 0.1, 1.0, 5.0, 20.0] {
            let nodes = emission_nodes(tau);
            for ((u, l), node) in nodes.iter().zip(legendre) {
                let depth = tau as f64 * 0.5 * (1.0 + erf(*l as f64 / std::f64::consts::SQRT_2));
                let want = node * (1.0 - (-(tau as f64)).exp());
                for got in [1.0 - (-depth).exp(), 1.0 - (-(*u as f64)).exp()] {
                    assert!(
                        (got - want).abs() < 1e-4 * want.max(1e-3),
                        "{tau}: {got} vs {want}"
                    );
                }
            }
            assert!(nodes[0].1 < nodes[1].1 && nodes[1].1 < nodes[2].1);
        }
        // The weights integrate quintics exactly on [0, 1].
        for k in 0..=5 {
            let sum: f64 = EMISSION_WEIGHTS
                .iter()
                .zip(legendre)
                .map(|(w, x)| *w as f64 * x.powi(k))
                .sum();
            assert!((sum - 1.0 / (k + 1) as f64).abs() < 1e-6, "{k}: {sum}");
        }
        // Thin: symmetric about the centre; thick: toward the eye.
        let thin = emission_nodes(1e-4);
        assert!(
            (thin[0].1 + thin[2].1).abs() < 1e-3
                && thin[1].1.abs() < 1e-3
                && (thin[2].1 - 1.21).abs() < 0.01,
            "{thin:?}"
        );
        assert!(emission_nodes(20.0)[2].1 < -1.0);
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
