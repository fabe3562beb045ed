//! `atmo view`: the interactive window (the `atmo-view` crate).

use std::path::PathBuf;
use std::sync::Arc;

use anyhow::Result;
use atmo::sky::SkylightTable;
use atmo::Error;
use atmo_view::sky::{SkyMode, SkySource};
use atmo_view::{Options, Script};
use clap::{Args, Subcommand};

use crate::args::{AtmosphereArgs, ShellArgs, SkyPictureArgs};
use crate::backend::{Backend, BackendArgs};
use crate::bench::percentile;

#[derive(Args)]
pub struct ViewArgs {
    #[command(subcommand)]
    mode: ViewMode,
}

#[derive(Subcommand)]
enum ViewMode {
    /// The sky, live: drag to look, arrows move the sun, R / F climb and descend,
    /// space runs the time of day, P saves a screenshot and its `atmo sky` command;
    /// every flag of `atmo sky` sets the first picture.
    Sky(ViewSkyArgs),
}

#[derive(Args)]
pub struct ViewSkyArgs {
    #[command(flatten)]
    picture: SkyPictureArgs,
    /// Draw from a skylight table (`atmo precompute sky`): any sun and altitude in its
    /// ranges, each frame in well under a millisecond.
    #[arg(long, value_name = "FILE.atmo-sky", conflicts_with_all = [
        "atmosphere", "ozone", "ground_albedo", "shells", "directions", "scattering_directions",
        "multiple_mie", "order",
    ])]
    table: Option<PathBuf>,
    #[command(flatten)]
    medium: AtmosphereArgs,
    #[command(flatten)]
    method: ShellArgs,
    #[command(flatten)]
    window: WindowArgs,
    #[command(flatten)]
    device: BackendArgs,
}

/// Runs without a person: for tests, benchmarks and reproducible shots.
#[derive(Args)]
struct WindowArgs {
    /// Draw this many frames, save the last to --screenshot (printing its still
    /// command) and close.
    #[arg(long, requires = "screenshot")]
    frames: Option<u64>,
    /// Where --frames saves the last frame: .png (8-bit sRGB) or .exr (linear).
    #[arg(long, value_name = "FILE", requires = "frames")]
    screenshot: Option<PathBuf>,
    /// At the end, print the frame and method times as one JSON line on stdout
    /// (median and 95th percentile, ms; what `atmo bench view` reads).
    #[arg(long)]
    timings: bool,
    /// Replay inputs, one a line: `FRAME key NAME`, `FRAME drag DX DY` or
    /// `FRAME set PARAMETER VALUE` (PARAMETER: a flag of atmo sky, without --).
    #[arg(long, value_name = "FILE")]
    script: Option<PathBuf>,
}

pub fn run(args: ViewArgs) -> Result<()> {
    let ViewMode::Sky(args) = args.mode;
    // Everything is checked before the window opens.
    let params = args.picture.params()?;
    if args.window.frames == Some(0) {
        return Err(Error::out_of_range("frames", 0.0, "[1, inf)").into());
    }
    let script = match &args.window.script {
        Some(path) => Script::read(path)?,
        None => Script::default(),
    };
    let (source, flags) = match &args.table {
        Some(path) => (
            SkySource::Table(Arc::new(SkylightTable::read(path)?)),
            format!("--table {}", path.display()),
        ),
        None => {
            let atmosphere = args.medium.load()?;
            let settings = args.method.settings();
            settings.validate(&atmosphere)?;
            let flags = format!("{} {}", args.medium.flags(), args.method.flags());
            (
                SkySource::Shells {
                    atmosphere: Box::new(atmosphere),
                    settings,
                },
                flags,
            )
        }
    };
    let mode = SkyMode::new(params, source, flags)?;
    let options = Options {
        size: (args.picture.width, args.picture.height),
        frames: args.window.frames,
        screenshot: args.window.screenshot,
        script,
        backend: match args.device.backend {
            Backend::Auto => atmo_view::Backend::Auto,
            Backend::Gpu => atmo_view::Backend::Gpu,
            Backend::Cpu => atmo_view::Backend::Cpu,
        },
        adapter: args.device.adapter,
    };
    let timings = atmo_view::run(options, mode)?;
    if args.window.timings {
        let stats = |v: &[f64]| {
            let at = |q| (!v.is_empty()).then(|| percentile(v.to_vec(), q));
            serde_json::json!({"median_ms": at(0.5), "p95_ms": at(0.95), "count": v.len()})
        };
        let line = serde_json::json!({
            "frame": stats(&timings.frame_ms),
            "method": stats(&timings.method_ms),
        });
        println!("{line}");
    }
    Ok(())
}
