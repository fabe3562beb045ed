//! `atmo clouds`: a particle cloud lit by the sun through the 3-D intensity buffer,
//! drawn as billboards; still or animated (the sun moving, or the wind).

use std::cell::{Ref, RefCell};
use std::path::PathBuf;
use std::time::Instant;

use anyhow::Result;
use atmo::atmosphere::PhaseFunction;
use atmo::clouds::buffer::{IntensityBuffer, Splat};
use atmo::clouds::files;
use atmo::clouds::generator::Cumulus;
use atmo::clouds::particles::Particle;
use atmo::clouds::render::{needs_depths, render_with_depths, Haze, Lighting, Scattering};
use atmo::clouds::shadow::{CloudShadow, Ground};
use atmo::clouds::{CloudDepths, Octaves, SkyLight};
use atmo::error::check_range;
use atmo::files::check_folder;
use atmo::image::{Display, Frame, ImageKind};
use atmo::sky::{Daylight, SkyModel, SkyPicture, SkySettings, View};
use atmo::view::{Camera, Fov, Sun};
use atmo::Atmosphere;
use clap::{Args, ValueEnum};
use glam::Vec3;

use atmo_gpu::clouds::{CloudsPass, GpuClouds};
use atmo_gpu::display::write_frame;
use atmo_gpu::Gpu;
use atmo_view::clouds::{CloudParams, CloudPictures};
use atmo_view::Picture;

use crate::args::{PlaceArgs, ToneMapArg};
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
    frames: usize,
    /// Output picture: .png or .exr (linear radiance, sun irradiance 1 per channel);
    /// with --animate, a folder.
    #[arg(short, long, value_name = "FILE")]
    output: PathBuf,
    #[command(flatten)]
    device: BackendArgs,
}

/// A cloud picture: the cloud, the sun, how it is lit, the camera and the display;
/// the still `atmo clouds` and the window `atmo view clouds` take the same flags.
#[derive(Args, Clone)]
pub struct CloudStill {
    /// Read the scene from a TOML file whose keys are this command's flags
    /// (`generate = "cumulus"`, `camera = [0, 1900, -3000]`, `sky = true`; see
    /// docs/clouds.md); flags on the command line override it.
    #[arg(long, value_name = "FILE")]
    scene: Option<PathBuf>,
    /// Make a cloud: `cumulus` (deterministic for a --seed).
    #[arg(
        long,
        value_enum,
        required_unless_present = "particles_file",
        conflicts_with = "particles_file"
    )]
    generate: Option<Generator>,
    /// Particles of the generated cloud (the paper's: 9382, 32914, 60134).
    #[arg(long, default_value_t = 60_134)]
    particles: usize,
    /// Seed of the generator.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Read the particles from a file (CSV `x,y,z,radius,density[,albedo]`, or the binary
    /// `.atmo-particles`; see docs/clouds.md).
    #[arg(long, value_name = "FILE")]
    particles_file: Option<PathBuf>,
    /// Carry the particles this long by the breeze of `--animate wind`, s: 6 m/s at the
    /// cloud's base, 1 m/s faster for each 100 m up, toward the east and a little south.
    #[arg(long, value_name = "SECONDS", default_value_t = 0.0)]
    wind_s: f32,
    /// Sun elevation above the horizon, degrees, in (0, 90].
    #[arg(long, default_value_t = 20.0)]
    sun_elevation: f32,
    /// The sun as a vector toward it, `X,Y,Z` in the world frame (x east, y up, z
    /// south), instead of --sun-elevation and --sun-azimuth.
    #[arg(long, value_name = "X,Y,Z", value_parser = parse_vec3, conflicts_with_all = ["sun_elevation", "sun_azimuth"])]
    sun_direction: Option<Vec3>,
    /// Sun azimuth, degrees clockwise from north.
    #[arg(long, default_value_t = 40.0)]
    sun_azimuth: f32,
    #[command(flatten)]
    place: PlaceArgs,
    /// Intensity buffer voxels along each axis (the paper: 128, 256, 384).
    #[arg(long, default_value_t = 256)]
    resolution: usize,
    /// Light scattered once (`single`, the paper's model) or every order: `multiple`, a
    /// transfer table fitted to a path tracer (docs/clouds.md), or `octaves`, the
    /// octaves fitted to it (faster on the GPU, which reads the table's depth toward
    /// the eye from a second light pass, lit from the eye, whenever the camera moves).
    #[arg(long, value_enum, default_value_t = ScatteringArg::Multiple)]
    scattering: ScatteringArg,
    /// With --scattering single: the part of scattered light taken to go on along the
    /// light, the paper's p(l,l)/4pi, in [0, 1] (the paper's forward scattering; 0, the
    /// default, makes the buffer the sun's transmittance and the picture exact single
    /// scattering).
    #[arg(long, default_value_t = 0.0)]
    forward: f32,
    /// Light from the sky scattered by the droplets: `none`, `sky` (the sky module's
    /// radiance all around the cloud, the ground's below; the droplets scatter toward
    /// the eye the part behind them most, dimmed inside the cloud with every order as
    /// the light from above and below diffuses down the vertical; needs --sky) or an
    /// RGB radiance `R,G,B` from every direction alike (not dimmed). Default:
    /// `sky` with --sky, else `none` (a cloud on black has no other light than the
    /// sun's).
    #[arg(long, value_name = "none|sky|R,G,B")]
    ambient: Option<String>,
    /// How particles enter the buffer: `pieces` (split exactly along the light) or
    /// `whole` (the paper's one factor per particle).
    #[arg(long, value_enum, default_value_t = SplatArg::Pieces)]
    splat: SplatArg,
    /// Phase function toward the eye: `mie` (two-lobe cloud fit) or `hg` (with --g).
    #[arg(long, value_enum, default_value_t = PhaseArg::Mie)]
    phase: PhaseArg,
    /// Henyey-Greenstein asymmetry for --phase hg.
    #[arg(long, default_value_t = 0.8)]
    g: f32,
    /// The camera's position, `X,Y,Z` m in the world frame, instead of --distance,
    /// --view-azimuth and --view-height.
    #[arg(long, value_name = "X,Y,Z", value_parser = parse_vec3, conflicts_with_all = ["distance", "view_azimuth", "view_height"])]
    camera: Option<Vec3>,
    /// The point the camera looks at, `X,Y,Z` m (default: the cloud's centre).
    #[arg(long, value_name = "X,Y,Z", value_parser = parse_vec3)]
    look_at: Option<Vec3>,
    /// Which side of the picture --fov spans.
    #[arg(long, value_enum, default_value_t = FovAxis::Vertical)]
    fov_axis: FovAxis,
    /// Camera distance from the cloud's centre, in cloud widths.
    #[arg(long, default_value_t = 2.2)]
    distance: f32,
    /// Where the camera stands, degrees clockwise from north seen from the cloud.
    #[arg(long, default_value_t = 200.0)]
    view_azimuth: f32,
    /// Camera height above the ground, m.
    #[arg(long, default_value_t = 900.0)]
    view_height: f32,
    /// Field of view, degrees, across the side --fov-axis names.
    #[arg(long, default_value_t = 40.0)]
    fov: f32,
    /// Image width, pixels.
    #[arg(long, default_value_t = 1280)]
    width: u32,
    /// Image height, pixels.
    #[arg(long, default_value_t = 720)]
    height: u32,
    /// Draw the cloud in front of the sky (the sky module, Earth atmosphere), lit by
    /// sunlight coloured by the atmosphere down to the cloud and by the sky's light.
    #[arg(long)]
    sky: bool,
    /// The ground beneath the cloud (the plane y = 0 of the world frame), its
    /// reflectance in [0, 1]: drawn lit by the sun through the cloud's shadow (what
    /// crosses the cloud and a share of what it scatters down) and by the ambient
    /// light. With --sky the sky module's ground is there anyway (albedo 0.1 unless
    /// this sets it) and the cloud's shadow is taken out of its sunlight.
    #[arg(long, value_name = "ALBEDO")]
    ground_albedo: Option<f32>,
    /// Multiplies radiance before the tone map (PNG only); default 10, or 0.15 with
    /// --sky (whose radiance is in the atmosphere's units).
    #[arg(long)]
    exposure: Option<f32>,
    /// Tone map for PNG output.
    #[arg(long, value_enum, default_value_t = ToneMapArg::Exponential)]
    tone_map: ToneMapArg,
}

