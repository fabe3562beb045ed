//! Multiple scattering in a cloud, approximated by octaves (Wrenninge, Kulla and
//! Lundqvist, "Oz: the great and volumetric", SIGGRAPH 2013 talk; used by Hillaire's
//! Frostbite clouds, 2016): light scattered many times is summed as further copies of
//! single scattering, octave `i` seeing the sun through `a^i` of the optical depth,
//! contributing `b^i` of the light, with a phase function softened toward isotropic
//! by `c^i`:
//!
//! ```text
//! L = sum_i b^i p_i(theta) exp(-a^i tau_sun),   p_i = c^i p + (1 - c^i) / (4 pi)
//! ```
//!
//! Octaves see only the optical depth toward the sun, so they light a thin edge as
//! much as the face of a thick core, where a path tracer shows the light of higher
//! orders coming back out of the cloud behind the point: the higher octaves of a pixel
//! are therefore scaled by `1 - exp(-k tau_view)`, `tau_view` the cloud's whole optical
//! depth on the pixel's ray (the share of diffuse light such a layer sends back, to
//! first order; atmo's addition). Against the path tracer (two cumulus clouds of
//! optical depth 8 to 17, sun from the front, the side and behind) this brought the
//! share of 8 x 8 blocks within 15 % from a quarter to three fifths, at the same mean.
//!
//! Octaves also carry the sun's light through a thick cloud with too much of the
//! droplets' forward lobe, where a path tracer's light has long lost it. So past the
//! first octaves, the orders a thick cloud sends are taken as a slab's diffuse light
//! (atmo's addition): the cloud along the sun's ray through the point is a slab of the
//! optical depth `T` the intensity buffer holds at its far end, the point at the depth
//! `tau_sun` of it, and the diffuse light there follows the two-stream (diffusion)
//! profile without absorption, linear in depth:
//!
//! ```text
//! L_diffuse = d (T - tau_sun + e) / (T + 2 e) (1 - exp(-T)) / (4 pi)
//! ```
//!
//! `e` the extrapolation length (optical depths past each face where the profile would
//! reach 0), `1 - exp(-T)` for a slab too thin to hold diffuse light, `d` its weight;
//! isotropic. A thick cloud then sends more back toward the sun than a thin one and
//! less through to its far side, which no power of `Gamma` can say. Over 36 views of
//! three clouds (docs/clouds.md) one octave beside the slab's light gives a worst view
//! of 1.24 times the path tracer and 56 % of the 8 x 8 blocks within 15 %, where three
//! octaves alone gave 2.1 and 44 % as first fitted (to thin clouds), 1.41 and 49 %
//! refitted to all 36.
//!
//! Why this method: it keeps the paper's structure whole (the intensity buffer holds
//! `ln Gamma = -tau_sun`, and every octave is a power of it, so the light pass costs
//! the same as single scattering), it runs per pixel on a CPU or a GPU at the cost of
//! a few `exp`s, and its numbers are fitted to a converged path tracer
//! ([`crate::reference::clouds::ReferenceCloud::path_traced`]) rather than guessed.
//! A diffusion of the buffer or a transfer table would add a pass over the whole grid
//! per sun direction. What octaves cannot do is carry light around a corner: a region
//! in a deep shadow lit only from the side stays a little dark (docs/clouds.md).

use super::render::OPAQUE;
use super::{exp_lanes, first, Lanes};

/// The octaves of the approximation: octave 0 is single scattering.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Octaves {
    /// Octaves summed (1: single scattering only), at most [`Octaves::MAX`].
    pub count: u32,
    /// `a`: the share of the sun's optical depth each further octave sees, in (0, 1].
    pub attenuation: f32,
    /// `b`: each further octave's light relative to the one before, in [0, 1).
    pub contribution: f32,
    /// `c`: how much of the phase function's shape each further octave keeps, in
    /// [0, 1].
    pub eccentricity: f32,
    /// `k`: the higher octaves of a pixel are scaled by `1 - exp(-k tau_view)`.
    pub depth_scale: f32,
    /// `d`: the weight of the slab's diffuse light (see the module doc), 0 for none.
    pub diffuse: f32,
    /// `e`: the slab's extrapolation length, optical depths, in [0.1, 100].
    pub extrapolation: f32,
}

