//! Quadrature rules shared by the fast methods and the references.

use glam::DVec3;

/// Gauss-Legendre nodes and weights on [-1, 1] for 4 points: exact for polynomials
/// of degree 7, enough for the smooth, exponential integrands of optical depth.
const GL4: [(f64, f64); 4] = [
    (-0.861_136_311_594_052_6, 0.347_854_845_137_453_9),
    (-0.339_981_043_584_856_3, 0.652_145_154_862_546_1),
    (0.339_981_043_584_856_3, 0.652_145_154_862_546_1),
    (0.861_136_311_594_052_6, 0.347_854_845_137_453_9),
];

/// Integrates `f` over `[a, b]` with `segments` equal pieces of 4-point Gauss-Legendre.
/// `f` is called once per node with (position, weight); it accumulates as it likes.
pub fn gauss_legendre(a: f64, b: f64, segments: usize, mut f: impl FnMut(f64, f64)) {
    let h = (b - a) / segments as f64;
    for s in 0..segments {
        let mid = a + (s as f64 + 0.5) * h;
        for &(x, w) in &GL4 {
            f(mid + 0.5 * h * x, 0.5 * h * w);
        }
    }
}

/// The Legendre polynomials `P_0(x)` to `P_last(x)`, by Bonnet's recurrence.
pub fn legendre(x: f64, last: usize) -> Vec<f64> {
    let mut p = vec![1.0, x];
    for l in 2..=last {
        p.push(((2 * l - 1) as f64 * x * p[l - 1] - (l - 1) as f64 * p[l - 2]) / l as f64);
    }
    p.truncate(last + 1);
    p
}

/// `n` directions spread evenly over the unit sphere (a spherical Fibonacci lattice),
/// each standing for the solid angle `4 pi / n` sr. The rule converges as `n` grows,
/// which a fixed hand-picked set of directions does not.
pub fn fibonacci_sphere(n: usize) -> Vec<DVec3> {
    let golden_angle = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    (0..n)
        .map(|i| {
            let z = 1.0 - (2.0 * i as f64 + 1.0) / n as f64;
            let rho = (1.0 - z * z).max(0.0).sqrt();
            let phi = golden_angle * i as f64;
            DVec3::new(rho * phi.cos(), rho * phi.sin(), z)
        })
        .collect()
}