/// The command-line arguments a cloud scene file stands for: each key a flag of
/// `atmo clouds` (its long name, `long_flags`), each value its argument (a string or
/// number as written, `[x, y, z]` as `x,y,z`, `true` as the bare flag, `false` as
/// nothing); `particles-file` relative to the scene's folder. An error naming the file,
/// the line and the key for anything else.
pub fn scene_arguments(path: &std::path::Path, long_flags: &[&str]) -> atmo::Result<Vec<String>> {
    let name = path.display();
    // Through the bounded reader, as every file a user names.
    let text = atmo::files::read_text(path, "cloud scene file", atmo::files::TEXT_LIMIT_BYTES)
        .map_err(|e| atmo::Error::Invalid(format!("--scene {e}")))?;
    let table: toml::Table = text
        .parse()
        .map_err(|e| atmo::Error::Invalid(format!("--scene {name}: {e}")))?;
    let folder = path.parent().unwrap_or(std::path::Path::new("."));
    let mut argv = Vec::new();
    for (key, value) in table {
        let bad = |why: &str| atmo::Error::Invalid(format!("--scene {name}: `{key}` {why}"));
        if key == "scene" || key == "output" || !long_flags.contains(&key.as_str()) {
            return Err(bad("is not a flag of atmo clouds a scene can set"));
        }
        let number = |v: &toml::Value| match v {
            toml::Value::Integer(i) => Some(i.to_string()),
            toml::Value::Float(f) => Some(f.to_string()),
            _ => None,
        };
        let argument = match &value {
            toml::Value::Boolean(true) => {
                argv.push(format!("--{key}"));
                continue;
            }
            toml::Value::Boolean(false) => continue,
            toml::Value::String(s) if key == "particles-file" => {
                folder.join(s).to_string_lossy().into_owned()
            }
            toml::Value::String(s) => s.clone(),
            toml::Value::Array(items) => items
                .iter()
                .map(number)
                .collect::<Option<Vec<_>>>()
                .ok_or_else(|| bad("must hold numbers only"))?
                .join(","),
            v => number(v)
                .ok_or_else(|| bad("must be a string, a number, true/false or [x, y, z]"))?,
        };
        argv.push(format!("--{key}"));
        argv.push(argument);
    }
    Ok(argv)
}

/// Texels a side of the cloud's shadow on the ground (some 10 m each across a cumulus).
const SHADOW_RESOLUTION: usize = 256;

/// How much coarser the window's previews light the cloud than its whole pictures:
/// the intensity buffer's and the shadow map's resolution divided by this (an eighth
/// of the buffer's cells, a quarter of the map's texels), while the picture itself is
/// drawn at a fraction of its size anyway.
const PREVIEW_COARSENING: usize = 2;

/// The coarsest intensity buffer a preview lights, voxels a side.
const PREVIEW_MIN_RESOLUTION: usize = 32;

/// The wind's time a frame of `--animate wind` (and of the window's wind), s.
pub const WIND_STEP_S: f32 = 4.0;

