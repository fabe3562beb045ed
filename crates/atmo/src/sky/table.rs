//! The skylight table: the sky for every sun elevation and viewpoint altitude, computed
//! once with the shell method and compressed by SVD, sky 4.1-4.2.
//!
//! The 4-D table `I_sky(theta, phi, sun elevation, altitude)` (sky (11)-(15)) becomes, per
//! colour channel, the matrix `A_sky` of sky (16): one row per view direction, one column
//! per (sun, altitude). Its truncated SVD gives `sum_k s_k(theta, phi) t_k(sun, h)`,
//! sky (17), with `sigma_k` folded into `t_k`. Each direction keeps only the `T(theta, phi)`
//! terms it needs for its largest error over all columns to stay within `epsilon` on the
//! display (see [`ErrorBound`]). Drawing interpolates `t_k` bilinearly at the wanted sun
//! and altitude and sums `T(theta, phi)` products per direction (sky 4.2).
//!
//! Beyond the paper (docs/sky-table.md has the measurements): the rows follow each
//! altitude's horizon; the sun grid starts below the horizon (dusk and dawn) and is
//! denser near it, the altitude grid denser near the ground, both including their ends;
//! the SVD sees the square root of radiance, runs on the three channels stacked (they
//! share `t_k`), and is truncated and randomized ([`super::svd`]); factors are stored in
//! 16-bit fixed point and the term counts measured on them as stored; and the table holds
//! linear sRGB radiance rather than 8-bit values, so any exposure can be drawn from it.

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Arc;

use faer::Mat;
use glam::Vec3;
use rayon::prelude::*;

use super::grid::DirectionGrid;
use super::svd::TruncatedSvd;
use super::{SkyModel, SkySettings, MEMORY_BUDGET_BYTES};
use crate::atmosphere::geometry::horizon_dip;
use crate::atmosphere::spectrum::SpectrumToRgb;
use crate::atmosphere::{Atmosphere, TransmittanceTable};
use crate::error::{check_budget, check_positive, check_range, Error, Result};
use crate::image::{srgb_decode, srgb_encode, Display, ToneMap};

/// Colour channels of the table: linear sRGB, as the paper decomposed R, G and B.
pub const CHANNELS: usize = 3;

/// Terms computed by the first SVD; doubled until every direction meets the bound, up
/// to [`MAX_RANK`]. The default table needs about 150.
const INITIAL_RANK: usize = 192;

/// The most terms computed before the bound is declared out of reach.
const MAX_RANK: usize = 768;

/// Largest magnitude of the 16-bit fixed-point values `s_k`, `t_k` are stored in.
const Q_MAX: f32 = 32767.0;

/// Half-width of the band around the horizon where sun elevations are denser (the extra
/// density falls to 1/e there), deg: the off-grid error of evenly spaced suns peaks
/// within 5 deg of the horizon (docs/sky-table.md).
const SUN_HORIZON_WIDTH_DEG: f64 = 5.0;

/// The term counts aim this fraction below `epsilon`, so rounding in the inverse display
/// transform can never carry an error over the bound.
const BOUND_MARGIN: f32 = 1e-3;

/// One axis of the (sun elevation, altitude) grid: increasing values, both ends
/// included, spaced as a density asks (more points where the sky changes fastest).
#[derive(Debug, Clone, PartialEq)]
pub struct TableAxis {
    values: Vec<f64>,
}

/// Points of the fine grid on which [`TableAxis::with_density`] integrates the density.
const DENSITY_SAMPLES: usize = 1 << 16;

impl TableAxis {
    /// `count` points from `min` to `max` at `min + (max - min) u^power`,
    /// `u = i / (count - 1)`: even for `power = 1`, denser near `min` above it.
    pub fn power(min: f64, max: f64, count: usize, power: f64) -> Self {
        let values = (0..count)
            .map(|i| {
                let u = i as f64 / (count - 1) as f64;
                min + (max - min) * u.powf(power)
            })
            .collect();
        TableAxis { values }
    }

