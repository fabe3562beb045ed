//! `atmo clouds`: a particle cloud lit by the sun through the 3-D intensity buffer,
//! drawn as billboards; still or animated (the sun moving, or the wind). The picture is
//! the library's ([`atmo::cloudscape`], drawn by [`atmo_gpu::cloudscape::CloudFrames`]
//! on the CPU or the GPU); this command parses and checks its flags ([`args`]) and
//! writes what it draws; [`window`] is the same for `atmo view clouds`.

mod args;
mod window;

use std::path::PathBuf;
use std::time::Instant;

use anyhow::Result;
use atmo::atmosphere::PhaseFunction;
use atmo::clouds::buffer::{IntensityBuffer, Splat};
use atmo::clouds::files;
use atmo::clouds::generator::Cumulus;
use atmo::clouds::particles::Particle;
use atmo::clouds::{Diffusion, Octaves, Scattering};
use atmo::cloudscape::Cloudscape;
use atmo::error::check_range;
use atmo::files::check_folder;
use atmo::image::{Display, Frame, ImageKind};
use atmo::view::{Camera, Fov, Sun};
use atmo_gpu::cloudscape::CloudFrames;
use clap::Args;
use glam::Vec3;

use args::{fixed_flags, placement, Animate, FovAxis, PhaseArg, ScatteringArg, SplatArg};
pub use args::{scene_arguments, scene_arguments_of, CloudStill};
pub use window::WindowClouds;

use crate::backend::{gpu_error, BackendArgs};
use crate::output::write_animation;

/// The library's fields that this command's flags set, for error messages.
pub const FLAGS: &[(&str, &str)] = &[
    ("latitude", "--latitude"),
    ("longitude", "--longitude"),
    ("time", "--time"),
    ("sun.azimuth_deg", "--sun-azimuth"),
    ("camera.fov_deg", "--fov"),
    ("buffer.resolution", "--resolution"),
    ("buffer.forward", "--forward"),
    ("width", "--width"),
    ("height", "--height"),
];

/// The wind's time a frame of `--animate wind` (and of the window's wind), s.
pub const WIND_STEP_S: f32 = 4.0;

#[derive(Args)]
pub struct CloudsArgs {
    #[command(flatten)]
    pub still: CloudStill,
    /// Also write the particles to this file (.csv or .atmo-particles).
    #[arg(long, value_name = "FILE")]
    save_particles: Option<PathBuf>,
    /// Animate: the sun going round (`sun`) or the wind moving the particles (`wind`),
    /// the light pass run again every frame; -o is then a folder.
    #[arg(long, value_enum)]
    animate: Option<Animate>,
    /// Frames of --animate.
    #[arg(long, default_value_t = 120, requires = "animate")]
    frame_count: usize,
    #[command(flatten)]
    chunk: crate::output::Chunk,
    /// Output picture: .png or .exr (linear radiance, sun irradiance 1 per channel);
    /// with --animate, a folder.
    #[arg(short, long, value_name = "FILE")]
    output: PathBuf,
    #[command(flatten)]
    device: BackendArgs,
}

/// A cloud picture's inputs, checked once: the scene (particles and how they are lit
/// and drawn), the wind, the sun, the camera and how the picture is shown. `atmo
/// clouds` draws it once (or as an animation); `atmo view clouds` draws it each frame
/// with the window's sun, wind and camera.
pub struct Cloud {
    pub scene: Cloudscape,
    /// The seconds of wind the particles are carried (`--wind-s`).
    pub wind_s: f32,
    /// The sun's elevation and azimuth, degrees (from the place and time, or from
    /// --sun-direction, where given).
    pub sun_elevation: f32,
    pub sun_azimuth: f32,
    pub camera: Camera,
    /// The point the camera looks at, m.
    pub look_at: Vec3,
    /// The field of view across `fov_axis`, degrees.
    pub fov_deg: f32,
    pub fov_axis: FovAxis,
    pub display: Display,
    /// `atmo clouds`'s flags for all of this but the sun, the camera and the display.
    flags: String,
}

