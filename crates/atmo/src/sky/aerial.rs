//! Aerial perspective: the light between the eye and a point at a distance, so that
//! terrain, objects and clouds are hazed by the same atmosphere as the sky. Seen from
//! the eye, a point at distance `d` along a direction shows `T(d) L_point + S(d)`: its
//! own radiance `L_point` times the transmittance `T(d)`, plus the light `S(d)` scattered
//! toward the eye between them (every order the model carries).
//!
//! Both come from the shell method's view rays cut at `d` (sky (3) summed up to the
//! point): [`SkyModel::aerial`] for any directions and distances, and [`AerialRays`],
//! the rays of a grid of elevations marked at fixed slice distances, which fills a
//! camera-aligned 3-D table ([`Froxels`]) for a sun in a few milliseconds.

use glam::{DVec3, Vec3};
use rayon::prelude::*;

use super::frame::sky_from_world;
use super::shells::cos_to_sun;
use super::shells::maps::MAX_CHANNELS;
use super::shells::maps::{pack, Lane, ScatteringMaps, SunGeometry, MAX_LANES};
use super::SkyModel;
use crate::atmosphere::spectrum::SpectrumToRgb;
use crate::atmosphere::Atmosphere;
use crate::error::{check_range, Error, Result};
use crate::view::{Camera, Sun};

/// Transmittance and in-scattered radiance per wavelength from the eye to a point.
#[derive(Debug, Clone, PartialEq)]
pub struct AerialLight {
    /// Transmittance from the eye to the point, per wavelength, in (0, 1].
    pub transmittance: Vec<f32>,
    /// Radiance scattered toward the eye between it and the point, per wavelength (the
    /// atmosphere's radiance units).
    pub inscatter: Vec<f32>,
}

impl AerialLight {
    /// As linear sRGB: (transmittance of sunlight-coloured light, in-scattered radiance).
    pub fn rgb(&self, atmosphere: &Atmosphere) -> (Vec3, Vec3) {
        AerialColour::new(atmosphere).rgb(&self.transmittance, &self.inscatter)
    }
}

/// Spectra of the aerial perspective to linear sRGB: radiance through the colour
/// matching functions, transmittance as that of sunlight-coloured light (each
/// wavelength weighted by the solar spectrum).
struct AerialColour {
    colour: SpectrumToRgb,
    solar: Vec<f32>,
    white: Vec3,
}

impl AerialColour {
    fn new(atmosphere: &Atmosphere) -> Self {
        let colour = SpectrumToRgb::for_atmosphere(atmosphere);
        let solar: Vec<f32> = atmosphere
            .solar_irradiance
            .iter()
            .map(|&e| e as f32)
            .collect();
        let white = Vec3::from(colour.rgb(&solar)).max(Vec3::splat(1e-30));
        AerialColour {
            colour,
            solar,
            white,
        }
    }

    /// (transmittance, in-scattered radiance) as linear sRGB.
    fn rgb(&self, transmittance: &[f32], inscatter: &[f32]) -> (Vec3, Vec3) {
        let mut lit = [0.0f32; MAX_CHANNELS];
        for (o, (t, e)) in lit.iter_mut().zip(transmittance.iter().zip(&self.solar)) {
            *o = t * e;
        }
        let lit = &lit[..transmittance.len()];
        (
            Vec3::from(self.colour.rgb(lit)) / self.white,
            Vec3::from(self.colour.rgb(inscatter)),
        )
    }
}

impl SkyModel {
    /// The aerial perspective along the direction at `azimuth` from the sun and
    /// `elevation` (rad), sun at `sun_elevation` rad, to each of `distances_m` (m,
    /// increasing, >= 0). Past the ground or the top of the atmosphere the values stay
    /// those of the whole ray (without the ground's own light).
    pub fn aerial(
        &self,
        sun_elevation: f64,
        azimuth: f64,
        elevation: f64,
        distances_m: &[f64],
    ) -> Result<Vec<AerialLight>> {
        check_distances(distances_m)?;
        let maps = self.marked_rays(&[elevation.sin()], distances_m);
        let nu = cos_to_sun(azimuth, elevation, sun_elevation);
        let n = self.atmosphere().channels();
        let k = distances_m.len();
        let (mut inscatter, mut transmittance) = (vec![0.0; k * n], vec![0.0; k * n]);
        maps.radiance_at_marks(
            0,
            SunGeometry {
                mu_s: sun_elevation.sin(),
                nu,
            },
            &self.sources(),
            self.all_orders(),
            &mut inscatter,
            &mut transmittance,
        );
        Ok(inscatter
            .chunks(n)
            .zip(transmittance.chunks(n))
            .map(|(s, t)| AerialLight {
                transmittance: t.to_vec(),
                inscatter: s.to_vec(),
            })
            .collect())
    }

