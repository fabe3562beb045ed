//! `atmo bench sky`: the skylight map by sampling shells against the reference
//! integrator; with `--backend gpu`, the shell method on the GPU beside the CPU.

use std::time::Instant;

use anyhow::Result;
use atmo::image::{Display, Frame, ToneMap};
use atmo::reference::sky::{ReferenceSettings, ReferenceSky};
use atmo::sky::aerial::{quadratic_slices, AerialRays};
use atmo::sky::{Order, SkyModel, SkyPicture, SkySettings, View};
use atmo::view::{Camera, Fov, Sun};
use atmo::Atmosphere;
use atmo_gpu::sky::{GpuAerial, GpuSkyModel, SkyPass, SkyTarget};
use atmo_gpu::{Gpu, GpuError, Rendered};
use glam::Vec3;
use indicatif::{ProgressBar, ProgressStyle};
use rayon::prelude::*;
use serde_json::{json, Value};

use super::{emit, levels, median, report, time_gpu, time_ms, Case};
use crate::backend::gpu_error;

/// The frame the sky benches draw: 1920 x 1080, looking north 15 deg up, 70 deg high.
pub(super) fn hd_view() -> atmo::Result<View> {
    Ok(View {
        camera: Camera::yaw_pitch(Vec3::ZERO, 0.0, 15.0, Fov::Vertical(70.0), (1920, 1080))?,
        sun_disc: true,
    })
}

pub fn cpu(quick: bool, json: bool) -> Result<()> {
    all_orders(quick, json)?;
    // The paper's Fig. 7(a): 7000 m, sun at 30 degrees; its orders (the reference
    // integrator's second order is brute force) and no ozone; a black ground, as the
    // brute-force second order has none.
    let (altitude, sun_deg) = (7000.0, 30.0f64);
    let mut atmosphere = Atmosphere::earth().with_ozone(false)?;
    atmosphere.ground_albedo = 0.0;
    let settings = SkySettings::paper();
    let (runs, cold_runs, subset) = if quick { (10, 2, 4) } else { (40, 5, 8) };
    let sun = sun_deg.to_radians();

    let model = SkyModel::new(&atmosphere, &settings, altitude)?;
    for k in 0..3 {
        std::hint::black_box(model.skylight_map(sun + k as f64 * 1e-3));
    }
    // The sun moves a little each run: everything sun-dependent is recomputed.
    let map_ms = moving_sun_ms(&model, sun, runs);
    let cold_ms = median(
        (0..cold_runs)
            .map(|_| {
                time_ms(|| {
                    let m =
                        SkyModel::new(&atmosphere, &settings, altitude).expect("validated above");
                    std::hint::black_box(m.skylight_map(sun));
                })
            })
            .collect(),
    );
    let map = model.skylight_map(sun);

    // The baseline: the converged reference on a subset of the map's directions, its
    // per-direction time scaled to the whole map.
    let grid = &map.grid;
    let pick = |count: usize, k: usize| k * (count - 1) / (subset - 1);
    let directions: Vec<(usize, usize)> = (0..subset)
        .flat_map(|a| (0..subset).map(move |e| (pick(grid.azimuths, a), pick(grid.elevations, e))))
        .collect();
    let reference = ReferenceSky::new(&atmosphere, altitude, sun, ReferenceSettings::CONVERGED);
    let progress = ProgressBar::new(directions.len() as u64).with_style(
        ProgressStyle::with_template("reference {bar:30} {pos}/{len} eta {eta}")
            .expect("static template"),
    );
    let results: Vec<(f64, Vec<f64>)> = directions
        .par_iter()
        .map(|&(i, j)| {
            let start = Instant::now();
            let r = reference.radiance(grid.azimuth(i), grid.elevation(j), 1, 2);
            progress.inc(1);
            (start.elapsed().as_secs_f64() * 1e3, r)
        })
        .collect();
    progress.finish_and_clear();
    let per_direction_ms = median(results.iter().map(|r| r.0).collect());
    // Rays ran two at a time on two cores: one ray's time / 2 per direction on the machine.
    let threads = rayon::current_num_threads() as f64;
    let baseline_ms = per_direction_ms * (grid.azimuths * grid.elevations) as f64 / threads;
    let mut errors = Vec::new();
    for (&(i, j), (_, want)) in directions.iter().zip(&results) {
        for (got, want) in map.at(i, j).iter().zip(want) {
            errors.push((*got as f64 - want) / want);
        }
    }
    let rms = (errors.iter().map(|e| e * e).sum::<f64>() / errors.len() as f64).sqrt();
    let max = errors.iter().fold(0.0f64, |m, e| m.max(e.abs()));

    // That the reference is converged: doubling all its counts, on two directions.
    let doubling_change = if quick {
        None
    } else {
        let doubled = ReferenceSky::new(
            &atmosphere,
            altitude,
            sun,
            ReferenceSettings::CONVERGED.doubled(),
        );
        let changes: Vec<f64> = [directions[1], directions[directions.len() / 2]]
            .par_iter()
            .map(|&(i, j)| {
                let a = reference.radiance(grid.azimuth(i), grid.elevation(j), 1, 2);
                let b = doubled.radiance(grid.azimuth(i), grid.elevation(j), 1, 2);
                a.iter()
                    .zip(&b)
                    .fold(0.0f64, |m, (a, b)| m.max(((a - b) / b).abs()))
            })
            .collect();
        Some(changes.into_iter().fold(0.0, f64::max))
    };

    let params = json!({
        "altitude_m": altitude, "sun_elevation_deg": sun_deg, "directions": settings.directions,
        "shells": settings.shells, "order": settings.order,
        "scattering_directions": settings.scattering_directions, "channels": atmosphere.channels(),
        "threads": rayon::current_num_threads(),
        "samples_per_map": model.view_samples() * grid.azimuths,
    });
    let reference_info = json!({
        "directions_timed": directions.len(), "scaled_to": grid.azimuths * grid.elevations,
        "per_direction_ms": per_direction_ms, "doubling_change": doubling_change,
    });
    let cases = [("sky.map", map_ms), ("sky.map-cold", cold_ms)];
    for (name, ms) in cases {
        let line = json!({
            "bench": name, "params": params, "median_ms": ms, "baseline": "sky.reference",
            "baseline_median_ms": baseline_ms, "ratio": baseline_ms / ms,
            "error": {"rms": rms, "max": max}, "reference": reference_info,
        });
        emit(
            json,
            line,
            format!(
                "{name:<14} {ms:>9.2} ms   reference {baseline_ms:>10.0} ms   ratio {:>8.0}   error rms {:.4} max {:.4}",
                baseline_ms / ms,
                rms,
                max
            ),
        );
    }
    if !json {
        outln!(
            "reference: {} directions timed ({per_direction_ms:.0} ms each), scaled to {}; doubling its counts changes it by {}",
            directions.len(),
            grid.azimuths * grid.elevations,
            doubling_change.map_or("(not checked with --quick)".into(), |c| format!("{:.3} %", 100.0 * c))
        );
    }
    Ok(())
}

