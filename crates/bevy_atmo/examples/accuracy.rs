//! How near the truth Bevy's own `Atmosphere` (Hillaire 2020, its LUTs and its
//! raymarched mode) and bevy_atmo's sky (from a model of the camera's altitude, and
//! from a skylight table of every altitude) come, each drawn by Bevy for the same
//! atmosphere, suns and altitudes, against atmo's reference: single scattering by
//! quadrature and orders 2 and up by its path tracer (`atmo::reference::sky`), for
//! Bevy's own Earth (`bevy-earth.toml` beside this file: its coefficients as Bevy's code
//! makes them) or Hillaire's (`--earth hillaire`, `hillaire-earth.toml`).
//!
//! ```text
//! cargo run -p bevy_atmo --example accuracy -- [--earth bevy|hillaire] [--paths N]
//!     [--json FILE] [--directions FILE]
//! ```
//! For every altitude (0, 1, 7, 13 km) and sun (0, 2, 5, 10, 30, 60 deg) each renderer
//! draws the five upper faces of a cube around the camera (128 x 128 pixels, no tone
//! map, read back as f32); the directions compared are the centres of the pixels nearest
//! 35 directions of the sky (7 elevations from 2 to 80 deg, 5 azimuths from the sun's
//! to its opposite), less those within 10 deg of the sun. The reference is computed at
//! exactly those pixels' directions (`--paths` per channel, 6,000 by default; kept in
//! `target/` and reused), and each renderer's relative error per channel is summed up
//! by its median and 95th percentile, over everything, by the sun's elevation and by the
//! altitude (Markdown tables). `--json FILE` writes a line a renderer of the summary (as
//! `atmo bench --json` does: docs/bench/bevy-accuracy.json), `--directions FILE` a line
//! a direction of every number.
//!
//! Bevy's Atmosphere crashes lavapipe 22.3 (Debian 12's Mesa): run this on a hardware
//! GPU, or on lavapipe 25 (`scripts/lavapipe-25.sh`).

use std::path::PathBuf;
use std::sync::Arc;

use atmo::reference::sky::{ReferenceSettings, ReferenceSky};
use atmo::sky::{Order, SkySettings, SkylightTable, TableSettings};
use bevy::camera::{Exposure, RenderTarget};
use bevy::core_pipeline::tonemapping::{DebandDither, Tonemapping};
use bevy::light::atmosphere::{Falloff, ScatteringMedium};
use bevy::light::{Atmosphere, SunDisk};
use bevy::pbr::{AtmosphereMode, AtmosphereSettings};
use bevy::prelude::*;
use bevy::render::gpu_readback::{Readback, ReadbackComplete};
use bevy::render::render_resource::{TextureFormat, TextureUsages};
use bevy::render::renderer::RenderAdapterInfo;
use bevy::render::RenderApp;
use bevy_atmo::prelude::*;
use rayon::prelude::*;
use serde_json::json;

mod scene;

/// The camera's altitudes, m.
const ALTITUDES_M: [f64; 4] = [0.0, 1000.0, 7000.0, 13_000.0];
/// The sun's elevations, deg.
const SUNS_DEG: [f64; 6] = [0.0, 2.0, 5.0, 10.0, 30.0, 60.0];
/// The directions aimed at: elevations and azimuths from the sun's, deg.
const ELEVATIONS_DEG: [f64; 7] = [2.0, 5.0, 10.0, 20.0, 35.0, 55.0, 80.0];
const AZIMUTHS_DEG: [f64; 5] = [0.0, 45.0, 90.0, 135.0, 180.0];
/// Directions nearer the sun than this are left out (its disc and the aerosols' sharp
/// forward peak, where a pixel's place matters more than the method), deg.
const AWAY_FROM_SUN_DEG: f64 = 10.0;
/// A cube face's pixels a side (rows of 128 f32 RGBA pixels are whole 256-byte copy
/// rows).
const FACE: u32 = 128;
/// The exposure of every picture, and Bevy's sun's illuminance (its light's colour times
/// illuminance is the sunlight at the top of the atmosphere): pictures near 1.
const EXPOSURE: Exposure = Exposure { ev100: 6.0 };
const BEVY_SUN_LUX: f32 = 100.0;

