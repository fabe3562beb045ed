//! The shell method, sky section 3: the atmosphere cut by sampling shells (3.2), the
//! light scattered toward the viewer as the sum over the shells of four maps (light,
//! phase, density, attenuation, sky (3)-(9)), and the second order from the light map of
//! first-order scattered light, sky (10)-(11).
//!
//! [`SkyModel`] holds everything that does not depend on the sun for one viewpoint
//! altitude: the sampling shells (`sampling_shells`), the density x attenuation maps of
//! the view rays (`maps`), and the light maps (`light_map`); [`SkyModel::skylight_map`]
//! then gives the skylight map for any sun elevation with lookups only. See docs/sky.md
//! for the derivation and the choices made beyond the paper. [`export`] lays the
//! sun-independent arrays out flat for the GPU.

pub mod export;
pub(crate) mod light_map;
pub(crate) mod maps;
pub(crate) mod sampling_shells;

use std::sync::Arc;

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::DirectionGrid;
use crate::atmosphere::geometry::horizon_dip;
use crate::atmosphere::spectrum::SpectrumToRgb;
use crate::atmosphere::{Atmosphere, TransmittanceTable};
use crate::error::{check_range, Error, Result};
use light_map::{LightMap, ScatteredLightMap, SPECIES};
use maps::{Orders, ScatteringMaps, Sources, SunGeometry};
use sampling_shells::SamplingShells;

/// Cosine of the angle between the view direction at `azimuth` from the sun and
/// `elevation`, and the sun at `sun_elevation` (all rad).
pub(crate) fn cos_to_sun(azimuth: f64, elevation: f64, sun_elevation: f64) -> f64 {
    elevation.cos() * azimuth.cos() * sun_elevation.cos() + elevation.sin() * sun_elevation.sin()
}

/// How far below the horizon's dip the ground map starts, rad (0.006 deg).
const GROUND_EDGE_RAD: f64 = 1e-4;

/// The highest scattering order the sky carries.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize)]
#[serde(try_from = "OrderSpec", into = "OrderSpec")]
pub enum Order {
    /// Orders 1 to n (the paper: 2).
    Through(u32),
    /// Every order: orders are added until the next one adds less than
    /// [`ALL_ORDERS_TOLERANCE`] of the scattered light anywhere (at most [`MAX_ORDER`]).
    All,
}

/// The most orders a model computes.
pub const MAX_ORDER: u32 = 60;

/// With [`Order::All`], the share of the light arriving at any shell, from any
/// direction, at any sun and wavelength, below which the next order is not added.
pub const ALL_ORDERS_TOLERANCE: f64 = 1e-3;

/// With [`Order::All`], the share of the light the latest order adds anywhere below
/// which the remaining orders are summed as a geometric series
/// (`ScatteredLightMap::geometric_tail`) instead of one by one: by then each order
/// is within 2 % of the same fraction of the one before (Earth: 0.38 to 0.37 from the
/// fourth order on), and the sky differs from twenty orders summed one by one by under
/// 0.1 % (`every_order_equals_twenty_orders`).
pub const GEOMETRIC_TAIL_SHARE: f64 = 0.05;

/// How an order is written in settings files and JSON: a number or "all".
#[derive(Deserialize, Serialize)]
#[serde(untagged)]
enum OrderSpec {
    Number(u32),
    Word(String),
}

impl TryFrom<OrderSpec> for Order {
    type Error = String;
    fn try_from(spec: OrderSpec) -> std::result::Result<Self, String> {
        match spec {
            OrderSpec::Number(n) => Ok(Order::Through(n)),
            OrderSpec::Word(w) => w.parse().map_err(|e: Error| e.to_string()),
        }
    }
}

impl From<Order> for OrderSpec {
    fn from(order: Order) -> Self {
        match order {
            Order::Through(n) => OrderSpec::Number(n),
            Order::All => OrderSpec::Word("all".into()),
        }
    }
}

impl std::str::FromStr for Order {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        if s == "all" {
            return Ok(Order::All);
        }
        s.parse::<u32>().map(Order::Through).map_err(|_| {
            Error::Invalid(format!(
                "order = {s:?} is not an order: allowed 1 to {MAX_ORDER}, or \"all\""
            ))
        })
    }
}

