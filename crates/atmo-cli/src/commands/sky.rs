//! `atmo sky`: a picture of the sky, or its radiance along given directions.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::Result;
use atmo::image::{Display, ImageKind};
use atmo::sky::{SkyModel, SkyPicture, SkylightTable};
use atmo::view::Sun;
use atmo::Atmosphere;
use atmo_gpu::sky::{GpuSkyModel, SkyPass, SkyTarget};
use clap::Args;
use indicatif::ProgressBar;

use super::sky_table::{self, Animate, Animation, TableDrawer};
use crate::args::{AtmosphereArgs, ShellArgs, SkyPictureArgs};
use crate::backend::{gpu_error, BackendArgs};

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
];

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
        "probe", "atmosphere", "ozone", "shells", "directions", "scattering_directions",
        "multiple_mie", "order", "max_interval",
    ])]
    table: Option<PathBuf>,
    /// With --table: write a sequence to the folder -o, the sun setting from
    /// --sun-elevation to the table's lowest, or a climb from --altitude to its highest;
    /// frame-0000.png ... and animation.png (an animated PNG).
    #[arg(long, value_enum, requires = "table")]
    animate: Option<Animate>,
    /// Frames of --animate.
    #[arg(long, default_value_t = 120, requires = "animate")]
    frames: usize,
    /// Output picture: .png (8-bit sRGB) or .exr (linear radiance); with --animate, a folder.
    #[arg(short, long, value_name = "FILE", required_unless_present = "probe")]
    output: Option<PathBuf>,
    #[command(flatten)]
    device: BackendArgs,
}

pub fn run(args: SkyArgs) -> Result<()> {
    // Everything is validated before any work or any file is written.
    let position = args.picture.sun_position()?;
    if let Some(p) = &position {
        eprintln!(
            "atmo: the sun at {:.3} deg elevation ({:.3} deg refracted), {:.3} deg azimuth (SPA)",
            p.elevation_deg, p.refracted_elevation_deg, p.azimuth_deg
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
    let view = match &args.output {
        Some(path) => {
            if args.animate.is_none() {
                ImageKind::of(path)?;
                // Checked before the work, not after it.
                atmo::files::check_folder(path)?;
                let inputs: Vec<(&str, &Path)> = [
                    ("--table", &args.table),
                    ("--atmosphere", &args.medium.atmosphere),
                ]
                .into_iter()
                .filter_map(|(flag, input)| Some((flag, input.as_deref()?)))
                .collect();
                atmo::files::check_distinct(path, &inputs)?;
            }
            // The sky's pictures are seen from the model's altitude; the camera turns.
            Some(picture.view((args.picture.width, args.picture.height))?)
        }
        None => None,
    };
    if let (Some(table), Some(view), Some(path)) = (&args.table, &view, &args.output) {
        let table = SkylightTable::read(table)?;
        let display = Display {
            exposure: picture.exposure,
            tone: picture.tone,
        };
        let gpu = args.device.open()?;
        let drawer = TableDrawer::new(&table, gpu.as_ref())?;
        return match args.animate {
            None => sky_table::draw(&drawer, sun, picture.altitude_m, view, display, path),
            Some(what) => {
                let frames = Animation {
                    what,
                    frames: args.frames,
                    sun,
                    altitude_m: picture.altitude_m,
                    day: args.picture.place.place_and_time(picture.altitude_m)?,
                };
                sky_table::animate(&drawer, &table, &frames, view, display, path)
            }
        };
    }
    // Without a table: the atmosphere and the shell method's settings.
    let atmosphere = args.medium.load()?;
    let settings = args.method.settings();
    settings.validate(&atmosphere)?;
    let start = Instant::now();
    // Light maps take 0.3 s at the defaults and seconds with --order 3 --multiple-mie.
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
    let frame = match args.device.open()? {
        Some(gpu) => {
            let sky = GpuSkyModel::new(&gpu, &model).map_err(gpu_error)?;
            let mut pass = SkyPass::new(&gpu, SkyTarget::HEADLESS).map_err(gpu_error)?;
            sky.render(&gpu, &mut pass, sun, &view)
                .map_err(gpu_error)?
                .frame
        }
        None => SkyPicture::new(&model, sun).render(&view),
    };
    frame.write(path, picture.exposure, picture.tone)?;
    eprintln!(
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
