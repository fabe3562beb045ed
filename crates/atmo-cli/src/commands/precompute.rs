//! `atmo precompute sky`: the skylight table over sun elevation and altitude,
//! compressed by SVD (sky 4.1), written to a `.atmo-sky` file.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use anyhow::Result;
use atmo::image::Display;
use atmo::sky::table::{parts, ErrorBound, SkylightTable, TablePart, TableSettings};
use clap::{Args, Subcommand, ValueEnum};
use indicatif::{ProgressBar, ProgressStyle};

use crate::args::{AtmosphereArgs, ShellArgs, ToneMapArg};

#[derive(Args)]
pub struct PrecomputeArgs {
    #[command(subcommand)]
    what: Precompute,
}

#[derive(Subcommand)]
enum Precompute {
    /// The skylight table for every sun elevation and viewpoint altitude (sky 4.1).
    Sky(SkyTableArgs),
}

#[derive(Args)]
pub struct SkyTableArgs {
    /// Output table file (.atmo-sky by convention); with --part, the folder the part's
    /// file goes into.
    #[arg(short, long, value_name = "FILE")]
    output: PathBuf,
    /// Compute part K of N (K from 1 to N) of the table's maps, for a render farm: the
    /// part's file goes into the folder -o, and is kept if it is there already (a
    /// requeued task resumes). `--merge` makes the table from all N.
    #[arg(long, value_name = "K/N", value_parser = crate::args::parse_part, conflicts_with = "merge")]
    part: Option<(usize, usize)>,
    /// Make the table from the parts in this folder (each once, of one precompute), with
    /// their atmosphere and settings (the settings given here are not used); byte for
    /// byte the table a whole run makes.
    #[arg(long, value_name = "FOLDER")]
    merge: Option<PathBuf>,
    #[command(flatten)]
    medium: AtmosphereArgs,
    #[command(flatten)]
    method: ShellArgs,
    /// Sun elevations M, from --min-sun-elevation to the zenith (sky (13)).
    #[arg(long, default_value_t = 128)]
    sun_steps: usize,
    /// Lowest sun elevation, degrees (the paper: 0; below 0 covers dusk and dawn).
    #[arg(long, default_value_t = -10.0)]
    min_sun_elevation: f64,
    /// How many times denser sun elevations are at the horizon than far from it (1:
    /// even, as the paper); the sky changes fastest there.
    #[arg(long, default_value_t = TableSettings::default().sun_horizon_density)]
    sun_horizon_density: f64,
    /// Viewpoint altitudes N, from the ground to --max-altitude (sky (14)).
    #[arg(long, default_value_t = 32)]
    altitude_steps: usize,
    /// Highest viewpoint altitude h0, metres (paper: 13000).
    #[arg(long, default_value_t = 13_000.0)]
    max_altitude: f64,
    /// Spacing of the altitude grid: h_i = h0 (i / (N - 1))^power (1: even).
    #[arg(long, default_value_t = TableSettings::default().altitude_power)]
    altitude_power: f64,
    /// Largest error per view direction over all suns and altitudes, in displayed sRGB
    /// values (1/255 is one 8-bit step) at --exposure and --tone-map; a number or a/b.
    #[arg(long, default_value = "1/255", value_parser = parse_fraction)]
    epsilon: f32,
    /// The exposure the error is measured at (as `atmo sky --exposure`).
    #[arg(long, default_value_t = 0.15)]
    exposure: f32,
    /// The tone map the error is measured through.
    #[arg(long, value_enum, default_value_t = ToneMapArg::Exponential)]
    tone_map: ToneMapArg,
    /// Measure the error on the sRGB-encoded values (what a PNG holds) or on the linear
    /// tone-mapped ones (a linear frame buffer, as the paper's 8-bit values).
    #[arg(long, value_enum, default_value_t = Measure::Srgb)]
    epsilon_on: Measure,
}

#[derive(Clone, Copy, ValueEnum)]
enum Measure {
    Srgb,
    Linear,
}

/// A number written as a decimal or a fraction `a/b`.
fn parse_fraction(s: &str) -> std::result::Result<f32, String> {
    let number = |t: &str| t.trim().parse::<f32>().map_err(|e| format!("`{t}`: {e}"));
    match s.split_once('/') {
        Some((a, b)) => Ok(number(a)? / number(b)?),
        None => number(s),
    }
}

