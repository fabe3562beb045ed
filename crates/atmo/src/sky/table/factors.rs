//! The SVD factors of sky (17) as the table stores them: `s_k(theta, phi)` and
//! `t_k(sun, h) sigma_k` in 16-bit fixed point, each direction's term count `T(theta,
//! phi)` chosen against the [`ErrorBound`], and the layout a draw runs over.

use faer::Mat;
use glam::Vec3;
use rayon::prelude::*;

use super::svd::TruncatedSvd;
use super::{ErrorBound, CHANNELS};
use crate::error::{Error, Result};

/// Terms computed by the first SVD; doubled until every direction meets the bound, up
/// to [`MAX_RANK`]. The default table needs about 150.
const INITIAL_RANK: usize = 192;

/// The most terms computed before the bound is declared out of reach.
const MAX_RANK: usize = 768;

/// Largest magnitude of the 16-bit fixed-point values `s_k`, `t_k` are stored in.
const Q_MAX: f32 = 32767.0;

/// The factors of the three channels' matrices stacked (`3 L^2` rows), which share the
/// functions `t_k`: the channels of a sky are so alike that one set of `t_k` serves all
/// three, a third of the storage of separate decompositions.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Factors {
    /// Every singular value computed, decreasing (for the decay plot).
    pub sigma: Vec<f32>,
    /// `T(theta, phi)` per row `channel * L^2 + direction`, directions
    /// `[elevation][azimuth]`.
    pub terms: Vec<u16>,
    /// Rows by decreasing term count (then by index): term `k` is used by the first
    /// `used[k]` of them, so the sum runs over contiguous memory.
    pub order: Vec<u32>,
    /// `used[k]`: rows with more than `k` terms.
    pub used: Vec<u32>,
    /// `s_k` in `order`, term after term (`used[k]` values each), multiples of
    /// `s_step[k]`.
    pub s: Vec<f32>,
    /// `t_k(sun, h) sigma_k`, `[k][altitude][sun]`, multiples of `t_step[k]`.
    pub t: Vec<f32>,
    /// Fixed-point steps of `s_k` and `t_k`, one per stored term.
    pub s_step: Vec<f32>,
    /// See `s_step`.
    pub t_step: Vec<f32>,
}

impl Factors {
    /// Builds the derived `order` and `used` from the term counts.
    pub fn layout(terms: &[u16]) -> (Vec<u32>, Vec<u32>) {
        let mut order: Vec<u32> = (0..terms.len() as u32).collect();
        order.sort_by_key(|&d| std::cmp::Reverse(terms[d as usize]));
        let most = terms.iter().copied().max().unwrap_or(0) as usize;
        let used = (0..most)
            .map(|k| terms.iter().filter(|&&t| t as usize > k).count() as u32)
            .collect();
        (order, used)
    }