    /// `count` points from `min` to `max` with as many points per unit near `v` as
    /// `density(v)` says (relative): point `i` is where the integral of the density
    /// from `min` reaches `i / (count - 1)` of the whole.
    pub fn with_density(min: f64, max: f64, count: usize, density: impl Fn(f64) -> f64) -> Self {
        let h = (max - min) / DENSITY_SAMPLES as f64;
        let mut cumulative = vec![0.0; DENSITY_SAMPLES + 1];
        for k in 0..DENSITY_SAMPLES {
            let v = min + (k as f64 + 0.5) * h;
            cumulative[k + 1] = cumulative[k] + density(v) * h;
        }
        let total = cumulative[DENSITY_SAMPLES];
        let mut values: Vec<f64> = (0..count)
            .map(|i| {
                let target = total * i as f64 / (count - 1) as f64;
                let k = cumulative
                    .partition_point(|&c| c < target)
                    .clamp(1, DENSITY_SAMPLES);
                let (c0, c1) = (cumulative[k - 1], cumulative[k]);
                let f = if c1 > c0 {
                    (target - c0) / (c1 - c0)
                } else {
                    0.0
                };
                min + (k as f64 - 1.0 + f) * h
            })
            .collect();
        (values[0], values[count - 1]) = (min, max);
        TableAxis { values }
    }

    /// Grid points.
    pub fn count(&self) -> usize {
        self.values.len()
    }

    /// First grid value.
    pub fn min(&self) -> f64 {
        self.values[0]
    }

    /// Last grid value.
    pub fn max(&self) -> f64 {
        self.values[self.values.len() - 1]
    }

    /// The value of grid point `i`.
    pub fn value(&self, i: usize) -> f64 {
        self.values[i]
    }

    /// The grid interval `[value(i), value(i + 1)]` holding `v` and the weight of its
    /// upper end for linear interpolation (exactly 0 or 1 at grid points), or `None`
    /// outside `[min, max]`.
    pub fn locate(&self, v: f64) -> Option<(usize, f32)> {
        if !(v >= self.min() && v <= self.max()) {
            return None;
        }
        let n = self.values.len();
        let i = self.values.partition_point(|&x| x <= v).clamp(1, n - 1) - 1;
        let (a, b) = (self.values[i], self.values[i + 1]);
        Some((i, ((v - a) / (b - a)).clamp(0.0, 1.0) as f32))
    }
}

/// What "an error of epsilon" means: the difference of the values a display is sent
/// for the table's and the directly computed radiance, channel by channel (linear sRGB
/// radiance times `display.exposure`, through `display.tone`, then sRGB-encoded if
/// `srgb`), in [0, 1]: 1/255 is one step of an 8-bit frame buffer.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ErrorBound {
    /// Largest difference of displayed values, in (0, 1).
    pub epsilon: f32,
    /// Exposure and tone map of the display.
    pub display: Display,
    /// Whether values are compared after sRGB encoding (what an 8-bit sRGB image holds)
    /// or before it (a linear frame buffer, as the paper's 8-bit values).
    pub srgb: bool,
}

impl ErrorBound {
    /// The value displayed for linear radiance `x`.
    #[inline]
    fn shown(&self, x: f32) -> f32 {
        let v = self.display.tone.apply(x * self.display.exposure);
        if self.srgb {
            srgb_encode(v)
        } else {
            v
        }
    }

    /// The linear radiance shown as `d` in [0, 1); `None` from 1 up, where every tone
    /// map saturates.
    fn radiance(&self, d: f32) -> Option<f32> {
        let v = if self.srgb {
            srgb_decode(d.max(0.0))
        } else {
            d.max(0.0)
        };
        (d < 1.0).then(|| self.display.tone.invert(v) / self.display.exposure)
    }

    /// The display error of `approx` against `exact` (linear radiance), in units of epsilon.
    #[inline]
    pub fn error(&self, approx: f32, exact: f32) -> f32 {
        (self.shown(approx) - self.shown(exact)).abs() / self.epsilon
    }

    /// The largest [`ErrorBound::error`] over two maps, channel by channel.
    pub fn max_error(&self, approx: &[Vec3], exact: &[Vec3]) -> f32 {
        approx
            .iter()
            .zip(exact)
            .flat_map(|(a, e)| (0..CHANNELS).map(move |c| self.error(a[c], e[c])))
            .fold(0.0, f32::max)
    }