impl std::fmt::Display for Order {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Order::Through(n) => write!(f, "{n}"),
            Order::All => f.write_str("all"),
        }
    }
}

impl Order {
    /// The most orders this asks for.
    pub fn most(&self) -> u32 {
        match self {
            Order::Through(n) => *n,
            Order::All => MAX_ORDER,
        }
    }
}

/// Quality settings of the shell method. The default is the truest sky atmo makes:
/// every scattering order, aerosols scattering them too; [`SkySettings::paper`] is the
/// paper's second order of Rayleigh scattering.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SkySettings {
    /// Sampling shells `K` from the ground to the top (sky 3.2; paper: 40).
    pub shells: usize,
    /// View directions per axis `L` of the skylight map (sky (11)-(12); paper: 64).
    pub directions: usize,
    /// Directions `N_omega` of the second-order quadrature (sky (11); paper: 15),
    /// rounded to the nearest double-Gauss layout. With Rayleigh's five moments they
    /// cost nothing per sun; 128 holds the second order within 2 % of the reference,
    /// the paper's 15 is up to 7.6 % off at sunset (docs/sky.md).
    pub scattering_directions: usize,
    /// Sun zenith bins of the scattered light maps.
    pub sun_bins: usize,
    /// Highest scattering order, 1 to [`MAX_ORDER`] or all (paper: 2).
    pub order: Order,
    /// Whether aerosols scatter the orders above the first (paper: no, Rayleigh only).
    pub multiple_mie: bool,
    /// Longest interval between samples along a ray, m: longer ones (near-horizontal
    /// rays near their lowest point cross successive shells up to 135 km apart) are
    /// split by sub-samples between the shells. Not in the paper.
    pub max_interval_m: f64,
}

impl Default for SkySettings {
    fn default() -> Self {
        SkySettings {
            shells: 40,
            directions: 64,
            scattering_directions: 128,
            sun_bins: 64,
            order: Order::All,
            multiple_mie: true,
            max_interval_m: 10_000.0,
        }
    }
}

impl SkySettings {
    /// The paper's orders: single scattering and the second order of molecules (sky
    /// (10)-(11)), aerosols scattering only the first; the quadrature as the default's.
    pub fn paper() -> Self {
        SkySettings {
            order: Order::Through(2),
            multiple_mie: false,
            ..SkySettings::default()
        }
    }
}

impl SkySettings {
    /// Checks every field, and that the maps for `atmosphere` fit the run's memory
    /// budget ([`crate::budget`]).
    pub fn validate(&self, atmosphere: &Atmosphere) -> Result<()> {
        check_range("shells", self.shells as f64, 2.0, 2000.0)?;
        check_range("directions", self.directions as f64, 2.0, 4096.0)?;
        check_range(
            "scattering_directions",
            self.scattering_directions as f64,
            1.0,
            4096.0,
        )?;
        check_range("sun_bins", self.sun_bins as f64, 4.0, 4096.0)?;
        check_range("order", self.order.most() as f64, 1.0, MAX_ORDER as f64)?;
        check_range("max_interval_m", self.max_interval_m, 100.0, 1e7)?;
        crate::budget::check(
            &format!("the sky maps of {}", atmosphere.name),
            self.memory_bytes(atmosphere),
            "directions, shells, scattering_directions or sun_bins, or raise max_interval_m (--max-interval)",
        )
    }

    /// An upper bound of the bytes the maps of one model take in `atmosphere`.
    pub fn memory_bytes(&self, atmosphere: &Atmosphere) -> u64 {
        let (k, l, nd, b, n) = (
            self.shells as u64 + 1,
            self.directions as u64,
            self.scattering_directions as u64,
            self.sun_bins as u64,
            atmosphere.channels() as u64,
        );
        // A ray crosses each shell at most twice, and sub-samples split the intervals
        // between crossings: at most the longest chord (tangent to the ground) over
        // max_interval_m of them along one ray. A sample
        // holds 2 maps per channel + 18 B, and the maps of all rays are held twice
        // while they are gathered.
        let (rb, rt) = (atmosphere.bottom_radius_m, atmosphere.top_radius_m);
        let chord = 2.0 * (rt * rt - rb * rb).sqrt();
        let per_ray = 2 * k + (chord / self.max_interval_m).ceil() as u64;
        let sample = 8 * n + 18;
        let view_rays = 2 * l;
        let light_rays = k * nd;
        let samples = (view_rays + light_rays)
            .saturating_mul(per_ray)
            .saturating_mul(2 * sample);
        // While orders are built: the sum, the last order and the next, each with its
        // radiance, moments and an aerosol table.
        let tables = if self.multiple_mie {
            (light_map::TABLE_MU * light_map::TABLE_PHI) as u64
        } else {
            0
        };
        let light_maps = if self.order.most() >= 2 {
            3 * k * b * (nd + 8 + tables) * n * 4
        } else {
            0
        };
        let skylight = 2 * l * l * n * 4;
        samples
            .saturating_add(light_maps)
            .saturating_add(skylight + k * 512 * n * 4)
    }
}

