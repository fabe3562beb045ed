//! Directions for the path tracers: scattering angles drawn from a phase function, and
//! cosine-weighted bounces off a Lambertian ground.

use glam::DVec3;

use crate::atmosphere::PhaseFunction;
use crate::clouds::generator::SplitMix64;

/// Draws scattering directions from one phase function: Rayleigh's exactly (inverting
/// its cumulative distribution in closed form), Henyey-Greenstein and the two-lobe
/// cloud phase exactly (a lobe chosen by its weight), the others by Henyey-Greenstein
/// proposals of the same asymmetry accepted in proportion to the phase's ratio to them.
#[derive(Debug, Clone, Copy)]
pub struct PhaseSampler {
    phase: PhaseFunction,
    /// Rejection sampling's largest ratio of the phase to its proposal (found on a fine
    /// grid, plus 1 %).
    bound: f64,
}

impl PhaseSampler {
    pub fn new(phase: PhaseFunction) -> PhaseSampler {
        let hg = proposal(&phase);
        let bound = (0..=2000)
            .map(|k| {
                let x = -1.0 + k as f64 / 1000.0;
                phase.eval(x) / hg.eval(x)
            })
            .fold(0.0, f64::max)
            * 1.01;
        PhaseSampler { phase, bound }
    }

    /// A direction scattered from the direction of travel `w`.
    pub fn sample(&self, w: DVec3, rng: &mut SplitMix64) -> DVec3 {
        let cos = match self.phase {
            PhaseFunction::Rayleigh => {
                // CDF of 3/8 (1 + x^2) over [-1, 1]: (x^3 + 3x + 4) / 8 = u.
                let q = 4.0 * rng.unit_f64() - 2.0;
                let root = (q * q + 1.0).sqrt();
                (q + root).cbrt() + (q - root).cbrt()
            }
            PhaseFunction::HenyeyGreenstein { g } => sample_henyey_greenstein(g, rng.unit_f64()),
            PhaseFunction::CloudMie => {
                // Its lobes and weights (PhaseFunction::CloudMie's definition).
                let g = if rng.unit_f64() < 0.75 { 0.8 } else { -0.3 };
                sample_henyey_greenstein(g, rng.unit_f64())
            }
            _ => {
                let hg = proposal(&self.phase);
                let PhaseFunction::HenyeyGreenstein { g } = hg else {
                    unreachable!("proposal is Henyey-Greenstein")
                };
                loop {
                    let x = sample_henyey_greenstein(g, rng.unit_f64());
                    if rng.unit_f64() * self.bound * hg.eval(x) <= self.phase.eval(x) {
                        break x;
                    }
                }
            }
        };
        around(w, cos.clamp(-1.0, 1.0), rng)
    }
}

/// The Henyey-Greenstein of the same asymmetry that proposes directions for `phase`
/// (isotropic for phases without one).
fn proposal(phase: &PhaseFunction) -> PhaseFunction {
    let g = match phase {
        PhaseFunction::HenyeyGreenstein { g } | PhaseFunction::CornetteShanks { g } => *g,
        _ => 0.0,
    };
    PhaseFunction::HenyeyGreenstein { g }
}

/// The cosine of a Henyey-Greenstein scattering angle for the uniform number `u`.
fn sample_henyey_greenstein(g: f64, u: f64) -> f64 {
    if g.abs() < 1e-6 {
        return 2.0 * u - 1.0;
    }
    let s = (1.0 - g * g) / (1.0 - g + 2.0 * g * u);
    (1.0 + g * g - s * s) / (2.0 * g)
}

/// A unit vector at cosine `cos` from `w`, uniform in azimuth around it.
fn around(w: DVec3, cos: f64, rng: &mut SplitMix64) -> DVec3 {
    let sin = (1.0 - cos * cos).max(0.0).sqrt();
    let phi = 2.0 * std::f64::consts::PI * rng.unit_f64();
    let (u, v) = w.any_orthonormal_pair();
    (w * cos + (u * phi.cos() + v * phi.sin()) * sin).normalize()
}

/// The mean of `samples` (a path tracer's estimates) and its standard error.
pub fn mean_and_error(samples: impl Iterator<Item = f64>) -> (f64, f64) {
    let (mut n, mut sum, mut squares) = (0usize, 0.0, 0.0);
    for v in samples {
        n += 1;
        sum += v;
        squares += v * v;
    }
    let n = n.max(1) as f64;
    let mean = sum / n;
    (mean, ((squares / n - mean * mean).max(0.0) / n).sqrt())
}

/// A cosine-distributed direction over the hemisphere about `normal`.
pub fn sample_cosine(normal: DVec3, rng: &mut SplitMix64) -> DVec3 {
    around(normal, rng.unit_f64().sqrt(), rng)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The sampled cosines' histogram follows each phase function (10 bins, 400,000
    /// draws: within 5 standard errors of the bin's probability, 3 % or less of it for
    /// the bins that hold over 2 % of the draws).
    #[test]
    fn sampled_angles_follow_the_phase_function() {
        for phase in [
            PhaseFunction::Rayleigh,
            PhaseFunction::CloudMie,
            PhaseFunction::HenyeyGreenstein { g: 0.6 },
            PhaseFunction::CornetteShanks { g: 0.7 },
        ] {
            let sampler = PhaseSampler::new(phase);
            let mut rng = SplitMix64::new(7);
            let w = DVec3::new(0.0, 0.6, 0.8);
            let mut bins = [0usize; 10];
            let draws = 400_000;
            for _ in 0..draws {
                let x = sampler.sample(w, &mut rng).dot(w);
                bins[(((x + 1.0) * 5.0) as usize).min(9)] += 1;
            }
            for (k, &count) in bins.iter().enumerate() {
                // The bin's probability: 2 pi times the phase integrated over its cosines.
                let (a, b) = (-1.0 + 0.2 * k as f64, -0.8 + 0.2 * k as f64);
                let want: f64 = (0..1000)
                    .map(|j| phase.eval(a + (j as f64 + 0.5) * (b - a) / 1000.0))
                    .sum::<f64>()
                    * (b - a)
                    / 1000.0
                    * 2.0
                    * std::f64::consts::PI;
                let got = count as f64 / draws as f64;
                let error = (want * (1.0 - want) / draws as f64).sqrt();
                assert!(
                    (got - want).abs() < 5.0 * error,
                    "{phase:?} bin {k}: {got} vs {want}"
                );
            }
        }
    }
}