/// The median time of `model`'s skylight map over `runs` runs, the sun moving a little
/// each run so that everything sun-dependent is recomputed.
fn moving_sun_ms(model: &SkyModel, sun: f64, runs: usize) -> f64 {
    median(
        (0..runs)
            .map(|k| {
                time_ms(|| {
                    std::hint::black_box(model.skylight_map(sun + k as f64 * 1e-4));
                })
            })
            .collect(),
    )
}

/// `sky.map` with every order of both species (`"order": "all"`): the map when the sun
/// moves and from nothing, against the path-traced reference of every order (single
/// scattering by quadrature plus the path tracer's higher orders) on a few directions,
/// its time scaled to the whole map.
pub fn all_orders(quick: bool, json: bool) -> Result<()> {
    let (altitude, sun_deg) = (7000.0, 30.0f64);
    let atmosphere = Atmosphere::earth();
    let settings = SkySettings {
        order: Order::All,
        multiple_mie: true,
        ..SkySettings::default()
    };
    let (runs, paths) = if quick { (10, 1000) } else { (40, 8000) };
    let sun = sun_deg.to_radians();
    let mut model = None;
    let cold_ms = time_ms(|| model = Some(SkyModel::new(&atmosphere, &settings, altitude)));
    let model = model.expect("timed above")?;
    let map_ms = moving_sun_ms(&model, sun, runs);
    let map = model.skylight_map(sun);
    let grid = &map.grid;
    let directions = [(0, 0), (0, 20), (32, 5), (63, 40), (20, 63), (50, 10)];
    let reference = ReferenceSky::new(&atmosphere, altitude, sun, ReferenceSettings::CONVERGED);
    let results: Vec<(f64, Vec<f64>)> = directions
        .par_iter()
        .map(|&(i, j)| {
            let start = Instant::now();
            let (azimuth, elevation) = (grid.azimuth(i), grid.elevation(j));
            let single = reference.radiance(azimuth, elevation, 1, 1);
            let (multiple, _) = reference.multiple_scattering(azimuth, elevation, paths, 1);
            let radiance = single.iter().zip(&multiple).map(|(s, m)| s + m).collect();
            (start.elapsed().as_secs_f64() * 1e3, radiance)
        })
        .collect();
    let per_direction_ms = median(results.iter().map(|r| r.0).collect());
    let threads = rayon::current_num_threads() as f64;
    let baseline_ms = per_direction_ms * (grid.azimuths * grid.elevations) as f64 / threads;
    let errors: Vec<f64> = directions
        .iter()
        .zip(&results)
        .flat_map(|(&(i, j), (_, want))| {
            map.at(i, j)
                .iter()
                .zip(want)
                .map(|(got, want)| (*got as f64 - want) / want)
                .collect::<Vec<_>>()
        })
        .collect();
    let mean = errors.iter().sum::<f64>() / errors.len() as f64;
    let params = json!({
        "altitude_m": altitude, "sun_elevation_deg": sun_deg, "directions": settings.directions,
        "shells": settings.shells, "order": settings.order, "orders_computed": model.orders(),
        "multiple_mie": true, "paths_per_channel": paths,
        "threads": rayon::current_num_threads(),
    });
    aerial(&model, quick, json)?;
    for (name, ms) in [("sky.map", map_ms), ("sky.map-cold", cold_ms)] {
        let line = json!({
            "bench": name, "params": params, "median_ms": ms, "baseline": "sky.path-traced",
            "baseline_median_ms": baseline_ms, "ratio": baseline_ms / ms,
            "error": {"mean": mean}, "reference": {"directions_timed": directions.len(),
            "per_direction_ms": per_direction_ms},
        });
        emit(
            json,
            line,
            format!(
                "{name:<14} {ms:>9.2} ms   path traced {baseline_ms:>10.0} ms   ratio {:>8.0}   mean error {:+.4} (order all)",
                baseline_ms / ms,
                mean
            ),
        );
    }
    Ok(())
}