/// The reference's radiance in red, green and blue, and its standard error.
type Truth = ([f64; 3], [f64; 3]);

/// Which cases (altitude m, sun deg) a column of a table sums up.
type Keep = Box<dyn Fn(f64, f64) -> bool>;

/// Who draws the sky.
#[derive(Clone, Copy, PartialEq)]
enum Renderer {
    BevyLut,
    BevyRaymarched,
    /// atmo's model of the camera's altitude.
    Atmo,
    /// atmo's skylight table (sky 4, its default settings): every altitude to 13 km.
    AtmoTable,
}

impl Renderer {
    const ALL: [Renderer; 4] = [
        Renderer::BevyLut,
        Renderer::BevyRaymarched,
        Renderer::Atmo,
        Renderer::AtmoTable,
    ];

    /// Its name in the JSON lines' `bench`.
    fn key(self) -> &'static str {
        match self {
            Renderer::BevyLut => "bevy-lut",
            Renderer::BevyRaymarched => "bevy-raymarched",
            Renderer::Atmo => "bevy-atmo",
            Renderer::AtmoTable => "bevy-atmo-table",
        }
    }

    fn name(self) -> &'static str {
        match self {
            Renderer::BevyLut => "Bevy's Atmosphere (LUTs, its default)",
            Renderer::BevyRaymarched => "Bevy's Atmosphere (raymarched)",
            Renderer::Atmo => "bevy_atmo (every order)",
            Renderer::AtmoTable => "bevy_atmo (a table)",
        }
    }

    /// What a pixel is per unit radiance (sunlight 1 at the top of the atmosphere).
    fn scale(self) -> f64 {
        let exposure = f64::from(EXPOSURE.exposure());
        match self {
            Renderer::BevyLut | Renderer::BevyRaymarched => f64::from(BEVY_SUN_LUX) * exposure,
            Renderer::Atmo | Renderer::AtmoTable => atmo::sky::lighting::LUMENS_PER_WATT * exposure,
        }
    }
}

/// The five upper faces of the cube: where each camera looks and its up.
const FACES: [(Vec3, Vec3); 5] = [
    (Vec3::NEG_Z, Vec3::Y),
    (Vec3::X, Vec3::Y),
    (Vec3::Z, Vec3::Y),
    (Vec3::NEG_X, Vec3::Y),
    (Vec3::Y, Vec3::Z),
];

/// A direction compared: which face and pixel shows it, and its elevation and azimuth
/// from the sun's (rad), of the pixel's centre.
#[derive(Clone, Copy)]
struct Probe {
    face: usize,
    pixel: (u32, u32),
    elevation: f64,
    azimuth: f64,
}

/// The world direction through the centre of `pixel` of face `face` (a 90 deg camera).
fn pixel_direction(face: usize, (x, y): (u32, u32)) -> Vec3 {
    let (look, up) = FACES[face];
    let rotation = Transform::default().looking_to(look, up).rotation;
    let u = 2.0 * (x as f32 + 0.5) / FACE as f32 - 1.0;
    let v = 1.0 - 2.0 * (y as f32 + 0.5) / FACE as f32;
    (rotation * Vec3::new(u, v, -1.0)).normalize()
}

/// The pixel showing the direction at `elevation` and `azimuth` (deg; the sun's azimuth
/// is north, -z): the face it is most central in.
fn probe(elevation: f64, azimuth: f64) -> Probe {
    let d = atmo::view::direction_of(azimuth.to_radians(), elevation.to_radians()).as_vec3();
    let (face, c) = (0..FACES.len())
        .map(|f| {
            let (look, up) = FACES[f];
            let rotation = Transform::default().looking_to(look, up).rotation;
            (f, rotation.inverse() * d)
        })
        .max_by(|a, b| (-a.1.z).total_cmp(&-b.1.z))
        .expect("five faces");
    let (u, v) = (c.x / -c.z, c.y / -c.z);
    let to_pixel = |t: f32| ((t * FACE as f32).floor() as u32).min(FACE - 1);
    let pixel = (to_pixel((u + 1.0) / 2.0), to_pixel((1.0 - v) / 2.0));
    let p = pixel_direction(face, pixel).as_dvec3();
    Probe {
        face,
        pixel,
        elevation: p.y.asin(),
        azimuth: p.x.atan2(-p.z),
    }
}