    /// Compresses the channels `values[c][direction * cols + column]` to the fewest
    /// terms per row that meet `bound`.
    pub(super) fn compress(
        values: &[Vec<f32>; CHANNELS],
        cols: usize,
        bound: &ErrorBound,
    ) -> Result<Self> {
        let directions = values[0].len() / cols;
        let rows = CHANNELS * directions;
        let value = |i: usize, j: usize| values[i / directions][(i % directions) * cols + j];
        let a = Mat::<f64>::from_fn(rows, cols, |i, j| encode(value(i, j)) as f64);
        let full = rows.min(cols);
        let mut rank = INITIAL_RANK.min(full);
        loop {
            let svd = TruncatedSvd::new(&a, rank);
            // The factors as the file stores them: each s_k and t_k in 16-bit fixed point
            // with its own step (f16's 11 bits lose the bound in dim skies).
            let s_step: Vec<f32> = (0..rank)
                .map(|k| step_of((0..rows).map(|i| svd.u[(i, k)])))
                .collect();
            let t_step: Vec<f32> = (0..rank)
                .map(|k| step_of((0..cols).map(|j| svd.sigma[k] * svd.v[(j, k)])))
                .collect();
            let s = Mat::<f32>::from_fn(rows, rank, |i, k| quantize(svd.u[(i, k)], s_step[k]));
            let t: Vec<f32> = (0..rank)
                .flat_map(|k| {
                    let svd = &svd;
                    let step = t_step[k];
                    (0..cols).map(move |j| quantize(svd.sigma[k] * svd.v[(j, k)], step))
                })
                .collect();
            let counts: Vec<Option<u16>> = (0..rows)
                .into_par_iter()
                .map(|i| {
                    let s_row: Vec<f32> = (0..rank).map(|k| s[(i, k)]).collect();
                    let (c, d) = (i / directions, i % directions);
                    term_count(&values[c][d * cols..(d + 1) * cols], &s_row, &t, bound)
                })
                .collect();
            if let Some(terms) = counts.iter().copied().collect::<Option<Vec<u16>>>() {
                let (order, used) = Self::layout(&terms);
                let packed = used
                    .iter()
                    .enumerate()
                    .flat_map(|(k, &n)| order[..n as usize].iter().map(move |&d| (d, k)))
                    .map(|(d, k)| s[(d as usize, k)])
                    .collect();
                let most = used.len();
                return Ok(Factors {
                    sigma: svd.sigma.iter().map(|&x| x as f32).collect(),
                    s_step: s_step[..most].to_vec(),
                    t_step: t_step[..most].to_vec(),
                    t: t[..most * cols].to_vec(),
                    terms,
                    order,
                    used,
                    s: packed,
                });
            }
            let most = full.min(MAX_RANK);
            if rank == most {
                let worst = counts.iter().position(Option::is_none).unwrap_or(0);
                return Err(Error::Invalid(format!(
                    "epsilon = {} cannot be met at view direction {} of channel {} with \
                     {most} terms; raise epsilon",
                    bound.epsilon,
                    worst % directions,
                    worst / directions
                )));
            }
            rank = (2 * rank).min(most);
        }
    }

    /// `t_k` interpolated at `corners` ((column, weight) pairs), one per stored term:
    /// the per-frame coefficients of sky (17), shared by the CPU and GPU draws.
    pub(super) fn coefficients(&self, corners: &[(usize, f32); 4], cols: usize) -> Vec<f32> {
        (0..self.used.len())
            .map(|k| {
                let t = &self.t[k * cols..(k + 1) * cols];
                corners.iter().map(|&(j, w)| t[j] * w).sum()
            })
            .collect()
    }

    /// The sky with `coefficients` into `out`, `[direction]` in linear sRGB; `acc` is
    /// scratch space.
    pub(super) fn draw(&self, coefficients: &[f32], acc: &mut Vec<f32>, out: &mut [Vec3]) {
        acc.clear();
        acc.resize(self.terms.len(), 0.0);
        let mut offset = 0;
        for (&n, &coefficient) in self.used.iter().zip(coefficients) {
            let n = n as usize;
            for (a, &s) in acc[..n].iter_mut().zip(&self.s[offset..offset + n]) {
                *a += coefficient * s;
            }
            offset += n;
        }
        let directions = out.len();
        for (&row, &a) in self.order.iter().zip(acc.iter()) {
            let row = row as usize;
            out[row % directions][row / directions] = decode(a);
        }
    }
}

/// Radiance as the SVD sees it: `sqrt`, close to the display's own gamma, so that the
/// truncation spreads its error evenly over what the eye sees (dim dusk skies are not
/// drowned by the bright ones).
#[inline]
fn encode(radiance: f32) -> f32 {
    radiance.max(0.0).sqrt()
}

/// The inverse of [`encode`]; negative sums (truncation ringing) give zero radiance.
#[inline]
fn decode(y: f32) -> f32 {
    let y = y.max(0.0);
    y * y
}

