//! `atmo view`: the interactive window (the `atmo-view` crate).

use std::path::PathBuf;
use std::sync::Arc;

use anyhow::Result;
use atmo::shafts::edits::Edit;
use atmo::sky::SkylightTable;
use atmo::Error;
use atmo_view::clouds::CloudsMode;
use atmo_view::sky::{SkyMode, SkySource};
use atmo_view::stage::StageMode;
use atmo_view::{Mode, Options, Script};
use clap::{Args, Subcommand};

use crate::args::{AtmosphereArgs, ShellArgs, SkyPictureArgs};
use crate::backend::BackendArgs;
use crate::bench::percentile;
use crate::commands::clouds::{Cloud, CloudStill, WindowClouds};

#[derive(Args)]
pub struct ViewArgs {
    #[command(subcommand)]
    mode: ViewMode,
}

impl ViewArgs {
    /// The library's fields that the mode's flags set, for error messages (the
    /// stage's errors name its scene keys and flags themselves).
    pub fn flags(&self) -> &'static [(&'static str, &'static str)] {
        match self.mode {
            ViewMode::Sky(_) => super::sky::FLAGS,
            ViewMode::Clouds(_) => super::clouds::FLAGS,
            ViewMode::Stage(_) => &[],
        }
    }
}

#[derive(Subcommand)]
enum ViewMode {
    /// The sky, live: drag to look, arrows move the sun, R / F climb and descend,
    /// space runs the time of day, P saves a screenshot and its `atmo sky` command;
    /// every flag of `atmo sky` sets the first picture.
    Sky(ViewSkyArgs),
    /// A shafts scene, live: drag to orbit, right-drag aims the panel's light, the
    /// panel edits the camera, haze, display and each light (every edit is one of
    /// `atmo shafts --set`), space plays the show, S saves the scene file, P saves a
    /// screenshot and its `atmo shafts` command; the file is read again when it
    /// changes on disk.
    Stage(ViewStageArgs),
    /// A cloud, live: arrows move the sun, drag orbits the camera, R / F nearer and
    /// farther, space sends the sun round, P saves a screenshot and its `atmo clouds`
    /// command; every flag of `atmo clouds` (but the animation's) sets the first
    /// picture.
    Clouds(ViewCloudsArgs),
}

#[derive(Args)]
pub struct ViewCloudsArgs {
    #[command(flatten)]
    still: CloudStill,
    #[command(flatten)]
    window: WindowArgs,
    #[command(flatten)]
    device: BackendArgs,
}

#[derive(Args)]
pub struct ViewStageArgs {
    /// Scene file (TOML; see docs/shafts.md and scenes/).
    scene: PathBuf,
    /// Change a key of the scene file first, as KEY=VALUE (repeatable), as `atmo
    /// shafts --set` does; "save scene" writes these edits too.
    #[arg(long = "set", value_name = "KEY=VALUE")]
    edits: Vec<String>,
    /// The show's time to start at, s.
    #[arg(long, default_value_t = 0.0)]
    time: f32,
    /// The window's width, pixels (default the scene camera's).
    #[arg(long)]
    width: Option<u32>,
    /// The window's height, pixels (default the scene camera's).
    #[arg(long)]
    height: Option<u32>,
    /// Listen to a lighting desk: its DMX by sACN (E1.31) or Art-Net moves the
    /// patched fixtures (docs/previz.md).
    #[arg(long, value_enum, value_name = "PROTOCOL")]
    dmx: Option<crate::commands::dmx::ProtocolArg>,
    #[command(flatten)]
    listen: crate::commands::dmx::ListenArgs,
    /// With --dmx: write what arrives to this .dmx file (in place when the window
    /// closes), which `atmo shafts --dmx-file` renders offline.
    #[arg(long, value_name = "FILE.dmx", requires = "dmx")]
    record: Option<PathBuf>,
    #[command(flatten)]
    window: WindowArgs,
    #[command(flatten)]
    device: BackendArgs,
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
    /// `FRAME aim LIGHT X Y` or `FRAME set PARAMETER VALUE` (sky: PARAMETER is a flag of
    /// atmo sky, without --; stage: a key of the scene file as --set takes it, or time).
    #[arg(long, value_name = "FILE")]
    script: Option<PathBuf>,
    /// While a picture drawn on the CPU keeps changing (a drag, a slider, a show
    /// playing), draw it at 1/K of the window's size in each direction, and whole as
    /// soon as it stops; 1 draws every frame whole (1-16).
    #[arg(long, value_name = "K", default_value_t = 4)]
    preview: u32,
}