/// The directions compared for a sun at `sun_deg`.
fn probes(sun_deg: f64) -> Vec<Probe> {
    let sun = atmo::view::direction_of(0.0, sun_deg.to_radians());
    let mut out = Vec::new();
    for e in ELEVATIONS_DEG {
        for a in AZIMUTHS_DEG {
            let d = atmo::view::direction_of(a.to_radians(), e.to_radians());
            if d.dot(sun).clamp(-1.0, 1.0).acos() >= AWAY_FROM_SUN_DEG.to_radians() {
                out.push(probe(e, a));
            }
        }
    }
    out
}

/// Which Earth both sides draw.
#[derive(Clone, Copy, PartialEq)]
enum Earth {
    /// Bevy's own (`ScatteringMedium::earth`, its default): `bevy-earth.toml`.
    Bevy,
    /// Hillaire's (2020, his paper's Earth): molecules of scale height 8 km, aerosols of
    /// 1.2 km scattering 3.996e-6 per m with an albedo of 0.9, Bevy's ozone and ground;
    /// for Bevy, a medium of those terms (`hillaire-earth.toml`).
    Hillaire,
}

impl Earth {
    fn name(self) -> &'static str {
        match self {
            Earth::Bevy => "bevy",
            Earth::Hillaire => "hillaire",
        }
    }

    /// The atmosphere as atmo's.
    fn atmo(self) -> atmo::Atmosphere {
        let (text, origin) = match self {
            Earth::Bevy => (include_str!("bevy-earth.toml"), "bevy-earth.toml"),
            Earth::Hillaire => (include_str!("hillaire-earth.toml"), "hillaire-earth.toml"),
        };
        atmo::Atmosphere::from_toml_str(text, origin).expect("the example's atmosphere is valid")
    }

    /// The atmosphere as Bevy's medium: its falloffs are fractions of Bevy's 100 km.
    fn medium(self) -> ScatteringMedium {
        match self {
            Earth::Bevy => ScatteringMedium::default(),
            Earth::Hillaire => {
                let mut medium = ScatteringMedium::default();
                let [rayleigh, mie, _ozone] = &mut medium.terms[..] else {
                    panic!("Bevy's Earth has three terms");
                };
                rayleigh.falloff = Falloff::Exponential { scale: 0.08 };
                mie.falloff = Falloff::Exponential { scale: 0.012 };
                mie.scattering = Vec3::splat(3.996e-6);
                mie.absorption = Vec3::splat(0.444e-6);
                medium
            }
        }
    }
}

/// What is compared: which Earth, and whether single scattering alone (`--single`:
/// Bevy's multiple-scattering LUT emptied, its ground black, atmo's model of order 1,
/// the reference's quadrature alone), which checks that both sides draw the same
/// atmosphere before the orders past the first are compared.
#[derive(Clone, Copy)]
struct Setup {
    earth: Earth,
    single: bool,
}

impl Setup {
    /// atmo's settings: every order, or with `--single` the first.
    fn sky_settings(self) -> SkySettings {
        SkySettings {
            order: if self.single {
                Order::Through(1)
            } else {
                Order::All
            },
            ..default()
        }
    }

    /// Its name in file names and the JSON lines' `bench`.
    fn name(self) -> String {
        let single = if self.single { "-single" } else { "" };
        format!("{}-earth{single}", self.earth.name())
    }
}

/// Where a file the example keeps between runs lies: in the workspace's `target/`.
fn kept(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../target")
        .join(name)
}

