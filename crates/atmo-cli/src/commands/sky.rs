//! `atmo sky`: a picture of the sky, or its radiance along given directions.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

use anyhow::Result;
use atmo::image::{Display, Frame, ImageKind};
use atmo::sky::envmap::{self, EnvmapKind, CUBE_FACES};
use atmo::sky::lighting::Lighting;
use atmo::sky::{SkyModel, SkyPicture, SkylightTable};
use atmo::view::Sun;
use atmo::Atmosphere;
use atmo_gpu::sky::{GpuSkyModel, SkyRenderer, SkySource};
use clap::{Args, ValueEnum};
use indicatif::ProgressBar;
use serde_json::json;

use super::sky_table::{self, Animate, Animation};
use crate::args::{AtmosphereArgs, ShellArgs, SkyPictureArgs};
use crate::backend::{gpu_error, BackendArgs};
use crate::output::Chunk;

/// The library's fields that this command's flags set, for error messages.
pub const FLAGS: &[(&str, &str)] = &[
    ("sun.elevation_deg", "--sun-elevation"),
    ("sun.azimuth_deg", "--sun-azimuth"),
    ("altitude_m", "--altitude"),
    ("camera.yaw_deg", "--yaw"),
    ("camera.pitch_deg", "--pitch"),
    ("camera.fov_deg", "--fov"),
    ("width", "--width"),
    ("height", "--height"),
    ("max_interval_m", "--max-interval"),
    ("exposure", "--exposure"),
    ("latitude", "--latitude"),
    ("longitude", "--longitude"),
    ("time", "--time"),
    ("envmap size", "--envmap-size"),
];

/// The kinds of `--envmap`.
#[derive(Clone, Copy, ValueEnum)]
pub enum EnvmapArg {
    /// One 2N x N latitude-longitude EXR.
    Equirect,
    /// Six N x N EXR faces.
    Cubemap,
}

#[derive(Args)]
pub struct SkyArgs {
    #[command(flatten)]
    picture: SkyPictureArgs,
    #[command(flatten)]
    medium: AtmosphereArgs,
    #[command(flatten)]
    method: ShellArgs,
    /// Print the radiance per wavelength (CSV) along the directions of this CSV file
    /// (header `azimuth_deg,elevation_deg`, azimuth from the sun's) instead of a picture.
    #[arg(long, value_name = "DIRS.csv", conflicts_with = "output")]
    probe: Option<PathBuf>,
    /// Draw from a skylight table (`atmo precompute sky`) instead of computing the sky:
    /// any sun elevation and altitude inside the table's ranges, in well under a millisecond.
    #[arg(long, value_name = "FILE.atmo-sky", conflicts_with_all = [
        "probe", "atmosphere", "ozone", "ground_albedo", "shells", "directions", "scattering_directions",
        "multiple_mie", "order", "max_interval",
    ])]
    table: Option<PathBuf>,
    /// With --table: write a sequence to the folder -o, the sun setting from
    /// --sun-elevation to the table's lowest, or a climb from --altitude to its highest;
    /// frame_000000.png ... and animation.png (an animated PNG, 30 frames/s).
    #[arg(long, value_enum, requires = "table")]
    animate: Option<Animate>,
    /// Frames of --animate.
    #[arg(long, default_value_t = 120, requires = "animate")]
    frame_count: usize,
    #[command(flatten)]
    chunk: Chunk,
    /// Output picture: .png (8-bit sRGB) or .exr (linear radiance); with --animate, a folder.
    #[arg(short, long, value_name = "FILE", required_unless_present_any = ["probe", "lighting"])]
    output: Option<PathBuf>,
    /// Write the whole sphere of directions to -o instead of a picture, as linear
    /// radiance in an .exr (a .png is a tone-mapped preview): `equirect`, 2N x N (azimuth from north clockwise left to right,
    /// zenith on top), or `cubemap`, six N x N faces FILE_px.exr, _nx, _py, _ny, _pz,
    /// _nz (OpenGL's order and orientation, world x east, y up, z south). Drawn on the
    /// CPU from the table's maps or the shell method's (on the GPU with --backend
    /// gpu); the sun's disc unless --no-sun-disc.
    #[arg(long, value_enum, conflicts_with_all = ["probe", "animate"])]
    envmap: Option<EnvmapArg>,
    /// N of --envmap: rows of the equirectangular map, or a cube face's side.
    #[arg(long, value_name = "N", default_value_t = 512, requires = "envmap")]
    envmap_size: u32,
    /// Write the light at the viewpoint as JSON: the sun (direction, colour,
    /// illuminance) and the sky's radiance as 9 spherical harmonics per linear-sRGB
    /// channel (docs/sky.md).
    #[arg(long, value_name = "FILE.json", conflicts_with_all = ["probe", "animate"])]
    lighting: Option<PathBuf>,
    #[command(flatten)]
    device: BackendArgs,
}