    /// The interval of linear radiance shown within `epsilon (1 - margin)` of `exact`.
    fn interval(&self, exact: f32) -> (f32, f32) {
        let eps = self.epsilon * (1.0 - BOUND_MARGIN);
        let d = self.shown(exact);
        let lo = if d - eps > 0.0 {
            self.radiance(d - eps).unwrap_or(f32::INFINITY)
        } else {
            f32::NEG_INFINITY
        };
        let hi = self.radiance(d + eps).unwrap_or(f32::INFINITY);
        (lo, hi)
    }
}

/// Parameters of a table: the grids, the shell method's settings and the bound.
#[derive(Debug, Clone, PartialEq)]
pub struct TableSettings {
    /// The shell method; `sky.directions` is `L` of sky (11)-(12).
    pub sky: SkySettings,
    /// Sun elevations `M`, sky (13).
    pub sun_steps: usize,
    /// Lowest sun elevation, rad; the highest is the zenith.
    pub min_sun_elevation: f64,
    /// How many times denser sun elevations are at the horizon than far from it (1:
    /// even, as the paper).
    pub sun_horizon_density: f64,
    /// Viewpoint altitudes `N`, sky (14).
    pub altitude_steps: usize,
    /// Highest viewpoint altitude `h0`, m (paper: 13 km); the lowest is the ground.
    pub max_altitude_m: f64,
    /// Spacing exponent of the altitude grid (1: even, as the paper).
    pub altitude_power: f64,
    /// The error bound that sets the term counts.
    pub bound: ErrorBound,
}

impl Default for TableSettings {
    fn default() -> Self {
        TableSettings {
            sky: SkySettings::default(),
            sun_steps: 128,
            min_sun_elevation: (-10f64).to_radians(),
            sun_horizon_density: 4.0,
            altitude_steps: 32,
            max_altitude_m: 13_000.0,
            // Measured against 1.0 and 2.0 (docs/sky-table.md): the most even error over
            // altitude, the aerosols near the ground changing the sky fastest.
            altitude_power: 1.5,
            bound: ErrorBound {
                epsilon: 1.0 / 255.0,
                display: Display {
                    exposure: 0.15,
                    tone: ToneMap::Exponential,
                },
                srgb: true,
            },
        }
    }
}

impl TableSettings {
    /// Checks every field and that the precompute fits [`MEMORY_BUDGET_BYTES`].
    pub fn validate(&self, atmosphere: &Atmosphere) -> Result<()> {
        self.sky.validate(atmosphere.channels())?;
        check_range("sun_steps", self.sun_steps as f64, 2.0, 4096.0)?;
        check_range("altitude_steps", self.altitude_steps as f64, 2.0, 1024.0)?;
        check_range(
            "min_sun_elevation (deg)",
            self.min_sun_elevation.to_degrees(),
            -90.0,
            89.0,
        )?;
        let top = atmosphere.thickness_m();
        if !(self.max_altitude_m > 0.0 && self.max_altitude_m < top) {
            return Err(Error::out_of_range(
                "max_altitude (m)",
                self.max_altitude_m,
                &format!("(0, {top}), below the top of the atmosphere"),
            ));
        }
        check_range("altitude_power", self.altitude_power, 0.25, 4.0)?;
        check_range("sun_horizon_density", self.sun_horizon_density, 1.0, 20.0)?;
        if !(self.bound.epsilon > 0.0 && self.bound.epsilon < 1.0) {
            return Err(Error::out_of_range(
                "epsilon",
                self.bound.epsilon,
                "(0, 1), in displayed values",
            ));
        }
        check_positive("exposure", self.bound.display.exposure as f64, 1e9)?;
        check_budget(
            "the skylight table's precompute",
            self.memory_bytes(atmosphere.channels()),
            MEMORY_BUDGET_BYTES,
            "directions, sun_steps or altitude_steps",
        )
    }

    /// An upper bound of the bytes the precompute holds at once: the table as maps and
    /// as one f32 matrix per channel, the stacked f64 matrix of the SVD, and the shell
    /// models of two altitudes.
    pub fn memory_bytes(&self, spectral_channels: usize) -> u64 {
        let entries = (self.sky.directions as u64).pow(2)
            * self.sun_steps as u64
            * self.altitude_steps as u64;
        entries * (12 + 12 + 24) + 2 * self.sky.memory_bytes(spectral_channels)
    }

