//! A [`SkyModel`]'s sun-independent maps as flat arrays in single precision, for a GPU
//! (or any other renderer) to evaluate sky (3) and (11) per sun the way
//! [`SkyModel::skylight_map`] does: the samples of each view ray with their density x
//! attenuation maps, the light map of sunlight per shell, the transmittance table for
//! samples between shells, the scattered light of the higher orders (moments for the
//! molecules, an in-scattering table for the aerosols, the ground's irradiance), and
//! the colour matrix.
//! Spectra are packed four wavelengths to a `[f32; 4]` lane, as the CPU packs them.

use super::light_map::{SunBins, LIGHT_MAP_SIZE};
use super::maps::{lanes, ScatteringMaps};
use super::{DirectionGrid, SkyModel};
use crate::atmosphere::spectrum::SpectrumToRgb;
use crate::atmosphere::PhaseFunction;

/// Moments of the scattered light a Rayleigh in-scattering needs, per shell and sun bin
/// (`sky::shells::light_map`); the GPU's shaders read it as `MOMENTS`.
pub const MOMENTS: usize = super::light_map::MOMENTS;

/// Zenith cosines and azimuths of the aerosols' in-scattering table; the shaders'
/// `TABLE_MU` and `TABLE_PHI`.
pub const TABLE_MU: usize = super::light_map::TABLE_MU;
pub const TABLE_PHI: usize = super::light_map::TABLE_PHI;

/// The most lanes of four spectral channels a model has; the shaders' `MAX_LANES`.
pub const MAX_LANES: usize = super::maps::MAX_CHANNELS / 4;

/// The samples of a bundle of view rays, one ray per grid elevation.
#[derive(Debug, Clone)]
pub struct RayArrays {
    /// The directions: ray `j` is elevation row `j`.
    pub grid: DirectionGrid,
    /// Samples of ray `j`: `ray_start[j]..ray_start[j + 1]`.
    pub ray_start: Vec<u32>,
    /// Radius of each ray's origin, m.
    pub origin_r: Vec<f32>,
    /// Per sample: its shell (or the one below it), its fractional position between that
    /// shell and the next (0 on the shell), its altitude above the ground (m), its
    /// distance from the ray's origin (m) and the ray's zenith cosine there.
    pub shell: Vec<u32>,
    pub between: Vec<f32>,
    pub altitude: Vec<f32>,
    pub distance: Vec<f32>,
    pub mu: Vec<f32>,
    /// `[sample][lane]`: scattering coefficient x density x attenuation x quadrature
    /// weight, Rayleigh and aerosols.
    pub rayleigh: Vec<[f32; 4]>,
    pub mie: Vec<[f32; 4]>,
    /// `[ray][lane]`: ground albedo / pi x attenuation to the ground (0 off the ground).
    pub ground: Vec<[f32; 4]>,
    /// Distance to the ground of each ray, m, or -1.
    pub ground_distance: Vec<f32>,
}

/// A phase function as a kind and its asymmetry: 0 Rayleigh, 1 the paper's aerosols,
/// 2 Henyey-Greenstein, 3 Cornette-Shanks.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PhaseArrays {
    pub kind: u32,
    pub g: f32,
}

/// Everything of a model that a per-sun evaluation reads.
#[derive(Debug, Clone)]
pub struct ModelArrays {
    /// Wavelengths, and the lanes of four that hold them.
    pub channels: usize,
    pub lanes: usize,
    /// Whether the model has orders above the first.
    pub multiple: bool,
    /// Ground radius and top radius, m; the sun's angular radius, rad.
    pub bottom_m: f32,
    pub top_m: f32,
    pub sun_radius: f32,
    /// Radius of each shell, m (the first is the ground).
    pub shell_radius: Vec<f32>,
    pub ground_albedo: f32,
    pub rayleigh_phase: PhaseArrays,
    pub mie_phase: PhaseArrays,
    /// The sky's rays (elevations from the horizon up) and the ground's (below).
    pub sky: RayArrays,
    pub ground_rays: RayArrays,
    /// Sunlight per shell over `mu_s`: `[shell][entry][lane]`, `entries` a shell, entry
    /// `k` at `mu_s = mu_low + k / scale`; nothing at or below `mu_low`.
    pub light_map: Vec<[f32; 4]>,
    pub light_map_entries: usize,
    pub light_mu_low: Vec<f32>,
    pub light_scale: Vec<f32>,
    /// The solar irradiance per lane.
    pub irradiance: Vec<[f32; 4]>,
    /// Transmittance to the top: `[r][mu][lane]`, `mu_size` x `r_size`.
    pub transmittance: Vec<[f32; 4]>,
    pub mu_size: usize,
    pub r_size: usize,
    /// The moments of the scattered light of the orders below the highest, summed:
    /// `[shell][bin][moment][lane]`, `sun_bins` bins over `mu_s` spaced
    /// `x (a + (1 - a)|x|)` with `a` = `sun_bins_a`.
    pub moments: Vec<[f32; 4]>,
    /// The aerosols' in-scattering of that light, `[bin][shell][cell][lane]` with cell
    /// `mu_index * TABLE_PHI + phi_index`; empty if aerosols scatter once only.
    pub aerosol_table: Vec<[f32; 4]>,
    /// The irradiance that light puts on the ground, `[bin][lane]`.
    pub ground_irradiance: Vec<[f32; 4]>,
    pub sun_bins: usize,
    pub sun_bins_a: f32,
    /// `[lane][channel in lane][rgb]`: linear sRGB of each wavelength.
    pub to_rgb: Vec<[[f32; 3]; 4]>,
}