impl SkyArgs {
    /// The files this command reads, with their flags: no output may be one of them.
    fn inputs(&self) -> Vec<(&str, &Path)> {
        [
            ("--table", &self.table),
            ("--atmosphere", &self.medium.atmosphere),
        ]
        .into_iter()
        .filter_map(|(flag, input)| Some((flag, input.as_deref()?)))
        .collect()
    }
}

pub fn run(args: SkyArgs) -> Result<()> {
    // Everything is validated before any work or any file is written.
    let position = args.picture.sun_position()?;
    if let Some(p) = &position {
        note!(
            "atmo: the sun at {:.3} deg elevation ({:.3} deg refracted), {:.3} deg azimuth (SPA)",
            p.elevation_deg,
            p.refracted_elevation_deg,
            p.azimuth_deg
        );
    }
    let picture = args.picture.params_at(position.as_ref());
    picture.validate()?;
    let sun = picture.sun()?;
    let probe = args
        .probe
        .as_deref()
        .map(atmo::sky::probe::read_directions)
        .transpose()?;
    if args.envmap.is_some() || args.lighting.is_some() {
        return environment(&args, &picture, sun);
    }
    let view = match &args.output {
        Some(path) => {
            if args.animate.is_none() {
                ImageKind::of(path)?;
                // Checked before the work, not after it.
                atmo::files::check_folder(path)?;
                atmo::files::check_distinct(path, &args.inputs())?;
            }
            // The sky's pictures are seen from the model's altitude; the camera turns.
            Some(picture.view((args.picture.width, args.picture.height))?)
        }
        None => None,
    };
    if let (Some(table), Some(view), Some(path)) = (&args.table, &view, &args.output) {
        let table = Arc::new(SkylightTable::read(table)?);
        let display = Display {
            exposure: picture.exposure,
            tone: picture.tone,
        };
        let gpu = args.device.open()?;
        let source = SkySource::Table(table.clone());
        let mut drawer = SkyRenderer::new(gpu.as_ref(), source).map_err(gpu_error)?;
        return match args.animate {
            None => sky_table::draw(&mut drawer, sun, picture.altitude_m, view, display, path),
            Some(what) => {
                let frames = Animation {
                    what,
                    frames: args.frame_count,
                    sun,
                    altitude_m: picture.altitude_m,
                    day: args.picture.place.place_and_time(picture.altitude_m)?,
                };
                sky_table::animate(
                    &mut drawer,
                    &table,
                    &frames,
                    view,
                    display,
                    path,
                    &args.chunk,
                )
            }
        };
    }
    // Without a table: the atmosphere and the shell method's settings.
    let atmosphere = args.medium.load()?;
    let settings = args.method.settings(&args.medium);
    // The maps beside the picture, which is held with them.
    let picture_bytes = view
        .as_ref()
        .map_or(0, |v| Frame::bytes_of(v.camera.width, v.camera.height));
    atmo::budget::beside(picture_bytes, "the picture", || {
        settings.validate(&atmosphere)
    })?;
    let start = Instant::now();
    // The maps take about 3 s for every order (the default), 0.4 s for the paper's two.
    let spinner = ProgressBar::new_spinner().with_message("computing the sampling-shell maps");
    spinner.enable_steady_tick(std::time::Duration::from_millis(120));
    let model = SkyModel::new(&atmosphere, &settings, picture.altitude_m);
    spinner.finish_and_clear();
    let model = model?;
    if let Some(directions) = probe {
        return print_probe(&model, &atmosphere, sun, &directions);
    }
    let (Some(view), Some(path)) = (view, &args.output) else {
        unreachable!("clap requires -o without --probe")
    };
    let gpu = args.device.open()?;
    let mut sky = SkyRenderer::new(gpu.as_ref(), SkySource::Model(model)).map_err(gpu_error)?;
    let frame = sky
        .frame(sun, picture.altitude_m, &view)
        .map_err(gpu_error)?;
    frame.write(path, picture.exposure, picture.tone)?;
    note!(
        "atmo: {} ({}x{}, {}, order {}) in {:.0} ms",
        path.display(),
        view.camera.width,
        view.camera.height,
        atmosphere.name,
        settings.order,
        start.elapsed().as_secs_f64() * 1e3
    );
    Ok(())
}