pub fn run(args: ViewArgs) -> Result<()> {
    // Everything is checked before the window opens.
    let (mode, size, window, device): (Box<dyn Mode>, _, _, _) = match args.mode {
        ViewMode::Sky(args) => {
            let size = (args.picture.width, args.picture.height);
            (Box::new(sky_mode(&args)?), size, args.window, args.device)
        }
        ViewMode::Stage(args) => {
            let edits = args
                .edits
                .iter()
                .map(|e| Edit::parse(e))
                .collect::<atmo::Result<Vec<_>>>()?;
            let mut mode = StageMode::new(&args.scene, edits, args.time)?;
            if let Some(protocol) = args.dmx {
                let patched = crate::commands::dmx::patched_universes(mode.scene());
                let settings = args.listen.settings(protocol.into(), &patched)?;
                if let Some(record) = &args.record {
                    atmo::files::check_folder(record)?;
                }
                mode.listen(settings, args.record.clone())?;
            } else if !args.listen.universes.is_empty() || args.listen.bind.is_some() {
                return Err(Error::Invalid(
                    "--universe and --bind say where to listen for DMX: give --dmx sacn or \
                     --dmx artnet with them"
                        .into(),
                )
                .into());
            }
            let camera = &mode.scene().camera;
            let size = (
                args.width.unwrap_or(camera.width),
                args.height.unwrap_or(camera.height),
            );
            for (field, v) in [("--width", size.0), ("--height", size.1)] {
                atmo::error::check_range(field, v as f64, 1.0, 16384.0)?;
            }
            (Box::new(mode), size, args.window, args.device)
        }
        ViewMode::Clouds(args) => {
            let cloud = Cloud::new(&args.still)?;
            let size = (cloud.camera.width, cloud.camera.height);
            let device = args.device;
            let pictures = WindowClouds::new(cloud);
            let params = pictures.params();
            let mode = CloudsMode::new(params, Box::new(pictures));
            (Box::new(mode), size, args.window, device)
        }
    };
    atmo::error::check_range("preview", window.preview as f64, 1.0, 16.0)?;
    if window.frames == Some(0) {
        return Err(Error::out_of_range("frames", 0.0, "[1, inf)").into());
    }
    let script = match &window.script {
        Some(path) => Script::read(path)?,
        None => Script::default(),
    };
    let options = Options {
        size,
        frames: window.frames,
        screenshot: window.screenshot,
        script,
        backend: device.backend,
        adapter: device.adapter,
        preview: window.preview,
    };
    let timings = atmo_view::run(options, mode)?;
    if window.timings {
        let stats = |v: &[f64]| {
            let at = |q| (!v.is_empty()).then(|| percentile(v.to_vec(), q));
            serde_json::json!({"median_ms": at(0.5), "p95_ms": at(0.95), "count": v.len()})
        };
        let mut line = serde_json::json!({
            "frame": stats(&timings.frame_ms),
            "method": stats(&timings.method_ms),
        });
        for (name, value) in &timings.figures.values {
            line[*name] = serde_json::json!(value);
        }
        for (name, series) in &timings.figures.series {
            line[*name] = stats(series);
        }
        outln!("{line}");
    }
    Ok(())
}

/// The sky mode of `atmo view sky`'s flags.
fn sky_mode(args: &ViewSkyArgs) -> Result<SkyMode> {
    let params = args.picture.params()?;
    let (source, flags) = match &args.table {
        Some(path) => (
            SkySource::Table(Arc::new(SkylightTable::read(path)?)),
            format!("--table {}", path.display()),
        ),
        None => {
            let atmosphere = args.medium.load()?;
            let settings = args.method.settings(&args.medium);
            settings.validate(&atmosphere)?;
            let flags = format!(
                "{} {}",
                args.medium.flags(),
                args.method.flags(&args.medium)
            );
            (
                SkySource::Shells {
                    atmosphere: Box::new(atmosphere),
                    settings,
                },
                flags,
            )
        }
    };
    SkyMode::new(params, source, flags)
}
