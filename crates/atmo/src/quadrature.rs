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
