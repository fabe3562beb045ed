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

use super::particles::{weighted_lanes, EMISSION_NODES};
use super::render::OPAQUE;
use crate::lanes::{exp_lanes, first, Lanes};

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
    /// and then the most 8 x 8 blocks within 15 % (`tools/fit-clouds`,
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
    /// optical depth `u` on the line, `0..tau` from the eye's side ([`Emission`]), each
    /// node's light dimmed by the depth its neighbours put in front of it
    /// ([`Emission::beside`]); `phase` is the phase function's value for the angle,
    /// 1/sr. Octave 0 (single scattering) and the sum of the higher ones with the
    /// slab's diffuse light (the module doc), apart (the pixel scales the latter,
    /// [`Octaves::higher_share`]), and the blob's transmittance `e^-tau`.
    ///
    /// Each octave's integral is the Gauss-Legendre rule in the absorbed fraction
    /// `v = 1 - e^-u` ([`crate::clouds::particles::emission_nodes`]):
    /// `(1 - e^-tau) sum_j w_j e^(a^i ln Gamma_j - beside_j)`, exact where `Gamma` is a
    /// polynomial of degree 5 or less in `v` (a blob lit from the eye's side alone is
    /// linear). Where `1 / a` is a whole number `k` (4 for the fitted `a`) the octaves
    /// are taken from the highest down, each one's `e^(a^i ln Gamma_j)` the `k`-th
    /// power of the one above's: three `exp`s a blob instead of three an octave. Each
    /// power multiplies the `exp`'s relative error (within 3e-7: the drawing's own
    /// `exp`, vectorised) by `k`, so powers are taken only while `k^(octaves - 1) <=
    /// 64`; the light is then within 4e-5 of the rule in double precision (three
    /// octaves, powers to the 16th: within 1e-5), far below a level of the picture.
    /// Computed as the drawing computes it, eight lanes at once.
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
/// `tau`, and at its emission nodes
/// ([`crate::clouds::particles::emission_nodes`]) the sunlight, `ln Gamma`, and
/// `beside`; and the optical depth `slab` of the whole cloud along the sun's ray
/// through it (read only where [`Octaves::diffuse`] is not 0). `T` is `f32`, or eight
/// lanes in the drawing.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Emission<T = f32> {
    pub tau: T,
    pub log_gamma: [T; EMISSION_NODES],
    /// The optical depth toward the eye in front of each node beyond the blobs drawn
    /// before this one (negative where they reach behind it; 0 for a lone blob):
    /// see [the drawing](mod@crate::clouds::render), "the blobs beside".
    pub beside: [T; EMISSION_NODES],
    pub slab: T,
}

