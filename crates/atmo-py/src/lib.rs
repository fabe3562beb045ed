//! atmo for Python: the extension module `atmo._atmo` behind the `atmo` package
//! (python/atmo). It takes flat, contiguous numpy arrays and gives numpy arrays back;
//! the package's Python layer broadcasts, names the arguments and converts times.
//! Every computation runs with the interpreter detached, so other Python threads go on
//! meanwhile, and on every core (rayon).

use std::collections::hash_map::Entry;
use std::collections::HashMap;
use std::path::PathBuf;
use std::str::FromStr;
use std::sync::{Arc, Mutex};

use atmo::atmosphere::spectrum::{srgb_luminance, SpectrumToRgb};
use atmo::atmosphere::PhaseFunction;
use atmo::clouds::{Cumulus, Particle, Scattering, Splat};
use atmo::cloudscape::{Ambient, Cloudscape, CpuClouds};
use atmo::error::check_range;
use atmo::image::Frame;
use atmo::quadrature::gauss_legendre_unit;
use atmo::shafts::planes::SamplePlanes;
use atmo::shafts::Scene;
use atmo::sky::lighting::LUMENS_PER_WATT;
use atmo::sky::table::SkylightTable;
use atmo::sky::{Order, SkyModel, SkyPicture, SkySettings, View, ViewRays};
use atmo::view::place::Place;
use atmo::view::{direction_of, Camera, Fov, Sun};
use atmo::Atmosphere;
use glam::{DVec3, Vec3};
use numpy::{PyArray1, PyArray2, PyArray3, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use rayon::prelude::*;

/// An atmo error as the `ValueError` Python code expects: the message names the
/// argument and its allowed range.
fn value_error(e: atmo::Error) -> PyErr {
    PyValueError::new_err(e.to_string())
}

/// The values of a contiguous one-dimensional array (the Python layer makes them so).
fn values<'a>(array: &'a PyReadonlyArray1<'_, f64>, name: &str) -> PyResult<&'a [f64]> {
    array
        .as_slice()
        .map_err(|_| PyValueError::new_err(format!("{name}: a contiguous array is expected")))
}

/// Points of the sky as four flat arrays of one length (the Python layer broadcasts
/// them): the sun's elevation, deg; the viewpoint's altitude, m; the azimuth from the
/// sun's and the elevation of the direction looked along, deg.
#[derive(FromPyObject)]
struct Points<'py>(
    PyReadonlyArray1<'py, f64>,
    PyReadonlyArray1<'py, f64>,
    PyReadonlyArray1<'py, f64>,
    PyReadonlyArray1<'py, f64>,
);

impl Points<'_> {
    /// The four arrays' values: sun elevation, altitude, azimuth, elevation.
    fn values(&self) -> PyResult<[&[f64]; 4]> {
        Ok([
            values(&self.0, "sun_elevation")?,
            values(&self.1, "altitude")?,
            values(&self.2, "azimuth")?,
            values(&self.3, "elevation")?,
        ])
    }
}

