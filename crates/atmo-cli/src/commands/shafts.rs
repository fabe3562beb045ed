//! `atmo shafts`: a scene of spotlights in haze, by the sample-plane method or the
//! ray-marching reference.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::Result;
use atmo::files::check_folder;
use atmo::image::{Frame, ImageKind};
use atmo::reference::shafts::RayMarcher;
use atmo::shafts::{SamplePlanes, Scene};
use atmo_gpu::shafts::{GpuShafts, ShaftsMethod};
use clap::{Args, ValueEnum};

use crate::args::ToneMapArg;
use crate::backend::{gpu_error, Backend, BackendArgs};

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
    scene.validate_planes()?;
    Ok(scene)
}

pub fn run(args: ShaftsArgs) -> Result<()> {
    ImageKind::of(&args.output)?;
    check_folder(&args.output)?;
    let mut scene = load_scene(&args.scene, args.planes, args.sub_planes, args.shadow_map)?;
    let inputs: Vec<(&str, &std::path::Path)> = std::iter::once(("the scene", &*args.scene))
        .chain(
            scene
                .files
                .iter()
                .map(|f| ("a file the scene names", f.as_path())),
        )
        .collect();
    atmo::files::check_distinct(&args.output, &inputs)?;
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