impl Emission {
    /// The same in every lane.
    fn lanes(&self) -> Emission<Lanes> {
        Emission {
            tau: Lanes::splat(self.tau),
            log_gamma: self.log_gamma.map(Lanes::splat),
            beside: self.beside.map(Lanes::splat),
            slab: Lanes::splat(self.slab),
        }
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
        // 1 - e^-tau; for a thin blob by its series (within 5e-8 below a column of
        // 1/4), where the difference would keep few of its digits.
        let tau = e.tau;
        let series = [6.0, 5.0, 4.0, 3.0, 2.0]
            .into_iter()
            .fold(Lanes::ONE, |inner, k| {
                Lanes::ONE - tau * splat(1.0 / k) * inner
            });
        let series = tau * series;
        let absorbed = tau
            .simd_lt(splat(0.25))
            .select(series, Lanes::ONE - transmitted);
        let mut light = BlobLight {
            single: Lanes::ZERO,
            higher: Lanes::ZERO,
            transmitted,
        };
        // Single scattering alone takes each node's dimming in the same `exp` as its
        // sunlight; otherwise the dimming is a factor of its own, common to the octaves.
        let fused = self.count == 1 && !self.needs_slab();
        let dimmed = if fused {
            [Lanes::ONE; EMISSION_NODES]
        } else {
            e.beside.map(|b| exp_lanes(-b))
        };
        let mut sunlit = [Lanes::ZERO; EMISSION_NODES];
        for i in (0..self.count).rev() {
            let share = splat(self.share[i]);
            for (j, g) in sunlit.iter_mut().enumerate() {
                *g = match self.whole {
                    Some(k) if i + 1 < self.count => powi(*g, k),
                    _ if fused => exp_lanes(e.log_gamma[j] - e.beside[j]),
                    _ => exp_lanes(share * e.log_gamma[j]),
                };
            }
            let integral = absorbed * weighted_lanes(|j| sunlit[j] * dimmed[j]);
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
            // The slab's profile at the emission nodes, each dimmed as its sunlight is,
            // by the Gauss-Legendre rule of its integral over the blob's depth in the
            // absorbed fraction.
            let (t, length) = (e.slab, splat(self.extrapolation));
            let profile = |log_gamma: Lanes| {
                ((t + log_gamma + length) / (t + splat(2.0) * length)).fast_max(Lanes::ZERO)
            };
            let mean = weighted_lanes(|j| profile(e.log_gamma[j]) * dimmed[j]);
            light.higher +=
                splat(self.diffuse) * mean * (Lanes::ONE - exp_lanes(-t)) * absorbed * isotropic;
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
    use crate::clouds::particles::EMISSION_WEIGHTS;

    /// The rule in double precision, every octave by its own `exp`s: what the powers
    /// of [`Octaves::light`] stand for (the octaves alone).
    fn light_f64(octaves: &Octaves, phase: f64, e: &Emission) -> [f64; 2] {
        let absorbed = -(-e.tau as f64).exp_m1();
        let (mut weight, mut shape, mut share) = (1.0f64, 1.0f64, 1.0f64);
        let mut out = [0.0; 2];
        for i in 0..octaves.count {
            let p = shape * phase + (1.0 - shape) / (4.0 * std::f64::consts::PI);
            let integral: f64 = (0..EMISSION_NODES)
                .map(|j| {
                    let exponent = share * e.log_gamma[j] as f64 - e.beside[j] as f64;
                    EMISSION_WEIGHTS[j] as f64 * exponent.exp()
                })
                .sum();
            out[(i > 0) as usize] += weight * p * absorbed * integral;
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

    /// The powers that replace `exp`s where `1 / a` is whole, against the rule in
    /// double precision over blobs thin to thick, light from full to deep shade and
    /// neighbours in front and behind: within 1e-5 of the light for the fitted octaves
    /// (powers to the 16th), 4e-5 for four (to the 64th); single scattering, each
    /// node's light and dimming in one `exp`, within 1e-6.
    #[test]
    fn octaves_by_powers_keep_the_rule() {
        let three = Octaves {
            count: 3,
            diffuse: 0.0,
            ..Octaves::MULTIPLE
        };
        let four = Octaves { count: 4, ..three };
        for (octaves, within) in [(three, 1e-5), (four, 4e-5), (Octaves::SINGLE, 2e-6)] {
            for k in 0..2000u32 {
                // A fixed scatter of inputs (a Weyl sequence in three dimensions).
                let f = |a: f64| (k as f64 * a).fract() as f32;
                let tau = 1e-3 * (4.0e4f32).powf(f(0.618_034));
                let deepest = -60.0 * f(0.569_840);
                let e = Emission {
                    tau,
                    log_gamma: [0.2, 0.5, 1.0].map(|x| x * deepest * f(0.754_878).powf(1.0 - x)),
                    beside: [-0.8, 0.1, 1.5].map(|x| x * f(0.362_109)),
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
    /// depth (the sun in front of the eye, across, behind), thin and thick blobs, both
    /// kinds (the octaves alone: the slab's light has its own test). The rule is exact
    /// (1e-5) where `Gamma` is a low polynomial in the absorbed fraction: a blob lit
    /// alone from the eye's side (slope -1, single scattering), or evenly; within 1e-5
    /// for blobs of column up to 0.5 and 0.6 % for those lit from the eye's side; it
    /// falls short for a
    /// thick blob lit from behind alone (18 % at a column of 4 by the rule's own
    /// numbers, 76 % at 15, where the blob sends `tau e^-tau` of the light a thin one
    /// would: its nodes sit in the front half of its depth). A constant `beside` scales
    /// the light by `e^-beside` (within 1e-6).
    #[test]
    fn the_blob_integral_follows_a_fine_sum() {
        let phase = 0.3;
        let octaves_alone = Octaves {
            diffuse: 0.0,
            ..Octaves::MULTIPLE
        };
        for octaves in [Octaves::SINGLE, octaves_alone] {
            for tau in [1e-3f32, 0.5, 4.0, 15.0] {
                for slope in [-1.0f32, -0.4, 0.0, 0.7, 1.0] {
                    // ln Gamma(u) = slope (u - tau), 0 at the far end for slope > 0,
                    // else slope u below 0 from the near end.
                    let ln_gamma = |u: f32| {
                        if slope > 0.0 {
                            slope * (u - tau)
                        } else {
                            slope * u
                        }
                    };
                    let nodes = crate::clouds::particles::emission_nodes(tau);
                    let e = Emission {
                        tau,
                        log_gamma: nodes.map(|(u, _)| ln_gamma(u)),
                        beside: [0.0; EMISSION_NODES],
                        slab: 0.0,
                    };
                    let light = octaves.light(phase, &e);
                    let got = light.single + light.higher;
                    let exact = (-tau as f64).exp();
                    assert!((light.transmitted as f64 - exact).abs() < 3e-7 * exact);
                    let dimmed = octaves.light(
                        phase,
                        &Emission {
                            beside: [0.7; 3],
                            ..e
                        },
                    );
                    let ratio = (dimmed.single + dimmed.higher) / got;
                    assert!((ratio as f64 - (-0.7f64).exp()).abs() < 1e-6, "{ratio}");
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
                    let error = got as f64 / want - 1.0;
                    let within = match (slope, tau) {
                        (s, _) if s == 0.0 || (s == -1.0 && octaves.count == 1) => 1e-5,
                        (_, t) if t <= 0.5 => 1e-5,
                        (s, _) if s < 0.0 => 6e-3,
                        (_, t) if t <= 4.0 => 0.19,
                        _ => 0.77,
                    };
                    assert!(
                        error.abs() < within,
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
                let ln_gamma = |u: f32| -(depth + slope * u).max(0.0);
                let e = Emission {
                    tau,
                    log_gamma: tabulated_emission_nodes(tau).map(|(u, _)| ln_gamma(u)),
                    beside: [0.0; EMISSION_NODES],
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
                log_gamma: [-depth; EMISSION_NODES],
                beside: [0.0; EMISSION_NODES],
                slab,
            };
            slab_alone(&e)
        };
        assert!(face(40.0, 0.5) > face(8.0, 0.5));
        assert!(face(40.0, 39.5) < face(8.0, 7.5));
        let e = Emission {
            tau: 1.0,
            log_gamma: [-1.0; EMISSION_NODES],
            beside: [0.0; EMISSION_NODES],
            slab: 20.0,
        };
        assert_eq!(Octaves::SINGLE.light(0.3, &e).higher, 0.0);
    }
}