/// Froxels a side, the farthest slice (m) and the elevation rows of the `sky.aerial`
/// cases, CPU and GPU.
const FROXELS: u32 = 32;
const FROXELS_FAR_M: f64 = 100_000.0;
const FROXEL_ROWS: usize = 512;

/// The `sky.aerial` cases' marked rays of `model` and camera (60 deg, 5 deg up).
fn froxel_case(model: &SkyModel) -> Result<(AerialRays, Camera)> {
    let slices = quadratic_slices(FROXELS as usize, FROXELS_FAR_M);
    let rays = model.aerial_rays(FROXEL_ROWS, &slices)?;
    let size = (FROXELS, FROXELS);
    let camera = Camera::yaw_pitch(Vec3::ZERO, 0.0, 5.0, Fov::Vertical(60.0), size)?;
    Ok((rays, camera))
}

/// `sky.aerial`: the 32 x 32 x 32 froxels of a camera (60 deg, slices out to 100 km)
/// for a moving sun from `model`'s marked rays, against the aerial perspective of each
/// column's own ray (`SkyModel::aerial`) on a few columns, scaled to all of them.
fn aerial(model: &SkyModel, quick: bool, json: bool) -> Result<()> {
    let runs = if quick { 10 } else { 40 };
    let (rays, camera) = froxel_case(model)?;
    let (size, slices) = (FROXELS, rays.slices_m());
    let sun = |k: usize| Sun::from_degrees(30.0 + 1e-3 * k as f64, 20.0).expect("in range");
    let froxels_ms = median(
        (0..runs)
            .map(|k| {
                time_ms(|| {
                    std::hint::black_box(rays.froxels(model, sun(k), &camera));
                })
            })
            .collect(),
    );
    let froxels = rays.froxels(model, sun(0), &camera);
    let colour = atmo::atmosphere::spectrum::SpectrumToRgb::for_atmosphere(model.atmosphere());
    let basis = camera.pixel_basis();
    let columns: Vec<(u32, u32)> = (0..16).map(|k| ((k * 7) % size, (k * 13) % size)).collect();
    let start = Instant::now();
    let mut worst = 0.0f32;
    for &(x, y) in &columns {
        let d = basis.direction(x, y).expect("a pinhole sees every pixel");
        let lights = model.aerial_along(sun(0), d, slices)?;
        for (k, light) in lights.iter().enumerate() {
            let want = Vec3::from(colour.rgb(&light.inscatter));
            let got = froxels.inscatter[(k as u32 * size * size + y * size + x) as usize];
            worst = worst.max((got - want).abs().max_element() / want.max_element().max(1e-12));
        }
    }
    let per_column_ms = start.elapsed().as_secs_f64() * 1e3 / columns.len() as f64;
    let baseline_ms = per_column_ms * (size * size) as f64;
    emit(
        json,
        json!({
            "bench": "sky.aerial", "params": {"width": size, "height": size, "depth": size,
            "far_m": FROXELS_FAR_M, "rows": FROXEL_ROWS, "order": model.settings().order},
            "median_ms": froxels_ms, "baseline": "a ray per froxel column (SkyModel::aerial)",
            "baseline_median_ms": baseline_ms, "ratio": baseline_ms / froxels_ms,
            "error": {"max_relative": worst},
        }),
        format!(
            "sky.aerial     {froxels_ms:>9.2} ms   a ray per column {baseline_ms:>8.0} ms   ratio {:>6.0}   max rel. error {worst:.4} (32^3 froxels)",
            baseline_ms / froxels_ms
        ),
    );
    Ok(())
}

