//! `atmo bench <area> --backend gpu`: each GPU pipeline timed beside the CPU path on the
//! same inputs in the same run, with the difference between their pictures in 8-bit
//! levels. Times are medians: wall (submission to read-back) and, where the adapter has
//! timestamp queries, the GPU's own.

use std::path::Path;

use anyhow::Result;
use atmo::clouds::buffer::{IntensityBuffer, Splat};
use atmo::clouds::generator::Cumulus;
use atmo::clouds::render::{render, CloudPhase, Lighting};
use atmo::image::{Display, Frame, ToneMap};
use atmo::shafts::Scene;
use atmo::sky::frame::{Projection, SkyPicture, View};
use atmo::sky::table::{SkylightTable, TableSettings};
use atmo::sky::{SkyModel, SkySettings, Sun};
use atmo::Atmosphere;
use atmo_gpu::clouds::GpuClouds;
use atmo_gpu::shafts::{GpuShafts, ShaftsMethod};
use atmo_gpu::sky::{GpuSkyModel, GpuSkyTable};
use atmo_gpu::{Gpu, GpuError, Rendered};
use serde_json::{json, Value};

use crate::backend::gpu_error;
use crate::bench::{median, time_ms};
use crate::bench_clouds::camera;
use crate::bench_shafts::time_planes;
use crate::bench_table::emit;
use crate::clouds::sun_direction;

/// Medians of `runs` GPU runs after a warm-up: (wall ms, GPU ms if timed) and the last
/// result.
fn time_gpu<T>(
    runs: usize,
    mut run: impl FnMut() -> Result<(T, Option<f64>), GpuError>,
) -> Result<(f64, Option<f64>, T)> {
    let (mut last, _) = run().map_err(gpu_error)?;
    let (mut walls, mut gpus) = (Vec::new(), Vec::new());
    for _ in 0..runs {
        let mut result = Ok(());
        walls.push(time_ms(|| match run() {
            Ok((value, gpu_ms)) => {
                last = value;
                gpus.extend(gpu_ms);
            }
            Err(e) => result = Err(e),
        }));
        result.map_err(gpu_error)?;
    }
    let gpu_ms = (!gpus.is_empty()).then(|| median(gpus));
    Ok((median(walls), gpu_ms, last))
}

/// One case: the GPU's times beside the CPU's, and how far the pictures are apart.
struct Case<'a> {
    name: &'a str,
    params: Value,
    wall_ms: f64,
    gpu_ms: Option<f64>,
    cpu_ms: f64,
    error: Option<atmo::image::LevelErrors>,
}

fn report(json: bool, gpu: &Gpu, case: Case) {
    let device = json!({"adapter": gpu.describe(), "software": gpu.is_software()});
    let error = case
        .error
        .map(|e| json!({"rms_levels": e.rms, "max_levels": e.max}));
    emit(
        json,
        json!({
            "bench": case.name, "params": case.params, "device": device,
            "median_ms": case.wall_ms, "gpu_ms": case.gpu_ms,
            "baseline": "the same method on the CPU", "baseline_median_ms": case.cpu_ms,
            "ratio": case.cpu_ms / case.wall_ms, "error": error,
        }),
        format!(
            "{:<24} GPU {:>9.2} ms (GPU time {})   CPU {:>8.2} ms   ratio {:>6.3}{}",
            case.name,
            case.wall_ms,
            case.gpu_ms
                .map_or("not measured".into(), |ms| format!("{ms:.2} ms")),
            case.cpu_ms,
            case.cpu_ms / case.wall_ms,
            case.error.map_or(String::new(), |e| format!(
                "   error rms {:.3} max {:.2} levels",
                e.rms, e.max
            ))
        ),
    );
}

