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
//! share `t_k`), and is truncated and randomized ([`svd`]); factors are stored in
//! 16-bit fixed point and the term counts measured on them as stored; and the table holds
//! linear sRGB radiance rather than 8-bit values, so any exposure can be drawn from it.

use std::ops::Range;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Arc;

use glam::Vec3;
use rayon::prelude::*;

mod axes;
mod draw;
mod error_bound;
mod factors;
mod file;
pub mod parts;
pub mod svd;

pub use axes::TableAxis;
pub use error_bound::ErrorBound;
pub use factors::TableFactors;
pub use parts::TablePart;

use super::grid::DirectionGrid;
use super::{ShellLight, SkyModel, SkySettings};
use crate::atmosphere::geometry::horizon_dip;
use crate::atmosphere::spectrum::SpectrumToRgb;
use crate::atmosphere::{Atmosphere, TransmittanceTable};
use crate::error::{check_positive, check_range, Error, Result};
use crate::image::{Display, ToneMap};
use factors::Factors;

/// Colour channels of the table: linear sRGB, as the paper decomposed R, G and B.
pub const CHANNELS: usize = 3;

/// Half-width of the band around the horizon where sun elevations are denser (the extra
/// density falls to 1/e there), deg: the off-grid error of evenly spaced suns peaks
/// within 5 deg of the horizon (docs/sky-table.md).
const SUN_HORIZON_WIDTH_DEG: f64 = 5.0;

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
    /// Checks every field and that the precompute fits the run's memory budget ([`crate::budget`]).
    pub fn validate(&self, atmosphere: &Atmosphere) -> Result<()> {
        self.check_fields(atmosphere)?;
        crate::budget::check(
            "the skylight table's precompute",
            self.memory_bytes(atmosphere),
            "directions, sun_steps or altitude_steps",
        )
    }

    /// Checks every field, not the precompute's memory: what a table read from a file
    /// needs (drawing from it holds the table, not its precompute, which once refused
    /// a table below 1,168 MiB that drawing needed a few MiB of).
    pub fn check_fields(&self, atmosphere: &Atmosphere) -> Result<()> {
        self.sky.validate(atmosphere)?;
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
        check_positive("exposure", self.bound.display.exposure as f64, 1e9)
    }

    /// An upper bound of the bytes the precompute holds at once: the table as maps and
    /// as one f32 matrix per channel, the stacked f64 matrix of the SVD, and the shell
    /// models of two altitudes.
    pub fn memory_bytes(&self, atmosphere: &Atmosphere) -> u64 {
        let entries = (self.sky.directions as u64).pow(2)
            * self.sun_steps as u64
            * self.altitude_steps as u64;
        (entries * (12 + 12 + 24)).saturating_add(2 * self.sky.memory_bytes(atmosphere))
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
        let total = settings.sun_steps * settings.altitude_steps;
        let maps = Self::skylight_maps(atmosphere, settings, 0..total, progress)?;
        Ok(matrices(settings, &maps))
    }

    /// The skylight maps of the columns `columns` of sky (16) (column `altitude * M +
    /// sun`), one after the other, each `L x L` linear sRGB values. A map depends on
    /// its column alone, so maps computed in parts are those of one whole run, bit for
    /// bit (each part computes the light at the shells of every altitude again).
    pub fn skylight_maps(
        atmosphere: &Atmosphere,
        settings: &TableSettings,
        columns: Range<usize>,
        progress: &(dyn Fn(usize, usize) + Sync),
    ) -> Result<Vec<[f32; 3]>> {
        settings.validate(atmosphere)?;
        let (sun, altitude) = (settings.sun_axis(), settings.altitude_axis());
        let total = sun.count() * altitude.count();
        if columns.start >= columns.end || columns.end > total {
            return Err(Error::Invalid(format!(
                "columns {columns:?} of a table with {total}"
            )));
        }
        let transmittance = Arc::new(TransmittanceTable::new(atmosphere));
        let colour = SpectrumToRgb::for_atmosphere(atmosphere);
        let done = AtomicUsize::new(0);
        // The light at the shells once, with a shell through every altitude: the
        // altitudes' models share it (the higher orders would cost seconds each).
        let altitudes: Vec<f64> = (0..altitude.count()).map(|a| altitude.value(a)).collect();
        let light = Arc::new(ShellLight::new(
            atmosphere,
            transmittance,
            &settings.sky,
            &altitudes,
        )?);
        // The model of each altitude the columns reach, then the columns in parallel
        // (a part may hold a single altitude).
        let m = sun.count();
        let first = columns.start / m;
        let models: Vec<SkyModel> = (first..=(columns.end - 1) / m)
            .into_par_iter()
            .map(|a| shared_model(atmosphere, settings, light.clone(), altitude.value(a)))
            .collect::<Result<_>>()?;
        let maps: Vec<Vec<[f32; 3]>> = columns
            .clone()
            .into_par_iter()
            .map(|column| {
                let model = &models[column / m - first];
                let map = model.skylight_map(sun.value(column % m)).to_rgb(&colour);
                progress(done.fetch_add(1, Ordering::Relaxed) + 1, columns.len());
                map
            })
            .collect();
        Ok(maps.concat())
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

    /// The light of the shell method with the table's shells (one through each of its
    /// altitudes) and one through each of `extra_altitudes_m`.
    fn direct_light(&self, extra_altitudes_m: &[f64]) -> Result<Arc<ShellLight>> {
        let axis = self.settings.altitude_axis();
        let mut altitudes: Vec<f64> = (0..axis.count()).map(|a| axis.value(a)).collect();
        altitudes.extend_from_slice(extra_altitudes_m);
        let transmittance = Arc::new(TransmittanceTable::new(&self.atmosphere));
        Ok(Arc::new(ShellLight::new(
            &self.atmosphere,
            transmittance,
            &self.settings.sky,
            &altitudes,
        )?))
    }

    /// The shell-method model at `altitude_m` on this table's grid, to compare with:
    /// at the table's altitudes, exactly the model its maps came from.
    pub fn direct_model(&self, altitude_m: f64) -> Result<SkyModel> {
        let light = self.direct_light(&[altitude_m])?;
        shared_model(&self.atmosphere, &self.settings, light, altitude_m)
    }

    /// The display errors (units of epsilon) of the table against the shell method at
    /// each (sun elevation rad, altitude m) pair, one per direction and channel; pairs at
    /// the same altitude share one model, so group them for speed.
    pub fn errors_against_direct(&self, pairs: &[(f64, f64)]) -> Result<Vec<Vec<f32>>> {
        let mut altitudes: Vec<f64> = pairs.iter().map(|p| p.1).collect();
        altitudes.sort_by(f64::total_cmp);
        altitudes.dedup();
        let light = self.direct_light(&altitudes)?;
        let per_altitude = altitudes
            .par_iter()
            .map(|&h| {
                let model = shared_model(&self.atmosphere, &self.settings, light.clone(), h)?;
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
        let colour = SpectrumToRgb::for_atmosphere(&self.atmosphere);
        model
            .skylight_map(sun_elevation)
            .to_rgb(&colour)
            .into_iter()
            .map(Vec3::from)
            .collect()
    }
}

/// The matrices of sky (16) from every column's map, as [`SkylightTable::skylight_maps`]
/// gives them: `[direction][column]` per channel.
fn matrices(settings: &TableSettings, maps: &[[f32; 3]]) -> [Vec<f32>; CHANNELS] {
    let rows = settings.sky.directions.pow(2);
    let total = maps.len() / rows;
    std::array::from_fn(|c| {
        let mut m = vec![0.0f32; rows * total];
        m.par_chunks_mut(total).enumerate().for_each(|(d, row)| {
            for (column, v) in row.iter_mut().enumerate() {
                *v = maps[column * rows + d][c];
            }
        });
        m
    })
}

/// The model at `altitude_m` on the table's grid, reading the shared `light`.
fn shared_model(
    atmosphere: &Atmosphere,
    settings: &TableSettings,
    light: Arc<ShellLight>,
    altitude_m: f64,
) -> Result<SkyModel> {
    let min_elevation = direction_grid(atmosphere, settings, altitude_m).elevation_min;
    SkyModel::with_light(light, altitude_m, min_elevation)
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