/// Gauss-Legendre nodes and weights of order `n` on [0, 1], by Newton's iteration on
/// the Legendre polynomial (converged to machine precision; the weights sum to 1).
pub fn gauss_legendre_unit(n: usize) -> Vec<(f64, f64)> {
    let mut rule = Vec::with_capacity(n);
    for i in 0..n {
        // Tricomi's initial guess, then Newton on P_n.
        let mut x = (std::f64::consts::PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
        let mut dp = 1.0;
        for _ in 0..100 {
            let (mut p0, mut p1) = (1.0, x);
            for k in 2..=n {
                let p2 = ((2 * k - 1) as f64 * x * p1 - (k - 1) as f64 * p0) / k as f64;
                p0 = p1;
                p1 = p2;
            }
            let p = if n == 0 { 1.0 } else { p1 };
            let p_prev = if n == 1 { 1.0 } else { p0 };
            dp = n as f64 * (x * p - p_prev) / (x * x - 1.0);
            let step = p / dp;
            x -= step;
            if step.abs() < 1e-15 {
                break;
            }
        }
        let w = 2.0 / ((1.0 - x * x) * dp * dp);
        rule.push((0.5 * (1.0 - x), 0.5 * w));
    }
    rule
}

/// A quadrature of the sphere for fields symmetric about the xz plane (the sun's
/// vertical plane): directions with y >= 0, each standing for itself and its mirror
/// image, with weights in sr that sum to 4 pi.
///
/// It is the double-Gauss rule of atmospheric radiative transfer (Sykes 1951),
/// split at the horizon of the point rather than at the horizontal: Gauss-Legendre in
/// the zenith cosine above and below the horizon separately, so the nodes crowd toward
/// it, where the light of a planet's atmosphere is concentrated and changes fastest,
/// times the midpoint rule in azimuth. It converges as the counts grow; a Fibonacci
/// set of the same size is several times less accurate here.
#[derive(Debug, Clone)]
pub struct SymmetricSphereRule {
    /// Unit directions, y >= 0.
    pub directions: Vec<DVec3>,
    /// Solid angle each direction stands for, with its mirror image, sr.
    pub weights: Vec<f64>,
}

impl SymmetricSphereRule {
    /// The rule with `per_side` zenith nodes above and below the zenith cosine
    /// `mu_split` (the horizon) and `azimuths` nodes over [0, pi]:
    /// `2 * per_side * azimuths` directions.
    pub fn double_gauss(mu_split: f64, per_side: usize, azimuths: usize) -> Self {
        let mu_rule = gauss_legendre_unit(per_side);
        let mut rule = SymmetricSphereRule {
            directions: Vec::new(),
            weights: Vec::new(),
        };
        for (low, high) in [(mu_split, 1.0), (-1.0, mu_split)] {
            for &(x, w_x) in &mu_rule {
                let (mu, w_mu) = (low + (high - low) * x, (high - low) * w_x);
                let sin = (1.0 - mu * mu).max(0.0).sqrt();
                for k in 0..azimuths {
                    let phi = std::f64::consts::PI * (k as f64 + 0.5) / azimuths as f64;
                    rule.directions
                        .push(DVec3::new(sin * phi.cos(), sin * phi.sin(), mu));
                    rule.weights
                        .push(2.0 * w_mu * std::f64::consts::PI / azimuths as f64);
                }
            }
        }
        rule
    }

    /// The double-Gauss layout closest to `count` directions (about as many zenith
    /// nodes on each side as azimuth nodes), split at `mu_split`.
    pub fn with_about(count: usize, mu_split: f64) -> Self {
        let azimuths = ((count as f64 / 2.0).sqrt().round() as usize).max(1);
        let per_side = ((count as f64 / (2.0 * azimuths as f64)).round() as usize).max(1);
        Self::double_gauss(mu_split, per_side, azimuths)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gauss_legendre_integrates_exponential() {
        let mut sum = 0.0;
        gauss_legendre(0.0, 3.0, 4, |x, w| sum += w * (-x).exp());
        let exact = 1.0 - (-3.0f64).exp();
        assert!((sum - exact).abs() < 1e-9, "{sum} vs {exact}");
    }

    #[test]
    fn gauss_legendre_unit_is_exact_for_polynomials() {
        for n in [1, 2, 3, 4, 7, 12] {
            let rule = gauss_legendre_unit(n);
            for degree in 0..2 * n {
                let sum: f64 = rule.iter().map(|(x, w)| w * x.powi(degree as i32)).sum();
                let exact = 1.0 / (degree + 1) as f64;
                assert!((sum - exact).abs() < 1e-12, "n {n} degree {degree}: {sum}");
            }
        }
    }

    #[test]
    fn double_gauss_integrates_the_sphere() {
        let rule = SymmetricSphereRule::with_about(18, -0.06);
        assert_eq!(rule.directions.len(), 18);
        let four_pi = 4.0 * std::f64::consts::PI;
        let total: f64 = rule.weights.iter().sum();
        assert!((total - four_pi).abs() < 1e-12);
        // Integral of z^2 and x^2 over the sphere: 4 pi / 3 each (x^2 needs azimuths).
        let zz: f64 = rule
            .directions
            .iter()
            .zip(&rule.weights)
            .map(|(d, w)| w * d.z * d.z)
            .sum();
        let xx: f64 = rule
            .directions
            .iter()
            .zip(&rule.weights)
            .map(|(d, w)| w * d.x * d.x)
            .sum();
        assert!((zz - four_pi / 3.0).abs() < 1e-12, "{zz}");
        assert!((xx - four_pi / 3.0).abs() < 1e-12, "{xx}");
        assert!(rule
            .directions
            .iter()
            .all(|d| d.y >= 0.0 && (d.length() - 1.0).abs() < 1e-12));
    }

    #[test]
    fn fibonacci_sphere_is_unit_and_balanced() {
        let dirs = fibonacci_sphere(501);
        let mean: DVec3 = dirs.iter().copied().sum::<DVec3>() / dirs.len() as f64;
        assert!(dirs.iter().all(|d| (d.length() - 1.0).abs() < 1e-12));
        assert!(mean.length() < 1e-2, "mean {mean}");
        // Integral of z^2 over the sphere is 4 pi / 3.
        let zz: f64 =
            dirs.iter().map(|d| d.z * d.z).sum::<f64>() * 4.0 * std::f64::consts::PI / 501.0;
        assert!((zz - 4.0 * std::f64::consts::PI / 3.0).abs() < 1e-2, "{zz}");
    }
}