/// atmo's skylight table of `setup`'s atmosphere and settings (the rest its defaults),
/// made once (about a minute on two cores) and kept in `target/`.
fn table(setup: Setup) -> Arc<SkylightTable> {
    let path = kept(&format!("bevy-accuracy-{}.atmo-sky", setup.name()));
    let table = SkylightTable::read(&path).unwrap_or_else(|_| {
        eprintln!("the table: {}", path.display());
        let settings = TableSettings {
            sky: setup.sky_settings(),
            ..TableSettings::default()
        };
        let table = SkylightTable::precompute(&setup.earth.atmo(), &settings, &|_, _| {})
            .expect("the example's table");
        // Kept for the next run where it can be; this one has it either way.
        let _ = table.write(&path);
        table
    });
    Arc::new(table)
}

/// The reference's radiance per channel (red, green, blue) and its standard error, for
/// every case's probes, in the order of [`cases`]; computed once for `paths` and kept.
fn reference(setup: Setup, paths: usize) -> Vec<Vec<Truth>> {
    let cache = kept(&format!(
        "bevy-accuracy-reference-{}-{paths}.json",
        setup.name()
    ));
    if let Ok(text) = std::fs::read_to_string(&cache) {
        if let Ok(kept) = serde_json::from_str(&text) {
            return kept;
        }
    }
    let atmosphere = setup.earth.atmo();
    let jobs: Vec<(usize, (f64, f64), Probe)> = cases()
        .into_iter()
        .enumerate()
        .flat_map(|(c, case)| probes(case.1).into_iter().map(move |p| (c, case, p)))
        .collect();
    eprintln!(
        "the reference: {} directions, {paths} paths a channel",
        jobs.len()
    );
    let done: Vec<(usize, Truth)> = jobs
        .par_iter()
        .map(|&(c, (altitude, sun), p)| {
            let sky = ReferenceSky::new(
                &atmosphere,
                altitude,
                sun.to_radians(),
                ReferenceSettings::CONVERGED,
            );
            let single = sky.radiance(p.azimuth, p.elevation, 1, 1);
            let (multiple, error) = if setup.single {
                (vec![0.0; 3], vec![0.0; 3])
            } else {
                sky.multiple_scattering(p.azimuth, p.elevation, paths, 7)
            };
            // atmo's channels are blue, green, red (increasing wavelength).
            let rgb = |v: &[f64]| [v[2], v[1], v[0]];
            let total: Vec<f64> = single.iter().zip(&multiple).map(|(s, m)| s + m).collect();
            (c, (rgb(&total), rgb(&error)))
        })
        .collect();
    let mut out: Vec<Vec<_>> = cases().iter().map(|_| Vec::new()).collect();
    for (c, r) in done {
        out[c].push(r);
    }
    if let Ok(text) = serde_json::to_string(&out) {
        let _ = std::fs::write(&cache, text);
    }
    out
}

/// Every (altitude m, sun deg), altitude outermost.
fn cases() -> Vec<(f64, f64)> {
    ALTITUDES_M
        .iter()
        .flat_map(|&a| SUNS_DEG.iter().map(move |&s| (a, s)))
        .collect()
}

/// What the last read-back of each face gave.
#[derive(Resource, Default)]
struct Shots([Option<Vec<[f32; 4]>>; 5]);