impl Cloud {
    /// The picture `still` asks for, every flag checked (exit 2 naming it).
    pub fn new(still: &CloudStill) -> Result<Cloud> {
        let mut sun = (still.sun_elevation, still.sun_azimuth);
        // The sun from a place and a time, where they are given (at the cloud's base).
        if let Some(p) = still.place.sun_position(Cumulus::default().base as f64)? {
            note!(
                "atmo: the sun at {:.3} deg elevation, {:.3} deg azimuth (SPA)",
                p.elevation_deg,
                p.azimuth_deg
            );
            sun = (p.elevation_deg as f32, p.azimuth_deg as f32);
        }
        if let Some(toward) = still.sun_direction {
            let s = Sun::from_toward(toward).map_err(|_| {
                atmo::Error::Invalid(format!(
                    "--sun-direction = {toward} has no direction: give a non-zero X,Y,Z toward the sun"
                ))
            })?;
            sun = (
                s.elevation().to_degrees() as f32,
                s.azimuth().to_degrees() as f32,
            );
        }
        check_sun(sun.0, sun.1)?;
        let exposure = still
            .exposure
            .unwrap_or(if still.sky { 0.15 } else { 10.0 });
        atmo::error::check_positive("--exposure", exposure as f64, 1e12)?;
        let calm = match &still.particles_file {
            Some(path) => files::read(path, 0.99)?,
            None => {
                check_range("--particles", still.particles as f64, 1.0, 5e6)?;
                atmo::clouds::particles::check_count(still.particles, "--particles")?;
                Cumulus {
                    particles: still.particles,
                    seed: still.seed,
                    ..Cumulus::default()
                }
                .generate()
            }
        };
        check_range("--wind-s", still.wind_s as f64, 0.0, 1e5)?;
        // The buffer beside the particles and the picture, which are held with it.
        let held = calm.len() as u64 * atmo::clouds::particles::BYTES_PER_PARTICLE
            + Frame::bytes_of(still.width, still.height);
        atmo::budget::beside(held, "the particles and the picture", || {
            IntensityBuffer::check_resolution(still.resolution)
        })?;
        check_range("buffer.forward", still.forward as f64, 0.0, 1.0)?;
        let ambient = args::ambient(still.ambient.as_deref(), still.sky)?;
        if let Some(albedo) = still.ground_albedo {
            check_range("--ground-albedo", albedo as f64, 0.0, 1.0)?;
        }
        let scattering = match still.scattering {
            ScatteringArg::Single => Scattering::SINGLE,
            every => {
                if still.forward != 0.0 {
                    return Err(atmo::Error::Invalid(format!(
                        "--forward = {} applies to --scattering single only (every order \
                         needs the sun's transmittance: --forward 0)",
                        still.forward
                    ))
                    .into());
                }
                match every {
                    ScatteringArg::Octaves => Scattering::Octaves(Octaves::MULTIPLE),
                    ScatteringArg::Solve => {
                        let cells = still.solve_cells.unwrap_or(Diffusion::DEFAULT.cells);
                        check_range("--solve-cells", cells as f64, 4.0, 256.0)?;
                        Scattering::Solve(Diffusion { cells })
                    }
                    _ => Scattering::MULTIPLE,
                }
            }
        };
        if let (Some(cells), false) = (
            still.solve_cells,
            matches!(still.scattering, ScatteringArg::Solve),
        ) {
            return Err(atmo::Error::Invalid(format!(
                "--solve-cells = {cells} applies to --scattering solve only"
            ))
            .into());
        }
        let phase = match still.phase {
            PhaseArg::Mie => PhaseFunction::CloudMie,
            PhaseArg::Hg => {
                check_range("--g", still.g as f64, -0.99, 0.99)?;
                PhaseFunction::HenyeyGreenstein { g: still.g as f64 }
            }
        };
        let scene = Cloudscape {
            calm,
            resolution: still.resolution,
            forward: still.forward,
            splat: match still.splat {
                SplatArg::Pieces => Splat::Pieces,
                SplatArg::Whole => Splat::Whole,
            },
            phase,
            scattering,
            ambient,
            sky: still.sky,
            ground_albedo: still.ground_albedo,
        };
        let particles = scene.blown(still.wind_s);
        let (position, look_at) = placement(&particles, still)?;
        let size = (still.width, still.height);
        let camera = camera_at(
            &particles,
            still.fov_axis,
            position,
            look_at,
            still.fov,
            size,
        )?;
        Ok(Cloud {
            scene,
            wind_s: still.wind_s,
            sun_elevation: sun.0,
            sun_azimuth: sun.1,
            camera,
            look_at,
            fov_deg: still.fov,
            fov_axis: still.fov_axis,
            display: Display {
                exposure,
                tone: still.tone_map.into(),
            },
            flags: fixed_flags(still),
        })
    }

    /// The sun at `azimuth_deg` and the cloud's elevation.
    fn sun_at(&self, azimuth_deg: f32) -> atmo::Result<Sun> {
        Sun::from_degrees(self.sun_elevation as f64, azimuth_deg as f64)
    }

    /// `atmo clouds`'s flags for the cloud and how it is lit: all but the sun, the
    /// camera and the display, which `atmo view clouds` adds from its window.
    pub fn fixed_flags(&self) -> &str {
        &self.flags
    }
}