    /// [`SkyModel::aerial`] along the world direction `direction` (any length) for
    /// `sun`.
    pub fn aerial_along(
        &self,
        sun: Sun,
        direction: Vec3,
        distances_m: &[f64],
    ) -> Result<Vec<AerialLight>> {
        let d = sky_from_world(direction.normalize_or(Vec3::Y)).as_dvec3();
        let s = sky_from_world(sun.toward()).as_dvec3();
        let (h, hs) = (
            d.truncate().normalize_or_zero(),
            s.truncate().normalize_or_zero(),
        );
        let azimuth = h.dot(hs).clamp(-1.0, 1.0).acos();
        self.aerial(
            sun.elevation(),
            azimuth,
            d.z.clamp(-1.0, 1.0).asin(),
            distances_m,
        )
    }

    /// The rays of `rows` elevations from the nadir to the zenith, marked at the slice
    /// distances `slices_m` (m, increasing): what [`AerialRays::froxels`] reads.
    pub fn aerial_rays(&self, rows: usize, slices_m: &[f64]) -> Result<AerialRays> {
        check_range("aerial rows", rows as f64, 2.0, 4096.0)?;
        check_distances(slices_m)?;
        let mus: Vec<f64> = (0..rows).map(|j| row_elevation(j, rows).sin()).collect();
        Ok(AerialRays {
            rows,
            bottom_m: self.atmosphere().bottom_radius_m,
            slices_m: slices_m.to_vec(),
            maps: self.marked_rays(&mus, slices_m),
        })
    }
}

fn check_distances(distances_m: &[f64]) -> Result<()> {
    check_range("aerial slices", distances_m.len() as f64, 1.0, 1024.0)?;
    for (k, &d) in distances_m.iter().enumerate() {
        check_range(&format!("distance_m[{k}]"), d, 0.0, 1e8)?;
        if k > 0 && d <= distances_m[k - 1] {
            return Err(Error::Invalid(format!(
                "distance_m[{k}] = {d}: distances must increase"
            )));
        }
    }
    Ok(())
}

/// Elevation of row `j` of `rows`, rad: uniform from the nadir to the zenith.
fn row_elevation(j: usize, rows: usize) -> f64 {
    -std::f64::consts::FRAC_PI_2 + std::f64::consts::PI * j as f64 / (rows - 1) as f64
}

/// Slice distances for froxels: `depth` slices out to `far_m`, spaced quadratically
/// (`far (k + 1)^2 / depth^2`: finer near the eye, where the haze changes fastest
/// across the picture).
pub fn quadratic_slices(depth: usize, far_m: f64) -> Vec<f64> {
    (1..=depth)
        .map(|k| far_m * (k as f64 / depth as f64).powi(2))
        .collect()
}

/// The sun-independent rays of a grid of elevations, marked at slice distances.
pub struct AerialRays {
    rows: usize,
    /// The ground's radius, m.
    bottom_m: f64,
    slices_m: Vec<f64>,
    maps: ScatteringMaps,
}

/// A camera-aligned 3-D table of the aerial perspective: for each pixel column of a
/// `width x height` grid over the camera's picture and each slice distance, the
/// in-scattered radiance and the transmittance as linear sRGB.
#[derive(Debug, Clone)]
pub struct Froxels {
    pub width: u32,
    pub height: u32,
    /// Distance of each slice from the eye, m.
    pub slices_m: Vec<f64>,
    /// `[slice][row][column]`, linear sRGB radiance.
    pub inscatter: Vec<Vec3>,
    /// `[slice][row][column]`, transmittance per linear-sRGB channel (of sunlight-
    /// coloured light: each wavelength weighted by the solar spectrum).
    pub transmittance: Vec<Vec3>,
}

impl AerialRays {
    /// The froxels of `camera` (its width and height are the table's) for `sun`: each
    /// column's direction through the centre of its pixel, the ray of the nearest
    /// elevation row evaluated at its angle to the sun (512 rows keep it within 1.4 % of
    /// the column's own ray; interpolating two rows of 128 was 4 % off and twice the
    /// time).
    pub fn froxels(&self, model: &SkyModel, sun: Sun, camera: &Camera) -> Froxels {
        let atmosphere = model.atmosphere();
        let n = atmosphere.channels();
        let depth = self.slices_m.len();
        let (w, h) = (camera.width, camera.height);
        let colour = AerialColour::new(atmosphere);
        let sources = model.sources();
        let orders = model.all_orders();
        let mu_s = sun.elevation().sin();
        let columns = self.columns(sun, camera);
        let columns: Vec<(Vec<Vec3>, Vec<Vec3>)> = columns
            .into_par_iter()
            .map_init(
                || [(); 2].map(|_| vec![0.0f32; depth * n]),
                |[inscatter, transmittance], (row, nu)| {
                    let geometry = SunGeometry { mu_s, nu };
                    self.maps.radiance_at_marks(
                        row,
                        geometry,
                        &sources,
                        orders,
                        inscatter,
                        transmittance,
                    );
                    let mut out_s = vec![Vec3::ZERO; depth];
                    let mut out_t = vec![Vec3::ZERO; depth];
                    for s in 0..depth {
                        (out_t[s], out_s[s]) = colour.rgb(
                            &transmittance[s * n..(s + 1) * n],
                            &inscatter[s * n..(s + 1) * n],
                        );
                    }
                    (out_s, out_t)
                },
            )
            .collect();
        let plane = (w * h) as usize;
        let (mut inscatter, mut transmittance) = (
            vec![Vec3::ZERO; depth * plane],
            vec![Vec3::ZERO; depth * plane],
        );
        for (k, (s, t)) in columns.into_iter().enumerate() {
            for slice in 0..depth {
                inscatter[slice * plane + k] = s[slice];
                transmittance[slice * plane + k] = t[slice];
            }
        }
        Froxels {
            width: w,
            height: h,
            slices_m: self.slices_m.clone(),
            inscatter,
            transmittance,
        }
    }