/// An app drawing the sky with `renderer` into five f32 images, one a face, read back
/// every frame.
fn app(renderer: Renderer, setup: Setup) -> App {
    let mut app = scene::headless_app();
    app.init_resource::<Shots>();
    let world = app.world_mut();
    // One atmosphere and sky for the five cameras (a table is read or made once).
    let atmo_sky = match renderer {
        Renderer::Atmo | Renderer::AtmoTable => Some(AtmoSky {
            atmosphere: Arc::new(setup.earth.atmo()),
            source: if renderer == Renderer::Atmo {
                SkySource::Model {
                    settings: setup.sky_settings(),
                    rebuild_after_m: 500.0,
                }
            } else {
                SkySource::Table(table(setup))
            },
            sun_disc: false,
            aerial_perspective: false,
            sky_light: SkyLight::Off,
            ..AtmoSky::earth()
        }),
        Renderer::BevyLut | Renderer::BevyRaymarched => None,
    };
    for (face, (look, up)) in FACES.into_iter().enumerate() {
        let mut image = Image::new_target_texture(FACE, FACE, TextureFormat::Rgba32Float, None);
        image.texture_descriptor.usage |= TextureUsages::COPY_SRC;
        let image = world.resource_mut::<Assets<Image>>().add(image);
        let mut camera = world.spawn((
            Camera3d::default(),
            Camera {
                order: face as isize,
                // Bevy's Atmosphere lets the clear colour through (as space behind).
                clear_color: ClearColorConfig::Custom(Color::BLACK),
                ..default()
            },
            Projection::Perspective(PerspectiveProjection {
                fov: std::f32::consts::FRAC_PI_2,
                ..default()
            }),
            RenderTarget::Image(image.clone().into()),
            EXPOSURE,
            Tonemapping::None,
            DebandDither::Disabled,
            Msaa::Off,
            Transform::default().looking_to(look, up),
        ));
        match &atmo_sky {
            Some(sky) => {
                camera.insert(sky.clone());
            }
            None => {
                camera.insert(AtmosphereSettings {
                    rendering_method: if renderer == Renderer::BevyLut {
                        AtmosphereMode::LookupTexture
                    } else {
                        AtmosphereMode::Raymarched
                    },
                    // No samples: only the ground's light would be left, and it is black.
                    multiscattering_lut_samples: if setup.single {
                        0
                    } else {
                        AtmosphereSettings::default().multiscattering_lut_samples
                    },
                    ..default()
                });
            }
        }
        world.spawn(Readback::texture(image)).observe(
            move |read: On<ReadbackComplete>, mut shots: ResMut<Shots>| {
                shots.0[face] = Some(bytemuck::cast_slice(&read.data).to_vec());
            },
        );
    }
    match renderer {
        Renderer::Atmo | Renderer::AtmoTable => {
            world.spawn((AtmoSun, Transform::default()));
        }
        Renderer::BevyLut | Renderer::BevyRaymarched => {
            let medium = world
                .resource_mut::<Assets<ScatteringMedium>>()
                .add(setup.earth.medium());
            let mut atmosphere = Atmosphere::earth(medium);
            if setup.single {
                atmosphere.ground_albedo = Vec3::ZERO;
            }
            world.spawn(atmosphere);
            world.spawn((
                DirectionalLight {
                    illuminance: BEVY_SUN_LUX,
                    color: Color::WHITE,
                    ..default()
                },
                SunDisk::OFF,
                Transform::default(),
            ));
        }
    }
    app
}

/// Puts every camera at `altitude` m and the sun at `sun` deg (north), then updates
/// until the pictures have settled (atmo's model built, two read-backs of every face in
/// a row within 1e-5 of each other), and returns the five faces.
fn draw(app: &mut App, altitude: f64, sun: f64) -> Vec<Vec<[f32; 4]>> {
    let world = app.world_mut();
    let mut cameras = world.query_filtered::<&mut Transform, With<Camera3d>>();
    for mut t in cameras.iter_mut(world) {
        t.translation = Vec3::new(0.0, altitude as f32, 0.0);
    }
    let toward = atmo::view::direction_of(0.0, sun.to_radians()).as_vec3();
    let mut lights = world.query_filtered::<&mut Transform, With<DirectionalLight>>();
    for mut t in lights.iter_mut(world) {
        *t = Transform::default().looking_to(-toward, Vec3::Y);
    }
    let mut last: Option<Vec<Vec<[f32; 4]>>> = None;
    let mut ready = 0;
    for _ in 0..2000 {
        app.update();
        assert!(app.should_exit().is_none(), "the renderer stopped the app");
        ready = if scene::built(app.world_mut()) {
            ready + 1
        } else {
            0
        };
        let shots = &mut app.world_mut().resource_mut::<Shots>().0;
        if ready < 4 || shots.iter().any(Option::is_none) {
            continue;
        }
        let now: Vec<Vec<[f32; 4]>> = shots.iter_mut().map(|s| s.take().unwrap()).collect();
        let same = last.as_ref().is_some_and(|last| {
            last.iter()
                .flatten()
                .zip(now.iter().flatten())
                .all(|(a, b)| (0..3).all(|c| (a[c] - b[c]).abs() <= 1e-5 * a[c].abs().max(1e-3)))
        });
        if same {
            return now;
        }
        last = Some(now);
    }
    panic!("no settled picture at {altitude} m, sun {sun} deg");
}