pub fn run(args: PrecomputeArgs) -> Result<()> {
    let Precompute::Sky(args) = args.what;
    if let Some(folder) = &args.merge {
        return merge(folder, &args.output);
    }
    let atmosphere = args.medium.load()?;
    let settings = TableSettings {
        sky: args.method.settings(&args.medium),
        sun_steps: args.sun_steps,
        min_sun_elevation: args.min_sun_elevation.to_radians(),
        altitude_steps: args.altitude_steps,
        max_altitude_m: args.max_altitude,
        altitude_power: args.altitude_power,
        sun_horizon_density: args.sun_horizon_density,
        bound: ErrorBound {
            epsilon: args.epsilon,
            display: Display {
                exposure: args.exposure,
                tone: args.tone_map.into(),
            },
            srgb: matches!(args.epsilon_on, Measure::Srgb),
        },
    };
    settings.validate(&atmosphere)?;
    if let Some((part, parts)) = args.part {
        return compute_part(&atmosphere, &settings, part, parts, &args.output);
    }
    atmo::files::check_folder(&args.output)?;
    if let Some(input) = &args.medium.atmosphere {
        atmo::files::check_distinct(&args.output, &[("--atmosphere", input)])?;
    }
    let start = Instant::now();
    let bar = maps_bar(settings.sun_steps * settings.altitude_steps);
    let values = SkylightTable::skylight_matrices(&atmosphere, &settings, &|done, _| {
        bar.set_position(done as u64)
    })?;
    bar.finish_and_clear();
    let maps_s = start.elapsed().as_secs_f64();
    let spinner = ProgressBar::new_spinner().with_message("SVD and term counts per channel");
    spinner.enable_steady_tick(Duration::from_millis(120));
    let svd_start = Instant::now();
    let table = SkylightTable::from_matrices(&atmosphere, &settings, &values);
    spinner.finish_and_clear();
    let table = table?;
    let svd_s = svd_start.elapsed().as_secs_f64();
    table.write(&args.output)?;
    let bytes = std::fs::metadata(&args.output)?.len();
    note!(
        "atmo: {} ({bytes} bytes): {} skylight maps in {maps_s:.1} s, SVD and term counts in \
         {svd_s:.1} s; {} terms at most; largest error at the grid points {:.3} epsilon",
        args.output.display(),
        settings.sun_steps * settings.altitude_steps,
        table.max_terms(),
        table.grid_error(),
    );
    Ok(())
}

/// A bar on the terminal counting `maps` skylight maps.
fn maps_bar(maps: usize) -> ProgressBar {
    ProgressBar::new(maps as u64)
        .with_style(
            ProgressStyle::with_template(
                "{msg} [{bar:32}] {pos}/{len} skylight maps, {elapsed} elapsed, ETA {eta}",
            )
            .expect("valid template")
            .progress_chars("=> "),
        )
        .with_message("shell method")
}

/// `--part K/N`: part `part` (from 0) of `parts` into the folder `folder`, unless a valid
/// file of that part with the same atmosphere and settings is there already.
fn compute_part(
    atmosphere: &atmo::Atmosphere,
    settings: &TableSettings,
    part: usize,
    parts: usize,
    folder: &Path,
) -> Result<()> {
    if folder.exists() && !folder.is_dir() {
        return Err(atmo::Error::Invalid(format!(
            "{}: with --part, -o names a folder for the parts",
            folder.display()
        ))
        .into());
    }
    let path = folder.join(TablePart::file_name(part, parts));
    let total = settings.sun_steps * settings.altitude_steps;
    let maps = TablePart::columns(total, part, parts).len();
    if let Ok(done) = TablePart::read(&path) {
        if done.index() == (part, parts) && done.is_of(atmosphere, settings) {
            note!(
                "atmo: {} is there already ({maps} skylight maps); kept",
                path.display()
            );
            return Ok(());
        }
    }
    std::fs::create_dir_all(folder).map_err(atmo::Error::io_at(folder))?;
    let start = Instant::now();
    let bar = maps_bar(maps);
    let computed = TablePart::compute(atmosphere, settings, part, parts, &|done, _| {
        bar.set_position(done as u64)
    });
    bar.finish_and_clear();
    computed?.write(&path)?;
    note!(
        "atmo: {} ({maps} skylight maps of {total}) in {:.1} s",
        path.display(),
        start.elapsed().as_secs_f64()
    );
    Ok(())
}

/// `--merge FOLDER`: the table from every part file in `folder`.
fn merge(folder: &Path, output: &Path) -> Result<()> {
    atmo::files::check_folder(output)?;
    let entries = std::fs::read_dir(folder).map_err(atmo::Error::io_at(folder))?;
    let mut paths = Vec::new();
    for entry in entries {
        let path = entry.map_err(atmo::Error::io_at(folder))?.path();
        if path.extension().is_some_and(|e| e == parts::EXTENSION) {
            paths.push(path);
        }
    }
    paths.sort();
    if paths.is_empty() {
        return Err(atmo::Error::Invalid(format!(
            "{}: no .{} files to merge (make them with `atmo precompute sky --part K/N`)",
            folder.display(),
            parts::EXTENSION
        ))
        .into());
    }
    let start = Instant::now();
    let parts = paths
        .iter()
        .map(|p| TablePart::read(p))
        .collect::<atmo::Result<Vec<_>>>()?;
    let read_s = start.elapsed().as_secs_f64();
    let count = parts.len();
    let spinner = ProgressBar::new_spinner().with_message("SVD and term counts per channel");
    spinner.enable_steady_tick(Duration::from_millis(120));
    let table = SkylightTable::merge(parts);
    spinner.finish_and_clear();
    let table = table?;
    table.write(output)?;
    note!(
        "atmo: {} ({} bytes) from {count} parts: read in {read_s:.1} s, SVD and term counts in \
         {:.1} s; {} terms at most; largest error at the grid points {:.3} epsilon",
        output.display(),
        std::fs::metadata(output)?.len(),
        start.elapsed().as_secs_f64() - read_s,
        table.max_terms(),
        table.grid_error(),
    );
    Ok(())
}
