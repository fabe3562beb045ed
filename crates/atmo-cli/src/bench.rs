//! `atmo bench`: each method timed against its baseline in the same run, as
//! DESIGN.md describes: medians after a warm-up, ratios, and the error between them.

use std::time::Instant;

use anyhow::Result;
use atmo::reference::sky::{ReferenceSettings, ReferenceSky};
use atmo::sky::{SkyModel, SkySettings};
use atmo::Atmosphere;
use clap::{Args, ValueEnum};
use indicatif::{ProgressBar, ProgressStyle};
use rayon::prelude::*;
use serde_json::json;

use crate::backend::{Backend, BackendArgs};

#[derive(Args)]
pub struct BenchArgs {
    /// What to time.
    #[arg(value_enum)]
    area: Area,
    /// Fewer repetitions and reference directions: a minute instead of several.
    #[arg(long)]
    quick: bool,
    /// One JSON object per case on its own line, instead of a table.
    #[arg(long)]
    json: bool,
    /// shafts: the folder holding spotlight-sphere.toml and stage.toml.
    #[arg(long, default_value = "scenes")]
    scenes: std::path::PathBuf,
    /// shafts: where the plane sweep's shafts-sweep.csv and .svg are written.
    #[arg(long, default_value = ".")]
    sweep_dir: std::path::PathBuf,
    /// cpu: each method against its baseline; gpu: each GPU pipeline beside the same
    /// method on the CPU.
    #[arg(long, value_enum, default_value_t = Backend::Cpu)]
    backend: Backend,
    /// With --backend gpu: the adapter (part of its name, or a backend).
    #[arg(long, value_name = "NAME")]
    adapter: Option<String>,
}

#[derive(Clone, Copy, ValueEnum)]
enum Area {
    /// The skylight map by sampling shells against the reference integrator.
    Sky,
    /// The SVD skylight table: precompute, size, error against the shell method, and
    /// drawing a map and a 1920 x 1080 frame from it.
    SkyTable,
    /// Shafts of light: sample planes against ray marching on the paper's Fig. 6 scene,
    /// the five-light stage, and the sweep of plane and sub-plane counts.
    Shafts,
    /// Clouds: the intensity buffer's light pass against the Harris baseline, its error,
    /// and a frame.
    Clouds,
}

pub fn run(args: BenchArgs) -> Result<()> {
    if args.backend != Backend::Cpu {
        let device = BackendArgs {
            backend: Backend::Gpu,
            adapter: args.adapter.clone(),
        };
        let gpu = device
            .open()?
            .expect("--backend gpu opens a device or fails");
        return match args.area {
            Area::Sky => crate::bench_gpu::bench_sky(&gpu, args.quick, args.json),
            Area::SkyTable => crate::bench_gpu::bench_sky_table(&gpu, args.quick, args.json),
            Area::Shafts => {
                crate::bench_gpu::bench_shafts(&gpu, args.quick, args.json, &args.scenes)
            }
            Area::Clouds => crate::bench_gpu::bench_clouds(&gpu, args.quick, args.json),
        };
    }
    match args.area {
        Area::Sky => bench_sky(args.quick, args.json),
        Area::SkyTable => crate::bench_table::bench_sky_table(args.quick, args.json),
        Area::Clouds => crate::bench_clouds::bench_clouds(args.quick, args.json),
        Area::Shafts => {
            atmo::image::check_folder(&args.sweep_dir.join("shafts-sweep.csv"))?;
            crate::bench_shafts::bench_shafts(args.quick, args.json, &args.scenes, &args.sweep_dir)
        }
    }
}

pub fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(|a, b| a.total_cmp(b));
    v[v.len() / 2]
}

/// Milliseconds taken by `f`.
pub fn time_ms(f: impl FnOnce()) -> f64 {
    let start = Instant::now();
    f();
    start.elapsed().as_secs_f64() * 1e3
}

fn bench_sky(quick: bool, json: bool) -> Result<()> {
    // The paper's Fig. 7(a): 7000 m, sun at 30 degrees; its default map settings.
    let (altitude, sun_deg) = (7000.0, 30.0f64);
    let atmosphere = Atmosphere::earth();
    let settings = SkySettings::default();
    let (runs, cold_runs, subset) = if quick { (10, 2, 4) } else { (40, 5, 8) };
    let sun = sun_deg.to_radians();

    let model = SkyModel::new(&atmosphere, &settings, altitude)?;
    for k in 0..3 {
        std::hint::black_box(model.skylight_map(sun + k as f64 * 1e-3));
    }
    // The sun moves a little each run: everything sun-dependent is recomputed.
    let map_ms = median(
        (0..runs)
            .map(|k| {
                time_ms(|| {
                    std::hint::black_box(model.skylight_map(sun + k as f64 * 1e-4));
                })
            })
            .collect(),
    );
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
        if json {
            println!("{line}");
        } else {
            println!(
                "{name:<14} {ms:>9.2} ms   reference {baseline_ms:>10.0} ms   ratio {:>8.0}   error rms {:.4} max {:.4}",
                baseline_ms / ms,
                rms,
                max
            );
        }
    }
    if !json {
        println!(
            "reference: {} directions timed ({per_direction_ms:.0} ms each), scaled to {}; doubling its counts changes it by {}",
            directions.len(),
            grid.azimuths * grid.elevations,
            doubling_change.map_or("(not checked with --quick)".into(), |c| format!("{:.3} %", 100.0 * c))
        );
    }
    Ok(())
}