/// `--envmap` and `--lighting`: the sky of `sun` around the viewpoint, from the table
/// or the shell method, as environment maps and as an engine's lights.
fn environment(args: &SkyArgs, picture: &atmo_view::sky::SkyParams, sun: Sun) -> Result<()> {
    let kind = args.envmap.map(|k| match k {
        EnvmapArg::Equirect => EnvmapKind::Equirect,
        EnvmapArg::Cubemap => EnvmapKind::Cubemap,
    });
    // Every output named and checked before the work.
    let mut outputs: Vec<PathBuf> = Vec::new();
    if let (Some(kind), Some(path)) = (kind, &args.output) {
        envmap::check_size(kind, args.envmap_size)?;
        let extension = match ImageKind::of(path)? {
            ImageKind::Exr => "exr",
            ImageKind::Png => "png",
        };
        match kind {
            EnvmapKind::Equirect => outputs.push(path.clone()),
            EnvmapKind::Cubemap => {
                let stem = path.file_stem().unwrap_or_default().to_string_lossy();
                outputs.extend(
                    CUBE_FACES
                        .iter()
                        .map(|f| path.with_file_name(format!("{stem}_{f}.{extension}"))),
                );
            }
        }
    }
    if kind.is_some() && args.output.is_none() {
        return Err(atmo::Error::Invalid("--envmap writes to -o: name an .exr file".into()).into());
    }
    // --lighting with -o and no --envmap: the picture too, of the same sky.
    let picture_view = match (kind, &args.output) {
        (None, Some(path)) => {
            ImageKind::of(path)?;
            outputs.push(path.clone());
            Some((
                picture.view((args.picture.width, args.picture.height))?,
                path,
            ))
        }
        _ => None,
    };
    outputs.extend(args.lighting.clone());
    let inputs = args.inputs();
    for path in &outputs {
        atmo::files::check_folder(path)?;
        atmo::files::check_distinct(path, &inputs)?;
    }
    let start = Instant::now();
    let (sky, atmosphere) = match &args.table {
        Some(table) => {
            let table = SkylightTable::read(table)?;
            let sky = SkyPicture::from_table(&table, sun, picture.altitude_m)?;
            (sky, table.atmosphere().clone())
        }
        None => {
            let atmosphere = args.medium.load()?;
            let settings = args.method.settings(&args.medium);
            settings.validate(&atmosphere)?;
            let model = SkyModel::new(&atmosphere, &settings, picture.altitude_m)?;
            let sky = match args.device.open()? {
                // The maps from the GPU's shell pass; the directions drawn on the CPU.
                Some(gpu) => {
                    let on_gpu = GpuSkyModel::new(&gpu, &model).map_err(gpu_error)?;
                    let [sky, ground] = on_gpu.maps(&gpu, sun.elevation()).map_err(gpu_error)?;
                    SkyPicture::from_model_maps(&model, sun, sky, ground)
                }
                None => SkyPicture::new(&model, sun),
            };
            (sky, atmosphere)
        }
    };
    let sun_disc = !args.picture.no_sun_disc;
    let faces = match kind {
        Some(EnvmapKind::Equirect) => vec![sky.equirect(args.envmap_size, sun_disc)],
        Some(EnvmapKind::Cubemap) => sky.cubemap(args.envmap_size, sun_disc),
        None => Vec::new(),
    };
    // The faces, the picture and the lighting: all of them, or none after an error.
    atmo::files::write_together(|| {
        for (frame, path) in faces.iter().zip(&outputs) {
            frame.write(path, picture.exposure, picture.tone)?;
        }
        if let Some((view, path)) = &picture_view {
            sky.render(view)
                .write(path, picture.exposure, picture.tone)?;
        }
        match &args.lighting {
            Some(path) => write_lighting(path, &sky, &atmosphere, picture, sun),
            None => Ok(()),
        }
    })?;
    note!(
        "atmo: {} in {:.0} ms",
        outputs
            .iter()
            .map(|p| p.display().to_string())
            .collect::<Vec<_>>()
            .join(", "),
        start.elapsed().as_secs_f64() * 1e3
    );
    Ok(())
}

