//! `atmo bench sky-table`: the SVD skylight table (sky 4) against the shell method it
//! compresses, timed in the same run.

use std::sync::Arc;
use std::time::Instant;

use anyhow::Result;
use atmo::atmosphere::TransmittanceTable;
use atmo::image::Frame;
use atmo::sky::lighting::Lighting;
use atmo::sky::{Order, SkyModel, SkyPicture, SkylightTable, TableSettings};
use atmo::view::Sun;
use atmo::Atmosphere;
use atmo_gpu::sky::{GpuSkyTable, SkyPass, SkyTarget};
use atmo_gpu::Gpu;
use glam::Vec3;
use indicatif::{ProgressBar, ProgressStyle};
use serde_json::json;

use super::sky::{hd_view, sky_frame};
use super::{emit, median, report, time_gpu, time_ms, Case};
use crate::backend::gpu_error;

/// The `i`-th point of the van der Corput sequence in `base`: well-spread, reproducible
/// positions in [0, 1) for the off-grid samples.
fn van_der_corput(mut i: usize, base: usize) -> f64 {
    let (mut x, mut f) = (0.0, 1.0 / base as f64);
    while i > 0 {
        x += f * (i % base) as f64;
        i /= base;
        f /= base as f64;
    }
    x
}

/// The `q`-quantile of `v` (sorted in place).
fn quantile(v: &mut [f32], q: f64) -> f32 {
    v.sort_by(f32::total_cmp);
    v[((v.len() - 1) as f64 * q).round() as usize]
}

/// The table the benches draw from: every order of both species over the `earth`
/// ground, or with --quick a coarse one of the defaults' orders (a tenth of a minute),
/// for a smoke test; not the figures.
pub(super) fn table_settings(quick: bool) -> TableSettings {
    let mut settings = TableSettings::default();
    if !quick {
        settings.sky.order = Order::All;
        settings.sky.multiple_mie = true;
    }
    if quick {
        settings.sky.directions = 32;
        settings.sun_steps = 32;
        settings.altitude_steps = 8;
    }
    settings
}

