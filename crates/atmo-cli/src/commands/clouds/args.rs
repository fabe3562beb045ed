//! The flags of a cloud picture, shared by `atmo clouds` and `atmo view clouds`, and
//! the scene files that stand for them.

use std::path::PathBuf;

use atmo::clouds::particles::Particle;
use atmo::cloudscape::Ambient;
use atmo::error::check_range;
use clap::{Args, ValueEnum};
use glam::Vec3;

use crate::args::{PlaceArgs, ToneMapArg};

/// A cloud picture: the cloud, the sun, how it is lit, the camera and the display;
/// the still `atmo clouds` and the window `atmo view clouds` take the same flags.
#[derive(Args, Clone)]
pub struct CloudStill {
    /// Read the scene from a TOML file whose keys are this command's flags
    /// (`generate = "cumulus"`, `camera = [0, 1900, -3000]`, `sky = true`; see
    /// docs/clouds.md); flags on the command line override it.
    #[arg(long, value_name = "FILE")]
    pub scene: Option<PathBuf>,
    /// Make a cloud: `cumulus` (deterministic for a --seed).
    #[arg(
        long,
        value_enum,
        required_unless_present = "particles_file",
        conflicts_with = "particles_file"
    )]
    pub generate: Option<Generator>,
    /// Particles of the generated cloud (the paper's: 9382, 32914, 60134).
    #[arg(long, default_value_t = 60_134)]
    pub particles: usize,
    /// Seed of the generator.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Read the particles from a file (CSV `x,y,z,radius,density[,albedo]`, or the binary
    /// `.atmo-particles`; see docs/clouds.md).
    #[arg(long, value_name = "FILE")]
    pub particles_file: Option<PathBuf>,
    /// Carry the particles this long by the breeze of `--animate wind`, s: 6 m/s at the
    /// cloud's base, 1 m/s faster for each 100 m up, toward the east and a little south.
    #[arg(long, value_name = "SECONDS", default_value_t = 0.0)]
    pub wind_s: f32,
    /// Sun elevation above the horizon, degrees, in (0, 90].
    #[arg(long, default_value_t = 20.0)]
    pub sun_elevation: f32,
    /// The sun as a vector toward it, `X,Y,Z` in the world frame (x east, y up, z
    /// south), instead of --sun-elevation and --sun-azimuth.
    #[arg(long, value_name = "X,Y,Z", value_parser = parse_vec3, conflicts_with_all = ["sun_elevation", "sun_azimuth"])]
    pub sun_direction: Option<Vec3>,
    /// Sun azimuth, degrees clockwise from north.
    #[arg(long, default_value_t = 40.0)]
    pub sun_azimuth: f32,
    #[command(flatten)]
    pub place: PlaceArgs,
    /// Intensity buffer voxels along each axis (the paper: 128, 256, 384).
    #[arg(long, default_value_t = 256)]
    pub resolution: usize,
    /// Light scattered once (`single`, the paper's model) or every order: `solve`, the
    /// orders past the first solved through the cloud (the second explicitly, the rest
    /// by flux-limited diffusion; redone when the sun or the particles move; the
    /// nearest the path tracer, docs/clouds.md), `multiple`, a transfer table fitted to
    /// the path tracer, or `octaves`, the octaves fitted to it (faster on the GPU,
    /// which reads the table's depth toward the eye from a second light pass, lit from
    /// the eye, whenever the camera moves).
    #[arg(long, value_enum, default_value_t = ScatteringArg::Solve)]
    pub scattering: ScatteringArg,
    /// With --scattering solve: the solve's cells along the cloud's longest side, in
    /// [4, 256] (default 32). Finer is nearer the path tracer in a thick cloud's core
    /// seen against the sun and costs about the cube of it (docs/clouds.md).
    #[arg(long)]
    pub solve_cells: Option<usize>,
    /// With --scattering single: the part of scattered light taken to go on along the
    /// light, the paper's p(l,l)/4pi, in [0, 1] (the paper's forward scattering; 0, the
    /// default, makes the buffer the sun's transmittance and the picture exact single
    /// scattering).
    #[arg(long, default_value_t = 0.0)]
    pub forward: f32,
    /// Light from the sky scattered by the droplets: `none`, `sky` (the sky module's
    /// radiance all around the cloud, the ground's below; the droplets scatter toward
    /// the eye the part behind them most, dimmed inside the cloud with every order as
    /// the light from above and below diffuses down the vertical; needs --sky) or an
    /// RGB radiance `R,G,B` from every direction alike (not dimmed). Default:
    /// `sky` with --sky, else `none` (a cloud on black has no other light than the
    /// sun's).
    #[arg(long, value_name = "none|sky|R,G,B")]
    pub ambient: Option<String>,
    /// How particles enter the buffer: `pieces` (split exactly along the light) or
    /// `whole` (the paper's one factor per particle).
    #[arg(long, value_enum, default_value_t = SplatArg::Pieces)]
    pub splat: SplatArg,
    /// Phase function toward the eye: `mie` (two-lobe cloud fit) or `hg` (with --g).
    #[arg(long, value_enum, default_value_t = PhaseArg::Mie)]
    pub phase: PhaseArg,
    /// Henyey-Greenstein asymmetry for --phase hg.
    #[arg(long, default_value_t = 0.8)]
    pub g: f32,
    /// The camera's position, `X,Y,Z` m in the world frame, instead of --distance,
    /// --view-azimuth and --view-height.
    #[arg(long, value_name = "X,Y,Z", value_parser = parse_vec3, conflicts_with_all = ["distance", "view_azimuth", "view_height"])]
    pub camera: Option<Vec3>,
    /// The point the camera looks at, `X,Y,Z` m (default: the cloud's centre).
    #[arg(long, value_name = "X,Y,Z", value_parser = parse_vec3)]
    pub look_at: Option<Vec3>,
    /// Which side of the picture --fov spans.
    #[arg(long, value_enum, default_value_t = FovAxis::Vertical)]
    pub fov_axis: FovAxis,
    /// Camera distance from the cloud's centre, in cloud widths.
    #[arg(long, default_value_t = 2.2)]
    pub distance: f32,
    /// Where the camera stands, degrees clockwise from north seen from the cloud.
    #[arg(long, default_value_t = 200.0)]
    pub view_azimuth: f32,
    /// Camera height above the ground, m.
    #[arg(long, default_value_t = 900.0)]
    pub view_height: f32,
    /// Field of view, degrees, across the side --fov-axis names.
    #[arg(long, default_value_t = 40.0)]
    pub fov: f32,
    /// Image width, pixels.
    #[arg(long, default_value_t = 1280)]
    pub width: u32,
    /// Image height, pixels.
    #[arg(long, default_value_t = 720)]
    pub height: u32,
    /// Draw the cloud in front of the sky (the sky module, Earth atmosphere), lit by
    /// sunlight coloured by the atmosphere down to the cloud and by the sky's light.
    #[arg(long)]
    pub sky: bool,
    /// The ground beneath the cloud (the plane y = 0 of the world frame), its
    /// reflectance in [0, 1]: drawn lit by the sun through the cloud's shadow (what
    /// crosses the cloud and a share of what it scatters down) and by the ambient
    /// light. With --sky the sky module's ground is there anyway (albedo 0.1 unless
    /// this sets it) and the cloud's shadow is taken out of its sunlight.
    #[arg(long, value_name = "ALBEDO")]
    pub ground_albedo: Option<f32>,
    /// Multiplies radiance before the tone map (PNG only); default 10, or 0.15 with
    /// --sky (whose radiance is in the atmosphere's units).
    #[arg(long)]
    pub exposure: Option<f32>,
    /// Tone map for PNG output.
    #[arg(long, value_enum, default_value_t = ToneMapArg::Exponential)]
    pub tone_map: ToneMapArg,
}