/// The sky's light on things at the viewpoint, as an engine takes it, into `path`
/// (JSON).
fn write_lighting(
    path: &Path,
    sky: &SkyPicture,
    atmosphere: &Atmosphere,
    picture: &atmo_view::sky::SkyParams,
    sun: Sun,
) -> atmo::Result<()> {
    let lighting = Lighting::new(sky, atmosphere, picture.altitude_m, sun);
    let up = lighting.sky_irradiance_up;
    let out = json!({
        "atmosphere": atmosphere.name,
        "altitude_m": picture.altitude_m,
        "frame": "world: x east, y up, z south",
        "sun": {
            "direction": lighting.sun.direction,
            "elevation_deg": sun.elevation().to_degrees(),
            "azimuth_deg": sun.azimuth().to_degrees(),
            "wavelengths_nm": atmosphere.wavelengths_nm,
            "direct_normal_irradiance_w_m2_nm": lighting.sun.spectrum,
            "illuminance_lux": {"normal": lighting.sun.normal_lux, "horizontal": lighting.sun.horizontal_lux},
            "linear_srgb_colour": lighting.sun.colour,
        },
        "sky": {
            "sh9_radiance_linear_srgb": lighting.sky_sh9,
            "sh_basis": "real, (l,m) = (0,0) (1,-1) (1,0) (1,1) (2,-2) (2,-1) (2,0) (2,1) (2,2); Y_1-1 ~ y, Y_10 ~ z, Y_11 ~ x",
            "irradiance_up_linear_srgb_w_m2": up,
            "illuminance_up_lux": atmo::sky::lighting::LUMENS_PER_WATT * atmo::atmosphere::spectrum::srgb_luminance(up),
        },
    });
    // A tree of numbers and strings, always serialisable.
    let text = serde_json::to_string_pretty(&out).expect("JSON of plain values") + "\n";
    atmo::files::write_atomically(path, |w| {
        use std::io::Write;
        w.write_all(text.as_bytes())
            .map_err(atmo::Error::io_at(path))
    })
}

/// Directions per block of `--probe`: each holds a few kB of scattering maps while its
/// block is computed, so a file of millions of directions streams in bounded memory.
const PROBE_BLOCK: usize = 4096;

fn print_probe(
    model: &SkyModel,
    atmosphere: &Atmosphere,
    sun: Sun,
    directions: &[(f64, f64)],
) -> Result<()> {
    use std::io::Write;
    let mut out = std::io::BufWriter::new(std::io::stdout().lock());
    let mut header = String::from("azimuth_deg,elevation_deg");
    for l in &atmosphere.wavelengths_nm {
        header.push_str(&format!(",radiance_{l}nm"));
    }
    writeln!(out, "{header}")?;
    for block in directions.chunks(PROBE_BLOCK) {
        let rad: Vec<(f64, f64)> = block
            .iter()
            .map(|&(a, e)| {
                let mut relative = a.to_radians().rem_euclid(std::f64::consts::TAU);
                if relative > std::f64::consts::PI {
                    relative = std::f64::consts::TAU - relative;
                }
                (relative, e.to_radians())
            })
            .collect();
        let spectra = model.radiance_along(sun.elevation(), &rad);
        for ((a, e), spectrum) in block.iter().zip(spectra) {
            write!(out, "{a},{e}")?;
            for v in spectrum {
                write!(out, ",{v:.6e}")?;
            }
            writeln!(out)?;
        }
    }
    out.flush()?;
    Ok(())
}