/// A skylight map: radiance per wavelength over a [`DirectionGrid`], sky (3.2).
#[derive(Debug, Clone)]
pub struct SkylightMap {
    /// The directions the map is sampled at.
    pub grid: DirectionGrid,
    /// Wavelengths per entry.
    pub channels: usize,
    /// `[elevation][azimuth][channel]`, radiance.
    pub radiance: Vec<f32>,
}

impl SkylightMap {
    /// Radiance per channel at grid point (azimuth index `i`, elevation index `j`).
    pub fn at(&self, i: usize, j: usize) -> &[f32] {
        let at = (j * self.grid.azimuths + i) * self.channels;
        &self.radiance[at..at + self.channels]
    }

    /// The map converted to linear sRGB, `[elevation][azimuth]`.
    pub fn to_rgb(&self, colour: &SpectrumToRgb) -> Vec<[f32; 3]> {
        self.radiance
            .chunks(self.channels)
            .map(|l| colour.rgb(l))
            .collect()
    }
}

/// View rays of a [`SkyModel`] at given elevations, sampled through the shells
/// ([`SkyModel::view_rays`]): what the radiance along them needs of the viewpoint,
/// kept for many suns and azimuths.
pub struct ViewRays {
    maps: ScatteringMaps,
    elevations: Vec<f64>,
}

impl ViewRays {
    /// How many rays.
    pub fn len(&self) -> usize {
        self.elevations.len()
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.elevations.is_empty()
    }
}

/// The light in the atmosphere that depends on neither the sun's position nor the
/// viewpoint's direction: the sampling shells (with one through each viewpoint it
/// serves), the light map of sunlight and the scattered light of the higher orders
/// arriving at the shells. One serves the [`SkyModel`]s of many altitudes (a skylight
/// table's), which then only add their view rays.
pub struct ShellLight {
    atmosphere: Atmosphere,
    settings: SkySettings,
    transmittance: Arc<TransmittanceTable>,
    shells: SamplingShells,
    sunlight: LightMap,
    /// The scattered light of orders 1 to `orders - 1` arriving at the shells, whose
    /// scattering makes orders 2 to `orders`; none for single scattering.
    higher: Option<ScatteredLightMap>,
    /// The highest order computed.
    orders: u32,
}

impl ShellLight {
    /// The light for viewpoints at `altitudes_m` (each in [0, top)), with a given
    /// transmittance table.
    pub fn new(
        atmosphere: &Atmosphere,
        transmittance: Arc<TransmittanceTable>,
        settings: &SkySettings,
        altitudes_m: &[f64],
    ) -> Result<Self> {
        let extra = SkySettings {
            shells: settings.shells + altitudes_m.len().saturating_sub(1),
            ..settings.clone()
        };
        extra.validate(atmosphere)?;
        let top = atmosphere.thickness_m();
        for &h in altitudes_m {
            if !(h.is_finite() && (0.0..top).contains(&h)) {
                return Err(Error::out_of_range("altitude_m", h, &format!("[0, {top})")));
            }
        }
        let shells = SamplingShells::new(atmosphere, settings.shells, altitudes_m);
        let sunlight = LightMap::new(atmosphere, transmittance.clone(), &shells);
        let (higher, orders) = if settings.order.most() >= 2 {
            let (map, orders) = higher_orders(atmosphere, settings, &shells, &sunlight);
            (Some(map), orders)
        } else {
            (None, 1)
        };
        Ok(ShellLight {
            atmosphere: atmosphere.clone(),
            settings: settings.clone(),
            transmittance,
            shells,
            sunlight,
            higher,
            orders,
        })
    }
}