/// `values` as a `rows x columns` numpy array.
fn matrix(py: Python<'_>, values: Vec<f32>, columns: usize) -> PyResult<Bound<'_, PyArray2<f32>>> {
    let rows = values.len() / columns.max(1);
    PyArray1::from_vec(py, values).reshape([rows, columns])
}

/// A picture as a `height x width x 3` array of linear radiance.
fn picture(py: Python<'_>, frame: Frame) -> PyResult<Bound<'_, PyArray3<f32>>> {
    let (w, h) = (frame.width as usize, frame.height as usize);
    let flat: Vec<f32> = frame.pixels.iter().flat_map(|p| p.to_array()).collect();
    PyArray1::from_vec(py, flat).reshape([h, w, 3])
}

/// A level pinhole camera's view of a sky picture, from the Python layer's dict.
#[derive(FromPyObject)]
#[pyo3(from_item_all)]
struct Look {
    width: u32,
    height: u32,
    /// Vertical field of view, deg.
    fov_deg: f64,
    /// Where the camera looks, deg (azimuth clockwise from north).
    azimuth_deg: f64,
    elevation_deg: f64,
    sun_disc: bool,
}

impl Look {
    fn render(&self, sky: &SkyPicture) -> atmo::Result<Frame> {
        let camera = Camera::yaw_pitch(
            Vec3::ZERO,
            self.azimuth_deg,
            self.elevation_deg,
            Fov::Vertical(self.fov_deg as f32),
            (self.width, self.height),
        )?;
        Ok(sky.render(&View {
            camera,
            sun_disc: self.sun_disc,
        }))
    }
}

/// The sky of one atmosphere by the shell method, every order by default: models are
/// made once per altitude and kept, so later calls at that altitude only sum.
#[pyclass(module = "atmo._atmo", frozen)]
struct Sky {
    atmosphere: Atmosphere,
    settings: SkySettings,
    colour: SpectrumToRgb,
    /// The models made so far, by altitude (the f64's bits).
    models: Mutex<HashMap<u64, Arc<SkyModel>>>,
    /// The diffuse irradiance's directions and their rays, by altitude.
    spheres: Mutex<HashMap<u64, Arc<Sphere>>>,
}

/// The directions the sky's radiance is integrated over for the diffuse irradiance: a
/// double-Gauss rule split at the horizon (Gauss-Legendre in the sine of the elevation
/// above and below it, the midpoint rule in azimuth), with each row's view ray.
struct Sphere {
    rays: ViewRays,
    /// Per direction: its row (view ray), its azimuth (rad, clockwise from north), its
    /// unit world vector and its solid angle, sr.
    directions: Vec<(usize, f64, DVec3, f64)>,
}

/// Rows of the diffuse rule above and below the horizon, and columns in azimuth: on a
/// horizontal surface within 1e-4 of the midpoint rule over half-degree rows of the
/// radiance (tests/test_sky.py holds it to 1e-3).
const SPHERE_ROWS: usize = 24;
const SPHERE_COLUMNS: usize = 96;

impl Sphere {
    fn new(model: &SkyModel) -> Sphere {
        let atmosphere = model.atmosphere();
        let r = atmosphere.bottom_radius_m + model.altitude_m();
        // The sine of the horizon's elevation (its dip below the horizontal).
        let horizon = -(1.0 - (atmosphere.bottom_radius_m / r).powi(2))
            .max(0.0)
            .sqrt();
        let rule = gauss_legendre_unit(SPHERE_ROWS);
        let mut rows = Vec::new();
        for (low, high) in [(horizon, 1.0), (-1.0, horizon)] {
            for &(x, w) in &rule {
                rows.push((low + (high - low) * x, (high - low) * w));
            }
        }
        let elevations: Vec<f64> = rows.iter().map(|&(mu, _)| mu.asin()).collect();
        let step = std::f64::consts::TAU / SPHERE_COLUMNS as f64;
        let directions = rows
            .iter()
            .enumerate()
            .flat_map(|(j, &(mu, w))| {
                (0..SPHERE_COLUMNS).map(move |i| {
                    let azimuth = (i as f64 + 0.5) * step;
                    (j, azimuth, direction_of(azimuth, mu.asin()), w * step)
                })
            })
            .collect();
        Sphere {
            rays: model.view_rays(&elevations),
            directions,
        }
    }
}

impl Sky {
    /// The model at `altitude_m`, made on first use.
    fn model(&self, altitude_m: f64) -> atmo::Result<Arc<SkyModel>> {
        let key = altitude_m.to_bits();
        if let Some(model) = self.models.lock().expect("not poisoned").get(&key) {
            return Ok(model.clone());
        }
        let model = Arc::new(SkyModel::new(&self.atmosphere, &self.settings, altitude_m)?);
        self.models
            .lock()
            .expect("not poisoned")
            .insert(key, model.clone());
        Ok(model)
    }

    /// The diffuse rule at `altitude_m`, made on first use.
    fn sphere(&self, model: &SkyModel) -> Arc<Sphere> {
        let key = model.altitude_m().to_bits();
        let mut spheres = self.spheres.lock().expect("not poisoned");
        spheres
            .entry(key)
            .or_insert_with(|| Arc::new(Sphere::new(model)))
            .clone()
    }

    /// Irradiance per wavelength on a surface facing `normal` (unit, world frame) from
    /// the sun `sun`: (direct, diffuse).
    fn irradiance_of(&self, model: &SkyModel, sun: Sun, normal: DVec3) -> (Vec<f64>, Vec<f64>) {
        let n = self.atmosphere.channels();
        let facing = normal.dot(sun.toward().as_dvec3()).max(0.0);
        let direct: Vec<f64> = self
            .atmosphere
            .direct_sunlight(model.altitude_m(), sun.elevation())
            .iter()
            .map(|e| e * facing)
            .collect();
        let sphere = self.sphere(model);
        let diffuse = sphere
            .directions
            .par_iter()
            .filter(|(_, _, d, _)| d.dot(normal) > 0.0)
            .fold(
                || (vec![0.0f64; n], vec![0.0f32; n]),
                |(mut sum, mut l), &(row, azimuth, d, w)| {
                    let from_sun = azimuth - sun.azimuth();
                    model.radiance_on(&sphere.rays, row, sun.elevation(), from_sun, &mut l);
                    let weight = w * d.dot(normal);
                    for (s, &v) in sum.iter_mut().zip(&l) {
                        *s += weight * v as f64;
                    }
                    (sum, l)
                },
            )
            .map(|(sum, _)| sum)
            .reduce(
                || vec![0.0; n],
                |a, b| a.iter().zip(&b).map(|(x, y)| x + y).collect(),
            );
        (direct, diffuse)
    }

    /// Illuminance, lux, of an irradiance spectrum (W m^-2 nm^-1) through the
    /// atmosphere's colour weights, as `atmo::sky::lighting` reckons it.
    fn lux(&self, spectrum: &[f64]) -> f64 {
        let spectrum: Vec<f32> = spectrum.iter().map(|&e| e as f32).collect();
        LUMENS_PER_WATT * srgb_luminance(self.colour.rgb(&spectrum).map(f64::from))
    }
}

#[pymethods]
impl Sky {
    /// The sky of the embedded preset `preset` or of the atmosphere file `toml_path`;
    /// `order` is "all" or the highest order (1 and up); `ozone` turns the ozone layer
    /// on or off where the atmosphere has one.
    #[new]
    #[pyo3(signature = (preset=None, toml_path=None, order="all", ozone=None))]
    fn new(
        preset: Option<&str>,
        toml_path: Option<PathBuf>,
        order: &str,
        ozone: Option<bool>,
    ) -> PyResult<Self> {
        let atmosphere = match (preset, toml_path) {
            (_, Some(path)) => Atmosphere::from_toml_file(&path),
            (name, None) => Atmosphere::preset(name.unwrap_or("earth")),
        }
        .map_err(value_error)?;
        let atmosphere = match ozone {
            Some(on) => atmosphere.with_ozone(on).map_err(value_error)?,
            None => atmosphere,
        };
        let settings = SkySettings {
            order: Order::from_str(order).map_err(value_error)?,
            ..SkySettings::default()
        };
        settings.validate(&atmosphere).map_err(value_error)?;
        Ok(Sky {
            colour: SpectrumToRgb::for_atmosphere(&atmosphere),
            atmosphere,
            settings,
            models: Mutex::default(),
            spheres: Mutex::default(),
        })
    }

    /// The wavelengths the radiance is given at, nm.
    #[getter]
    fn wavelengths_nm<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, &self.atmosphere.wavelengths_nm)
    }

    /// The atmosphere's name.
    #[getter]
    fn name(&self) -> &str {
        &self.atmosphere.name
    }

    /// The solar irradiance at the top of the atmosphere per wavelength, W m^-2 nm^-1.
    #[getter]
    fn solar_irradiance<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, &self.atmosphere.solar_irradiance)
    }

    /// The vertical optical depth from `altitude_m` to space per wavelength of each
    /// constituent: (air molecules, aerosols' extinction, ozone's absorption).
    #[allow(clippy::type_complexity)]
    fn optical_depths<'py>(
        &self,
        py: Python<'py>,
        altitude_m: f64,
    ) -> PyResult<(
        Bound<'py, PyArray1<f64>>,
        Bound<'py, PyArray1<f64>>,
        Bound<'py, PyArray1<f64>>,
    )> {
        let a = &self.atmosphere;
        check_range("altitude", altitude_m, 0.0, a.thickness_m()).map_err(value_error)?;
        // The columns (m of air at density 1) by the midpoint rule, 1 m steps to 60 km
        // in 0.1 % of the time a sky takes; the tent's kinks fall on steps.
        let steps = a.thickness_m().ceil() as usize;
        let dz = (a.thickness_m() - altitude_m) / steps as f64;
        let mut columns = [0.0f64; 3];
        for k in 0..steps {
            let d = a.densities(altitude_m + (k as f64 + 0.5) * dz);
            for (c, d) in columns.iter_mut().zip(d) {
                *c += d * dz;
            }
        }
        let ozone = a.absorbing_ozone();
        let depth =
            |per_m: &[f64], column: f64| -> Vec<f64> { per_m.iter().map(|k| k * column).collect() };
        Ok((
            PyArray1::from_vec(py, depth(&a.rayleigh.extinction_per_m, columns[0])),
            PyArray1::from_vec(py, depth(&a.mie.extinction_per_m, columns[1])),
            PyArray1::from_vec(
                py,
                ozone.map_or(vec![0.0; a.channels()], |o| {
                    depth(&o.absorption_per_m, columns[2])
                }),
            ),
        ))
    }

    /// The highest scattering order: "all" or a number.
    #[getter]
    fn order(&self) -> String {
        self.settings.order.to_string()
    }

    /// Radiance per wavelength, W m^-2 sr^-1 nm^-1, at each of `points` (below the
    /// horizon: the lit ground): `(points, wavelengths)`.
    fn radiance<'py>(
        &self,
        py: Python<'py>,
        points: Points<'py>,
    ) -> PyResult<Bound<'py, PyArray2<f32>>> {
        let [sun, altitude, azimuth, elevation] = points.values()?;
        let n = self.atmosphere.channels();
        let out = py
            .detach(|| -> atmo::Result<Vec<f32>> {
                for (field, list, min, max) in [
                    ("sun_elevation", sun, -90.0, 90.0),
                    ("elevation", elevation, -90.0, 90.0),
                    ("azimuth", azimuth, -1e6, 1e6),
                ] {
                    list.iter()
                        .try_for_each(|&v| check_range(field, v, min, max))?;
                }
                // One model a distinct altitude, one view ray a distinct elevation in it.
                let mut groups: Vec<(f64, Arc<SkyModel>, Vec<f64>)> = Vec::new();
                let mut group_of = Vec::with_capacity(altitude.len());
                for (k, &h) in altitude.iter().enumerate() {
                    let g = match groups.iter().position(|(a, ..)| a.to_bits() == h.to_bits()) {
                        Some(g) => g,
                        None => {
                            groups.push((h, self.model(h)?, Vec::new()));
                            groups.len() - 1
                        }
                    };
                    groups[g].2.push(elevation[k].to_radians());
                    group_of.push(g);
                }
                let rays: Vec<(Arc<SkyModel>, Vec<f64>, ViewRays)> = groups
                    .into_iter()
                    .map(|(_, model, mut elevations)| {
                        elevations.sort_by(f64::total_cmp);
                        elevations.dedup();
                        let rays = model.view_rays(&elevations);
                        (model, elevations, rays)
                    })
                    .collect();
                let mut out = vec![0.0f32; altitude.len() * n];
                out.par_chunks_mut(n).enumerate().for_each(|(k, l)| {
                    let (model, elevations, rays) = &rays[group_of[k]];
                    let e = elevation[k].to_radians();
                    let ray = elevations
                        .binary_search_by(|x| x.total_cmp(&e))
                        .expect("every elevation has its ray");
                    let (s, a) = (sun[k].to_radians(), azimuth[k].to_radians());
                    model.radiance_on(rays, ray, s, a, l);
                });
                Ok(out)
            })
            .map_err(value_error)?;
        matrix(py, out, n)
    }

    /// The sky as a pinhole camera sees it: a `height x width x 3` array of linear sRGB
    /// radiance, W m^-2 sr^-1 (the sun's disc included with `look.sun_disc`).
    fn render<'py>(
        &self,
        py: Python<'py>,
        sun_elevation_deg: f64,
        sun_azimuth_deg: f64,
        altitude_m: f64,
        look: Look,
    ) -> PyResult<Bound<'py, PyArray3<f32>>> {
        let frame = py
            .detach(|| -> atmo::Result<Frame> {
                let sun = Sun::from_degrees(sun_elevation_deg, sun_azimuth_deg)?;
                let model = self.model(altitude_m)?;
                look.render(&SkyPicture::new(&model, sun))
            })
            .map_err(value_error)?;
        picture(py, frame)
    }

    /// Irradiance per wavelength, W m^-2 nm^-1, on surfaces facing `normals` (k x 3,
    /// unit vectors, world frame: x east, y up, z south) under suns at
    /// (`sun_elevation_deg[k]`, `sun_azimuth_deg[k]`), `altitude_m` high: direct (the
    /// sun's disc through the atmosphere) and diffuse (the sky and the lit ground over
    /// the surface's hemisphere, every order the sky carries), each `(k, wavelengths)`,
    /// and their illuminances, lux, each `(k,)`.
    #[allow(clippy::type_complexity)]
    fn irradiance<'py>(
        &self,
        py: Python<'py>,
        sun_elevation_deg: PyReadonlyArray1<'py, f64>,
        sun_azimuth_deg: PyReadonlyArray1<'py, f64>,
        altitude_m: f64,
        normals: PyReadonlyArray1<'py, f64>,
    ) -> PyResult<(
        Bound<'py, PyArray2<f32>>,
        Bound<'py, PyArray2<f32>>,
        Bound<'py, PyArray1<f64>>,
        Bound<'py, PyArray1<f64>>,
    )> {
        let elevation = values(&sun_elevation_deg, "sun_elevation")?;
        let azimuth = values(&sun_azimuth_deg, "sun_azimuth")?;
        let normals = values(&normals, "normal")?;
        let n = self.atmosphere.channels();
        let results = py
            .detach(|| -> atmo::Result<Vec<(Vec<f64>, Vec<f64>)>> {
                let model = self.model(altitude_m)?;
                elevation
                    .iter()
                    .zip(azimuth)
                    .zip(normals.as_chunks::<3>().0)
                    .map(|((&e, &a), normal)| {
                        let sun = Sun::from_degrees(e, a)?;
                        let normal =
                            DVec3::from_array(*normal).try_normalize().ok_or_else(|| {
                                atmo::Error::out_of_range(
                                    "normal",
                                    format!("{normal:?}"),
                                    "a vector of non-zero length",
                                )
                            })?;
                        Ok(self.irradiance_of(&model, sun, normal))
                    })
                    .collect()
            })
            .map_err(value_error)?;
        let spectra = |pick: fn(&(Vec<f64>, Vec<f64>)) -> &Vec<f64>| -> Vec<f32> {
            results
                .iter()
                .flat_map(|r| pick(r).iter().map(|&v| v as f32))
                .collect()
        };
        let lux = |pick: fn(&(Vec<f64>, Vec<f64>)) -> &Vec<f64>| -> Vec<f64> {
            results.iter().map(|r| self.lux(pick(r))).collect()
        };
        Ok((
            matrix(py, spectra(|r| &r.0), n)?,
            matrix(py, spectra(|r| &r.1), n)?,
            PyArray1::from_vec(py, lux(|r| &r.0)),
            PyArray1::from_vec(py, lux(|r| &r.1)),
        ))
    }
}