    /// For each froxel column of `camera` (row by row): the elevation row whose ray it
    /// reads, the nearest to the direction through the centre of its pixel (512 rows
    /// keep it within 1.4 % of the column's own ray; interpolating two rows of 128 was
    /// 4 % off and twice the time), and the cosine of its angle to `sun`.
    pub fn columns(&self, sun: Sun, camera: &Camera) -> Vec<(usize, f64)> {
        let basis = camera.pixel_basis().rotated(sky_from_world);
        let sun_sky = sky_from_world(sun.toward()).as_dvec3();
        let w = camera.width;
        (0..w * camera.height)
            .map(|k| {
                let d = basis
                    .direction(k % w, k / w)
                    .map_or(DVec3::Z, |d| d.as_dvec3().normalize());
                let x = (d.z.clamp(-1.0, 1.0).asin() + std::f64::consts::FRAC_PI_2)
                    / std::f64::consts::PI
                    * (self.rows - 1) as f64;
                ((x.round() as usize).min(self.rows - 1), d.dot(sun_sky))
            })
            .collect()
    }

    /// The slice distances, m.
    pub fn slices_m(&self) -> &[f64] {
        &self.slices_m
    }

    /// The marked rays as flat arrays for a GPU, spectra packed four wavelengths to a
    /// `[f32; 4]` lane as the CPU packs them (see [`AerialArrays`]).
    pub fn arrays(&self) -> AerialArrays {
        let m = &self.maps;
        let l = m.rayleigh.len() / m.shell.len().max(1);
        let n = m.mark_transmittance.len() / m.mark_sample.len().max(1);
        let rows = (0..=self.rows)
            .map(|j| {
                let at = j.min(self.rows - 1);
                let (start, end) = if j < self.rows {
                    (m.ray_start[j], m.ray_start[j + 1])
                } else {
                    (0, 0)
                };
                [
                    f32::from_bits(start),
                    f32::from_bits(end),
                    m.origin_r[at] as f32,
                    f32::from_bits(m.mark_start[j]),
                ]
            })
            .collect();
        let samples = (0..m.shell.len())
            .flat_map(|s| {
                [
                    [
                        f32::from_bits(m.shell[s] as u32),
                        m.between[s],
                        (m.radius[s] - self.bottom_m) as f32,
                        m.distance[s] as f32,
                    ],
                    [m.mu[s] as f32, 0.0, 0.0, 0.0],
                ]
            })
            .collect();
        let marks = (0..m.mark_sample.len())
            .flat_map(|k| {
                let mut record = vec![[f32::from_bits(m.mark_sample[k]), 0.0, 0.0, 0.0]];
                record.extend(
                    m.mark_left[2 * k * l..2 * (k + 1) * l]
                        .iter()
                        .map(|v| v.to_array()),
                );
                let mut t = [Lane::ZERO; MAX_LANES];
                pack(&m.mark_transmittance[k * n..(k + 1) * n], &mut t[..l]);
                record.extend(t[..l].iter().map(|v| v.to_array()));
                record
            })
            .collect();
        AerialArrays {
            rows,
            samples,
            rayleigh: m.rayleigh.iter().map(|v| v.to_array()).collect(),
            mie: m.mie.iter().map(|v| v.to_array()).collect(),
            marks,
            lanes: l,
        }
    }
}

/// [`AerialRays`] as flat arrays (`[f32; 4]` records; indices as `u32` bits).
#[derive(Debug, Clone)]
pub struct AerialArrays {
    /// Per row, and one past the last: (first sample, end sample, origin radius m,
    /// first mark); a row's marks end at the next record's first mark.
    pub rows: Vec<[f32; 4]>,
    /// Per sample, two records: (shell, fraction between it and the next, altitude m,
    /// distance m) and (zenith cosine of the ray there, 0, 0, 0), as the sky's rays.
    pub samples: Vec<[f32; 4]>,
    /// `[sample][lane]`: the Rayleigh and aerosol weights.
    pub rayleigh: Vec<[f32; 4]>,
    pub mie: Vec<[f32; 4]>,
    /// Per mark, `1 + 3 lanes` records: (its sample, 0, 0, 0), the Rayleigh and aerosol
    /// weights' parts before it (`lanes` each), the transmittance to it (`lanes`).
    pub marks: Vec<[f32; 4]>,
    /// Lanes of four wavelengths.
    pub lanes: usize,
}
