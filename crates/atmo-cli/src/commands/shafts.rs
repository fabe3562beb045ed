//! `atmo shafts`: a scene of spotlights in haze, by the sample-plane method or the
//! ray-marching reference.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::Result;
use atmo::files::check_folder;
use atmo::image::{Frame, ImageKind};
use atmo::reference::shafts::RayMarcher;
use atmo::shafts::dmx::recording::{self, Player};
use atmo::shafts::edits::Edit;
use atmo::shafts::Scene;
use atmo_gpu::shafts::{ShaftsMethod, ShaftsRenderer};
use clap::{Args, ValueEnum};

use crate::args::ToneMapArg;
use crate::backend::{gpu_error, Backend, BackendArgs};

#[derive(Args)]
pub struct ShaftsArgs {
    /// Scene file (TOML; see docs/shafts.md and scenes/).
    scene: PathBuf,
    /// Change a key of the scene file before it is read, as KEY=VALUE (repeatable, in
    /// order): `--set spotlight[0].intensity=5000 --set 'camera.position=[0, 2, 9]'`;
    /// `KEY=` removes the key. What `atmo view stage` prints for its edits.
    #[arg(long = "set", value_name = "KEY=VALUE")]
    edits: Vec<String>,
    /// Output picture: .png (8-bit sRGB after the scene's exposure and tone map) or .exr
    /// (linear radiance, in cd/m^2 when intensities are in cd); with --animate a folder.
    #[arg(short, long, value_name = "FILE")]
    output: PathBuf,
    /// Play the scene's show (its `[[cue]]`s) into the folder -o names: frame_000000.png
    /// ... and animation.png (an animated PNG), from 0 to the end of the last cue's fade.
    #[arg(long, conflicts_with = "reference")]
    animate: bool,
    #[command(flatten)]
    chunk: crate::output::Chunk,
    /// With --animate: frames per second of show time.
    #[arg(long, requires = "animate", default_value_t = 24)]
    fps: u16,
    /// A still at this time into the show, s (default 0, the show's start).
    #[arg(long, conflicts_with = "animate")]
    time: Option<f32>,
    /// Drive the patched fixtures from a DMX recording (`atmo dmx record`, or `atmo
    /// view stage --dmx ... --record`): with --animate from 0 to its last frame (or the
    /// cues' end, if later), else a still at --time; the pictures the window drew at
    /// those times.
    #[arg(long, value_name = "FILE.dmx", conflicts_with = "reference")]
    dmx_file: Option<PathBuf>,
    /// Render with the ray-marching reference (shadow rays, exact phase and attenuation)
    /// instead of the sample planes.
    #[arg(long)]
    reference: bool,
    /// With --reference: samples per ray and light over the stretch inside the beam
    /// (default: converged, 2048).
    #[arg(long, requires = "reference", conflicts_with = "baseline")]
    samples: Option<u32>,
    /// With --reference: the paper's baseline instead, planes x sub-planes samples
    /// (180 at the defaults) over the whole ray.
    #[arg(long, requires = "reference")]
    baseline: bool,
    /// Sample planes (overrides the scene's render.planes).
    #[arg(long)]
    planes: Option<u32>,
    /// Sub-sample planes per interval (overrides render.sub_planes).
    #[arg(long)]
    sub_planes: Option<u32>,
    /// Shadow map texels along a side (overrides render.shadow_map).
    #[arg(long)]
    shadow_map: Option<u32>,
    /// Compute the scattered light only where the picture needs it and interpolate
    /// between (render.adaptive = true, the default; the CPU method: the GPU draws
    /// every pixel).
    #[arg(long, conflicts_with = "every_pixel")]
    adaptive: bool,
    /// Compute the scattered light at every pixel, the paper's method (render.adaptive
    /// = false).
    #[arg(long)]
    every_pixel: bool,
    /// Rays per pixel along each axis (overrides camera.supersampling).
    #[arg(long)]
    supersampling: Option<u32>,
    /// Exposure for PNG output (overrides display.exposure).
    #[arg(long)]
    exposure: Option<f32>,
    /// Tone map for PNG output (overrides display.tone_map).
    #[arg(long, value_enum)]
    tone_map: Option<ToneMapArg>,
    #[command(flatten)]
    device: BackendArgs,
    /// On the GPU: the planes drawn as additive quads (the paper's), or the same sums
    /// in one compute pass.
    #[arg(long, value_enum, default_value_t = GpuMethod::Planes)]
    gpu_method: GpuMethod,
}

/// `--gpu-method`.
#[derive(Clone, Copy, ValueEnum)]
pub enum GpuMethod {
    Planes,
    Compute,
}

impl From<GpuMethod> for ShaftsMethod {
    fn from(m: GpuMethod) -> Self {
        match m {
            GpuMethod::Planes => ShaftsMethod::Planes,
            GpuMethod::Compute => ShaftsMethod::Compute,
        }
    }
}

