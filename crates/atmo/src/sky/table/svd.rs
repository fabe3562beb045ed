//! Truncated singular value decomposition of the skylight matrix, sky (16)-(17) and
//! appendix B: `A ~ sum_k sigma_k u_k v_k^T` for the largest `sigma_k`.
//!
//! The paper decomposed the whole 4096 x 4096 matrix (10 hours); only its leading terms
//! are ever used, so we compute just those with the randomized range finder of Halko,
//! Martinsson and Tropp (2011, algorithms 4.4 and 5.1): sample the range of `A` with a
//! random block, sharpen it with power iterations, and decompose the small projection
//! exactly with faer (built without its thread pool: its parallel products round
//! differently with the number of threads, and the table must not depend on the machine;
//! sequential, the SVD of the default table takes under 7 s). With power iterations the leading terms match the exact SVD to
//! working precision for a matrix whose singular values fall as fast as the sky's; the
//! term counts of [`super`] (the table) are measured on the factors actually stored, so the
//! error bound never rests on that claim.

use faer::Mat;

/// Extra samples beyond the wanted rank (Halko et al. recommend 5 to 10; more is cheap).
const OVERSAMPLING: usize = 16;

/// Power iterations: each multiplies the gap between kept and dropped terms by the
/// ratio of their singular values once more.
const POWER_ITERATIONS: usize = 2;

/// The leading terms of an SVD: `A ~ U diag(sigma) V^T`.
#[derive(Debug, Clone)]
pub struct TruncatedSvd {
    /// Singular values, decreasing.
    pub sigma: Vec<f64>,
    /// Left singular vectors, `rows x rank`.
    pub u: Mat<f64>,
    /// Right singular vectors, `cols x rank`.
    pub v: Mat<f64>,
}

impl TruncatedSvd {
    /// The `rank` leading terms of `a` (all of them when `rank >= min(rows, cols)`),
    /// deterministic: the random block comes from a fixed seed.
    pub fn new(a: &Mat<f64>, rank: usize) -> Self {
        let (m, n) = (a.nrows(), a.ncols());
        let full = m.min(n);
        let rank = rank.min(full);
        let samples = (rank + OVERSAMPLING).min(full);
        let mut seed = 0x9e37_79b9_7f4a_7c15_u64;
        let omega = Mat::<f64>::from_fn(n, samples, |_, _| uniform(&mut seed));
        let mut q = (a * &omega).qr().compute_thin_Q();
        for _ in 0..POWER_ITERATIONS {
            let z = (a.transpose() * &q).qr().compute_thin_Q();
            q = (a * &z).qr().compute_thin_Q();
        }
        let b = q.transpose() * a;
        let svd = b.thin_svd().expect("the SVD of a finite matrix converges");
        let s = svd.S().column_vector();
        let u = &q * svd.U();
        TruncatedSvd {
            sigma: (0..rank).map(|k| s[k]).collect(),
            u: Mat::from_fn(m, rank, |i, k| u[(i, k)]),
            v: Mat::from_fn(n, rank, |j, k| svd.V()[(j, k)]),
        }
    }

    /// The number of terms kept.
    pub fn rank(&self) -> usize {
        self.sigma.len()
    }
}

/// A uniform number in [-1, 1) from a SplitMix64 step: the range finder needs any
/// fixed, well-spread block, not a statistically strong generator, so no crate.
fn uniform(state: &mut u64) -> f64 {
    *state = state.wrapping_add(0x9e37_79b9_7f4a_7c15);
    let mut z = *state;
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^= z >> 31;
    (z >> 11) as f64 / (1u64 << 52) as f64 - 1.0
}

#[cfg(test)]
mod tests {
    use super::*;

    fn reconstruct(svd: &TruncatedSvd, i: usize, j: usize) -> f64 {
        (0..svd.rank())
            .map(|k| svd.sigma[k] * svd.u[(i, k)] * svd.v[(j, k)])
            .sum()
    }

    /// A smooth, positive matrix like a sky's, with quickly falling singular values.
    fn sky_like(m: usize, n: usize) -> Mat<f64> {
        Mat::from_fn(m, n, |i, j| {
            let (x, y) = (i as f64 / m as f64, j as f64 / n as f64);
            (1.0 + x * y).recip() + 0.3 * (-(x - y).powi(2) * 8.0).exp() + 0.1 * (7.0 * x).sin() * y
        })
    }

    #[test]
    fn all_terms_reconstruct_the_matrix() {
        let a = sky_like(60, 24);
        let svd = TruncatedSvd::new(&a, 100);
        assert_eq!(svd.rank(), 24);
        for i in 0..60 {
            for j in 0..24 {
                let e = (reconstruct(&svd, i, j) - a[(i, j)]).abs();
                assert!(e < 1e-12, "({i}, {j}): {e}");
            }
        }
    }

    #[test]
    fn leading_terms_match_the_exact_svd() {
        let a = sky_like(300, 200);
        let exact = a.thin_svd().unwrap();
        let s = exact.S().column_vector();
        let svd = TruncatedSvd::new(&a, 8);
        for k in 0..8 {
            let rel = (svd.sigma[k] - s[k]).abs() / s[0];
            assert!(
                rel < 1e-10,
                "sigma_{k}: {} vs {}: {rel}",
                svd.sigma[k],
                s[k]
            );
        }
        // Singular vectors agree up to sign.
        for k in 0..4 {
            let dot: f64 = (0..300).map(|i| svd.u[(i, k)] * exact.U()[(i, k)]).sum();
            assert!((dot.abs() - 1.0).abs() < 1e-8, "u_{k}: {dot}");
        }
    }
}
