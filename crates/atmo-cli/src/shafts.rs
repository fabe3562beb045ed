//! `atmo shafts`: a scene of spotlights in haze, by the sample-plane method or the
//! ray-marching reference; `atmo compare`: how far two renders are apart.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::Result;
use atmo::image::{check_folder, Display, Frame, ImageKind};
use atmo::reference::shafts::RayMarcher;
use atmo::shafts::{SamplePlanes, Scene};
use atmo_gpu::shafts::{GpuShafts, ShaftsMethod};
use clap::{Args, ValueEnum};

use crate::backend::{gpu_error, Backend, BackendArgs};
use crate::sky::ToneMapArg;

#[derive(Args)]
pub struct ShaftsArgs {
    /// Scene file (TOML; see docs/shafts.md and scenes/).
    scene: PathBuf,
    /// Output picture: .png (8-bit sRGB after the scene's exposure and tone map) or .exr
    /// (linear radiance, in cd/m^2 when intensities are in cd).
    #[arg(short, long, value_name = "FILE")]
    output: PathBuf,
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

/// The scene of `path` with the command line's overrides, validated.
pub fn load_scene(
    path: &std::path::Path,
    planes: Option<u32>,
    sub_planes: Option<u32>,
    shadow_map: Option<u32>,
) -> Result<Scene> {
    let mut scene = Scene::from_file(path)?;
    scene.planes.planes = planes.unwrap_or(scene.planes.planes);
    scene.planes.sub_planes = sub_planes.unwrap_or(scene.planes.sub_planes);
    scene.planes.shadow_map = shadow_map.unwrap_or(scene.planes.shadow_map);
    scene.planes.validate()?;
    Ok(scene)
}

pub fn run(args: ShaftsArgs) -> Result<()> {
    ImageKind::of(&args.output)?;
    check_folder(&args.output)?;
    let mut scene = load_scene(&args.scene, args.planes, args.sub_planes, args.shadow_map)?;
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
    let start = Instant::now();
    let (frame, method): (Frame, String) = if let Some(gpu) = &gpu {
        let shafts = GpuShafts::new(gpu, &scene).map_err(gpu_error)?;
        let rendered = shafts
            .render(gpu, args.gpu_method.into())
            .map_err(gpu_error)?;
        (
            rendered.frame,
            format!(
                "{} planes x {} sub-planes, {}^2 shadow maps on the GPU ({:?}{})",
                scene.planes.planes,
                scene.planes.sub_planes,
                scene.planes.shadow_map,
                ShaftsMethod::from(args.gpu_method),
                rendered
                    .gpu_ms
                    .map_or(String::new(), |ms| format!(", {ms:.1} ms of GPU time"))
            ),
        )
    } else if args.reference {
        let marcher = if args.baseline {
            RayMarcher::baseline(&scene)
        } else {
            RayMarcher {
                samples: args.samples.unwrap_or(RayMarcher::CONVERGED.samples),
                ..RayMarcher::CONVERGED
            }
        };
        atmo::error::check_range("--samples", marcher.samples as f64, 1.0, 1e6)?;
        (
            marcher.render(&scene),
            format!(
                "reference, {} samples per ray ({:?})",
                marcher.samples, marcher.span
            ),
        )
    } else {
        let planes = SamplePlanes::new(&scene);
        let prepared_ms = start.elapsed().as_secs_f64() * 1e3;
        (
            planes.render(),
            format!(
                "{} planes x {} sub-planes, {}^2 shadow maps (built in {prepared_ms:.1} ms)",
                scene.planes.planes, scene.planes.sub_planes, scene.planes.shadow_map
            ),
        )
    };
    let ms = start.elapsed().as_secs_f64() * 1e3;
    frame.write(&args.output, display.exposure, display.tone)?;
    eprintln!(
        "{}: {} x {}, {} light(s), {method}: {ms:.1} ms; pixels in {}",
        args.output.display(),
        frame.width,
        frame.height,
        scene.lights.len(),
        scene.unit.radiance_unit()
    );
    Ok(())
}

#[derive(Args)]
pub struct CompareArgs {
    /// First picture (.exr, linear radiance).
    a: PathBuf,
    /// Second picture (.exr), e.g. the reference.
    b: PathBuf,
    /// Difference image: |A - B| in 8-bit levels after the display below, times 10
    /// (white = 25.5 levels or more).
    #[arg(short, long, value_name = "FILE.png", default_value = "difference.png")]
    output: PathBuf,
    /// Exposure the levels are measured after.
    #[arg(long, default_value_t = 1.0)]
    exposure: f32,
    /// Tone map the levels are measured after.
    #[arg(long, value_enum, default_value_t = ToneMapArg::Exponential)]
    tone_map: ToneMapArg,
}

pub fn compare(args: CompareArgs) -> Result<()> {
    atmo::error::check_positive("--exposure", args.exposure as f64, 1e12)?;
    if ImageKind::of(&args.output)? != ImageKind::Png {
        return Err(
            atmo::Error::out_of_range("--output", args.output.display(), "a .png file").into(),
        );
    }
    check_folder(&args.output)?;
    let (a, b) = (Frame::read_exr(&args.a)?, Frame::read_exr(&args.b)?);
    let display = Display {
        exposure: args.exposure,
        tone: args.tone_map.into(),
    };
    let levels = a.level_errors(&b, display)?;
    let mut difference = Frame::new(a.width, a.height);
    let (mut sum, mut sum_b, mut max) = (0.0f64, 0.0f64, 0.0f64);
    for ((d, pa), pb) in difference.pixels.iter_mut().zip(&a.pixels).zip(&b.pixels) {
        for c in 0..3 {
            let diff = (pa[c] - pb[c]) as f64;
            sum += diff * diff;
            sum_b += (pb[c] as f64).powi(2);
            max = max.max(diff.abs());
            d[c] = 10.0 * (display.value(pa[c]) - display.value(pb[c])).abs();
        }
    }
    // The difference is already in display units: written with exposure 1, clamped.
    difference
        .pixels
        .iter_mut()
        .for_each(|p| *p = p.map(atmo::image::srgb_decode));
    difference.write(&args.output, 1.0, atmo::image::ToneMap::Clamp)?;
    let n = 3.0 * a.pixels.len() as f64;
    println!(
        "levels (8-bit, after exposure {} and the {:?} tone map): rms {:.3} ({:.3} % of 255), max {:.2}",
        args.exposure,
        display.tone,
        levels.rms,
        100.0 * levels.rms / 255.0,
        levels.max
    );
    println!(
        "linear: rms {:.4e} ({:.3} % of B's rms), max {:.4e}",
        (sum / n).sqrt(),
        100.0 * (sum / sum_b.max(1e-300)).sqrt(),
        max
    );
    println!("difference image: {}", args.output.display());
    Ok(())
}