/// The light pass and the drawing, on the CPU or on a GPU.
enum Renderer {
    /// The buffer and its resolution (none before the first light pass), and the
    /// particles' depths in the cloud for the sky's light inside it and the transfer
    /// table.
    Cpu(Option<IntensityBuffer>, usize, KeptDepths),
    /// The device and the cloud on it.
    Gpu(Box<(Gpu, GpuClouds)>),
}

/// The particles' depths in the cloud ([`CloudDepths`]) and the particles they were
/// made for: they depend on the particles alone, so frames of the same particles under a
/// moving sun or camera (`--animate sun`, the window) make them once. (The GPU keeps
/// its own in the particles' records.)
#[derive(Default)]
struct KeptDepths(RefCell<Option<(Vec<Particle>, CloudDepths)>>);

impl KeptDepths {
    /// The depths of `particles`, made again only where they are not those last given.
    fn of(&self, particles: &[Particle]) -> Result<Ref<'_, CloudDepths>> {
        let stale = self
            .0
            .borrow()
            .as_ref()
            .is_none_or(|(kept, _)| kept != particles);
        if stale {
            *self.0.borrow_mut() = Some((particles.to_vec(), CloudDepths::of(particles)?));
        }
        Ok(Ref::map(self.0.borrow(), |kept| {
            &kept.as_ref().expect("made above").1
        }))
    }
}

impl Renderer {
    /// The renderer for `cloud`: on `gpu` where there is one, else on the CPU.
    fn new(gpu: Option<&Gpu>, cloud: &Cloud) -> Result<Renderer> {
        Ok(match gpu {
            Some(gpu) => Renderer::Gpu(Box::new((
                gpu.clone(),
                GpuClouds::new(gpu, &cloud.particles, cloud.resolution).map_err(gpu_error)?,
            ))),
            None => Renderer::Cpu(None, cloud.resolution, KeptDepths::default()),
        })
    }

    /// The intensity buffer of `particles` (which may have moved) lit from `to_sun`.
    fn light(
        &mut self,
        particles: &[Particle],
        to_sun: Vec3,
        forward: f32,
        splat: Splat,
    ) -> Result<()> {
        match self {
            Renderer::Cpu(Some(buffer), ..) => buffer.update(particles, to_sun, forward, splat)?,
            Renderer::Cpu(buffer, resolution, _) => {
                *buffer = Some(IntensityBuffer::new(
                    particles,
                    to_sun,
                    *resolution,
                    forward,
                    splat,
                )?)
            }
            Renderer::Gpu(on) => {
                let (gpu, clouds) = &mut **on;
                clouds.move_particles(gpu, particles).map_err(gpu_error)?;
                clouds
                    .light(gpu, to_sun, forward, splat)
                    .map_err(gpu_error)?;
            }
        }
        Ok(())
    }

    fn draw(
        &self,
        particles: &[Particle],
        camera: &Camera,
        light: &Lighting,
        background: Option<&Frame>,
    ) -> Result<Frame> {
        Ok(match self {
            Renderer::Cpu(buffer, _, kept) => {
                let buffer = buffer.as_ref().expect("a light pass comes first");
                let none = CloudDepths::default();
                let depths = needs_depths(light)
                    .then(|| kept.of(particles))
                    .transpose()?;
                let depths = depths.as_deref().unwrap_or(&none);
                render_with_depths(particles, depths, buffer, camera, light, background)?
            }
            Renderer::Gpu(on) => {
                let (gpu, clouds) = &**on;
                clouds
                    .render(gpu, camera, light, background)
                    .map_err(gpu_error)?
                    .frame
            }
        })
    }
}

#[derive(Clone, Copy, ValueEnum)]
enum Generator {
    Cumulus,
}

#[derive(Clone, Copy, ValueEnum)]
enum SplatArg {
    Pieces,
    Whole,
}

#[derive(Clone, Copy, ValueEnum)]
enum FovAxis {
    Horizontal,
    Vertical,
}

/// `X,Y,Z`: three finite numbers.
fn parse_vec3(text: &str) -> Result<Vec3, String> {
    let values: Vec<f32> = text
        .split(',')
        .map(|v| v.trim().parse::<f32>())
        .collect::<Result<_, _>>()
        .map_err(|e| format!("{text:?} is not X,Y,Z: {e}"))?;
    match values[..] {
        [x, y, z] if values.iter().all(|v| v.is_finite()) => Ok(Vec3::new(x, y, z)),
        _ => Err(format!("{text:?} is not three finite numbers X,Y,Z")),
    }
}

#[derive(Clone, Copy, ValueEnum, PartialEq)]
enum ScatteringArg {
    Single,
    Multiple,
    Octaves,
}

/// Where the ambient light comes from.
#[derive(Clone, Copy, PartialEq)]
enum Ambient {
    Rgb(Vec3),
    Sky,
}

impl Ambient {
    /// `--ambient` (or its default, `sky` with `--sky`), refused as exit 2 when it
    /// does not parse or asks for a sky that is not there.
    fn parse(arg: Option<&str>, sky: bool) -> atmo::Result<Ambient> {
        let text = arg.unwrap_or(if sky { "sky" } else { "none" });
        let bad = |why: &str| {
            atmo::Error::Invalid(format!(
                "--ambient = {text:?}: {why} (allowed: none, sky, or R,G,B radiances >= 0)"
            ))
        };
        match text {
            "none" => Ok(Ambient::Rgb(Vec3::ZERO)),
            "sky" if sky => Ok(Ambient::Sky),
            "sky" => Err(bad("the sky's light needs --sky")),
            _ => match parse_vec3(text) {
                Ok(rgb) if rgb.min_element() >= 0.0 => Ok(Ambient::Rgb(rgb)),
                _ => Err(bad("not three finite numbers >= 0")),
            },
        }
    }
}