/// Everything about the sky at one viewpoint altitude that does not depend on the sun.
pub struct SkyModel {
    light: Arc<ShellLight>,
    altitude_m: f64,
    /// The shell through the viewpoint.
    viewpoint: usize,
    /// The sky grid (elevation from the horizon's dip to the zenith) and its view rays,
    /// one per elevation: the maps do not depend on the azimuth.
    sky_grid: DirectionGrid,
    sky_rays: ScatteringMaps,
    /// Rays below the horizon, which end on the ground, for pictures.
    ground_grid: DirectionGrid,
    ground_rays: ScatteringMaps,
}

impl SkyModel {
    /// The model at `altitude_m` above the ground, with the paper's skylight grid
    /// (elevations from minus the horizon's dip to the zenith, sky (12), (15)).
    pub fn new(atmosphere: &Atmosphere, settings: &SkySettings, altitude_m: f64) -> Result<Self> {
        let table = Arc::new(TransmittanceTable::new(atmosphere));
        let dip = horizon_dip(atmosphere.bottom_radius_m, altitude_m.max(0.0));
        Self::with_grid(atmosphere, table, settings, altitude_m, -dip)
    }

    /// The model with a given transmittance table (shared between altitudes) and a
    /// skylight grid starting at `min_elevation` rad (a fixed `-phi(h0)` for tables
    /// over many altitudes, sky (12)).
    pub fn with_grid(
        atmosphere: &Atmosphere,
        transmittance: Arc<TransmittanceTable>,
        settings: &SkySettings,
        altitude_m: f64,
        min_elevation: f64,
    ) -> Result<Self> {
        let light = ShellLight::new(atmosphere, transmittance, settings, &[altitude_m])?;
        Self::with_light(Arc::new(light), altitude_m, min_elevation)
    }

    /// The model at `altitude_m`, one of `light`'s viewpoints, with a skylight grid
    /// starting at `min_elevation` rad.
    pub fn with_light(light: Arc<ShellLight>, altitude_m: f64, min_elevation: f64) -> Result<Self> {
        let atmosphere = &light.atmosphere;
        let shells = &light.shells;
        let viewpoint = shells.index_of(atmosphere, altitude_m).ok_or_else(|| {
            Error::Invalid(format!(
                "altitude_m = {altitude_m} is not a viewpoint the sky's light was made for"
            ))
        })?;
        let l = light.settings.directions;
        let dip = horizon_dip(atmosphere.bottom_radius_m, altitude_m);
        let sky_grid = DirectionGrid::new(l, l, min_elevation, std::f64::consts::FRAC_PI_2);
        // The ground grid's top row is the horizon approached from below: rays that hit
        // the ground, not the grazing ray that escapes to the sky.
        let ground_top = -dip - GROUND_EDGE_RAD;
        let ground_grid =
            DirectionGrid::new(l, l.div_ceil(2), -std::f64::consts::FRAC_PI_2, ground_top);
        let rays_of = |grid: &DirectionGrid| -> Vec<(usize, f64)> {
            (0..grid.elevations)
                .map(|j| (viewpoint, grid.elevation(j).sin()))
                .collect()
        };
        let max = light.settings.max_interval_m;
        let sky_rays = ScatteringMaps::new(atmosphere, shells, &rays_of(&sky_grid), max);
        let ground_rays = ScatteringMaps::new(atmosphere, shells, &rays_of(&ground_grid), max);
        Ok(SkyModel {
            light,
            altitude_m,
            viewpoint,
            sky_grid,
            sky_rays,
            ground_grid,
            ground_rays,
        })
    }

    /// The viewpoint altitude, m.
    pub fn altitude_m(&self) -> f64 {
        self.altitude_m
    }

    /// The atmosphere the model was built for.
    pub fn atmosphere(&self) -> &Atmosphere {
        &self.light.atmosphere
    }

    /// The settings the model was built with.
    pub fn settings(&self) -> &SkySettings {
        &self.light.settings
    }

    /// The direction grids of the skylight map and of the ground map.
    pub fn grids(&self) -> (&DirectionGrid, &DirectionGrid) {
        (&self.sky_grid, &self.ground_grid)
    }

    /// The light the model reads, shared with other altitudes' models.
    pub fn light(&self) -> &Arc<ShellLight> {
        &self.light
    }