pub fn gpu(gpu: &Gpu, quick: bool, json: bool) -> Result<()> {
    // The CPU bench's case: the paper's Fig. 7(a), 7000 m, sun at 30 degrees.
    let atmosphere = Atmosphere::earth();
    let settings = SkySettings::default();
    let model = SkyModel::new(&atmosphere, &settings, 7000.0)?;
    let sky = GpuSkyModel::new(gpu, &model).map_err(gpu_error)?;
    let mut pass = SkyPass::new(gpu, SkyTarget::HEADLESS).map_err(gpu_error)?;
    let runs = if quick { 5 } else { 21 };
    let sun = Sun::from_degrees(30.0, 0.0)?;
    let (wall, gpu_ms, ()) = time_gpu(runs, || Ok(((), sky.maps_timed(gpu, sun.elevation())?)))?;
    let cpu_ms = median(
        (0..runs)
            .map(|_| {
                time_ms(|| {
                    std::hint::black_box((
                        model.skylight_map(sun.elevation()),
                        model.ground_map(sun.elevation()),
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
    // The aerial perspective's 32^3 froxels on the GPU (read back) and on the CPU.
    let (rays, camera) = froxel_case(&model)?;
    let aerial = GpuAerial::new(gpu, &sky, rays).map_err(gpu_error)?;
    let rays = aerial.rays();
    let mut froxels_wall = Vec::new();
    for _ in 0..runs {
        let start = Instant::now();
        aerial.froxels(gpu, &sky, sun, &camera).map_err(gpu_error)?;
        froxels_wall.push(start.elapsed().as_secs_f64() * 1e3);
    }
    let froxels_cpu = median(
        (0..runs)
            .map(|_| {
                time_ms(|| {
                    std::hint::black_box(rays.froxels(&model, sun, &camera));
                })
            })
            .collect(),
    );
    report(
        json,
        gpu,
        Case {
            name: "sky.aerial.gpu",
            params: json!({"width": FROXELS, "height": FROXELS, "depth": FROXELS,
                "far_m": FROXELS_FAR_M, "rows": FROXEL_ROWS, "model": params}),
            wall_ms: median(froxels_wall),
            gpu_ms: None,
            cpu_ms: froxels_cpu,
            error: None,
        },
    );
    sky_frame(
        gpu,
        json,
        ("sky.frame.gpu", json!({"model": params})),
        runs.min(7),
        |view| sky.render(gpu, &mut pass, sun, view),
        |view, frame| SkyPicture::new(&model, sun).render_into(view, frame),
    )
}

/// A 1920 x 1080 sky frame drawn `runs` times on the GPU and on the CPU, timed and
/// compared at the sky's exposure.
pub(super) fn sky_frame(
    gpu: &Gpu,
    json: bool,
    (name, params): (&str, Value),
    runs: usize,
    mut on_gpu: impl FnMut(&View) -> Result<Rendered, GpuError>,
    mut on_cpu: impl FnMut(&View, &mut Frame),
) -> Result<()> {
    let view = hd_view()?;
    let (wall, gpu_ms, frame) = time_gpu(runs, || {
        let r = on_gpu(&view)?;
        Ok((r.frame, r.gpu_ms))
    })?;
    let mut cpu = Frame::new(view.camera.width, view.camera.height);
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
            params: json!({"of": params, "width": view.camera.width, "height": view.camera.height}),
            wall_ms: wall,
            gpu_ms,
            cpu_ms,
            error: Some(levels(frame.level_errors(&cpu, display)?)),
        },
    );
    Ok(())
}