impl Octaves {
    /// The most octaves a picture sums.
    pub const MAX: u32 = 8;

    /// Single scattering: the paper's model.
    pub const SINGLE: Octaves = Octaves {
        count: 1,
        attenuation: 1.0,
        contribution: 0.0,
        eccentricity: 1.0,
        depth_scale: 0.0,
        diffuse: 0.0,
        extrapolation: 5.0,
    };

    /// Every order, with the numbers fitted to the path tracer over 36 views: three
    /// cumulus clouds (200 and 2,000 particles of optical depth 8-17, and 9,382 of the
    /// generator's density 0.04, about 55 through its centre) each seen from above,
    /// level and below, the sun 25 deg high from the front, the side and behind and
    /// 60 deg high. A grid search over the seven; of the numbers whose worst view is
    /// within 8 % of the best worst view (1.24), the most views within 10 % in the mean
    /// and then the most 8 x 8 blocks within 15 % (`examples/fit_clouds.rs`,
    /// docs/clouds.md "Every order: octaves"); tests/clouds_light.rs holds them to it.
    pub const MULTIPLE: Octaves = Octaves {
        count: 2,
        attenuation: 0.25,
        contribution: 0.9,
        eccentricity: 0.4,
        depth_scale: 0.3,
        diffuse: 1.5,
        extrapolation: 2.5,
    };

    /// What the higher octaves of a pixel that the cloud lets `through` of what is
    /// behind are scaled by: `1 - exp(-k tau_view)`, `tau_view = -ln through` counted
    /// up to where the pixel is finished ([`OPAQUE`]: the billboards stop there).
    #[inline]
    pub fn higher_share(&self, through: f32) -> f32 {
        -(self.depth_scale * through.max(OPAQUE).ln()).exp_m1()
    }

    /// The sunlight one blob sends toward the eye per unit sun irradiance and unit
    /// albedo along a line through it:
    /// `sum_i b^i p_i integral exp(a^i ln Gamma(u)) e^-u du` over the blob's own
    /// optical depth `u` on the line, `0..tau` from the eye's side ([`Emission`]);
    /// `phase` is the phase function's value for the angle, 1/sr. Octave 0 (single
    /// scattering) and the sum of the higher ones with the slab's diffuse light (the
    /// module doc), apart (the pixel scales the latter, [`Octaves::higher_share`]), and
    /// the blob's transmittance `e^-tau`.
    ///
    /// Each octave's integral is exact for `ln Gamma` linear in `u` and capped at 0
    /// ([`Emission::log_ends`]): `tau (e^(a^i end - tau) - e^(a^i start)) / x`,
    /// `x = a^i (end - start) - tau`. Where `1 / a` is a whole number `k` (4 for the
    /// fitted `a`) the octaves are taken from the highest down, each one's
    /// `e^(a^i start)` the `k`-th power of the one above's: two `exp`s a blob instead
    /// of two an octave. Each power multiplies the `exp`'s relative error (within 3e-7:
    /// the drawing's own `exp`, vectorised) by `k`, so powers are taken only while
    /// `k^(octaves - 1) <= 64`; the light is then within 4e-5 of the closed form in
    /// double precision (three octaves, powers to the 16th: within 1e-5), far below a
    /// level of the picture. Computed as the drawing computes it, eight lanes at once.
    pub fn light(&self, phase: f32, e: &Emission) -> BlobLight {
        let light = self.terms().light(Lanes::splat(phase), &e.lanes());
        BlobLight {
            single: first(light.single),
            higher: first(light.higher),
            transmitted: first(light.transmitted),
        }
    }