/// A camera at `position` looking at `target` with a field of view of `fov_deg` across
/// `axis`, for a `size` picture. Refused inside a particle (a billboard cannot be drawn
/// around the eye).
pub(crate) fn camera_at(
    particles: &[Particle],
    axis: FovAxis,
    position: Vec3,
    target: Vec3,
    fov_deg: f32,
    size: (u32, u32),
) -> atmo::Result<Camera> {
    check_range("--fov", fov_deg as f64, 1.0, 170.0)?;
    Frame::check_size(size.0, size.1)?;
    if let Some((k, p)) = particles
        .iter()
        .enumerate()
        .find(|(_, p)| (p.position - position).length() < p.radius)
    {
        return Err(atmo::Error::Invalid(format!(
            "--camera = {position} is inside particle {k} (centre {}, radius {} m): \
             place the camera outside the cloud",
            p.position, p.radius
        )));
    }
    if target == position {
        return Err(atmo::Error::Invalid(format!(
            "--look-at = {target} is where the camera is (--camera): the camera has no \
             view direction"
        )));
    }
    let fov = match axis {
        FovAxis::Vertical => Fov::Vertical(fov_deg),
        FovAxis::Horizontal => Fov::Horizontal(fov_deg),
    };
    Camera::look_at(position, target, Vec3::Y, fov, size)
}

/// The sun's angles, checked.
pub(crate) fn check_sun(elevation_deg: f32, azimuth_deg: f32) -> atmo::Result<()> {
    check_range(
        "--sun-elevation (a sun at or below the horizon does not light a cloud from above)",
        elevation_deg as f64,
        0.5,
        90.0,
    )?;
    check_range("--sun-azimuth", azimuth_deg as f64, -360.0, 360.0)
}

pub fn run(args: CloudsArgs) -> Result<()> {
    match args.animate {
        None => {
            ImageKind::of(&args.output)?;
            check_folder(&args.output)?;
        }
        Some(_) => check_range("--frame-count", args.frame_count as f64, 2.0, 10_000.0)?,
    }
    let cloud = Cloud::new(&args.still)?;
    if let Some(path) = &args.save_particles {
        check_folder(path)?;
        if let Some(input) = &args.still.particles_file {
            atmo::files::check_distinct(path, &[("--particles-file", input)])?;
        }
    }
    let camera = &cloud.camera;
    let sun = cloud.sun_at(cloud.sun_azimuth)?;
    let gpu = args.device.open()?;
    let gpu = gpu.as_ref();
    let mut frames = CloudFrames::new(cloud.scene.clone(), cloud.wind_s);
    frames.sky(camera).map_err(gpu_error)?;
    let start = Instant::now();
    frames
        .light(gpu, sun, cloud.wind_s, false)
        .map_err(gpu_error)?;
    let light_ms = start.elapsed().as_secs_f64() * 1e3;
    // Everything is validated now (the light pass checked the buffer's settings).
    if let Some(path) = &args.save_particles {
        files::write(path, frames.particles())?;
    }
    let display = cloud.display;
    match args.animate {
        None => {
            let start = Instant::now();
            let frame = frames
                .draw(gpu, sun, cloud.wind_s, camera, false)
                .map_err(gpu_error)?;
            let draw_ms = start.elapsed().as_secs_f64() * 1e3;
            frame.write(&args.output, display.exposure, display.tone)?;
            note!(
                "{}: {} x {}, {} particles, {}^3 buffer: light pass {light_ms:.1} ms, drawing {draw_ms:.1} ms",
                args.output.display(),
                frame.width,
                frame.height,
                frames.particles().len(),
                cloud.scene.resolution
            );
        }
        Some(animate) => {
            let start = Instant::now();
            let count = args.frame_count;
            let written = write_animation(
                &crate::output::Animation {
                    command: "clouds",
                    folder: &args.output,
                    count,
                    fps: 30,
                    size: (camera.width, camera.height),
                    display,
                    chunk: &args.chunk,
                },
                |k, frame| {
                    let (sun, wind_s) = match animate {
                        // Once round, the azimuth kept in [0, 360).
                        Animate::Sun => (
                            cloud.sun_at(
                                (cloud.sun_azimuth + 360.0 * k as f32 / count as f32)
                                    .rem_euclid(360.0),
                            )?,
                            cloud.wind_s,
                        ),
                        // The breeze, WIND_STEP_S a frame.
                        Animate::Wind => (sun, cloud.wind_s + WIND_STEP_S * k as f32),
                    };
                    *frame = frames
                        .draw(gpu, sun, wind_s, camera, false)
                        .map_err(gpu_error)?;
                    Ok(())
                },
            )?;
            crate::output::report(&args.output, &written, start);
        }
    }
    Ok(())
}