/// A skylight table (`atmo precompute sky`, sky section 4): linear sRGB radiance for
/// any sun and altitude in its ranges, a map in well under a millisecond.
#[pyclass(module = "atmo._atmo", frozen)]
struct SkyTable {
    table: SkylightTable,
}

#[pymethods]
impl SkyTable {
    /// The table in the file at `path` (.atmo-sky).
    #[new]
    fn new(py: Python<'_>, path: PathBuf) -> PyResult<Self> {
        let table = py
            .detach(|| SkylightTable::read(&path))
            .map_err(value_error)?;
        Ok(SkyTable { table })
    }

    /// The atmosphere's name.
    #[getter]
    fn name(&self) -> String {
        self.table.atmosphere().name.clone()
    }

    /// The sun elevations the table covers, deg (lowest, highest).
    #[getter]
    fn sun_elevation_range(&self) -> (f64, f64) {
        let axis = self.table.sun_axis();
        (axis.min().to_degrees(), axis.max().to_degrees())
    }

    /// The viewpoint altitudes the table covers, m (lowest, highest).
    #[getter]
    fn altitude_range(&self) -> (f64, f64) {
        let axis = self.table.altitude_axis();
        (axis.min(), axis.max())
    }

    /// Linear sRGB radiance, W m^-2 sr^-1, at each of `points` (below the horizon,
    /// where the table holds no sky, 0): `(points, 3)`. One map a distinct (sun,
    /// altitude) pair.
    fn radiance<'py>(
        &self,
        py: Python<'py>,
        points: Points<'py>,
    ) -> PyResult<Bound<'py, PyArray2<f32>>> {
        let [sun, altitude, azimuth, elevation] = points.values()?;
        let out = py
            .detach(|| -> atmo::Result<Vec<f32>> {
                let mut pictures: HashMap<(u64, u64), SkyPicture> = HashMap::new();
                let mut out = Vec::with_capacity(3 * sun.len());
                for k in 0..sun.len() {
                    check_range("elevation", elevation[k], -90.0, 90.0)?;
                    let key = (sun[k].to_bits(), altitude[k].to_bits());
                    let picture = match pictures.entry(key) {
                        Entry::Occupied(found) => found.into_mut(),
                        Entry::Vacant(slot) => {
                            let at = Sun::from_degrees(sun[k], 0.0)?;
                            slot.insert(SkyPicture::from_table(&self.table, at, altitude[k])?)
                        }
                    };
                    let d = direction_of(azimuth[k].to_radians(), elevation[k].to_radians());
                    out.extend(picture.radiance(d, false).to_array());
                }
                Ok(out)
            })
            .map_err(value_error)?;
        matrix(py, out, 3)
    }

    /// The sky as a pinhole camera sees it, from the table (as [`Sky::render`]).
    fn render<'py>(
        &self,
        py: Python<'py>,
        sun_elevation_deg: f64,
        sun_azimuth_deg: f64,
        altitude_m: f64,
        look: Look,
    ) -> PyResult<Bound<'py, PyArray3<f32>>> {
        let frame = py
            .detach(|| -> atmo::Result<Frame> {
                let sun = Sun::from_degrees(sun_elevation_deg, sun_azimuth_deg)?;
                look.render(&SkyPicture::from_table(&self.table, sun, altitude_m)?)
            })
            .map_err(value_error)?;
        picture(py, frame)
    }
}