    /// What [`Octaves::light`] needs of the octaves, worked out once for a picture
    /// rather than at each of its millions of blob-pixels.
    pub fn terms(&self) -> OctaveTerms {
        let count = self.count.clamp(1, Self::MAX) as usize;
        let mut terms = OctaveTerms {
            count,
            share: [1.0; Self::MAX as usize],
            weight: [1.0; Self::MAX as usize],
            shape: [1.0; Self::MAX as usize],
            whole: None,
            diffuse: self.diffuse,
            extrapolation: self.extrapolation,
        };
        for i in 1..count {
            terms.weight[i] = terms.weight[i - 1] * self.contribution;
            terms.shape[i] = terms.shape[i - 1] * self.eccentricity;
            terms.share[i] = terms.share[i - 1] * self.attenuation;
        }
        let ratio = 1.0 / self.attenuation;
        let exact = ratio.fract() == 0.0 && ratio.powi(count as i32 - 1) <= 64.0;
        terms.whole = exact.then_some(ratio as i32);
        terms
    }

    /// How much of the phase function's shape the octaves keep, weighted by their
    /// light: `sum b^i c^i / sum b^i` (1 for single scattering). The sky's light
    /// scattered by every order is tilted by this share of the droplets' phase
    /// ([`crate::clouds::SkyLight::scattered`]).
    pub fn phase_share(&self) -> f32 {
        let t = self.terms();
        let (kept, total) = (0..t.count).fold((0.0f32, 0.0f32), |(kept, total), i| {
            (kept + t.weight[i] * t.shape[i], total + t.weight[i])
        });
        kept / total
    }

    /// Refuses numbers outside their ranges, naming the field.
    pub fn validate(&self) -> crate::error::Result<()> {
        let fields = [
            ("octaves.count", self.count as f64, 1.0, Self::MAX as f64),
            ("octaves.attenuation", self.attenuation as f64, 1e-3, 1.0),
            ("octaves.contribution", self.contribution as f64, 0.0, 1.0),
            ("octaves.eccentricity", self.eccentricity as f64, 0.0, 1.0),
            ("octaves.depth_scale", self.depth_scale as f64, 0.0, 100.0),
            ("octaves.diffuse", self.diffuse as f64, 0.0, 10.0),
            (
                "octaves.extrapolation",
                self.extrapolation as f64,
                0.1,
                100.0,
            ),
        ];
        for (name, value, least, most) in fields {
            crate::error::check_range(name, value, least, most)?;
        }
        Ok(())
    }
}

/// What one blob's light toward the eye along a pixel's ray is made from: its column
/// `tau`, and at two depths `u` of it (its emission nodes,
/// [`crate::clouds::particles::emission_nodes`]) the sunlight, `ln Gamma`; and the
/// optical depth `slab` of the whole cloud along the sun's ray through it (read only
/// where [`Octaves::diffuse`] is not 0). `T` is `f32`, or eight lanes in the drawing.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Emission<T = f32> {
    pub tau: T,
    pub u: [T; 2],
    pub log_gamma: [T; 2],
    pub slab: T,
}

impl Emission {
    /// `ln Gamma` at the blob's near and far ends on the line (`u = 0` and `tau`): the
    /// line through the values at the two depths, capped at 0 (no more than the sun's
    /// whole light). With them the light is exact for a lone blob lit along the line
    /// of sight from either end ([`Octaves::light`]).
    pub fn log_ends(&self) -> [f32; 2] {
        self.lanes().log_ends().map(first)
    }

    /// The same in every lane.
    fn lanes(&self) -> Emission<Lanes> {
        Emission {
            tau: Lanes::splat(self.tau),
            u: self.u.map(Lanes::splat),
            log_gamma: self.log_gamma.map(Lanes::splat),
            slab: Lanes::splat(self.slab),
        }
    }
}

impl Emission<Lanes> {
    /// [`Emission::log_ends`] in lanes.
    #[inline(always)]
    fn log_ends(&self) -> [Lanes; 2] {
        let [u0, u1] = self.u;
        let [g0, g1] = self.log_gamma;
        let span = u1 - u0;
        let slope = span
            .simd_gt(Lanes::splat(1e-6) * self.tau)
            .select((g1 - g0) / span, Lanes::ZERO);
        let start = (g0 - slope * u0).fast_min(Lanes::ZERO);
        let end = (g0 + slope * (self.tau - u0)).fast_min(Lanes::ZERO);
        [start, end]
    }
}