pub fn cpu(quick: bool, json: bool) -> Result<()> {
    let atmosphere = Atmosphere::earth();
    let settings = table_settings(quick);
    let (altitudes, suns_each, map_runs, frame_runs) = if quick {
        (5, 4, 50, 3)
    } else {
        (50, 20, 400, 15)
    };
    let maps = settings.sun_steps * settings.altitude_steps;
    let bar = ProgressBar::new(maps as u64).with_style(
        ProgressStyle::with_template("precompute {bar:30} {pos}/{len} maps, ETA {eta}")
            .expect("static template"),
    );
    let start = Instant::now();
    let values = SkylightTable::skylight_matrices(&atmosphere, &settings, &|done, _| {
        bar.set_position(done as u64)
    })?;
    bar.finish_and_clear();
    let maps_ms = start.elapsed().as_secs_f64() * 1e3;
    let svd_start = Instant::now();
    let table = SkylightTable::from_matrices(&atmosphere, &settings, &values)?;
    let svd_ms = svd_start.elapsed().as_secs_f64() * 1e3;
    let precompute_ms = start.elapsed().as_secs_f64() * 1e3;
    drop(values);
    let file_bytes = table.to_bytes().len();
    let (sun_axis, altitude_axis) = (table.sun_axis(), table.altitude_axis());
    let params = json!({
        "directions": settings.sky.directions, "sun_steps": settings.sun_steps,
        "altitude_steps": settings.altitude_steps,
        "sun_range_deg": [sun_axis.min().to_degrees(), sun_axis.max().to_degrees()],
        "altitude_range_m": [altitude_axis.min(), altitude_axis.max()],
        "altitude_power": settings.altitude_power,
        "sun_horizon_density": settings.sun_horizon_density, "epsilon": settings.bound.epsilon,
        "exposure": settings.bound.display.exposure, "srgb": settings.bound.srgb,
        "shells": settings.sky.shells, "order": settings.sky.order,
        "threads": rayon::current_num_threads(),
    });
    let terms: Vec<f64> = (0..3)
        .flat_map(|c| table.terms(c).iter().map(|&t| t as f64))
        .collect();
    let mean_terms = terms.iter().sum::<f64>() / terms.len() as f64;
    emit(
        json,
        json!({
            "bench": "sky-table.precompute", "params": params, "median_ms": precompute_ms,
            "runs": 1, "svd_ms": svd_ms, "file_bytes": file_bytes,
            "baseline": "sky-table.maps (the uncompressed table)", "baseline_median_ms": maps_ms,
            "ratio": maps_ms / precompute_ms, "max_terms": table.max_terms(),
            "mean_terms": mean_terms,
            "uncompressed_bytes_8bit": settings.sky.directions.pow(2) * maps * 3,
        }),
        format!(
            "sky-table.precompute {precompute_ms:>9.0} ms (maps {maps_ms:.0} ms, SVD and term \
             counts {svd_ms:.0} ms); file {file_bytes} bytes; terms: max {}, mean {mean_terms:.1}",
            table.max_terms()
        ),
    );

    // Errors: at the grid points (measured by the precompute against the very maps it
    // compressed) and at quasi-random off-grid pairs, several suns per altitude.
    let pairs: Vec<(f64, f64)> = (0..altitudes)
        .flat_map(|a| {
            let h = altitude_axis.max() * van_der_corput(a + 1, 3);
            (0..suns_each).map(move |s| {
                let u = van_der_corput(a * suns_each + s + 1, 2);
                (sun_axis.min() + (sun_axis.max() - sun_axis.min()) * u, h)
            })
        })
        .collect();
    let errors = table.errors_against_direct(&pairs)?;
    let mut all: Vec<f32> = errors.iter().flatten().copied().collect();
    let offgrid_max = all.iter().copied().fold(0.0, f32::max);
    let offgrid_p999 = quantile(&mut all, 0.999);
    let offgrid_p99 = quantile(&mut all, 0.99);
    let worst = errors
        .iter()
        .zip(&pairs)
        .map(|(e, p)| (e.iter().copied().fold(0.0, f32::max), p))
        .max_by(|a, b| a.0.total_cmp(&b.0))
        .map(|(_, &(s, h))| json!({"sun_elevation_deg": s.to_degrees(), "altitude_m": h}));
    emit(
        json,
        json!({
            "bench": "sky-table.error", "params": params, "unit": "epsilon",
            "grid_max": table.grid_error(), "offgrid_max": offgrid_max,
            "offgrid_p999": offgrid_p999, "offgrid_p99": offgrid_p99,
            "offgrid_pairs": pairs.len(), "offgrid_worst_pair": worst,
            "baseline": "sky.map (the shell method, direct)",
        }),
        format!(
            "sky-table.error      grid max {:.3}, off-grid ({} pairs) max {offgrid_max:.2}, \
             p99.9 {offgrid_p999:.2}, p99 {offgrid_p99:.2} (units of epsilon)",
            table.grid_error(),
            pairs.len()
        ),
    );

    // Drawing: a skylight map at a new sun and altitude each run, against the shell
    // method at a new altitude (which builds its model) and at a fixed one (warm).
    let directions = settings.sky.directions.pow(2);
    let mut map = vec![Vec3::ZERO; directions];
    let mut scratch = Vec::new();
    let at = |k: usize| pairs[k % pairs.len()];
    for k in 0..10 {
        table.map_into(at(k).0, at(k).1, &mut map, &mut scratch)?;
    }
    let map_ms = median(
        (0..map_runs)
            .map(|k| {
                let (sun, h) = at(k);
                time_ms(|| {
                    table
                        .map_into(sun, h, &mut map, &mut scratch)
                        .expect("inside the table");
                    std::hint::black_box(&map);
                })
            })
            .collect(),
    );
    // Without the table: a model of the new altitude alone, from nothing.
    let cold_ms = median(
        (0..3)
            .map(|k| {
                let (sun, h) = at(k);
                time_ms(|| {
                    let transmittance = Arc::new(TransmittanceTable::new(table.atmosphere()));
                    let model = SkyModel::with_grid(
                        table.atmosphere(),
                        transmittance,
                        &table.settings().sky,
                        h,
                        table.grid(h).elevation_min,
                    )
                    .expect("inside the table");
                    std::hint::black_box(model.skylight_map(sun));
                })
            })
            .collect(),
    );
    let model: SkyModel = table.direct_model(7000.0)?;
    let warm_ms = median(
        (0..20)
            .map(|k| {
                time_ms(|| {
                    std::hint::black_box(model.skylight_map(at(k).0));
                })
            })
            .collect(),
    );
    emit(
        json,
        json!({
            "bench": "sky-table.map", "params": params, "median_ms": map_ms, "runs": map_runs,
            "baseline": "sky.map-cold (shell method at a new altitude)",
            "baseline_median_ms": cold_ms, "ratio": cold_ms / map_ms,
            "warm_shell_map_ms": warm_ms,
        }),
        format!(
            "sky-table.map        {map_ms:>9.4} ms   shell method cold {cold_ms:.0} ms (ratio \
             {:.0}), warm {warm_ms:.2} ms",
            cold_ms / map_ms
        ),
    );

    // A 1920 x 1080 frame from the table's map, against the same frame from the shell
    // method's maps (computed at that altitude, warm).
    let view = hd_view()?;
    let sun = Sun::from_degrees(30.0, 0.0)?;
    let picture = SkyPicture::from_table(&table, sun, 7000.0)?;
    let mut frame = Frame::new(view.camera.width, view.camera.height);
    picture.render_into(&view, &mut frame);
    let frame_ms = median(
        (0..frame_runs)
            .map(|_| time_ms(|| picture.render_into(&view, &mut frame)))
            .collect(),
    );
    let direct_ms = median(
        (0..3)
            .map(|_| time_ms(|| SkyPicture::new(&model, sun).render_into(&view, &mut frame)))
            .collect(),
    );
    emit(
        json,
        json!({
            "bench": "sky-table.frame", "params": params, "median_ms": frame_ms,
            "runs": frame_runs, "width": view.camera.width, "height": view.camera.height,
            "baseline": "sky.frame (shell method's maps, then the same frame)",
            "baseline_median_ms": direct_ms, "ratio": direct_ms / frame_ms,
        }),
        format!(
            "sky-table.frame      {frame_ms:>9.2} ms   shell method {direct_ms:.0} ms (ratio {:.1}), 1920x1080",
            direct_ms / frame_ms
        ),
    );

    // An engine's environment: the table's map for a new sun, the 1024 x 512
    // equirectangular map and the lighting (harmonics and irradiance, from its own 256
    // x 128 map), against the same from the shell method's maps.
    let envmap = |picture: &SkyPicture| {
        let map = picture.equirect(512, true);
        let lighting = Lighting::new(picture, table.atmosphere(), 7000.0, sun);
        std::hint::black_box((map, lighting));
    };
    let envmap_ms = median(
        (0..frame_runs)
            .map(|k| {
                time_ms(|| {
                    let moved = Sun::from_degrees(30.0 + 1e-3 * k as f64, 0.0).expect("in range");
                    let picture = SkyPicture::from_table(&table, moved, 7000.0).expect("in range");
                    envmap(&picture);
                })
            })
            .collect(),
    );
    let shell_ms = median(
        (0..3)
            .map(|_| time_ms(|| envmap(&SkyPicture::new(&model, sun))))
            .collect(),
    );
    emit(
        json,
        json!({
            "bench": "sky.envmap", "params": {"table": params, "width": 1024, "height": 512,
            "lighting": true}, "median_ms": envmap_ms, "runs": frame_runs,
            "baseline": "the same from the shell method's maps (warm model)",
            "baseline_median_ms": shell_ms, "ratio": shell_ms / envmap_ms,
        }),
        format!(
            "sky.envmap           {envmap_ms:>9.2} ms   shell method {shell_ms:.0} ms (ratio {:.1}), 1024x512 + lighting",
            shell_ms / envmap_ms
        ),
    );
    Ok(())
}

pub fn gpu(gpu: &Gpu, quick: bool, json: bool) -> Result<()> {
    let settings = table_settings(quick);
    note!("atmo: precomputing the table on the CPU (a minute at the defaults)");
    let table = SkylightTable::precompute(&Atmosphere::earth(), &settings, &|_, _| {})?;
    let sky = GpuSkyTable::new(gpu, &table).map_err(gpu_error)?;
    let mut pass = SkyPass::new(gpu, SkyTarget::HEADLESS).map_err(gpu_error)?;
    let runs = if quick { 5 } else { 21 };
    let (sun, altitude) = (Sun::from_degrees(30.0, 0.0)?, 7000.0);
    let (wall, gpu_ms, map) = time_gpu(runs, || sky.map(gpu, sun.elevation(), altitude))?;
    let cpu_map_ms = median(
        (0..runs)
            .map(|_| time_ms(|| drop(table.map(sun.elevation(), altitude))))
            .collect(),
    );
    let cpu_map = table.map(sun.elevation(), altitude)?;
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
        |view| sky.render(gpu, &mut pass, sun, altitude, view),
        |view, frame| {
            SkyPicture::from_table(&table, sun, altitude)
                .expect("inside the table")
                .render_into(view, frame)
        },
    )
}