/// The sun's position (NREL SPA) at a place for times given as nanoseconds since
/// 1970-01-01 UTC: (elevation, refracted elevation, azimuth clockwise from north), deg.
#[pyfunction]
#[allow(clippy::type_complexity)]
fn sun_position<'py>(
    py: Python<'py>,
    latitude_deg: f64,
    longitude_deg: f64,
    altitude_m: f64,
    unix_ns: PyReadonlyArray1<'py, i64>,
) -> PyResult<(
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray1<f64>>,
)> {
    let times = unix_ns
        .as_slice()
        .map_err(|_| PyValueError::new_err("times: a contiguous array is expected"))?;
    let place = Place {
        latitude_deg,
        longitude_deg,
        altitude_m,
    };
    let positions = py
        .detach(|| {
            place.validate()?;
            times
                .par_iter()
                .map(|&ns| {
                    let time = chrono::DateTime::from_timestamp_nanos(ns).fixed_offset();
                    place.sun_at(time)
                })
                .collect::<atmo::Result<Vec<_>>>()
        })
        .map_err(value_error)?;
    let column = |f: fn(&atmo::view::place::SunPosition) -> f64| -> Vec<f64> {
        positions.iter().map(f).collect()
    };
    Ok((
        PyArray1::from_vec(py, column(|p| p.elevation_deg)),
        PyArray1::from_vec(py, column(|p| p.refracted_elevation_deg)),
        PyArray1::from_vec(py, column(|p| p.azimuth_deg)),
    ))
}