/// The scene of `path` with the command line's edits and overrides, validated. The
/// overrides are edits of the file's `[render]` after the `--set`s, so the scene is
/// built (its shadow maps charged to the memory budget) with them, and a message that
/// names `--shadow-map` is one the flag answers.
pub fn load_scene(
    path: &std::path::Path,
    edits: &[String],
    planes: Option<u32>,
    sub_planes: Option<u32>,
    shadow_map: Option<u32>,
) -> Result<Scene> {
    let overrides = [
        ("planes", planes),
        ("sub_planes", sub_planes),
        ("shadow_map", shadow_map),
    ];
    let mut edits = edits
        .iter()
        .map(|e| Edit::parse(e))
        .collect::<atmo::Result<Vec<_>>>()?;
    edits.extend(overrides.iter().filter_map(|(key, value)| {
        value.map(|v| Edit::set(&format!("render.{key}"), v.to_string()))
    }));
    let scene = atmo::shafts::edits::load(path, &edits)?;
    scene.validate_planes()?;
    Ok(scene)
}

pub fn run(args: ShaftsArgs) -> Result<()> {
    if !args.animate {
        ImageKind::of(&args.output)?;
    }
    check_folder(&args.output)?;
    let mut scene = load_scene(
        &args.scene,
        &args.edits,
        args.planes,
        args.sub_planes,
        args.shadow_map,
    )?;
    let recording = args
        .dmx_file
        .as_ref()
        .map(|path| read_recording(path, &scene))
        .transpose()?;
    if let Some(t) = args.time {
        atmo::error::check_range("--time", t as f64, 0.0, 1e6)?;
        scene.at_time(t);
    }
    if let (Some((bytes, _)), Some(path)) = (&recording, &args.dmx_file) {
        let t = args.time.unwrap_or(0.0);
        Player::new(bytes, &path.display().to_string(), &scene.show)?
            .pose(&mut scene, (t as f64 * 1e6).round() as u64)?;
    }
    let inputs: Vec<(&str, &std::path::Path)> = std::iter::once(("the scene", &*args.scene))
        .chain(
            args.dmx_file
                .iter()
                .map(|f| ("the DMX recording", f.as_path())),
        )
        .chain(
            scene
                .files
                .iter()
                .map(|f| ("a file the scene names", f.as_path())),
        )
        .collect();
    atmo::files::check_distinct(&args.output, &inputs)?;
    if args.adaptive || args.every_pixel {
        scene.planes.adaptive = args.adaptive;
    }
    if let Some(k) = args.supersampling {
        atmo::error::check_range("--supersampling", k as f64, 1.0, 16.0)?;
        scene.camera.supersampling = k;
    }
    let mut display = scene.display;
    if let Some(e) = args.exposure {
        atmo::error::check_positive("--exposure", e as f64, 1e12)?;
        display.exposure = e;
    }
    if let Some(t) = args.tone_map {
        display.tone = t.into();
    }
    if args.reference && args.device.backend == Backend::Gpu {
        return Err(atmo::Error::Invalid(
            "--reference runs on the CPU only; leave out --backend gpu".into(),
        )
        .into());
    }
    let gpu = if args.reference {
        None
    } else {
        args.device.open()?
    };
    if gpu.is_some() && args.adaptive {
        note!("atmo: the GPU draws the scattered light at every pixel; render.adaptive applies to the CPU method");
    }
    if args.animate {
        return animate(&args, scene, display, gpu.as_ref(), recording.as_ref());
    }
    let start = Instant::now();
    let (frame, method): (Frame, String) = if args.reference {
        let marcher = if args.baseline {
            RayMarcher::baseline(&scene)
        } else {
            RayMarcher {
                samples: args.samples.unwrap_or(RayMarcher::CONVERGED.samples),
                ..RayMarcher::CONVERGED
            }
        };
        atmo::error::check_range("--samples", marcher.samples as f64, 1.0, 1e6)?;
        let spinner = indicatif::ProgressBar::new_spinner()
            .with_message(format!("ray marching, {} samples a ray", marcher.samples));
        spinner.enable_steady_tick(std::time::Duration::from_millis(120));
        let frame = marcher.render(&scene);
        spinner.finish_and_clear();
        (
            frame,
            format!(
                "reference, {} samples per ray ({:?})",
                marcher.samples, marcher.span
            ),
        )
    } else {
        let method = ShaftsMethod::from(args.gpu_method);
        let drawn = ShaftsRenderer::new(gpu.as_ref(), method)
            .and_then(|mut shafts| shafts.draw(&scene))
            .map_err(gpu_error)?;
        let planes = format!(
            "{} planes x {} sub-planes, {}^2 shadow maps",
            scene.planes.planes, scene.planes.sub_planes, scene.planes.shadow_map
        );
        let how = match (&drawn.counts, drawn.gpu_ms) {
            (Some(counts), _) => format!(
                " (built in {:.1} ms){}",
                drawn.prepared_ms,
                if scene.planes.adaptive {
                    format!(
                        ", scattered light computed at {:.1} % of the pixels",
                        100.0 * counts.computed_share()
                    )
                } else {
                    String::new()
                }
            ),
            (None, gpu_ms) => format!(
                " on the GPU ({method:?}{})",
                gpu_ms.map_or(String::new(), |ms| format!(", {ms:.1} ms of GPU time"))
            ),
        };
        (drawn.frame, planes + &how)
    };
    let ms = start.elapsed().as_secs_f64() * 1e3;
    frame.write(&args.output, display.exposure, display.tone)?;
    note!(
        "{}: {} x {}, {} light(s), {method}: {ms:.1} ms; pixels in {}",
        args.output.display(),
        frame.width,
        frame.height,
        scene.light_count(),
        scene.unit.radiance_unit()
    );
    Ok(())
}