/// The median and the 95th percentile of `values`' magnitudes.
fn median_and_p95(values: &[f64]) -> (f64, f64) {
    let mut v: Vec<f64> = values.iter().map(|x| x.abs()).collect();
    v.sort_by(f64::total_cmp);
    let at = |q: f64| v[((v.len() - 1) as f64 * q).round() as usize];
    (at(0.5), at(0.95))
}

fn main() {
    let value = scene::option;
    let paths: usize = value("--paths").map_or(6000, |p| p.parse().expect("--paths: a count"));
    let earth = match value("--earth").as_deref() {
        None | Some("bevy") => Earth::Bevy,
        Some("hillaire") => Earth::Hillaire,
        Some(other) => panic!("--earth: bevy or hillaire, not {other}"),
    };
    let setup = Setup {
        earth,
        single: scene::switch("--single"),
    };
    let reference = reference(setup, paths);
    // errors[renderer][case][probe][channel], relative
    let mut errors = Vec::new();
    let mut directions = Vec::new();
    let mut device = String::new();
    for renderer in Renderer::ALL {
        let mut app = app(renderer, setup);
        let info = app
            .sub_app(RenderApp)
            .world()
            .resource::<RenderAdapterInfo>();
        device = format!("{} ({})", info.name, info.driver_info);
        let mut per_case = Vec::new();
        for (c, &(altitude, sun)) in cases().iter().enumerate() {
            let faces = draw(&mut app, altitude, sun);
            let mut per_probe = Vec::new();
            for (p, probe) in probes(sun).iter().enumerate() {
                let (x, y) = probe.pixel;
                let pixel = faces[probe.face][(y * FACE + x) as usize];
                let (truth, error) = reference[c][p];
                let got: [f64; 3] = std::array::from_fn(|k| f64::from(pixel[k]) / renderer.scale());
                directions.push(json!({
                    "renderer": renderer.key(), "altitude_m": altitude, "sun_deg": sun,
                    "elevation_deg": probe.elevation.to_degrees(),
                    "azimuth_from_sun_deg": probe.azimuth.to_degrees(),
                    "radiance_rgb": got, "reference_rgb": truth,
                    "reference_standard_error_rgb": error,
                }));
                per_probe.push(std::array::from_fn(|k| got[k] / truth[k] - 1.0));
            }
            per_case.push(per_probe);
        }
        errors.push(per_case);
        eprintln!("drawn: {}", renderer.name());
    }
    if let Some(path) = value("--directions") {
        write_lines(&path, &directions);
    }
    if let Some(path) = value("--json") {
        let noise = median_and_p95(&reference_noise(&reference)).0;
        let lines: Vec<serde_json::Value> = Renderer::ALL
            .iter()
            .zip(&errors)
            .map(|(renderer, errors)| {
                let channel =
                    |k: usize| -> Vec<f64> { errors.iter().flatten().map(|e| e[k]).collect() };
                let stats: [(f64, f64); 3] = std::array::from_fn(|k| median_and_p95(&channel(k)));
                let bias: [f64; 3] = std::array::from_fn(|k| {
                    let v = channel(k);
                    100.0 * v.iter().sum::<f64>() / v.len() as f64
                });
                json!({
                    "bench": format!("bevy.accuracy.{}.{}", setup.name(), renderer.key()),
                    "command": format!(
                        "cargo run -p bevy_atmo --example accuracy -- --earth {}{} --json FILE",
                        earth.name(),
                        if setup.single { " --single" } else { "" }
                    ),
                    "params": {
                        "earth": earth.name(), "single": setup.single, "paths_per_channel": paths,
                        "altitudes_m": ALTITUDES_M, "suns_deg": SUNS_DEG,
                        "directions": directions.len() / Renderer::ALL.len(),
                    },
                    "device": device,
                    "renderer": renderer.name(),
                    "median_error_pct_rgb": stats.map(|s| 100.0 * s.0),
                    "p95_error_pct_rgb": stats.map(|s| 100.0 * s.1),
                    "mean_signed_error_pct_rgb": bias,
                    "reference_noise_median_pct": 100.0 * noise,
                })
            })
            .collect();
        write_lines(&path, &lines);
    }
    println!("Drawn on {device}.\n");
    print_tables(&errors, &reference, paths);
}