impl SkyModel {
    /// The model's maps as flat arrays; `None` for an atmosphere whose molecules
    /// scatter the higher orders with a phase other than Rayleigh's (the arrays carry
    /// their moments only).
    pub fn arrays(&self) -> Option<ModelArrays> {
        if self
            .light
            .higher
            .as_ref()
            .is_some_and(|h| h.tables[0].is_some())
        {
            return None;
        }
        let (a, light) = (&self.light.atmosphere, &self.light);
        let n = a.channels();
        let l = lanes(n);
        let pad = |values: &[f32]| -> Vec<[f32; 4]> {
            let mut out = vec![[0.0f32; 4]; values.len().div_ceil(n) * l];
            for (k, v) in values.iter().enumerate() {
                let (row, c) = (k / n, k % n);
                out[row * l + c / 4][c % 4] = *v;
            }
            out
        };
        let lanes_of =
            |v: &[crate::sky::shells::maps::Lane]| v.iter().map(|x| x.to_array()).collect();
        let table = &light.sunlight.table;
        let colour = SpectrumToRgb::for_atmosphere(a);
        let mut to_rgb = vec![[[0.0f32; 3]; 4]; l];
        for c in 0..n {
            for (rgb, weights) in colour.weights.iter().enumerate() {
                to_rgb[c / 4][c % 4][rgb] = weights[c];
            }
        }
        let higher = light.higher.as_ref();
        let bins = higher.map_or(SunBins { count: 2 }, |m| m.bins);
        Some(ModelArrays {
            channels: n,
            lanes: l,
            multiple: higher.is_some(),
            bottom_m: a.bottom_radius_m as f32,
            top_m: a.top_radius_m as f32,
            sun_radius: a.sun_angular_radius as f32,
            shell_radius: light.shells.radii().iter().map(|&r| r as f32).collect(),
            ground_albedo: a.ground_albedo as f32,
            rayleigh_phase: phase(&a.rayleigh.phase),
            mie_phase: phase(&a.mie.phase),
            sky: rays(&self.sky_rays, &self.sky_grid, a.bottom_radius_m, &pad),
            ground_rays: rays(
                &self.ground_rays,
                &self.ground_grid,
                a.bottom_radius_m,
                &pad,
            ),
            light_map: lanes_of(&light.sunlight.values),
            light_map_entries: LIGHT_MAP_SIZE,
            light_mu_low: light.sunlight.mu_low.iter().map(|&m| m as f32).collect(),
            light_scale: light.sunlight.scale.iter().map(|&s| s as f32).collect(),
            irradiance: pad(&light.sunlight.irradiance),
            transmittance: pad(&table.values),
            mu_size: table.mu_size,
            r_size: table.r_size,
            moments: higher.map_or(Vec::new(), |m| lanes_of(&m.moments)),
            aerosol_table: higher
                .and_then(|m| m.tables[1].as_deref())
                .map_or(Vec::new(), lanes_of),
            ground_irradiance: higher.map_or(Vec::new(), |m| pad(&m.ground_irradiance)),
            sun_bins: bins.count,
            sun_bins_a: SunBins::A as f32,
            to_rgb,
        })
    }
}

fn phase(p: &PhaseFunction) -> PhaseArrays {
    let (kind, g) = p.code();
    PhaseArrays { kind, g: g as f32 }
}

fn rays(
    maps: &ScatteringMaps,
    grid: &DirectionGrid,
    bottom: f64,
    pad: &dyn Fn(&[f32]) -> Vec<[f32; 4]>,
) -> RayArrays {
    RayArrays {
        grid: grid.clone(),
        ray_start: maps.ray_start.clone(),
        origin_r: maps.origin_r.iter().map(|&r| r as f32).collect(),
        shell: maps.shell.iter().map(|&s| s as u32).collect(),
        between: maps.between.clone(),
        altitude: maps.radius.iter().map(|&r| (r - bottom) as f32).collect(),
        distance: maps.distance.iter().map(|&d| d as f32).collect(),
        mu: maps.mu.iter().map(|&m| m as f32).collect(),
        rayleigh: maps.rayleigh.iter().map(|x| x.to_array()).collect(),
        mie: maps.mie.iter().map(|x| x.to_array()).collect(),
        ground: pad(&maps.ground),
        ground_distance: maps.ground_distance.iter().map(|&d| d as f32).collect(),
    }
}