/// The command-line arguments a cloud scene file stands for: each key a flag of
/// `atmo clouds` (its long name, `long_flags`), each value its argument (a string or
/// number as written, `[x, y, z]` as `x,y,z`, `true` as the bare flag, `false` as
/// nothing); `particles-file` relative to the scene's folder. An error naming the file,
/// the line and the key for anything else.
pub fn scene_arguments(path: &std::path::Path, long_flags: &[&str]) -> atmo::Result<Vec<String>> {
    // Through the bounded reader, as every file a user names.
    let text = atmo::files::read_toml(path, "cloud scene file")
        .map_err(|e| atmo::Error::Invalid(format!("--scene {e}")))?;
    let folder = path.parent().unwrap_or(std::path::Path::new("."));
    scene_arguments_of(&text, &path.display().to_string(), folder, long_flags)
}

/// [`scene_arguments`] of a scene file's `text`, `name` naming it in messages, its
/// relative paths from `folder`.
pub fn scene_arguments_of(
    text: &str,
    name: &str,
    folder: &std::path::Path,
    long_flags: &[&str],
) -> atmo::Result<Vec<String>> {
    let table: toml::Table = text
        .parse()
        .map_err(|e| atmo::Error::Invalid(format!("--scene {name}: {e}")))?;
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

#[derive(Clone, Copy, ValueEnum)]
pub enum Generator {
    Cumulus,
}

#[derive(Clone, Copy, ValueEnum)]
pub enum SplatArg {
    Pieces,
    Whole,
}

#[derive(Clone, Copy, ValueEnum)]
pub enum FovAxis {
    Horizontal,
    Vertical,
}

/// `X,Y,Z`: three finite numbers.
pub fn parse_vec3(text: &str) -> Result<Vec3, String> {
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
pub enum ScatteringArg {
    Single,
    Multiple,
    Octaves,
    Solve,
}

/// `--ambient` (or its default, `sky` with `--sky`), refused as exit 2 when it does
/// not parse or asks for a sky that is not there.
pub fn ambient(arg: Option<&str>, sky: bool) -> atmo::Result<Ambient> {
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

#[derive(Clone, Copy, ValueEnum)]
pub enum PhaseArg {
    Mie,
    Hg,
}

#[derive(Clone, Copy, ValueEnum, PartialEq)]
pub enum Animate {
    Sun,
    Wind,
}

/// Where the camera stands and what it looks at: --camera, or looking at the cloud's
/// centre from --view-azimuth, --distance widths away, at --view-height m; toward
/// --look-at (default the centre).
pub fn placement(particles: &[Particle], still: &CloudStill) -> atmo::Result<(Vec3, Vec3)> {
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

/// The flags of [`super::Cloud::fixed_flags`], each value as clap reads it back.
pub fn fixed_flags(still: &CloudStill) -> String {
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
    if let Some(cells) = still.solve_cells {
        flags.push(format!("--solve-cells {cells}"));
    }
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