    /// Samples (shell crossings and sub-samples) along the sky grid's view rays, one
    /// ray per elevation; a map evaluates each for every azimuth.
    pub fn view_samples(&self) -> usize {
        self.sky_rays.samples()
    }

    /// The skylight map for a sun at `sun_elevation` rad, orders 1 to the model's order:
    /// the sum over the shells of sky (3), plus sky (11) for the higher orders.
    pub fn skylight_map(&self, sun_elevation: f64) -> SkylightMap {
        self.map(
            &self.sky_grid,
            &self.sky_rays,
            sun_elevation,
            self.all_orders(),
        )
    }

    /// The skylight map of single scattering only (`multiple` false), or of the higher
    /// orders only (`single` false).
    pub fn skylight_map_parts(
        &self,
        sun_elevation: f64,
        single: bool,
        multiple: bool,
    ) -> SkylightMap {
        self.map(
            &self.sky_grid,
            &self.sky_rays,
            sun_elevation,
            Orders { single, multiple },
        )
    }

    /// The highest scattering order the model carries (with [`Order::All`], where the
    /// orders converged).
    pub fn orders(&self) -> u32 {
        self.light.orders
    }

    /// The map of the directions below the horizon, which end on the ground.
    pub fn ground_map(&self, sun_elevation: f64) -> SkylightMap {
        self.map(
            &self.ground_grid,
            &self.ground_rays,
            sun_elevation,
            self.all_orders(),
        )
    }

    pub(crate) fn all_orders(&self) -> Orders {
        Orders {
            single: true,
            multiple: true,
        }
    }

    fn map(
        &self,
        grid: &DirectionGrid,
        rays: &ScatteringMaps,
        sun_elevation: f64,
        orders: Orders,
    ) -> SkylightMap {
        let n = self.atmosphere().channels();
        let sources = self.sources();
        let sin_s = sun_elevation.sin();
        let mut radiance = vec![0.0f32; grid.azimuths * grid.elevations * n];
        radiance
            .par_chunks_mut(grid.azimuths * n)
            .enumerate()
            .for_each(|(j, row)| {
                let elevation = grid.elevation(j);
                for (i, out) in row.chunks_mut(n).enumerate() {
                    let nu = cos_to_sun(grid.azimuth(i), elevation, sun_elevation);
                    rays.radiance(j, SunGeometry { mu_s: sin_s, nu }, &sources, orders, out);
                }
            });
        SkylightMap {
            grid: grid.clone(),
            channels: n,
            radiance,
        }
    }

    /// Maps of rays from the viewpoint with zenith cosines `mus`, each marked at the
    /// distances `marks` (m, increasing; for the aerial perspective).
    pub(crate) fn marked_rays(&self, mus: &[f64], marks: &[f64]) -> ScatteringMaps {
        let rays: Vec<(usize, f64)> = mus.iter().map(|&mu| (self.viewpoint, mu)).collect();
        let light = &self.light;
        ScatteringMaps::with_marks(
            &light.atmosphere,
            &light.shells,
            &rays,
            light.settings.max_interval_m,
            marks,
        )
    }

    /// Radiance per wavelength along arbitrary directions, given as (azimuth from the
    /// sun, elevation) in rad, by the same shell sums as the map but without
    /// interpolation between grid directions. Directions below the horizon end on the
    /// ground. Returns one spectrum per direction.
    pub fn radiance_along(&self, sun_elevation: f64, directions: &[(f64, f64)]) -> Vec<Vec<f32>> {
        let elevations: Vec<f64> = directions.iter().map(|&(_, e)| e).collect();
        let rays = self.view_rays(&elevations);
        let n = self.atmosphere().channels();
        directions
            .par_iter()
            .enumerate()
            .map(|(k, &(azimuth, _))| {
                let mut out = vec![0.0f32; n];
                self.radiance_on(&rays, k, sun_elevation, azimuth, &mut out);
                out
            })
            .collect()
    }

    /// The view rays from the viewpoint at `elevations` (rad, below the horizon too),
    /// sampled once for any number of suns and azimuths ([`SkyModel::radiance_on`]):
    /// the part of [`SkyModel::radiance_along`] that depends on neither.
    pub fn view_rays(&self, elevations: &[f64]) -> ViewRays {
        let view = self.viewpoint;
        let rays: Vec<(usize, f64)> = elevations.iter().map(|&e| (view, e.sin())).collect();
        let light = &self.light;
        ViewRays {
            maps: ScatteringMaps::new(
                &light.atmosphere,
                &light.shells,
                &rays,
                light.settings.max_interval_m,
            ),
            elevations: elevations.to_vec(),
        }
    }