#[derive(Clone, Copy, ValueEnum)]
enum PhaseArg {
    Mie,
    Hg,
}

#[derive(Clone, Copy, ValueEnum, PartialEq)]
enum Animate {
    Sun,
    Wind,
}

/// A cloud picture's inputs, checked once: the particles, the sun, the camera, how the
/// cloud is lit and how the picture is shown. `atmo clouds` draws it once (or as an
/// animation); `atmo view clouds` draws it each frame with the window's sun and camera.
pub struct Cloud {
    /// The particles as given, before the wind.
    pub calm: Vec<Particle>,
    /// The seconds of wind they are carried (`--wind-s`), and where that takes them.
    pub wind_s: f32,
    pub particles: Vec<Particle>,
    /// The sun's elevation and azimuth, degrees (from the place and time, or from
    /// --sun-direction, where given).
    pub sun_elevation: f32,
    pub sun_azimuth: f32,
    pub camera: Camera,
    /// The point the camera looks at, m.
    pub look_at: Vec3,
    /// The field of view across `fov_axis`, degrees.
    pub fov_deg: f32,
    pub display: Display,
    fov_axis: FovAxis,
    resolution: usize,
    forward: f32,
    splat: Splat,
    phase: PhaseFunction,
    scattering: Scattering,
    ambient: Ambient,
    sky: bool,
    ground_albedo: Option<f32>,
    /// `atmo clouds`'s flags for all of this but the sun, the camera and the display.
    flags: String,
}