/// The fixed-point step of a vector: its largest magnitude maps to [`Q_MAX`].
pub(crate) fn step_of(values: impl Iterator<Item = f64>) -> f32 {
    let max = values.fold(0.0f64, |m, v| m.max(v.abs()));
    if max > 0.0 {
        (max / Q_MAX as f64) as f32
    } else {
        1.0
    }
}

/// `x` as the file stores it: the nearest multiple of `step` within +-[`Q_MAX`] steps.
pub(crate) fn quantize(x: f64, step: f32) -> f32 {
    dequantize(to_fixed(x as f32, step), step)
}

/// The 16-bit fixed-point value of `x` (a multiple of `step` if it came from
/// [`quantize`]).
pub(crate) fn to_fixed(x: f32, step: f32) -> i16 {
    (x / step).round().clamp(-Q_MAX, Q_MAX) as i16
}

/// The value of fixed-point `q` with `step`.
#[inline]
pub(crate) fn dequantize(q: i16, step: f32) -> f32 {
    q as f32 * step
}

/// The fewest terms of `s_row` (this direction's `s_k`) and `t` (`[k][column]`) that
/// bring every column of `exact` within the bound, or `None` if all of them do not.
/// The sum runs in the order and precision of [`ChannelTable::draw`].
fn term_count(exact: &[f32], s_row: &[f32], t: &[f32], bound: &ErrorBound) -> Option<u16> {
    let cols = exact.len();
    let intervals: Vec<(f32, f32)> = exact.iter().map(|&x| bound.interval(x)).collect();
    let mut approx = vec![0.0f32; cols];
    for k in 0..=s_row.len() {
        let inside = approx
            .iter()
            .zip(&intervals)
            .all(|(&x, &(lo, hi))| (lo..=hi).contains(&decode(x)));
        if inside {
            return Some(k as u16);
        }
        if k == s_row.len() {
            return None;
        }
        for (a, &t) in approx.iter_mut().zip(&t[k * cols..(k + 1) * cols]) {
            *a += t * s_row[k];
        }
    }
    None
}

/// The factors `s_k` of a table as a draw reads them: rows (`channel * directions +
/// direction`) sorted by decreasing term count, and term after term the `s_k` of the
/// rows that use it, so that row `order[i]` finds its term `k` at `s[offset_k + i]`
/// with `offset_k = used[0] + ... + used[k - 1]`.
#[derive(Debug, Clone, Copy)]
pub struct TableFactors<'a> {
    /// `s_k`, term after term.
    pub s: &'a [f32],
    /// Row of each position.
    pub order: &'a [u32],
    /// Rows using term `k`: `used[k]`.
    pub used: &'a [u32],
    /// View directions per channel (`L^2`).
    pub directions: usize,
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sky::table::TableSettings;

    #[test]
    fn layout_orders_directions_by_term_count() {
        let (order, used) = Factors::layout(&[2, 0, 3, 2]);
        assert_eq!(order, vec![2, 0, 3, 1]);
        assert_eq!(used, vec![3, 3, 1]);
    }

    #[test]
    fn term_count_is_the_fewest_terms_within_the_bound() {
        let bound = TableSettings::default().bound;
        // One direction, two columns; the sums run on encoded (square-root) radiance:
        // y = 1.0 [1, 2] + 0.05 [1, -1]. Dropping the second term moves the radiance
        // by 0.1 to 0.2, which shows (0.015 and more at exposure 0.15, above 1/255).
        let exact = [1.05f32 * 1.05, 1.95 * 1.95];
        let t = [1.0f32, 2.0, 1.0, -1.0];
        assert_eq!(term_count(&exact, &[1.0, 0.05], &t, &bound), Some(2));
        // A term too small to see is not needed.
        let faint = [1.0001f32 * 1.0001, 1.9999 * 1.9999];
        assert_eq!(term_count(&faint, &[1.0, 1e-4], &t, &bound), Some(1));
        // No terms cannot reach a bright sky.
        assert_eq!(term_count(&exact, &[], &t, &bound), None);
    }
}