    /// Radiance per wavelength written into `out` (one a channel) along view ray `ray` of
    /// `rays`, at `azimuth` rad from the sun's, for a sun at `sun_elevation` rad: every
    /// order the model carries, the sun's disc left out.
    pub fn radiance_on(
        &self,
        rays: &ViewRays,
        ray: usize,
        sun_elevation: f64,
        azimuth: f64,
        out: &mut [f32],
    ) {
        let nu = cos_to_sun(azimuth, rays.elevations[ray], sun_elevation);
        let geometry = SunGeometry {
            mu_s: sun_elevation.sin(),
            nu,
        };
        out.fill(0.0);
        rays.maps
            .radiance(ray, geometry, &self.sources(), self.all_orders(), out);
    }

    pub(crate) fn sources(&self) -> Sources<'_> {
        Sources {
            atmosphere: &self.light.atmosphere,
            shells: &self.light.shells,
            sunlight: &self.light.sunlight,
            higher: self.light.higher.as_ref(),
        }
    }

    /// Radiance per wavelength of the sun's disc seen from the viewpoint (no limb
    /// darkening): irradiance / (pi alpha^2), through the atmosphere.
    pub fn sun_radiance(&self, sun_elevation: f64, out: &mut [f32]) {
        let r = self.light.atmosphere.bottom_radius_m + self.altitude_m;
        self.light.transmittance.to_sun(r, sun_elevation.sin(), out);
        sun_disc_radiance(&self.light.atmosphere, out);
    }
}

/// The scattered light of orders 1 to N - 1 arriving at the shells, summed, and N:
/// each order's light is integrated along the light rays from the order below it
/// (sky (10)-(11) repeated), until `settings.order` or, for [`Order::All`], until an
/// order adds less than [`ALL_ORDERS_TOLERANCE`] anywhere, or less than
/// [`GEOMETRIC_TAIL_SHARE`] and the rest is a geometric series (N then counts the
/// orders computed one by one). The molecules scatter every
/// order, the aerosols too with `multiple_mie`; a bright ground reflects every order.
fn higher_orders(
    atmosphere: &Atmosphere,
    settings: &SkySettings,
    shells: &SamplingShells,
    sunlight: &LightMap,
) -> (ScatteredLightMap, u32) {
    let (rules, rays) = ScatteredLightMap::rays(
        atmosphere,
        shells,
        settings.scattering_directions,
        settings.max_interval_m,
    );
    let scatters: [bool; SPECIES] = [true, settings.multiple_mie];
    let build = |orders, higher: Option<&ScatteredLightMap>| {
        let sources = Sources {
            atmosphere,
            shells,
            sunlight,
            higher,
        };
        ScatteredLightMap::new(&rules, &rays, &sources, orders, settings.sun_bins, scatters)
    };
    let single = Orders {
        single: true,
        multiple: false,
    };
    let multiple = Orders {
        single: false,
        multiple: true,
    };
    let mut last = build(single, None);
    let mut sum = last.clone();
    let mut order = 2;
    while order < settings.order.most() {
        let next = build(multiple, Some(&last));
        let share = sum.largest_share(&next);
        sum.add(&next);
        order += 1;
        if settings.order == Order::All {
            if share < ALL_ORDERS_TOLERANCE {
                break;
            }
            if share < GEOMETRIC_TAIL_SHARE {
                sum.add(&next.geometric_tail(&last, &rules, atmosphere));
                break;
            }
        }
        last = next;
    }
    sum.drop_values();
    (sum, order)
}

/// Turns the transmittance to the sun `out` into the radiance of the sun's disc:
/// irradiance / (pi alpha^2) x transmittance (no limb darkening).
pub(crate) fn sun_disc_radiance(atmosphere: &Atmosphere, out: &mut [f32]) {
    let solid_angle = std::f64::consts::PI * atmosphere.sun_angular_radius.powi(2);
    for (o, e) in out.iter_mut().zip(&atmosphere.solar_irradiance) {
        *o *= (*e / solid_angle) as f32;
    }
}