/// A shafts scene file drawn by the sample planes at `time_s` into its show: a
/// `height x width x 3` array of linear radiance in the scene's unit per m^2.
#[pyfunction]
#[pyo3(signature = (path, time_s=0.0))]
fn render_shafts(py: Python<'_>, path: PathBuf, time_s: f32) -> PyResult<Bound<'_, PyArray3<f32>>> {
    let frame = py
        .detach(|| -> atmo::Result<Frame> {
            check_range("time", time_s as f64, 0.0, 1e6)?;
            let mut scene = Scene::from_file(&path)?;
            scene.at_time(time_s);
            Ok(SamplePlanes::new(&scene).render())
        })
        .map_err(value_error)?;
    picture(py, frame)
}

/// The particles of a cumulus from atmo's generator, `(particles, 6)`: x, y, z (m,
/// the base `base_m` above the ground), radius (m), peak extinction (1/m) and albedo.
#[pyfunction]
#[pyo3(signature = (particles, seed, width_m, base_m))]
fn cumulus(
    py: Python<'_>,
    particles: usize,
    seed: u64,
    width_m: f32,
    base_m: f32,
) -> PyResult<Bound<'_, PyArray2<f32>>> {
    let list = py
        .detach(|| -> atmo::Result<Vec<Particle>> {
            check_range("particles", particles as f64, 1.0, 1e7)?;
            atmo::clouds::particles::check_count(particles, "particles")?;
            check_range("width", width_m as f64, 1.0, 1e5)?;
            check_range("base", base_m as f64, 0.0, 2e4)?;
            Ok(Cumulus {
                particles,
                seed,
                width: width_m,
                base: base_m,
                ..Cumulus::default()
            }
            .generate())
        })
        .map_err(value_error)?;
    let flat: Vec<f32> = list
        .iter()
        .flat_map(|p| {
            let [x, y, z] = p.position.to_array();
            [x, y, z, p.radius, p.density, p.albedo]
        })
        .collect();
    matrix(py, flat, 6)
}