pub fn bench_sky(gpu: &Gpu, quick: bool, json: bool) -> Result<()> {
    // The CPU bench's case: the paper's Fig. 7(a), 7000 m, sun at 30 degrees.
    let atmosphere = Atmosphere::earth();
    let settings = SkySettings::default();
    let model = SkyModel::new(&atmosphere, &settings, 7000.0)?;
    let sky = GpuSkyModel::new(gpu, &model).map_err(gpu_error)?;
    let runs = if quick { 5 } else { 21 };
    let sun = Sun::from_degrees(30.0, 0.0)?;
    let (wall, gpu_ms, ()) = time_gpu(runs, || Ok(((), sky.maps_timed(gpu, sun.elevation)?)))?;
    let cpu_ms = median(
        (0..runs)
            .map(|_| {
                time_ms(|| {
                    std::hint::black_box((
                        model.skylight_map(sun.elevation),
                        model.ground_map(sun.elevation),
                    ));
                })
            })
            .collect(),
    );
    let params = json!({"altitude_m": 7000.0, "sun_elevation_deg": 30.0,
        "directions": settings.directions, "shells": settings.shells, "order": settings.order});
    report(
        json,
        gpu,
        Case {
            name: "sky.maps.gpu",
            params: params.clone(),
            wall_ms: wall,
            gpu_ms,
            cpu_ms,
            error: None,
        },
    );
    sky_frame(
        gpu,
        json,
        ("sky.frame.gpu", json!({"model": params})),
        runs.min(7),
        |view| sky.render(gpu, sun, view),
        |view, frame| SkyPicture::new(&model, sun).render_into(view, frame),
    )
}

/// A 1920 x 1080 sky frame drawn `runs` times on the GPU and on the CPU, timed and
/// compared at the sky's exposure.
fn sky_frame(
    gpu: &Gpu,
    json: bool,
    (name, params): (&str, Value),
    runs: usize,
    mut on_gpu: impl FnMut(&View) -> Result<Rendered, GpuError>,
    mut on_cpu: impl FnMut(&View, &mut Frame),
) -> Result<()> {
    let view = View {
        width: 1920,
        height: 1080,
        projection: Projection::perspective_degrees(0.0, 15.0, 70.0)?,
        sun_disc: true,
    };
    let (wall, gpu_ms, frame) = time_gpu(runs, || {
        let r = on_gpu(&view)?;
        Ok((r.frame, r.gpu_ms))
    })?;
    let mut cpu = Frame::new(view.width, view.height);
    let cpu_ms = median(
        (0..runs)
            .map(|_| time_ms(|| on_cpu(&view, &mut cpu)))
            .collect(),
    );
    let display = Display {
        exposure: 0.15,
        tone: ToneMap::Exponential,
    };
    report(
        json,
        gpu,
        Case {
            name,
            params: json!({"of": params, "width": view.width, "height": view.height}),
            wall_ms: wall,
            gpu_ms,
            cpu_ms,
            error: Some(frame.level_errors(&cpu, display)?),
        },
    );
    Ok(())
}

pub fn bench_sky_table(gpu: &Gpu, quick: bool, json: bool) -> Result<()> {
    let mut settings = TableSettings::default();
    if quick {
        settings.sky.directions = 32;
        settings.sun_steps = 32;
        settings.altitude_steps = 8;
    }
    eprintln!("atmo: precomputing the table on the CPU (a minute at the defaults)");
    let table = SkylightTable::precompute(&Atmosphere::earth(), &settings, &|_, _| {})?;
    let sky = GpuSkyTable::new(gpu, &table).map_err(gpu_error)?;
    let runs = if quick { 5 } else { 21 };
    let (sun, altitude) = (Sun::from_degrees(30.0, 0.0)?, 7000.0);
    let (wall, gpu_ms, map) = time_gpu(runs, || sky.map(gpu, sun.elevation, altitude))?;
    let cpu_map_ms = median(
        (0..runs)
            .map(|_| time_ms(|| drop(table.map(sun.elevation, altitude))))
            .collect(),
    );
    let cpu_map = table.map(sun.elevation, altitude)?;
    let worst = map
        .iter()
        .zip(&cpu_map)
        .map(|(a, b)| ((*a - *b).abs() / b.max(glam::Vec3::splat(1e-6))).max_element())
        .fold(0.0f32, f32::max);
    let params = json!({"directions": settings.sky.directions, "terms": table.max_terms()});
    report(
        json,
        gpu,
        Case {
            name: "sky-table.map.gpu",
            params: json!({"table": params.clone(), "max_relative_difference": worst}),
            wall_ms: wall,
            gpu_ms,
            cpu_ms: cpu_map_ms,
            error: None,
        },
    );
    sky_frame(
        gpu,
        json,
        ("sky-table.frame.gpu", json!({"table": params})),
        runs.min(7),
        |view| sky.render(gpu, sun, altitude, view),
        |view, frame| {
            SkyPicture::from_table(&table, sun, altitude)
                .expect("inside the table")
                .render_into(view, frame)
        },
    )
}