/// What one blob sends toward the eye along a pixel's ray ([`Octaves::light`]); `T`
/// as in [`Emission`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BlobLight<T = f32> {
    /// Single scattering (octave 0), per unit sun irradiance and albedo, 1/sr.
    pub single: T,
    /// The higher octaves, summed.
    pub higher: T,
    /// What the blob lets through of what is behind it, `e^-tau`.
    pub transmitted: T,
}

/// The octaves' weights `b^i`, phase shares `c^i` and sun shares `a^i` (as
/// [`Octaves::light`] multiplies them up), and `1 / a` where it is a whole number
/// whose powers stand for the lower octaves' `exp`s.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OctaveTerms {
    count: usize,
    share: [f32; Octaves::MAX as usize],
    weight: [f32; Octaves::MAX as usize],
    shape: [f32; Octaves::MAX as usize],
    whole: Option<i32>,
    diffuse: f32,
    extrapolation: f32,
}

impl OctaveTerms {
    /// Whether the light needs [`Emission::slab`].
    #[inline]
    pub fn needs_slab(&self) -> bool {
        self.diffuse > 0.0
    }

    /// [`Octaves::light`] of the octaves these terms are of, for eight blob-pixels.
    #[inline(always)]
    pub(crate) fn light(&self, phase: Lanes, e: &Emission<Lanes>) -> BlobLight<Lanes> {
        let splat = Lanes::splat;
        let isotropic = splat(1.0 / (4.0 * std::f32::consts::PI));
        let transmitted = exp_lanes(-e.tau);
        let [start, end] = e.log_ends();
        let mut light = BlobLight {
            single: Lanes::ZERO,
            higher: Lanes::ZERO,
            transmitted,
        };
        let (mut near, mut far) = (Lanes::ZERO, Lanes::ZERO);
        for i in (0..self.count).rev() {
            let share = splat(self.share[i]);
            (near, far) = match self.whole {
                Some(k) if i + 1 < self.count => (powi(near, k), powi(far, k)),
                _ => (exp_lanes(share * start), exp_lanes(share * end)),
            };
            // (e^x - 1) / x times e^(a^i start); near 0 by its series (within 5e-8 for
            // |x| < 1/4), where the difference of the two ends' light would lose the
            // digits that the powers' error leaves.
            let x = share * (end - start) - e.tau;
            let series = splat(1.0 / 120.0) + x * splat(1.0 / 720.0);
            let series = splat(1.0 / 6.0) + x * (splat(1.0 / 24.0) + x * series);
            let series = near * (Lanes::ONE + x * (splat(0.5) + x * series));
            let integral = e.tau
                * x.abs()
                    .simd_lt(splat(0.25))
                    .select(series, (far * transmitted - near) / x);
            if i == 0 {
                light.single = phase * integral;
            } else {
                let shape = splat(self.shape[i]);
                light.higher += splat(self.weight[i])
                    * (shape * phase + (Lanes::ONE - shape) * isotropic)
                    * integral;
            }
        }
        if self.needs_slab() {
            // The slab's profile at the two emission nodes, whose mean times the blob's
            // absorbed fraction is the two-point Gauss-Legendre rule of its integral
            // over the blob's depth (the nodes are that rule's in the absorbed fraction).
            let (t, length) = (e.slab, splat(self.extrapolation));
            let profile = |log_gamma: Lanes| {
                ((t + log_gamma + length) / (t + splat(2.0) * length)).fast_max(Lanes::ZERO)
            };
            let mean = splat(0.5) * (profile(e.log_gamma[0]) + profile(e.log_gamma[1]));
            light.higher += splat(self.diffuse)
                * mean
                * (Lanes::ONE - exp_lanes(-t))
                * (Lanes::ONE - transmitted)
                * isotropic;
        }
        light
    }
}