/// Particles (rows of x, y, z, radius, density, albedo, as [`cumulus`] gives) lit by
/// the sun at (`sun_elevation_deg`, `sun_azimuth_deg`) and drawn from `eye` toward
/// `target` (m; by default from south-west of the cloud, a little below it), in front
/// of the Earth's sky with every order, lit by it and hazed, when `sky` (else the
/// sun's light alone, on black): a
/// `height x width x 3` array of linear radiance, W m^-2 sr^-1. `scattering` is
/// `"single"` (the paper's first order), `"multiple"` (every order by the fitted
/// transfer table) or `"solve"` (every order by the transfer solve).
#[pyfunction]
#[pyo3(signature = (particles, sun_elevation_deg, sun_azimuth_deg, eye, target, width, height, fov_deg, scattering, sky, resolution))]
#[allow(clippy::too_many_arguments)]
fn render_clouds<'py>(
    py: Python<'py>,
    particles: PyReadonlyArray2<'py, f32>,
    sun_elevation_deg: f64,
    sun_azimuth_deg: f64,
    eye: Option<[f32; 3]>,
    target: Option<[f32; 3]>,
    width: u32,
    height: u32,
    fov_deg: f32,
    scattering: &str,
    sky: bool,
    resolution: usize,
) -> PyResult<Bound<'py, PyArray3<f32>>> {
    let scattering = match scattering {
        "single" => Scattering::SINGLE,
        "multiple" => Scattering::MULTIPLE,
        "solve" => Scattering::SOLVE,
        other => {
            return Err(PyValueError::new_err(format!(
                "scattering: 'single', 'multiple' or 'solve', got {other:?}"
            )))
        }
    };
    let array = particles.as_array();
    if array.ncols() != 6 {
        return Err(PyValueError::new_err(format!(
            "particles: rows of six values (x, y, z, radius, density, albedo), got {}",
            array.ncols()
        )));
    }
    // Charged before the rows are copied, as a file's particles are.
    atmo::clouds::particles::check_count(array.nrows(), "particles").map_err(value_error)?;
    let list: Vec<Particle> = array
        .rows()
        .into_iter()
        .map(|r| Particle {
            position: Vec3::new(r[0], r[1], r[2]),
            radius: r[3],
            density: r[4],
            albedo: r[5],
        })
        .collect();
    let frame = py
        .detach(|| -> atmo::Result<Frame> {
            if list.is_empty() {
                return Err(atmo::Error::Invalid("particles: none given".into()));
            }
            for (k, p) in list.iter().enumerate() {
                atmo::clouds::files::check(p, &format!("particles[{k}]"))?;
            }
            check_range("resolution", resolution as f64, 16.0, 512.0)?;
            let scene = Cloudscape {
                calm: list,
                resolution,
                forward: 0.0,
                splat: Splat::Pieces,
                phase: PhaseFunction::CloudMie,
                scattering,
                // Without the sky, nothing but the sun lights the cloud.
                ambient: if sky {
                    Ambient::Sky
                } else {
                    Ambient::Rgb(Vec3::ZERO)
                },
                sky,
                ground_albedo: None,
            };
            let particles = scene.blown(0.0);
            let centre = Cloudscape::centre_of(&particles);
            let eye = eye.map_or(centre + Vec3::new(-1500.0, -300.0, 2500.0), Vec3::from);
            let target = target.map_or(centre, Vec3::from);
            let camera = Camera::look_at(
                eye,
                target,
                Vec3::Y,
                Fov::Vertical(fov_deg),
                (width, height),
            )?;
            let sun = Sun::from_degrees(sun_elevation_deg, sun_azimuth_deg)?;
            let mut clouds = CpuClouds::new(scene.resolution);
            clouds.light(&particles, sun.toward(), scene.forward, scene.splat)?;
            let around = scene.sky_around(&particles, &camera)?;
            let shadow = scene.shadow(&particles, sun, 256)?;
            let (light, behind) = scene.lighting(around.as_ref(), shadow.as_ref(), sun, &camera)?;
            clouds.draw(&particles, &camera, &light, behind.as_ref())
        })
        .map_err(value_error)?;
    picture(py, frame)
}

/// The names of the embedded atmospheres, the default first.
#[pyfunction]
fn presets() -> Vec<&'static str> {
    Atmosphere::preset_names().collect()
}

#[pymodule]
fn _atmo(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Sky>()?;
    m.add_class::<SkyTable>()?;
    m.add_function(wrap_pyfunction!(sun_position, m)?)?;
    m.add_function(wrap_pyfunction!(render_shafts, m)?)?;
    m.add_function(wrap_pyfunction!(cumulus, m)?)?;
    m.add_function(wrap_pyfunction!(render_clouds, m)?)?;
    m.add_function(wrap_pyfunction!(presets, m)?)?;
    Ok(())
}