pub fn bench_shafts(gpu: &Gpu, quick: bool, json: bool, scenes: &Path) -> Result<()> {
    let runs = if quick { 3 } else { 7 };
    for (name, file) in [
        ("shafts.fig6", "spotlight-sphere.toml"),
        ("shafts.stage", "stage.toml"),
    ] {
        let scene = Scene::from_file(&scenes.join(file))?;
        let (cpu_ms, cpu) = time_planes(&scene, runs);
        let shafts = GpuShafts::new(gpu, &scene).map_err(gpu_error)?;
        for method in [ShaftsMethod::Planes, ShaftsMethod::Compute] {
            let (wall, gpu_ms, frame) = time_gpu(runs, || {
                let Rendered { frame, gpu_ms } = shafts.render(gpu, method)?;
                Ok((frame, gpu_ms))
            })?;
            let suffix = match method {
                ShaftsMethod::Planes => "gpu-planes",
                ShaftsMethod::Compute => "gpu-compute",
            };
            report(
                json,
                gpu,
                Case {
                    name: &format!("{name}.{suffix}"),
                    params: json!({
                        "width": scene.camera.width, "height": scene.camera.height,
                        "lights": scene.lights.len(), "planes": scene.planes.planes,
                        "sub_planes": scene.planes.sub_planes, "shadow_map": scene.planes.shadow_map,
                    }),
                    wall_ms: wall,
                    gpu_ms,
                    cpu_ms,
                    error: Some(frame.level_errors(&cpu, scene.display)?),
                },
            );
        }
    }
    Ok(())
}

pub fn bench_clouds(gpu: &Gpu, quick: bool, json: bool) -> Result<()> {
    let runs = if quick { 3 } else { 7 };
    let particles = Cumulus::default().generate();
    let to_sun = sun_direction(20.0, 40.0);
    let forward = 0.5;
    let sizes: &[usize] = if quick { &[128] } else { &[128, 256] };
    for &n in sizes {
        let mut buffer = IntensityBuffer::new(&particles, to_sun, n, forward, Splat::Pieces)?;
        let cpu_ms = median(
            (0..runs)
                .map(|_| {
                    time_ms(|| {
                        buffer
                            .update(&particles, to_sun, forward, Splat::Pieces)
                            .expect("valid")
                    })
                })
                .collect(),
        );
        let mut clouds = GpuClouds::new(gpu, &particles, n).map_err(gpu_error)?;
        let (wall, gpu_ms, ()) = time_gpu(runs, || {
            let ms = clouds.light(gpu, to_sun, forward, Splat::Pieces)?;
            Ok(((), ms))
        })?;
        let log_gamma = clouds.log_gamma(gpu).map_err(gpu_error)?;
        let worst = log_gamma
            .iter()
            .zip(&buffer.log_gamma)
            .map(|(a, b)| (a - b).abs() * b.exp())
            .fold(0.0f32, f32::max);
        report(
            json,
            gpu,
            Case {
                name: "clouds.light-pass.gpu",
                params: json!({"particles": particles.len(), "resolution": n, "splat": "pieces",
                               "max_gamma_difference": worst}),
                wall_ms: wall,
                gpu_ms,
                cpu_ms,
                error: None,
            },
        );
    }
    let buffer = IntensityBuffer::new(&particles, to_sun, 256, forward, Splat::Pieces)?;
    let mut clouds = GpuClouds::new(gpu, &particles, 256).map_err(gpu_error)?;
    clouds
        .light(gpu, to_sun, forward, Splat::Pieces)
        .map_err(gpu_error)?;
    let camera = camera(&particles);
    let light = Lighting {
        to_sun,
        sun: glam::Vec3::ONE,
        ambient: glam::Vec3::splat(0.04),
        phase: CloudPhase::CloudMie,
    };
    let mut cpu = Frame::new(1, 1);
    let cpu_ms = median(
        (0..runs)
            .map(|_| time_ms(|| cpu = render(&particles, &buffer, &camera, &light, None)))
            .collect(),
    );
    let (wall, gpu_ms, frame) = time_gpu(runs, || {
        let Rendered { frame, gpu_ms } = clouds.render(gpu, &camera, &light, None)?;
        Ok((frame, gpu_ms))
    })?;
    let display = Display {
        exposure: 10.0,
        tone: ToneMap::Exponential,
    };
    report(
        json,
        gpu,
        Case {
            name: "clouds.frame.gpu",
            params: json!({"particles": particles.len(), "width": camera.width, "height": camera.height}),
            wall_ms: wall,
            gpu_ms,
            cpu_ms,
            error: Some(frame.level_errors(&cpu, display)?),
        },
    );
    Ok(())
}