/// Writes one JSON object a line to `path`, through a temporary file renamed when whole.
fn write_lines(path: &str, lines: &[serde_json::Value]) {
    let text: String = lines.iter().map(|l| format!("{l}\n")).collect();
    let part = format!("{path}.part");
    std::fs::write(&part, text).expect("a writable file for --json or --directions");
    std::fs::rename(&part, path).expect("a writable file for --json or --directions");
}

/// The reference's standard error over its radiance, every direction and channel.
fn reference_noise(reference: &[Vec<Truth>]) -> Vec<f64> {
    reference
        .iter()
        .flatten()
        .flat_map(|(t, e)| (0..3).map(move |k| e[k] / t[k]))
        .collect()
}

/// The summary tables, as Markdown.
fn print_tables(errors: &[Vec<Vec<[f64; 3]>>], reference: &[Vec<Truth>], paths: usize) {
    let cell = |values: Vec<f64>| {
        let (m, p) = median_and_p95(&values);
        format!("{:.1} / {:.1}", 100.0 * m, 100.0 * p)
    };
    let noise = reference_noise(reference);
    println!(
        "The reference's own noise (standard error over the radiance, {paths} paths a channel): median {:.2} %, 95th percentile {:.2} %.\n",
        100.0 * median_and_p95(&noise).0,
        100.0 * median_and_p95(&noise).1
    );
    println!("| renderer | red | green | blue |\n| --- | --- | --- | --- |");
    for (r, renderer) in Renderer::ALL.iter().enumerate() {
        let channel = |k: usize| cell(errors[r].iter().flatten().map(|e| e[k]).collect());
        println!(
            "| {} | {} | {} | {} |",
            renderer.name(),
            channel(0),
            channel(1),
            channel(2)
        );
    }
    // By the sun's elevation, then by the altitude: each column the cases that have it.
    let by = |title: &str, columns: Vec<(String, Keep)>| {
        println!(
            "\n| {title} | {} |",
            columns
                .iter()
                .map(|c| c.0.as_str())
                .collect::<Vec<_>>()
                .join(" | ")
        );
        println!("| --- |{}", " --- |".repeat(columns.len()));
        for (r, renderer) in Renderer::ALL.iter().enumerate() {
            for (k, channel) in ["red", "green", "blue"].iter().enumerate() {
                let cells: Vec<String> = columns
                    .iter()
                    .map(|(_, keep)| {
                        let values = cases()
                            .iter()
                            .zip(&errors[r])
                            .filter(|((altitude, sun), _)| keep(*altitude, *sun))
                            .flat_map(|(_, case)| case.iter().map(|e| e[k]))
                            .collect();
                        cell(values)
                    })
                    .collect();
                println!("| {}, {channel} | {} |", renderer.name(), cells.join(" | "));
            }
        }
    };
    by(
        "renderer, channel",
        SUNS_DEG
            .iter()
            .map(|&s| {
                let keep: Keep = Box::new(move |_, sun| sun == s);
                (format!("sun {s} deg"), keep)
            })
            .collect(),
    );
    by(
        "renderer, channel",
        ALTITUDES_M
            .iter()
            .map(|&a| {
                let keep: Keep = Box::new(move |altitude, _| altitude == a);
                (format!("{} km", a / 1000.0), keep)
            })
            .collect(),
    );
}