/// `x^k` for `k >= 0` by repeated squaring, the steps of `f32::powi` (compiler-builtins'
/// `__powisf2`, to the bit) without a call a blob-pixel; in lanes or not.
#[inline(always)]
fn powi<T: Copy + std::ops::Mul<Output = T> + From<f32>>(mut x: T, mut k: i32) -> T {
    let mut product = T::from(1.0);
    loop {
        if k & 1 != 0 {
            product = product * x;
        }
        k >>= 1;
        if k == 0 {
            return product;
        }
        x = x * x;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The closed form in double precision, every octave by its own `exp`s: what the
    /// powers of [`Octaves::light`] stand for (the octaves alone).
    fn light_f64(octaves: &Octaves, phase: f64, e: &Emission) -> [f64; 2] {
        let [start, end] = e.log_ends().map(f64::from);
        let tau = e.tau as f64;
        let (mut weight, mut shape, mut share) = (1.0f64, 1.0f64, 1.0f64);
        let mut out = [0.0; 2];
        for i in 0..octaves.count {
            let p = shape * phase + (1.0 - shape) / (4.0 * std::f64::consts::PI);
            let x = share * (end - start) - tau;
            let integral = tau * (share * start).exp() * (x.exp_m1() / x);
            out[(i > 0) as usize] += weight * p * integral;
            weight *= octaves.contribution as f64;
            shape *= octaves.eccentricity as f64;
            share *= octaves.attenuation as f64;
        }
        out
    }

    /// The octaves' own powers are `f32::powi`'s to the bit (the pictures stay the same).
    #[test]
    fn powers_by_squaring_are_powi_to_the_bit() {
        for k in 0..=64 {
            for j in 0..500u32 {
                let x = f32::from_bits(0x3000_0000 + j * 0x0011_7a3b);
                assert_eq!(powi(x, k).to_bits(), x.powi(k).to_bits(), "{x}^{k}");
            }
        }
    }

    /// The powers that replace `exp`s where `1 / a` is whole, against the closed form
    /// in double precision over blobs thin to thick and light from full to deep shade:
    /// within 1e-5 of the light for the fitted octaves (powers to the 16th), 4e-5 for
    /// four (to the 64th).
    #[test]
    fn octaves_by_powers_keep_the_closed_form() {
        let three = Octaves {
            count: 3,
            diffuse: 0.0,
            ..Octaves::MULTIPLE
        };
        let four = Octaves { count: 4, ..three };
        for (octaves, within) in [(three, 1e-5), (four, 4e-5)] {
            for k in 0..2000u32 {
                // A fixed scatter of inputs (a Weyl sequence in three dimensions).
                let f = |a: f64| (k as f64 * a).fract() as f32;
                let tau = 1e-3 * (4.0e4f32).powf(f(0.618_034));
                let log_gamma = [-60.0 * f(0.754_878) * f(0.569_840), -60.0 * f(0.569_840)];
                let e = Emission {
                    tau,
                    u: [0.2 * tau, 0.85 * tau],
                    log_gamma,
                    slab: 0.0,
                };
                let got = octaves.light(0.3, &e);
                let want = light_f64(&octaves, 0.3, &e);
                for (g, w) in [got.single, got.higher].into_iter().zip(want) {
                    assert!(
                        (g as f64 - w).abs() <= within * w + 1e-30,
                        "{octaves:?} {e:?}: {g} vs {w}"
                    );
                }
            }
        }
    }

    /// Against a fine midpoint sum of the same integral, for `ln Gamma` linear in the
    /// depth (the sun behind, in front, across), thin and thick blobs, both kinds (the
    /// octaves alone: the slab's light has its own test).
    #[test]
    fn the_blob_integral_is_exact_for_linear_light() {
        let phase = 0.3;
        let octaves_alone = Octaves {
            diffuse: 0.0,
            ..Octaves::MULTIPLE
        };
        for octaves in [Octaves::SINGLE, octaves_alone] {
            for tau in [1e-3f32, 0.5, 4.0, 15.0] {
                for slope in [-1.0f32, -0.4, 0.0, 0.7, 1.0] {
                    // ln Gamma(u) = slope (u - tau), 0 at the far end for slope > 0,
                    // else -slope u below 0 from the near end.
                    let ln_gamma = |u: f32| {
                        if slope > 0.0 {
                            slope * (u - tau)
                        } else {
                            slope * u
                        }
                    };
                    let u = [0.2 * tau, 0.9 * tau];
                    let e = Emission {
                        tau,
                        u,
                        log_gamma: u.map(ln_gamma),
                        slab: 0.0,
                    };
                    let light = octaves.light(phase, &e);
                    let got = light.single + light.higher;
                    let exact = (-tau as f64).exp();
                    assert!((light.transmitted as f64 - exact).abs() < 3e-7 * exact);
                    let steps = 20_000;
                    let h = tau as f64 / steps as f64;
                    let mut want = 0.0f64;
                    let (mut weight, mut shape, mut share) = (1.0f64, 1.0f64, 1.0f64);
                    for _ in 0..octaves.count {
                        let p = shape * phase as f64 + (1.0 - shape) / (4.0 * std::f64::consts::PI);
                        let integral: f64 = (0..steps)
                            .map(|k| {
                                let u = (k as f64 + 0.5) * h;
                                (share * ln_gamma(u as f32) as f64 - u).exp() * h
                            })
                            .sum();
                        want += weight * p * integral;
                        weight *= octaves.contribution as f64;
                        shape *= octaves.eccentricity as f64;
                        share *= octaves.attenuation as f64;
                    }
                    assert!(
                        (got as f64 - want).abs() < 1e-4 * want,
                        "{octaves:?} tau {tau} slope {slope}: {got} vs {want}"
                    );
                }
            }
        }
    }

    /// The slab's diffuse light: at the emission nodes of real blobs (the table the
    /// renderer reads) against a fine midpoint sum of `d profile(u) e^-u / 4 pi` over
    /// the blob's depth, the profile linear in the sun's optical depth and that linear
    /// in `u`, within 2 %; more light at the sun's face of a thick slab than of a thin
    /// one, less at its far face; none without the weight.
    #[test]
    fn the_slab_light_integrates_its_profile() {
        use crate::clouds::particles::tabulated_emission_nodes;
        let octaves = Octaves::MULTIPLE;
        let slab_alone = |e: &Emission| {
            let none = Octaves {
                diffuse: 0.0,
                ..octaves
            };
            octaves.light(0.3, e).higher - none.light(0.3, e).higher
        };
        let (d, length) = (octaves.diffuse as f64, octaves.extrapolation as f64);
        for tau in [0.05f32, 0.5, 2.0, 8.0] {
            for (slab, depth, slope) in [
                (3.0f32, 0.5f32, 0.4f32),
                (40.0, 1.0, 1.0),
                (40.0, 30.0, -0.5),
            ] {
                let [(u0, _), (u1, _)] = tabulated_emission_nodes(tau);
                let ln_gamma = |u: f32| -(depth + slope * u).max(0.0);
                let e = Emission {
                    tau,
                    u: [u0, u1],
                    log_gamma: [ln_gamma(u0), ln_gamma(u1)],
                    slab,
                };
                let (t, steps) = (slab as f64, 20_000);
                let h = tau as f64 / steps as f64;
                let want: f64 = (0..steps)
                    .map(|k| {
                        let u = (k as f64 + 0.5) * h;
                        let profile = ((t + ln_gamma(u as f32) as f64 + length)
                            / (t + 2.0 * length))
                            .max(0.0);
                        profile * (-u).exp() * h
                    })
                    .sum::<f64>()
                    * d
                    * -(-t).exp_m1()
                    / (4.0 * std::f64::consts::PI);
                let got = slab_alone(&e) as f64;
                assert!(
                    (got - want).abs() < 0.02 * want,
                    "tau {tau} slab {slab}: {got} vs {want}"
                );
            }
        }
        let face = |slab: f32, depth: f32| {
            let e = Emission {
                tau: 1.0,
                u: [0.2, 0.8],
                log_gamma: [-depth, -depth],
                slab,
            };
            slab_alone(&e)
        };
        assert!(face(40.0, 0.5) > face(8.0, 0.5));
        assert!(face(40.0, 39.5) < face(8.0, 7.5));
        let e = Emission {
            tau: 1.0,
            u: [0.2, 0.8],
            log_gamma: [-1.0, -1.0],
            slab: 20.0,
        };
        assert_eq!(Octaves::SINGLE.light(0.3, &e).higher, 0.0);
    }
}