/// `--animate`: the show from 0 to its end at `args.fps`, each frame's moving heads
/// posed at its time; on the CPU a light's shadow map is rebuilt only when it moved, on
/// the GPU the passes are compiled once for all frames.
fn animate(
    args: &ShaftsArgs,
    mut scene: Scene,
    display: atmo::image::Display,
    gpu: Option<&atmo_gpu::Gpu>,
    recording: Option<&(Vec<u8>, u64)>,
) -> Result<()> {
    atmo::error::check_range("--fps", args.fps as f64, 1.0, 240.0)?;
    let recorded_s = recording.map_or(0.0, |(_, last_us)| *last_us as f64 * 1e-6) as f32;
    let duration = scene.show.duration().max(recorded_s);
    if duration <= 0.0 {
        return Err(atmo::Error::Invalid(format!(
            "{}: --animate plays the scene's cues{}, and {} none that take time (add \
             [[cue]]s with time_s or fade_s > 0)",
            args.scene.display(),
            if recording.is_some() {
                " and the DMX recording"
            } else {
                ""
            },
            if recording.is_some() {
                "they have"
            } else {
                "it has"
            },
        ))
        .into());
    }
    let origin = args
        .dmx_file
        .as_ref()
        .map_or(String::new(), |p| p.display().to_string());
    let mut player = recording
        .map(|(bytes, _)| Player::new(bytes, &origin, &scene.show))
        .transpose()?;
    let frames = (duration * args.fps as f32).ceil() as usize + 1;
    if frames > crate::output::MAX_FRAMES {
        return Err(atmo::Error::Invalid(format!(
            "--fps {}: the show's {duration} s at {} frames/s are {frames} frames; allowed at \
             most {} (lower --fps, or the last cue's time_s + fade_s)",
            args.fps,
            args.fps,
            crate::output::MAX_FRAMES
        ))
        .into());
    }
    let camera = &scene.camera;
    let size = (camera.width, camera.height);
    let mut shafts =
        ShaftsRenderer::new(gpu, ShaftsMethod::from(args.gpu_method)).map_err(gpu_error)?;
    // Shadow maps rebuilt and lights drawn over the frames (a prism in or out changes
    // the count).
    let (mut rebuilt, mut lights, start) = (0, 0, Instant::now());
    let written = crate::output::write_animation(
        &crate::output::Animation {
            command: "shafts",
            folder: &args.output,
            count: frames,
            fps: args.fps,
            size,
            display,
            chunk: &args.chunk,
        },
        |k, frame| {
            let t_s = k as f64 / args.fps as f64;
            match &mut player {
                Some(player) => player.pose(&mut scene, (t_s * 1e6).round() as u64)?,
                None => scene.at_time(t_s as f32),
            }
            lights += scene.light_count();
            let drawn = shafts.draw(&scene).map_err(gpu_error)?;
            rebuilt += drawn.maps_rebuilt;
            *frame = drawn.frame;
            Ok(())
        },
    )?;
    crate::output::report(&args.output, &written, start);
    let drawn = written.drawn.max(1);
    note!(
        "atmo: a show of {frames} frames, {} x {} at {} frames/s ({duration:.2} s of show), {:.1} light(s) a frame{}: {:.0} ms a frame drawn",
        size.0,
        size.1,
        args.fps,
        lights as f64 / drawn as f64,
        if gpu.is_some() {
            " on the GPU".to_string()
        } else {
            format!(", {rebuilt} of {lights} shadow maps rebuilt")
        },
        start.elapsed().as_secs_f64() * 1e3 / drawn as f64
    );
    Ok(())
}

/// The recording at `path` for `scene`, checked whole (a malformed record is an error
/// before anything is drawn), and the time of its last frame, us.
fn read_recording(path: &std::path::Path, scene: &Scene) -> Result<(Vec<u8>, u64)> {
    if scene.show.fixtures.iter().all(|f| f.patch.is_none()) {
        return Err(atmo::Error::Invalid(format!(
            "--dmx-file {}: the scene patches no fixture (give a fixture `dmx = {{ universe \
             = 1, address = 1 }}`; see docs/previz.md)",
            path.display()
        ))
        .into());
    }
    let bytes = atmo::files::read_bounded(path, "DMX recording", atmo::files::DATA_LIMIT_BYTES)?;
    let (last_us, _) = recording::extent(&bytes, &path.display().to_string())?;
    Ok((bytes, last_us))
}