    /// The sun elevation axis, rad: `sun_horizon_density` times denser at the horizon
    /// than far from it, where the glow at the horizon follows the sun faster than
    /// interpolation between evenly spaced suns can (docs/sky-table.md).
    pub fn sun_axis(&self) -> TableAxis {
        let ratio = self.sun_horizon_density;
        let width = SUN_HORIZON_WIDTH_DEG.to_radians();
        TableAxis::with_density(
            self.min_sun_elevation,
            std::f64::consts::FRAC_PI_2,
            self.sun_steps,
            |e| 1.0 + (ratio - 1.0) * (-(e / width).powi(2)).exp(),
        )
    }

    /// The altitude axis, m.
    pub fn altitude_axis(&self) -> TableAxis {
        TableAxis::power(
            0.0,
            self.max_altitude_m,
            self.altitude_steps,
            self.altitude_power,
        )
    }
}

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
    fn compress(values: &[Vec<f32>; CHANNELS], cols: usize, bound: &ErrorBound) -> Result<Self> {
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
    fn coefficients(&self, corners: &[(usize, f32); 4], cols: usize) -> Vec<f32> {
        (0..self.used.len())
            .map(|k| {
                let t = &self.t[k * cols..(k + 1) * cols];
                corners.iter().map(|&(j, w)| t[j] * w).sum()
            })
            .collect()
    }

    /// The sky with `coefficients` into `out`, `[direction]` in linear sRGB; `acc` is
    /// scratch space.
    fn draw(&self, coefficients: &[f32], acc: &mut Vec<f32>, out: &mut [Vec3]) {
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

/// The skylight table of one atmosphere: grids, bound, and per channel the SVD factors
/// with their term counts.
#[derive(Debug, Clone, PartialEq)]
pub struct SkylightTable {
    pub(crate) atmosphere: Atmosphere,
    pub(crate) settings: TableSettings,
    /// Largest display error at the grid points, in units of epsilon (at most 1).
    pub(crate) grid_error: f32,
    /// The axes the settings describe, kept: drawing looks them up every time.
    pub(crate) sun: TableAxis,
    pub(crate) altitude: TableAxis,
    pub(crate) factors: Factors,
}

impl SkylightTable {
    /// Computes the table: `M x N` skylight maps with the shell method (altitudes in
    /// parallel, deterministic), then per channel the truncated SVD and the term counts.
    /// `progress(done, total)` is called after each skylight map.
    pub fn precompute(
        atmosphere: &Atmosphere,
        settings: &TableSettings,
        progress: &(dyn Fn(usize, usize) + Sync),
    ) -> Result<Self> {
        let values = Self::skylight_matrices(atmosphere, settings, progress)?;
        Self::from_matrices(atmosphere, settings, &values)
    }

    /// The matrices `A_sky` of sky (16), one per channel, `[direction][column]` with
    /// column `altitude * M + sun`.
    pub fn skylight_matrices(
        atmosphere: &Atmosphere,
        settings: &TableSettings,
        progress: &(dyn Fn(usize, usize) + Sync),
    ) -> Result<[Vec<f32>; CHANNELS]> {
        settings.validate(atmosphere)?;
        let (sun, altitude) = (settings.sun_axis(), settings.altitude_axis());
        let transmittance = Arc::new(TransmittanceTable::new(atmosphere));
        let colour = SpectrumToRgb::new(&atmosphere.wavelengths_nm);
        let total = sun.count() * altitude.count();
        let done = AtomicUsize::new(0);
        // Per altitude, the maps of every sun: [sun][direction].
        let maps: Vec<Vec<[f32; 3]>> = (0..altitude.count())
            .into_par_iter()
            .map(|a| {
                let model = shell_model(
                    atmosphere,
                    settings,
                    transmittance.clone(),
                    altitude.value(a),
                )?;
                let mut out = Vec::new();
                for s in 0..sun.count() {
                    out.extend(model.skylight_map(sun.value(s)).to_rgb(&colour));
                    progress(done.fetch_add(1, Ordering::Relaxed) + 1, total);
                }
                Ok(out)
            })
            .collect::<Result<_>>()?;
        let rows = settings.sky.directions.pow(2);
        Ok(std::array::from_fn(|c| {
            let mut m = vec![0.0f32; rows * total];
            m.par_chunks_mut(total).enumerate().for_each(|(d, row)| {
                for (column, v) in row.iter_mut().enumerate() {
                    let (a, s) = (column / sun.count(), column % sun.count());
                    *v = maps[a][s * rows + d][c];
                }
            });
            m
        }))
    }

    /// The table from the matrices of [`SkylightTable::skylight_matrices`].
    pub fn from_matrices(
        atmosphere: &Atmosphere,
        settings: &TableSettings,
        values: &[Vec<f32>; CHANNELS],
    ) -> Result<Self> {
        settings.validate(atmosphere)?;
        let rows = settings.sky.directions.pow(2);
        let cols = settings.sun_steps * settings.altitude_steps;
        if values.iter().any(|v| v.len() != rows * cols) {
            return Err(Error::Invalid(format!(
                "skylight matrices must hold {rows} x {cols} values each"
            )));
        }
        let factors = Factors::compress(values, cols, &settings.bound)?;
        let mut table = SkylightTable {
            atmosphere: atmosphere.clone(),
            settings: settings.clone(),
            grid_error: 0.0,
            sun: settings.sun_axis(),
            altitude: settings.altitude_axis(),
            factors,
        };
        table.grid_error = table.error_against(values);
        Ok(table)
    }

    /// The largest display error (units of epsilon) of the table against `values` at
    /// every grid point, drawn as [`SkylightTable::map_into`] draws.
    pub fn error_against(&self, values: &[Vec<f32>; CHANNELS]) -> f32 {
        let (sun, altitude) = (self.sun_axis(), self.altitude_axis());
        let cols = sun.count() * altitude.count();
        (0..cols)
            .into_par_iter()
            .map(|column| {
                let (a, s) = (column / sun.count(), column % sun.count());
                let map = self
                    .map(sun.value(s), altitude.value(a))
                    .expect("grid points lie in the table");
                let exact: Vec<Vec3> = (0..map.len())
                    .map(|d| {
                        let at = d * cols + column;
                        Vec3::new(values[0][at], values[1][at], values[2][at])
                    })
                    .collect();
                self.settings.bound.max_error(&map, &exact)
            })
            .reduce(|| 0.0, f32::max)
    }

    /// The atmosphere the table was computed for.
    pub fn atmosphere(&self) -> &Atmosphere {
        &self.atmosphere
    }

    /// The parameters it was computed with.
    pub fn settings(&self) -> &TableSettings {
        &self.settings
    }

    /// The view directions of its skylight maps seen from `altitude_m`: `L x L`, from
    /// the horizon (its dip below the horizontal) to the zenith.
    pub fn grid(&self, altitude_m: f64) -> DirectionGrid {
        direction_grid(&self.atmosphere, &self.settings, altitude_m)
    }

    /// The sun elevation axis, rad.
    pub fn sun_axis(&self) -> &TableAxis {
        &self.sun
    }

    /// The altitude axis, m.
    pub fn altitude_axis(&self) -> &TableAxis {
        &self.altitude
    }

    /// The largest display error at the grid points, in units of epsilon.
    pub fn grid_error(&self) -> f32 {
        self.grid_error
    }

    /// `T(theta, phi)` of channel `c` (0 red, 1 green, 2 blue), `[elevation][azimuth]`.
    pub fn terms(&self, c: usize) -> &[u16] {
        let n = self.factors.terms.len() / CHANNELS;
        &self.factors.terms[c * n..(c + 1) * n]
    }

    /// The singular values computed, decreasing.
    pub fn singular_values(&self) -> &[f32] {
        &self.factors.sigma
    }

    /// The most terms any direction uses, in any channel: the number of `t_k` stored.
    pub fn max_terms(&self) -> usize {
        self.factors.used.len()
    }

    /// Values stored for `s_k` and `t_k`.
    pub fn stored_values(&self) -> usize {
        self.factors.s.len() + self.factors.t.len()
    }

    /// The skylight map (linear sRGB, `[elevation][azimuth]` over [`SkylightTable::grid`])
    /// for a sun at `sun_elevation` rad seen from `altitude_m`.
    pub fn map(&self, sun_elevation: f64, altitude_m: f64) -> Result<Vec<Vec3>> {
        let mut out = vec![Vec3::ZERO; self.settings.sky.directions.pow(2)];
        self.map_into(sun_elevation, altitude_m, &mut out, &mut Vec::new())?;
        Ok(out)
    }

    /// [`SkylightTable::map`] into `out`, with `scratch` reused between calls: sky 4.2,
    /// bilinear interpolation of `t_k` and `T(theta, phi)` products per direction.
    /// Outside the table's sun or altitude range it is an error, never a clamp.
    pub fn map_into(
        &self,
        sun_elevation: f64,
        altitude_m: f64,
        out: &mut [Vec3],
        scratch: &mut Vec<f32>,
    ) -> Result<()> {
        let coefficients = self.coefficients(sun_elevation, altitude_m)?;
        self.factors.draw(&coefficients, scratch, out);
        Ok(())
    }

    /// The coefficients `t_k` of sky (17) for a sun at `sun_elevation` rad seen from
    /// `altitude_m`, bilinear in the table's grid, one per stored term: all a draw
    /// needs per frame besides the stored `s_k`. An error outside the table's ranges.
    pub fn coefficients(&self, sun_elevation: f64, altitude_m: f64) -> Result<Vec<f32>> {
        let (sun, altitude) = (self.sun_axis(), self.altitude_axis());
        let (s, ws) = sun.locate(sun_elevation).ok_or_else(|| {
            Error::out_of_range(
                "sun elevation (deg)",
                // Degrees to radians and back: round away the last bits.
                (sun_elevation.to_degrees() * 1e9).round() / 1e9,
                &format!(
                    "the table's [{}, {}]",
                    sun.min().to_degrees(),
                    sun.max().to_degrees()
                ),
            )
        })?;
        let (a, wa) = altitude.locate(altitude_m).ok_or_else(|| {
            Error::out_of_range(
                "altitude (m)",
                altitude_m,
                &format!("the table's [{}, {}]", altitude.min(), altitude.max()),
            )
        })?;
        let m = sun.count();
        let corners = [
            (a * m + s, (1.0 - ws) * (1.0 - wa)),
            (a * m + s + 1, ws * (1.0 - wa)),
            ((a + 1) * m + s, (1.0 - ws) * wa),
            ((a + 1) * m + s + 1, ws * wa),
        ];
        Ok(self.factors.coefficients(&corners, m * altitude.count()))
    }

    /// The stored factors in the layout a draw runs over, for uploading to a GPU.
    pub fn factors(&self) -> TableFactors<'_> {
        TableFactors {
            s: &self.factors.s,
            order: &self.factors.order,
            used: &self.factors.used,
            directions: self.settings.sky.directions.pow(2),
        }
    }

    /// The shell-method model at `altitude_m` on this table's grid, to compare with.
    pub fn direct_model(&self, altitude_m: f64) -> Result<SkyModel> {
        let transmittance = Arc::new(TransmittanceTable::new(&self.atmosphere));
        shell_model(&self.atmosphere, &self.settings, transmittance, altitude_m)
    }

    /// The display errors (units of epsilon) of the table against the shell method at
    /// each (sun elevation rad, altitude m) pair, one per direction and channel; pairs at
    /// the same altitude share one model, so group them for speed.
    pub fn errors_against_direct(&self, pairs: &[(f64, f64)]) -> Result<Vec<Vec<f32>>> {
        let mut altitudes: Vec<f64> = pairs.iter().map(|p| p.1).collect();
        altitudes.sort_by(f64::total_cmp);
        altitudes.dedup();
        let transmittance = Arc::new(TransmittanceTable::new(&self.atmosphere));
        let per_altitude = altitudes
            .par_iter()
            .map(|&h| {
                let model =
                    shell_model(&self.atmosphere, &self.settings, transmittance.clone(), h)?;
                pairs
                    .iter()
                    .enumerate()
                    .filter(|(_, p)| p.1 == h)
                    .map(|(k, &(sun, _))| {
                        let table = self.map(sun, h)?;
                        let direct = self.direct_map(&model, sun);
                        let errors = table
                            .iter()
                            .zip(&direct)
                            .flat_map(|(a, e)| {
                                (0..CHANNELS).map(move |c| self.settings.bound.error(a[c], e[c]))
                            })
                            .collect();
                        Ok((k, errors))
                    })
                    .collect::<Result<Vec<_>>>()
            })
            .collect::<Result<Vec<_>>>()?;
        let mut out = vec![Vec::new(); pairs.len()];
        for (k, errors) in per_altitude.into_iter().flatten() {
            out[k] = errors;
        }
        Ok(out)
    }

    /// The skylight map computed directly by `model` for a sun at `sun_elevation` rad,
    /// in the table's channels.
    pub fn direct_map(&self, model: &SkyModel, sun_elevation: f64) -> Vec<Vec3> {
        let colour = SpectrumToRgb::new(&self.atmosphere.wavelengths_nm);
        model
            .skylight_map(sun_elevation)
            .to_rgb(&colour)
            .into_iter()
            .map(Vec3::from)
            .collect()
    }
}

/// The shell method at `altitude_m` on the table's grid, with a transmittance table
/// shared between altitudes.
fn shell_model(
    atmosphere: &Atmosphere,
    settings: &TableSettings,
    transmittance: Arc<TransmittanceTable>,
    altitude_m: f64,
) -> Result<SkyModel> {
    let min_elevation = direction_grid(atmosphere, settings, altitude_m).elevation_min;
    SkyModel::with_grid(
        atmosphere,
        transmittance,
        &settings.sky,
        altitude_m,
        min_elevation,
    )
}

/// The `L x L` view grid of a table at `altitude_m`: elevations from the horizon
/// (`-phi(h)`, sky (15)) to the zenith. Unlike sky (12), whose rows start at the dip of the
/// highest altitude for every altitude, the rows follow the horizon: in the paper's grid
/// the rows between `-phi(h0)` and `-phi(h)` look at the ground from low altitudes and at
/// the sky from high ones, a jump that moves with altitude, which no interpolation
/// between altitudes can follow (up to 100 epsilon off near the horizon, measured) and
/// which costs the SVD terms.
fn direction_grid(
    atmosphere: &Atmosphere,
    settings: &TableSettings,
    altitude_m: f64,
) -> DirectionGrid {
    let l = settings.sky.directions;
    let dip = horizon_dip(atmosphere.bottom_radius_m, altitude_m);
    DirectionGrid::new(l, l, -dip, std::f64::consts::FRAC_PI_2)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn axes_locate_their_own_points_and_refuse_outside() {
        let dense = |v: f64| 1.0 + 4.0 * (-(v - 2.0f64).powi(2)).exp();
        let axes = [
            TableAxis::power(-0.2, 13.0, 9, 1.0),
            TableAxis::power(-0.2, 13.0, 9, 1.7),
            TableAxis::with_density(-0.2, 13.0, 9, dense),
        ];
        for axis in &axes {
            assert_eq!((axis.count(), axis.min(), axis.max()), (9, -0.2, 13.0));
            for i in 0..9 {
                let (j, w) = axis.locate(axis.value(i)).unwrap();
                assert!(w == 0.0 || w == 1.0, "{axis:?} {i}: {w}");
                assert_eq!(if w == 0.0 { j } else { j + 1 }, i);
            }
            let (j, w) = axis.locate(0.5 * (axis.value(3) + axis.value(4))).unwrap();
            assert_eq!(j, 3);
            assert!((w - 0.5).abs() < 1e-6);
            assert!(axis.locate(-0.21).is_none() && axis.locate(13.01).is_none());
            assert!(axis.locate(f64::NAN).is_none());
        }
        // The density puts the points where it is high: steps near 2 are ~5x shorter.
        let d = &axes[2];
        let steps: Vec<f64> = (0..8).map(|i| d.value(i + 1) - d.value(i)).collect();
        let near = (0..8)
            .find(|&i| d.value(i) <= 2.0 && d.value(i + 1) > 2.0)
            .unwrap();
        assert!(steps[near] * 3.0 < steps[7], "{steps:?}");
        assert!(steps.iter().all(|&s| s > 0.0), "{steps:?}");
    }

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