impl Cloud {
    /// The picture `still` asks for, every flag checked (exit 2 naming it).
    pub fn new(still: &CloudStill) -> Result<Cloud> {
        let mut sun = (still.sun_elevation, still.sun_azimuth);
        // The sun from a place and a time, where they are given (at the cloud's base).
        if let Some(p) = still.place.sun_position(Cumulus::default().base as f64)? {
            eprintln!(
                "atmo: the sun at {:.3} deg elevation, {:.3} deg azimuth (SPA)",
                p.elevation_deg, p.azimuth_deg
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
        let particles = match &still.particles_file {
            Some(path) => files::read(path, 0.99)?,
            None => {
                check_range("--particles", still.particles as f64, 1.0, 5e6)?;
                Cumulus {
                    particles: still.particles,
                    seed: still.seed,
                    ..Cumulus::default()
                }
                .generate()
            }
        };
        check_range("--wind-s", still.wind_s as f64, 0.0, 1e5)?;
        IntensityBuffer::check_resolution(still.resolution)?;
        check_range("buffer.forward", still.forward as f64, 0.0, 1.0)?;
        let calm = particles;
        let particles = blown(&calm, still.wind_s);
        let (position, look_at) = placement(&particles, still)?;
        let ambient = Ambient::parse(still.ambient.as_deref(), still.sky)?;
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
                    _ => Scattering::MULTIPLE,
                }
            }
        };
        let phase = match still.phase {
            PhaseArg::Mie => PhaseFunction::CloudMie,
            PhaseArg::Hg => {
                check_range("--g", still.g as f64, -0.99, 0.99)?;
                PhaseFunction::HenyeyGreenstein { g: still.g as f64 }
            }
        };
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
            camera,
            calm,
            wind_s: still.wind_s,
            particles,
            sun_elevation: sun.0,
            sun_azimuth: sun.1,
            look_at,
            fov_deg: still.fov,
            display: Display {
                exposure,
                tone: still.tone_map.into(),
            },
            fov_axis: still.fov_axis,
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
            flags: fixed_flags(still),
        })
    }

    /// The sun at `azimuth_deg` and the cloud's elevation.
    fn sun_at(&self, azimuth_deg: f32) -> atmo::Result<Sun> {
        Sun::from_degrees(self.sun_elevation as f64, azimuth_deg as f64)
    }

    /// The sky around `particles` seen from `camera`, where the picture has one.
    fn sky_for(&self, particles: &[Particle], camera: &Camera) -> atmo::Result<Option<SkyAround>> {
        self.sky
            .then(|| SkyAround::new(particles, camera, self.ground_albedo))
            .transpose()
    }

    /// The cloud's shadow for `sun`, where the picture shows the ground (with --sky or
    /// --ground-albedo): made with each light pass.
    fn shadow(
        &self,
        particles: &[Particle],
        sun: Sun,
        resolution: usize,
    ) -> atmo::Result<Option<CloudShadow>> {
        (self.sky || self.ground_albedo.is_some())
            .then(|| CloudShadow::new(particles, sun.toward(), resolution))
            .transpose()
    }

    /// Sunlight and sky light at the cloud for `sun`, and what `camera` sees behind it:
    /// the sky and the ground (where the picture has them), the ground under the
    /// cloud's `shadow`.
    fn lighting(
        &self,
        sky: Option<&SkyAround>,
        shadow: Option<&CloudShadow>,
        sun: Sun,
        camera: &Camera,
    ) -> atmo::Result<(Lighting, Option<Frame>)> {
        let (sunlight, ambient, haze, mut background) = match (sky, self.ambient) {
            (None, Ambient::Rgb(rgb)) => (Vec3::ONE, SkyLight::uniform(rgb), Haze::CLEAR, None),
            (None, Ambient::Sky) => unreachable!("Ambient::parse needs --sky for it"),
            (Some(sky), ambient) => {
                let (sunlight, skylight, haze, background) = sky.at(sun, camera)?;
                let ambient = match ambient {
                    Ambient::Rgb(rgb) => SkyLight::uniform(rgb),
                    Ambient::Sky => skylight,
                };
                (sunlight, ambient, haze, Some(background))
            }
        };
        let ground = match (sky, self.ground_albedo) {
            (Some(sky), _) => {
                let atmosphere = sky.at_camera.atmosphere();
                let altitude = SkyAround::altitude(atmosphere, camera.position.y as f64);
                Some(Ground::seen_through(atmosphere, altitude, sun))
            }
            (None, Some(albedo)) => Some(Ground::painted(
                albedo,
                sunlight,
                sun.toward(),
                ambient.mean(),
            )),
            (None, None) => None,
        };
        if let (Some(shadow), Some(ground)) = (shadow, ground) {
            let frame = background.get_or_insert_with(|| Frame::new(camera.width, camera.height));
            shadow.shade_ground(frame, camera, &ground);
        }
        let light = Lighting {
            to_sun: sun.toward(),
            sun: sunlight,
            ambient,
            phase: self.phase,
            haze,
            scattering: self.scattering,
        };
        Ok((light, background))
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
fn camera_at(
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

/// `particles` carried `seconds` by a sheared breeze: 6 m/s at the cloud's base and
/// 1 m/s faster for each 100 m up, toward +x and a little +z (east, a little south).
/// The wind's picture at any time, the same whether reached at once or frame by frame.
fn blown(particles: &[Particle], seconds: f32) -> Vec<Particle> {
    let base = particles
        .iter()
        .map(|p| p.position.y)
        .fold(f32::INFINITY, f32::min);
    particles
        .iter()
        .map(|p| {
            let speed = 6.0 + 0.01 * (p.position.y - base);
            Particle {
                position: p.position + Vec3::new(speed, 0.0, 0.3 * speed) * seconds,
                ..*p
            }
        })
        .collect()
}

/// The sun's angles, checked.
fn check_sun(elevation_deg: f32, azimuth_deg: f32) -> atmo::Result<()> {
    check_range(
        "--sun-elevation (a sun at or below the horizon does not light a cloud from above)",
        elevation_deg as f64,
        0.5,
        90.0,
    )?;
    check_range("--sun-azimuth", azimuth_deg as f64, -360.0, 360.0)
}

/// Where the camera stands and what it looks at: --camera, or looking at the cloud's
/// centre from --view-azimuth, --distance widths away, at --view-height m; toward
/// --look-at (default the centre).
fn placement(particles: &[Particle], still: &CloudStill) -> atmo::Result<(Vec3, Vec3)> {
    let (lo, hi) = particles.iter().fold(
        (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
        |(l, h), p| (l.min(p.position), h.max(p.position)),
    );
    let centre = 0.5 * (lo + hi);
    let position = match still.camera {
        Some(position) => position,
        None => {
            check_range("--distance", still.distance as f64, 0.1, 1000.0)?;
            check_range("--view-azimuth", still.view_azimuth as f64, -360.0, 360.0)?;
            check_range("--view-height", still.view_height as f64, -1e5, 1e5)?;
            let width = (hi - lo).x.max((hi - lo).z).max(1.0);
            let a = still.view_azimuth.to_radians();
            Vec3::new(
                centre.x + a.sin() * width * still.distance,
                still.view_height,
                centre.z - a.cos() * width * still.distance,
            )
        }
    };
    Ok((position, still.look_at.unwrap_or(centre)))
}

/// The flags of [`Cloud::fixed_flags`], each value as clap reads it back.
fn fixed_flags(still: &CloudStill) -> String {
    let name = |v: &dyn Fn() -> Option<clap::builder::PossibleValue>| {
        v().map(|p| p.get_name().to_string()).unwrap_or_default()
    };
    let mut flags = match &still.particles_file {
        Some(path) => vec![format!("--particles-file {}", path.display())],
        None => vec![format!(
            "--generate cumulus --particles {} --seed {}",
            still.particles, still.seed
        )],
    };
    flags.push(format!(
        "--resolution {} --scattering {} --forward {} --splat {} --phase {} --g {} --fov-axis {}",
        still.resolution,
        name(&|| still.scattering.to_possible_value()),
        still.forward,
        name(&|| still.splat.to_possible_value()),
        name(&|| still.phase.to_possible_value()),
        still.g,
        name(&|| still.fov_axis.to_possible_value()),
    ));
    if still.sky {
        flags.push("--sky".into());
    }
    if let Some(albedo) = still.ground_albedo {
        flags.push(format!("--ground-albedo {albedo}"));
    }
    if let Some(ambient) = &still.ambient {
        flags.push(format!("--ambient {ambient}"));
    }
    flags.join(" ")
}

pub fn run(args: CloudsArgs) -> Result<()> {
    match args.animate {
        None => {
            ImageKind::of(&args.output)?;
            check_folder(&args.output)?;
        }
        Some(_) => check_range("--frames", args.frames as f64, 2.0, 10_000.0)?,
    }
    let cloud = Cloud::new(&args.still)?;
    if let Some(path) = &args.save_particles {
        check_folder(path)?;
        if let Some(input) = &args.still.particles_file {
            atmo::files::check_distinct(path, &[("--particles-file", input)])?;
        }
    }
    let camera = &cloud.camera;
    let sky = cloud.sky_for(&cloud.particles, camera)?;
    let sun = cloud.sun_at(cloud.sun_azimuth)?;
    let gpu = args.device.open()?;
    let gpu = gpu.as_ref();
    let mut renderer = Renderer::new(gpu, &cloud)?;
    let (forward, splat) = (cloud.forward, cloud.splat);
    let mut particles = cloud.particles.clone();
    let start = Instant::now();
    renderer.light(&particles, sun.toward(), forward, splat)?;
    let mut shadow = cloud.shadow(&particles, sun, SHADOW_RESOLUTION)?;
    let light_ms = start.elapsed().as_secs_f64() * 1e3;
    // Everything is validated now (the light pass checked the buffer's settings).
    if let Some(path) = &args.save_particles {
        files::write(path, &particles)?;
    }
    let display = cloud.display;
    match args.animate {
        None => {
            let start = Instant::now();
            let (light, background) = cloud.lighting(sky.as_ref(), shadow.as_ref(), sun, camera)?;
            let frame = renderer.draw(&particles, camera, &light, background.as_ref())?;
            let draw_ms = start.elapsed().as_secs_f64() * 1e3;
            frame.write(&args.output, display.exposure, display.tone)?;
            eprintln!(
                "{}: {} x {}, {} particles, {}^3 buffer: light pass {light_ms:.1} ms, drawing {draw_ms:.1} ms",
                args.output.display(),
                frame.width,
                frame.height,
                particles.len(),
                cloud.resolution
            );
        }
        Some(animate) => {
            let start = Instant::now();
            let apng = write_animation(
                &args.output,
                args.frames,
                30,
                (camera.width, camera.height),
                display,
                |k, frame| {
                    let sun = match animate {
                        // Once round, the azimuth kept in [0, 360).
                        Animate::Sun => cloud.sun_at(
                            (cloud.sun_azimuth + 360.0 * k as f32 / args.frames as f32)
                                .rem_euclid(360.0),
                        )?,
                        Animate::Wind => {
                            // The breeze, WIND_STEP_S a frame.
                            let wind_s = cloud.wind_s + WIND_STEP_S * k as f32;
                            particles = blown(&cloud.calm, wind_s);
                            sun
                        }
                    };
                    renderer.light(&particles, sun.toward(), forward, splat)?;
                    shadow = cloud.shadow(&particles, sun, SHADOW_RESOLUTION)?;
                    let (light, background) =
                        cloud.lighting(sky.as_ref(), shadow.as_ref(), sun, camera)?;
                    *frame = renderer.draw(&particles, camera, &light, background.as_ref())?;
                    Ok(())
                },
            )?;
            eprintln!(
                "atmo: {} frames and {} in {:.1} s",
                args.frames,
                apng.display(),
                start.elapsed().as_secs_f64()
            );
        }
    }
    Ok(())
}

/// The cloud as `atmo view clouds` draws it, frame after frame: the light pass run
/// again only when the sun or the device changed, the sky around the cloud made again
/// only when the camera's height changed (the sky in front of it is drawn from there).
pub struct WindowClouds {
    cloud: Cloud,
    /// The particles where the window's wind has carried them, and its seconds.
    particles: Vec<Particle>,
    wind_s: f32,
    /// The renderer of whole pictures, and whether it is the GPU's.
    whole: Option<(bool, Lit)>,
    /// The CPU's renderer of previews: the light pass and the shadow map
    /// [`PREVIEW_COARSENING`] times coarser, lit apart from the whole pictures' (a
    /// preview does not spoil the buffer the next whole picture reuses).
    preview: Option<Lit>,
    /// The sky around the cloud, and the camera height it was made for.
    sky: Option<(f32, Option<SkyAround>)>,
    /// On the GPU: the pass that puts the cloud over what is behind it.
    pass: Option<CloudsPass>,
}

impl WindowClouds {
    pub fn new(cloud: Cloud) -> WindowClouds {
        WindowClouds {
            particles: cloud.particles.clone(),
            wind_s: cloud.wind_s,
            cloud,
            whole: None,
            preview: None,
            sky: None,
            pass: None,
        }
    }

    /// The window's first parameters: the still's.
    pub fn params(&self) -> CloudParams {
        let c = &self.cloud;
        CloudParams {
            sun_elevation_deg: c.sun_elevation,
            sun_azimuth_deg: c.sun_azimuth,
            camera: c.camera.position,
            look_at: c.look_at,
            fov_deg: c.fov_deg,
            wind_s: c.wind_s,
            exposure: c.display.exposure,
            tone: c.display.tone,
        }
    }
}

/// A renderer, the sun its intensity buffer was last lit by (none before its first
/// light pass, or after the wind moved the particles) and the cloud's shadow then.
struct Lit {
    renderer: Renderer,
    sun: Option<Sun>,
    shadow: Option<CloudShadow>,
    /// Texels a side of the shadow map.
    shadow_resolution: usize,
}

/// Of a window's renderers, the previews' where `coarse`, else the whole pictures'.
fn chosen<'a>(
    whole: &'a mut Option<(bool, Lit)>,
    preview: &'a mut Option<Lit>,
    coarse: bool,
) -> Option<&'a mut Lit> {
    if coarse {
        preview.as_mut()
    } else {
        whole.as_mut().map(|(_, lit)| lit)
    }
}

impl WindowClouds {
    /// What a frame at `p` and `size` needs, on `gpu` where given, else on the CPU (a
    /// `preview` more coarsely lit): the parameters checked, the
    /// particles where the wind took them, the light pass where the sun or the wind
    /// changed, the sky around the cloud where the camera's height changed; the camera,
    /// the light at the cloud and what is behind it.
    fn prepare(
        &mut self,
        gpu: Option<&Gpu>,
        p: &CloudParams,
        size: (u32, u32),
        preview: bool,
    ) -> Result<(Camera, Lighting, Option<Frame>)> {
        check_sun(p.sun_elevation_deg, p.sun_azimuth_deg)?;
        atmo::error::check_positive("--exposure", p.exposure as f64, 1e12)?;
        let cloud = &self.cloud;
        if p.wind_s != self.wind_s {
            check_range("--wind-s", p.wind_s as f64, 0.0, 1e5)?;
            self.particles = blown(&cloud.calm, p.wind_s);
            self.wind_s = p.wind_s;
            let lit = self
                .whole
                .iter_mut()
                .map(|(_, lit)| lit)
                .chain(&mut self.preview);
            lit.for_each(|lit| lit.sun = None);
            if let Some((_, Some(sky))) = &mut self.sky {
                sky.centre = SkyAround::centre_of(&self.particles);
            }
        }
        let particles = &self.particles;
        let (axis, position, target) = (cloud.fov_axis, p.camera, p.look_at);
        let camera = camera_at(particles, axis, position, target, p.fov_deg, size)?;
        let sun = Sun::from_degrees(p.sun_elevation_deg as f64, p.sun_azimuth_deg as f64)?;
        let unlit = |renderer, shadow_resolution| Lit {
            renderer,
            sun: None,
            shadow: None,
            shadow_resolution,
        };
        let coarse = preview && gpu.is_none();
        if coarse && self.preview.is_none() {
            let resolution = (cloud.resolution / PREVIEW_COARSENING).max(PREVIEW_MIN_RESOLUTION);
            let renderer = Renderer::Cpu(
                None,
                resolution.min(cloud.resolution),
                KeptDepths::default(),
            );
            self.preview = Some(unlit(renderer, SHADOW_RESOLUTION / PREVIEW_COARSENING));
        }
        let on_gpu = gpu.is_some();
        if !coarse && !matches!(self.whole, Some((on, _)) if on == on_gpu) {
            let renderer = Renderer::new(gpu, cloud)?;
            self.whole = Some((on_gpu, unlit(renderer, SHADOW_RESOLUTION)));
        }
        let lit = chosen(&mut self.whole, &mut self.preview, coarse).expect("made above");
        if lit.sun != Some(sun) {
            let renderer = &mut lit.renderer;
            renderer.light(particles, sun.toward(), cloud.forward, cloud.splat)?;
            lit.shadow = cloud.shadow(particles, sun, lit.shadow_resolution)?;
            lit.sun = Some(sun);
        }
        let height = camera.position.y;
        let sky = match &mut self.sky {
            Some((h, sky)) if *h == height => sky,
            slot => {
                let sky = cloud.sky_for(particles, &camera)?;
                &mut slot.insert((height, sky)).1
            }
        };
        let (light, background) =
            cloud.lighting(sky.as_ref(), lit.shadow.as_ref(), sun, &camera)?;
        Ok((camera, light, background))
    }
}

impl CloudPictures for WindowClouds {
    fn draw(&mut self, p: &CloudParams, size: (u32, u32), preview: bool) -> Result<Frame> {
        let (camera, light, background) = self.prepare(None, p, size, preview)?;
        let lit = chosen(&mut self.whole, &mut self.preview, preview).expect("made by prepare");
        lit.renderer
            .draw(&self.particles, &camera, &light, background.as_ref())
    }

    fn draw_on(
        &mut self,
        gpu: &Gpu,
        encoder: &mut atmo_gpu::wgpu::CommandEncoder,
        picture: &mut Picture,
        p: &CloudParams,
    ) -> Result<()> {
        let (camera, light, background) = self.prepare(Some(gpu), p, picture.size, false)?;
        let Some((
            _,
            Lit {
                renderer: Renderer::Gpu(on),
                ..
            },
        )) = &self.whole
        else {
            unreachable!("prepare made the GPU's renderer")
        };
        let clouds = &on.1;
        let behind = background.unwrap_or_else(|| Frame::new(picture.size.0, picture.size.1));
        write_frame(gpu, &picture.texture, &behind);
        let pass = match &mut self.pass {
            Some(pass) => pass,
            slot => slot.insert(CloudsPass::new(gpu, picture.texture.format()).map_err(gpu_error)?),
        };
        clouds
            .prepare(gpu, encoder, pass, &camera, &light)
            .map_err(gpu_error)?;
        picture.draw_over(encoder, |render| pass.draw(render));
        Ok(())
    }

    fn flags(&self) -> String {
        self.cloud.fixed_flags().to_string()
    }
}

/// The sky around a cloud (Earth atmosphere, default settings): its light at the
/// cloud's mean height, and the sky behind it and the air in front of it from the
/// camera's height.
struct SkyAround {
    at_cloud: Daylight,
    at_camera: SkyModel,
    /// The cloud's centre, m, world frame.
    centre: Vec3,
}

impl SkyAround {
    /// The sky around `particles` seen from `camera`, over a ground of `ground_albedo`
    /// (the Earth atmosphere's where not given).
    fn new(
        particles: &[Particle],
        camera: &Camera,
        ground_albedo: Option<f32>,
    ) -> atmo::Result<SkyAround> {
        let mut atmosphere = Atmosphere::earth();
        if let Some(albedo) = ground_albedo {
            atmosphere.ground_albedo = albedo as f64;
        }
        let settings = SkySettings::default();
        let height =
            particles.iter().map(|p| p.position.y as f64).sum::<f64>() / particles.len() as f64;
        let altitude = |h: f64| SkyAround::altitude(&atmosphere, h);
        Ok(SkyAround {
            at_cloud: Daylight::new(&atmosphere, &settings, altitude(height))?,
            at_camera: SkyModel::new(&atmosphere, &settings, altitude(camera.position.y as f64))?,
            centre: SkyAround::centre_of(particles),
        })
    }

    /// The world frame's height `y` m as an altitude the sky module takes: inside
    /// `atmosphere`.
    fn altitude(atmosphere: &Atmosphere, y: f64) -> f64 {
        y.clamp(
            0.0,
            atmosphere.top_radius_m - atmosphere.bottom_radius_m - 1.0,
        )
    }

    /// The cloud's centre: its particles' mean position, m.
    fn centre_of(particles: &[Particle]) -> Vec3 {
        particles.iter().map(|p| p.position).sum::<Vec3>() / particles.len() as f32
    }

    /// The air between `camera` and the cloud's centre for `sun`: the aerial
    /// perspective at that distance and direction (every order the model carries).
    fn haze(&self, sun: Sun, camera: &Camera) -> atmo::Result<Haze> {
        let to_cloud = self.centre - camera.position;
        let distance = to_cloud.length() as f64;
        let light = self.at_camera.aerial_along(sun, to_cloud, &[distance])?;
        let (transmittance, inscatter) = light[0].rgb(self.at_camera.atmosphere());
        Ok(Haze {
            transmittance,
            inscatter,
        })
    }

    /// For `sun`: the sun's irradiance at the cloud (RGB, through the atmosphere), the
    /// sky's radiance all around it (its ambient light), the air in front of the cloud,
    /// and the sky behind it as `camera` sees it.
    fn at(&self, sun: Sun, camera: &Camera) -> atmo::Result<(Vec3, SkyLight, Haze, Frame)> {
        let view = View {
            camera: camera.clone(),
            sun_disc: true,
        };
        let background = SkyPicture::new(&self.at_camera, sun).render(&view);
        Ok((
            self.at_cloud.sunlight(sun),
            SkyLight::from_harmonics(&self.at_cloud.skylight(sun)),
            self.haze(sun, camera)?,
            background,
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;

    #[derive(Parser)]
    struct Flags {
        #[command(flatten)]
        still: CloudStill,
    }

    /// A small cloud over a painted ground (so that it has a shadow map).
    fn small_cloud() -> Cloud {
        let args = "clouds --generate cumulus --particles 300 --resolution 64 --ground-albedo 0.3 \
                    --width 64 --height 36";
        let flags = Flags::try_parse_from(args.split_whitespace()).unwrap();
        Cloud::new(&flags.still).unwrap()
    }

    /// The buffer's resolution and the shadow map's of a renderer that was lit.
    fn resolutions(lit: &Lit) -> (usize, usize) {
        let Renderer::Cpu(Some(buffer), ..) = &lit.renderer else {
            panic!("a CPU renderer, lit");
        };
        let shadow = lit.shadow.as_ref().expect("a ground, so a shadow map");
        (buffer.resolution, shadow.resolution)
    }

    #[test]
    fn previews_are_lit_coarsely_apart_from_the_whole_pictures() {
        let whole_size = (64, 36);
        let mut window = WindowClouds::new(small_cloud());
        let mut p = window.params();
        window.draw(&p, whole_size, false).unwrap();
        // The sun and then the wind move while previews are drawn; each whole picture
        // after them is the one a fresh window draws, bit for bit (its own light pass
        // redone for the new sun and particles, not the preview's reused).
        for change in [0, 1] {
            if change == 0 {
                p.sun_azimuth_deg += 10.0;
            } else {
                p.wind_s = 120.0;
            }
            let preview = window.draw(&p, (16, 9), true).unwrap();
            assert_eq!((preview.width, preview.height), (16, 9));
            let sun =
                Sun::from_degrees(p.sun_elevation_deg as f64, p.sun_azimuth_deg as f64).unwrap();
            let coarse = window.preview.as_ref().unwrap();
            assert_eq!(coarse.sun, Some(sun));
            // Half the whole pictures' resolution (at least 32 voxels), half the map's.
            assert_eq!(resolutions(coarse), (32, SHADOW_RESOLUTION / 2));
            let whole = window.draw(&p, whole_size, false).unwrap();
            let (_, lit) = window.whole.as_ref().unwrap();
            assert_eq!(resolutions(lit), (64, SHADOW_RESOLUTION));
            let fresh = WindowClouds::new(small_cloud())
                .draw(&p, whole_size, false)
                .unwrap();
            assert!(whole.pixels == fresh.pixels, "change {change}");
        }
    }

    /// With the sky's light dimmed inside the cloud, a window on the CPU keeps the
    /// particles' depths in the cloud while only the sun moves and makes them again
    /// once the wind has moved the particles: each picture is a fresh window's, bit for
    /// bit.
    #[test]
    fn the_sky_depths_are_kept_while_the_particles_stay() {
        let args = "clouds --generate cumulus --particles 300 --resolution 32 --sky \
                    --width 48 --height 27";
        let cloud = || {
            Cloud::new(
                &Flags::try_parse_from(args.split_whitespace())
                    .unwrap()
                    .still,
            )
        };
        let size = (48, 27);
        let fresh = |p: &CloudParams| WindowClouds::new(cloud().unwrap()).draw(p, size, false);
        let mut window = WindowClouds::new(cloud().unwrap());
        let kept = |window: &WindowClouds| {
            let Some((_, lit)) = &window.whole else {
                panic!("drawn");
            };
            let Renderer::Cpu(_, _, kept) = &lit.renderer else {
                panic!("on the CPU");
            };
            let depths = kept.0.borrow().as_ref().expect("made").1.out.as_ptr();
            depths
        };
        let mut p = window.params();
        window.draw(&p, size, false).unwrap();
        let first = kept(&window);
        p.sun_azimuth_deg += 30.0;
        let lit = window.draw(&p, size, false).unwrap();
        assert_eq!(
            kept(&window),
            first,
            "the same depths for the same particles"
        );
        assert!(lit.pixels == fresh(&p).unwrap().pixels);
        p.wind_s = 120.0;
        let blown = window.draw(&p, size, false).unwrap();
        assert!(blown.pixels == fresh(&p).unwrap().pixels);
    }
}
