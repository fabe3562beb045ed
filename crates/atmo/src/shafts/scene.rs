//! The scene file: camera, haze, spotlights and objects in physical units (TOML, see
//! docs/shafts.md for every key and convention). Parsed with `deny_unknown_fields` so a
//! misspelt key is an error with its line and column, validated once here into the
//! types the renderers use, with messages naming the field and its allowed range.

use std::path::{Path, PathBuf};

use glam::Vec3;
use serde::Deserialize;

use super::gdtf;
use super::haze::Haze;
use super::objects::{Object, Objects};
use super::photometry::Photometry;
use super::show::{profile_solid_angle, Change, Cue, Fixture, Prism, Show, State, CHANNELS};
use super::spotlight::{light_frame, Falloff, Gobo, Profile, Sampling, Spotlight};
use super::PlaneSettings;
use crate::atmosphere::phase::PhaseFunction;
use crate::atmosphere::spectrum::blackbody_srgb;
use crate::error::{check_positive, check_range, from_toml, Error, Result};
use crate::geometry::{Aabb, Mesh, Shape};
use crate::image::{Display, ToneMap};
use crate::view::{Camera, Fov};

/// A validated scene: everything a renderer needs.
#[derive(Debug, Clone)]
pub struct Scene {
    /// The camera: a pinhole, as scene files make it (the sample planes are parallel to
    /// its screen, shafts 4.2).
    pub camera: Camera,
    /// The haze.
    pub haze: Haze,
    /// The spotlights.
    pub lights: Vec<Spotlight>,
    /// The opaque objects.
    pub objects: Objects,
    /// Sample planes, sub-planes and shadow maps of the plane method.
    pub planes: PlaneSettings,
    /// How the picture is shown in 8-bit files.
    pub display: Display,
    /// The unit of the lights' intensities, and so of the pixels' radiance.
    pub unit: IntensityUnit,
    /// The files the scene names (gobo images, meshes, photometric files) as they
    /// were read, so that a command does not write over one of them.
    pub files: Vec<PathBuf>,
    /// The moving heads and their cues; the heads are the last lights of
    /// [`Scene::lights`], posed at [`Scene::time_s`].
    pub show: Show,
    /// The show's time the heads are posed at, s ([`Scene::at_time`]; 0 as loaded).
    pub time_s: f32,
}

/// What a light's `intensity` means; pixels are radiance in the same unit per m^2.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
pub enum IntensityUnit {
    /// Luminous intensity, candela: pixels in cd/m^2 (nits).
    #[serde(rename = "cd")]
    Candela,
    /// Radiant intensity, W/sr: pixels in W/(sr m^2).
    #[serde(rename = "W/sr")]
    WattPerSteradian,
}

impl IntensityUnit {
    /// The unit of a pixel's radiance.
    pub fn radiance_unit(self) -> &'static str {
        match self {
            IntensityUnit::Candela => "cd/m^2",
            IntensityUnit::WattPerSteradian => "W/(sr m^2)",
        }
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneSpec {
    camera: CameraSpec,
    haze: HazeSpec,
    #[serde(default)]
    render: RenderSpec,
    #[serde(default)]
    display: DisplaySpec,
    #[serde(default)]
    spotlight: Vec<SpotlightSpec>,
    #[serde(default)]
    object: Vec<ObjectSpec>,
    #[serde(default)]
    fixture: Vec<FixtureSpec>,
    #[serde(default)]
    cue: Vec<CueSpec>,
}

/// A moving head ([`super::show::Fixture`]); angles in degrees. With `gdtf` the file
/// gives the intensity, the ranges, the field ratio and the gobo wheel.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct FixtureSpec {
    name: String,
    position: [f32; 3],
    #[serde(default = "down")]
    axis: [f32; 3],
    #[serde(default = "z_front")]
    front: [f32; 3],
    gdtf: Option<PathBuf>,
    mode: Option<String>,
    intensity: Option<f32>,
    pan_range_deg: Option<[f32; 2]>,
    tilt_range_deg: Option<[f32; 2]>,
    zoom_range_deg: Option<[f32; 2]>,
    field_ratio: Option<f32>,
    #[serde(default)]
    falloff: FalloffSpec,
    gobo_wheel: Option<Vec<PathBuf>>,
    #[serde(default)]
    gobo_sampling: SamplingSpec,
    #[serde(default)]
    gobo_rotation_deg: f32,
    /// The attributes at the show's start (the rest at rest: along the axis, widest,
    /// open, full, white, no gobo).
    #[serde(default)]
    start: AttributesSpec,
    /// A prism in the beam: `{ facets = 3, angle_deg = 8 }` (its turn is the
    /// `prism_deg` attribute).
    prism: Option<PrismSpec>,
}

/// A fixture's prism, as the scene gives it (see [`Prism`]).
#[derive(Deserialize, Clone, Copy)]
#[serde(deny_unknown_fields)]
struct PrismSpec {
    facets: u32,
    angle_deg: f32,
}

impl PrismSpec {
    /// The prism, every number in its range ([`Prism::FACETS`], each beam at most
    /// [`Prism::MAX_ANGLE_DEG`] off the head's).
    fn validate(&self, at: &str) -> Result<Prism> {
        let [fewest, most] = Prism::FACETS.map(f64::from);
        check_range(&format!("{at}.facets"), self.facets as f64, fewest, most)?;
        let most_deg = Prism::MAX_ANGLE_DEG as f64;
        check_range(
            &format!("{at}.angle_deg"),
            self.angle_deg as f64,
            0.0,
            most_deg,
        )?;
        Ok(Prism {
            facets: self.facets,
            angle_deg: self.angle_deg,
        })
    }
}

/// What a fixture's attributes may be: pan, tilt and zoom ranges (degrees) and the
/// gobo wheel's slots.
struct Limits {
    pan: [f32; 2],
    tilt: [f32; 2],
    zoom: [f32; 2],
    slots: usize,
    /// Whether the head has a prism to put in and take out.
    prism: bool,
}

/// A fixture's light as its keys or its GDTF file give it.
struct Light {
    intensity: f32,
    zoom_scale: f32,
    field_ratio: f32,
    wheel: Vec<Gobo>,
    kelvin: Option<f32>,
    /// The prism a GDTF file gives (keys give theirs with `prism`).
    prism: Option<Prism>,
    limits: Limits,
}

fn down() -> [f32; 3] {
    [0.0, -1.0, 0.0]
}
fn z_front() -> [f32; 3] {
    [0.0, 0.0, 1.0]
}
/// A fixture's ranges and field ratio where neither its keys nor a file give them.
const DEFAULT_PAN: [f32; 2] = [-270.0, 270.0];
const DEFAULT_TILT: [f32; 2] = [-135.0, 135.0];
const DEFAULT_ZOOM: [f32; 2] = [10.0, 40.0];
const DEFAULT_FIELD_RATIO: f32 = 1.3;

/// A fixture's attributes, as set at the start or by a cue; absent ones unchanged.
#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct AttributesSpec {
    pan_deg: Option<f32>,
    tilt_deg: Option<f32>,
    zoom_deg: Option<f32>,
    iris: Option<f32>,
    dimmer: Option<f32>,
    color: Option<[f32; 3]>,
    cmy: Option<[f32; 3]>,
    kelvin: Option<f32>,
    gobo: Option<usize>,
    gobo_speed_dps: Option<f32>,
    prism_deg: Option<f32>,
    prism_in: Option<bool>,
}

/// A cue: at `time_s`, the attributes it sets per fixture fade over `fade_s`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CueSpec {
    time_s: f32,
    #[serde(default)]
    fade_s: f32,
    #[serde(default)]
    set: std::collections::BTreeMap<String, AttributesSpec>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CameraSpec {
    position: [f32; 3],
    look_at: [f32; 3],
    #[serde(default = "y_up")]
    up: [f32; 3],
    fov_deg: f32,
    #[serde(default)]
    fov_axis: FovAxis,
    width: u32,
    height: u32,
    #[serde(default = "one")]
    supersampling: u32,
    #[serde(default = "default_far")]
    far_m: f32,
}

fn y_up() -> [f32; 3] {
    [0.0, 1.0, 0.0]
}
fn one() -> u32 {
    1
}
fn default_far() -> f32 {
    1000.0
}

#[derive(Deserialize, Default, Clone, Copy)]
#[serde(rename_all = "lowercase")]
enum FovAxis {
    #[default]
    Vertical,
    Horizontal,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct HazeSpec {
    extinction: f32,
    #[serde(default = "one_f")]
    albedo: f32,
    #[serde(default)]
    phase: PhaseSpec,
    #[serde(rename = "box")]
    bounds: Option<BoxSpec>,
}

fn one_f() -> f32 {
    1.0
}

#[derive(Deserialize)]
#[serde(tag = "kind", rename_all = "kebab-case", deny_unknown_fields)]
enum PhaseSpec {
    Paper {
        #[serde(default = "sixteen")]
        exponent: f32,
    },
    HenyeyGreenstein {
        g: f32,
    },
}

fn sixteen() -> f32 {
    16.0
}

impl Default for PhaseSpec {
    fn default() -> Self {
        PhaseSpec::Paper { exponent: 16.0 }
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct BoxSpec {
    min: [f32; 3],
    max: [f32; 3],
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RenderSpec {
    #[serde(default = "default_planes")]
    planes: u32,
    #[serde(default = "default_sub_planes")]
    sub_planes: u32,
    #[serde(default = "default_shadow_map")]
    shadow_map: u32,
    #[serde(default = "default_adaptive")]
    adaptive: bool,
}

fn default_planes() -> u32 {
    PlaneSettings::default().planes
}
fn default_sub_planes() -> u32 {
    PlaneSettings::default().sub_planes
}
fn default_shadow_map() -> u32 {
    PlaneSettings::default().shadow_map
}
fn default_adaptive() -> bool {
    PlaneSettings::default().adaptive
}

impl Default for RenderSpec {
    fn default() -> Self {
        RenderSpec {
            planes: default_planes(),
            sub_planes: default_sub_planes(),
            shadow_map: default_shadow_map(),
            adaptive: default_adaptive(),
        }
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct DisplaySpec {
    #[serde(default = "one_f")]
    exposure: f32,
    #[serde(default)]
    tone_map: ToneMapSpec,
}

impl Default for DisplaySpec {
    fn default() -> Self {
        DisplaySpec {
            exposure: 1.0,
            tone_map: ToneMapSpec::Exponential,
        }
    }
}

#[derive(Deserialize, Default, Clone, Copy)]
#[serde(rename_all = "lowercase")]
enum ToneMapSpec {
    #[default]
    Exponential,
    Aces,
    Clamp,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SpotlightSpec {
    position: [f32; 3],
    aim: Option<[f32; 3]>,
    direction: Option<[f32; 3]>,
    up: Option<[f32; 3]>,
    color: Option<[f32; 3]>,
    kelvin: Option<f32>,
    intensity: Option<f32>,
    #[serde(default = "one_f")]
    dimmer: f32,
    #[serde(default = "candela")]
    intensity_unit: IntensityUnit,
    beam_deg: Option<f32>,
    field_deg: Option<f32>,
    falloff: Option<FalloffSpec>,
    profile: Option<ProfileSpec>,
    gobo: Option<PathBuf>,
    #[serde(default)]
    gobo_sampling: SamplingSpec,
}

fn candela() -> IntensityUnit {
    IntensityUnit::Candela
}

/// A measured profile: one photometric file.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ProfileSpec {
    ies: Option<PathBuf>,
    ldt: Option<PathBuf>,
}

impl ProfileSpec {
    /// The file and whether it is EULUMDAT.
    fn file(&self, at: &str) -> Result<(&Path, bool)> {
        match (&self.ies, &self.ldt) {
            (Some(f), None) => Ok((f, false)),
            (None, Some(f)) => Ok((f, true)),
            _ => Err(Error::Invalid(format!(
                "{at}.profile: give exactly one of `ies` (an IES LM-63 file) and `ldt` (a EULUMDAT file)"
            ))),
        }
    }
}

impl From<FalloffSpec> for Falloff {
    fn from(f: FalloffSpec) -> Falloff {
        match f {
            FalloffSpec::Linear => Falloff::Linear,
            FalloffSpec::Smooth => Falloff::Smooth,
        }
    }
}

#[derive(Deserialize, Default, Clone, Copy)]
#[serde(rename_all = "lowercase")]
enum FalloffSpec {
    Linear,
    #[default]
    Smooth,
}

impl From<SamplingSpec> for Sampling {
    fn from(s: SamplingSpec) -> Sampling {
        match s {
            SamplingSpec::Nearest => Sampling::Nearest,
            SamplingSpec::Bilinear => Sampling::Bilinear,
        }
    }
}

#[derive(Deserialize, Default, Clone, Copy)]
#[serde(rename_all = "lowercase")]
enum SamplingSpec {
    Nearest,
    #[default]
    Bilinear,
}

/// An albedo: one grey value or linear RGB.
#[derive(Deserialize, Clone, Copy)]
#[serde(untagged)]
enum AlbedoSpec {
    Grey(f32),
    Rgb([f32; 3]),
}

#[derive(Deserialize)]
#[serde(tag = "kind", rename_all = "lowercase", deny_unknown_fields)]
enum ObjectSpec {
    Plane {
        point: [f32; 3],
        normal: [f32; 3],
        albedo: AlbedoSpec,
    },
    Rect {
        corner: [f32; 3],
        edge_a: [f32; 3],
        edge_b: [f32; 3],
        albedo: AlbedoSpec,
    },
    Sphere {
        center: [f32; 3],
        radius: f32,
        albedo: AlbedoSpec,
    },
    Box {
        min: [f32; 3],
        max: [f32; 3],
        albedo: AlbedoSpec,
    },
    Mesh {
        file: PathBuf,
        #[serde(default = "one_f")]
        scale: f32,
        #[serde(default)]
        rotate_y_deg: f32,
        #[serde(default)]
        translate: [f32; 3],
        albedo: AlbedoSpec,
    },
}

impl Scene {
    /// Loads and validates the scene file at `path`; gobo and OBJ paths in it are
    /// relative to its folder.
    pub fn from_file(path: &Path) -> Result<Scene> {
        Scene::from_text_at(&Scene::read_text(path)?, path)
    }

    /// The text of the scene file at `path` (through the bounded reader).
    pub fn read_text(path: &Path) -> Result<String> {
        crate::files::read_text(path, "scene file", crate::files::TEXT_LIMIT_BYTES)
    }

    /// The scene of `text` as if it were the file at `path` (named so in messages, its
    /// relative paths from its folder): a file edited before it is read.
    pub fn from_text_at(text: &str, path: &Path) -> Result<Scene> {
        let folder = path.parent().unwrap_or(Path::new("."));
        Scene::from_toml_str(text, &path.display().to_string(), folder)
    }

    /// The camera of scene TOML `text` alone, parsed and validated as
    /// [`Scene::from_toml_str`] does (`origin` names the text in messages), the rest of
    /// the text unread: what a viewer whose edit moved only the camera reads again,
    /// without the objects' and the lights' files.
    pub fn camera_from_toml_str(text: &str, origin: &str) -> Result<Camera> {
        /// The camera table of a scene; the other tables are the whole scene's to check.
        #[derive(Deserialize)]
        struct CameraOnly {
            camera: CameraSpec,
        }
        let spec: CameraOnly = from_toml(text, origin)?;
        spec.camera.validate()
    }

    /// Parses and validates scene TOML; `origin` names it in messages, `folder` is where
    /// relative gobo and OBJ paths start.
    pub fn from_toml_str(text: &str, origin: &str, folder: &Path) -> Result<Scene> {
        let spec: SceneSpec = from_toml(text, origin)?;
        let camera = spec.camera.validate()?;
        let haze = spec.haze.validate()?;
        let planes = PlaneSettings {
            planes: spec.render.planes,
            sub_planes: spec.render.sub_planes,
            shadow_map: spec.render.shadow_map,
            adaptive: spec.render.adaptive,
        };
        check_positive("display.exposure", spec.display.exposure as f64, 1e12)?;
        let display = Display {
            exposure: spec.display.exposure,
            tone: match spec.display.tone_map {
                ToneMapSpec::Exponential => ToneMap::Exponential,
                ToneMapSpec::Aces => ToneMap::Aces,
                ToneMapSpec::Clamp => ToneMap::Clamp,
            },
        };
        let unit = spec
            .spotlight
            .first()
            .map_or(IntensityUnit::Candela, |l| l.intensity_unit);
        let lights = spec
            .spotlight
            .iter()
            .enumerate()
            .map(|(i, l)| l.validate(&format!("spotlight[{i}]"), unit, folder))
            .collect::<Result<Vec<_>>>()?;
        let list = spec
            .object
            .iter()
            .enumerate()
            .map(|(i, o)| o.validate(&format!("object[{i}]"), folder))
            .collect::<Result<Vec<_>>>()?;
        let show = show(&spec, unit, folder)?;
        let mut lights = lights;
        lights.extend(show.pose(0.0));
        let wheels = spec
            .fixture
            .iter()
            .flat_map(|f| f.gobo_wheel.iter().flatten().chain(f.gdtf.iter()));
        let gobos = spec.spotlight.iter().flat_map(|l| {
            let profile = l
                .profile
                .as_ref()
                .and_then(|p| p.ies.as_ref().or(p.ldt.as_ref()));
            l.gobo.iter().chain(profile)
        });
        let meshes = spec.object.iter().filter_map(|o| match o {
            ObjectSpec::Mesh { file, .. } => Some(file),
            _ => None,
        });
        let scene = Scene {
            camera,
            haze,
            lights,
            objects: Objects { list },
            planes,
            display,
            unit,
            files: gobos
                .chain(wheels)
                .chain(meshes)
                .map(|f| folder.join(f))
                .collect(),
            show,
            time_s: 0.0,
        };
        scene.validate_planes()?;
        Ok(scene)
    }

    /// The scene at `time_s` seconds into its show: its moving heads posed as its cues
    /// have them then (the other lights do not change).
    pub fn at_time(&mut self, time_s: f32) {
        let first = self.lights.len() - self.show.light_count(self.time_s);
        self.lights.truncate(first);
        self.lights.extend(self.show.pose(time_s));
        self.time_s = time_s;
    }

    /// Checks the plane settings, and that the shadow maps they make for these lights
    /// fit the run's memory budget ([`crate::budget`]); again after a caller changes
    /// them.
    pub fn validate_planes(&self) -> Result<()> {
        self.planes.validate()?;
        // Each light's shadow map, 4 bytes a texel, on the CPU or on the GPU, at the
        // time of the show with the most (every prism in).
        let most = self.lights.len() - self.show.light_count(self.time_s) + self.show.most_lights();
        let texels = most as u64 * (self.planes.shadow_map as u64).pow(2);
        crate::budget::check(
            &format!("{most} shadow maps of {}^2", self.planes.shadow_map),
            4 * texels,
            "render.shadow_map (--shadow-map) or the number of spotlights",
        )
    }
}

/// A light's colour from at most one of `color` (linear RGB), `cmy` (0-1 each; the
/// colour is `1 - cmy`; only where `has_cmy`, the light having that key) and `kelvin`,
/// checked; `None` when none is given.
fn colour(
    at: &str,
    color: Option<[f32; 3]>,
    (has_cmy, cmy): (bool, Option<[f32; 3]>),
    kelvin: Option<f32>,
) -> Result<Option<Vec3>> {
    let checked = |key: &str, v: [f32; 3], max: f64| -> Result<Vec3> {
        for (c, x) in v.iter().enumerate() {
            check_range(&format!("{at}.{key}[{c}]"), *x as f64, 0.0, max)?;
        }
        Ok(Vec3::from(v))
    };
    Ok(match (color, cmy, kelvin) {
        (None, None, None) => None,
        (Some(rgb), None, None) => Some(checked("color", rgb, 1e6)?),
        (None, Some(cmy), None) => Some(Vec3::ONE - checked("cmy", cmy, 1.0)?),
        (None, None, Some(k)) => {
            check_range(&format!("{at}.kelvin"), k as f64, 1000.0, 40000.0)?;
            Some(kelvin_colour(k))
        }
        _ if !has_cmy => {
            return Err(Error::Invalid(format!(
                "{at}: give at most one of `color` (linear RGB) and `kelvin`"
            )))
        }
        _ => {
            return Err(Error::Invalid(format!(
                "{at}: give at most one of `color` (linear RGB), `cmy` and `kelvin`"
            )))
        }
    })
}

/// The colour of a black body at `kelvin`, normalised to luminance 1, linear sRGB.
fn kelvin_colour(kelvin: f32) -> Vec3 {
    Vec3::from(blackbody_srgb(kelvin as f64).map(|c| c as f32))
}

/// Refuses the keys of `given` that are set: `why` says where their values come from.
fn refuse_given(at: &str, given: &[(&str, bool)], why: &str) -> Result<()> {
    match given.iter().find(|(_, set)| *set) {
        Some((key, _)) => Err(Error::Invalid(format!(
            "{at}.{key}: {why}; leave `{key}` out"
        ))),
        None => Ok(()),
    }
}

fn vec3(field: &str, v: [f32; 3]) -> Result<Vec3> {
    let v = Vec3::from(v);
    if v.is_finite() {
        Ok(v)
    } else {
        Err(Error::out_of_range(
            field,
            format!("{v:?}"),
            "finite numbers",
        ))
    }
}

fn unit_vector(field: &str, v: [f32; 3]) -> Result<Vec3> {
    vec3(field, v)?
        .try_normalize()
        .ok_or_else(|| Error::out_of_range(field, format!("{v:?}"), "a non-zero vector"))
}

fn albedo(field: &str, a: AlbedoSpec) -> Result<Vec3> {
    let rgb = match a {
        AlbedoSpec::Grey(g) => [g; 3],
        AlbedoSpec::Rgb(rgb) => rgb,
    };
    for (c, v) in rgb.iter().enumerate() {
        check_range(&format!("{field}[{c}]"), *v as f64, 0.0, 1.0)?;
    }
    Ok(Vec3::from(rgb))
}

impl CameraSpec {
    fn validate(&self) -> Result<Camera> {
        let position = vec3("camera.position", self.position)?;
        let look_at = vec3("camera.look_at", self.look_at)?;
        let up = vec3("camera.up", self.up)?;
        let fov = match self.fov_axis {
            FovAxis::Vertical => Fov::Vertical(self.fov_deg),
            FovAxis::Horizontal => Fov::Horizontal(self.fov_deg),
        };
        Camera::look_at(position, look_at, up, fov, (self.width, self.height))?
            .with_supersampling(self.supersampling)?
            .with_far(self.far_m)
    }
}

impl HazeSpec {
    fn validate(&self) -> Result<Haze> {
        check_positive("haze.extinction", self.extinction as f64, 100.0)?;
        check_range("haze.albedo", self.albedo as f64, 0.0, 1.0)?;
        let phase = match self.phase {
            PhaseSpec::Paper { exponent } => {
                check_range("haze.phase.exponent", exponent as f64, 0.0, 1000.0)?;
                PhaseFunction::PaperHaze {
                    exponent: exponent as f64,
                }
            }
            PhaseSpec::HenyeyGreenstein { g } => {
                check_range("haze.phase.g", g as f64, -0.99, 0.99)?;
                PhaseFunction::HenyeyGreenstein { g: g as f64 }
            }
        };
        let bounds = match &self.bounds {
            None => None,
            Some(b) => {
                let (min, max) = (vec3("haze.box.min", b.min)?, vec3("haze.box.max", b.max)?);
                if !min.cmplt(max).all() {
                    return Err(Error::out_of_range(
                        "haze.box.max",
                        format!("{max:?}"),
                        &format!("greater than haze.box.min = {min:?} on every axis"),
                    ));
                }
                Some(Aabb { min, max })
            }
        };
        Ok(Haze {
            extinction: self.extinction,
            albedo: self.albedo,
            phase,
            bounds,
        })
    }
}

impl SpotlightSpec {
    fn validate(&self, at: &str, unit: IntensityUnit, folder: &Path) -> Result<Spotlight> {
        let position = vec3(&format!("{at}.position"), self.position)?;
        let axis = match (self.aim, self.direction) {
            (Some(aim), None) => {
                let aim = vec3(&format!("{at}.aim"), aim)?;
                (aim - position).try_normalize().ok_or_else(|| {
                    Error::Invalid(format!(
                        "{at}.aim equals {at}.position: the light has no axis"
                    ))
                })?
            }
            (None, Some(d)) => unit_vector(&format!("{at}.direction"), d)?,
            _ => {
                return Err(Error::Invalid(format!(
                    "{at}: give exactly one of `aim` (a point) and `direction` (a vector)"
                )))
            }
        };
        // The light's up: the given one, else world y (z for a beam along y).
        let up = match self.up {
            Some(up) => unit_vector(&format!("{at}.up"), up)?,
            None if axis.y.abs() > 0.999 => Vec3::Z,
            None => Vec3::Y,
        };
        let light_from_world = light_frame(axis, up)
            .ok_or_else(|| Error::Invalid(format!("{at}.up is parallel to the beam axis")))?;
        let colour = colour(at, self.color, (false, None), self.kelvin)?.unwrap_or(Vec3::ONE);
        check_range(&format!("{at}.dimmer"), self.dimmer as f64, 0.0, 1.0)?;
        if self.intensity_unit != unit {
            return Err(Error::Invalid(format!(
                "{at}.intensity_unit differs from spotlight[0]'s: all lights of a scene share one unit"
            )));
        }
        let (intensity, field_half, profile) = match &self.profile {
            None => self.beam(at)?,
            Some(spec) => self.measured(at, spec, folder)?,
        };
        let gobo = match &self.gobo {
            None => None,
            Some(file) => Some(load_gobo(&folder.join(file), self.gobo_sampling.into())?),
        };
        Ok(Spotlight::new(
            position,
            light_from_world,
            colour * (self.dimmer * intensity),
            field_half,
            profile,
            gobo,
        ))
    }

    /// A beam and field light: its intensity, half field angle (rad) and profile.
    fn beam(&self, at: &str) -> Result<(f32, f32, Profile)> {
        let need = |value: Option<f32>, key: &str| {
            value.ok_or_else(|| {
                Error::Invalid(format!(
                    "{at}: `{key}` is missing (a light needs `intensity`, `beam_deg` and \
                     `field_deg`, or a measured `profile`)"
                ))
            })
        };
        let intensity = need(self.intensity, "intensity")?;
        let (beam_deg, field_deg) = (
            need(self.beam_deg, "beam_deg")?,
            need(self.field_deg, "field_deg")?,
        );
        check_positive(&format!("{at}.intensity"), intensity as f64, 1e9)?;
        check_range(&format!("{at}.field_deg"), field_deg as f64, 0.1, 170.0)?;
        check_range(
            &format!("{at}.beam_deg"),
            beam_deg as f64,
            0.0,
            field_deg as f64,
        )?;
        let falloff = self.falloff.unwrap_or_default().into();
        Ok((
            intensity,
            0.5 * field_deg.to_radians(),
            Profile::Beam {
                beam_half: 0.5 * beam_deg.to_radians(),
                falloff,
            },
        ))
    }

    /// A light with a measured profile: its peak candela, half field angle (rad: where
    /// the file's light ends, at most [`MEASURED_REACH_DEG`]) and profile.
    fn measured(&self, at: &str, spec: &ProfileSpec, folder: &Path) -> Result<(f32, f32, Profile)> {
        refuse_given(
            at,
            &[
                ("intensity", self.intensity.is_some()),
                ("beam_deg", self.beam_deg.is_some()),
                ("field_deg", self.field_deg.is_some()),
                ("falloff", self.falloff.is_some()),
            ],
            "a light with a measured `profile` takes its intensity and angles from the \
             file (`dimmer` scales it)",
        )?;
        if self.intensity_unit != IntensityUnit::Candela {
            return Err(Error::Invalid(format!(
                "{at}.intensity_unit: a photometric file gives candela; the scene's unit must be \"cd\""
            )));
        }
        let (file, eulumdat) = spec.file(at)?;
        let photometry = load_photometry(&folder.join(file), eulumdat)?;
        let reach = photometry.reach().min(MEASURED_REACH_DEG);
        Ok((
            photometry.peak(),
            reach.to_radians(),
            Profile::Measured(std::sync::Arc::new(photometry)),
        ))
    }
}

/// The scene's moving heads and cues, validated: ranges, names, gobo slots, cue order.
fn show(spec: &SceneSpec, unit: IntensityUnit, folder: &Path) -> Result<Show> {
    let (fixtures, limits): (Vec<Fixture>, Vec<Limits>) = spec
        .fixture
        .iter()
        .enumerate()
        .map(|(i, f)| f.validate(&format!("fixture[{i}] ({})", f.name), unit, folder))
        .collect::<Result<Vec<_>>>()?
        .into_iter()
        .unzip();
    for (i, f) in fixtures.iter().enumerate() {
        if fixtures[..i].iter().any(|g| g.name == f.name) {
            return Err(Error::Invalid(format!(
                "fixture[{i}].name = {:?} is used twice: cues name fixtures, so names must differ",
                f.name
            )));
        }
    }
    let mut cues = Vec::with_capacity(spec.cue.len());
    for (i, c) in spec.cue.iter().enumerate() {
        let at = format!("cue[{i}]");
        check_range(&format!("{at}.time_s"), c.time_s as f64, 0.0, 1e6)?;
        check_range(&format!("{at}.fade_s"), c.fade_s as f64, 0.0, 1e6)?;
        if let Some(before) = spec.cue[..i].last() {
            if c.time_s < before.time_s {
                return Err(Error::out_of_range(
                    &format!("{at}.time_s"),
                    c.time_s,
                    &format!(
                        "at least cue[{}].time_s = {}: cues in time order",
                        i - 1,
                        before.time_s
                    ),
                ));
            }
        }
        let changes = c
            .set
            .iter()
            .map(|(name, attributes)| {
                let k = fixtures
                    .iter()
                    .position(|f| &f.name == name)
                    .ok_or_else(|| {
                        Error::Invalid(format!(
                            "{at}.set.{name}: no fixture is named {name:?} (fixtures: {})",
                            fixtures
                                .iter()
                                .map(|f| f.name.as_str())
                                .collect::<Vec<_>>()
                                .join(", ")
                        ))
                    })?;
                let change = attributes.validate(&format!("{at}.set.{name}"), &limits[k])?;
                Ok((k, change))
            })
            .collect::<Result<Vec<_>>>()?;
        cues.push(Cue {
            time_s: c.time_s,
            fade_s: c.fade_s,
            changes,
        });
    }
    Ok(Show { fixtures, cues })
}

impl FixtureSpec {
    fn validate(&self, at: &str, unit: IntensityUnit, folder: &Path) -> Result<(Fixture, Limits)> {
        let field = |name: &str| format!("{at}.{name}");
        let position = vec3(&field("position"), self.position)?;
        let axis = unit_vector(&field("axis"), self.axis)?;
        let front = vec3(&field("front"), self.front)?;
        let front = (front - axis * front.dot(axis))
            .try_normalize()
            .ok_or_else(|| Error::Invalid(format!("{at}.front is parallel to its axis")))?;
        check_range(
            &field("gobo_rotation_deg"),
            self.gobo_rotation_deg as f64,
            -360.0,
            360.0,
        )?;
        let sampling = self.gobo_sampling.into();
        let mut light = match &self.gdtf {
            None => self.keyed(at, folder, sampling)?,
            Some(file) => self.gdtf_light(at, unit, &folder.join(file), sampling)?,
        };
        // A prism the scene gives is in the beam at rest; a GDTF file's is out, as a
        // desk's prism channel at its default (the wheel's open slot).
        let (prism, prism_at_rest) = match self.prism {
            Some(p) => (Some(p.validate(&field("prism"))?), true),
            None => (light.prism, false),
        };
        light.limits.prism = prism.is_some();
        let limits = &light.limits;
        for (name, [lo, hi], limit) in [
            ("pan_range_deg", limits.pan, 720.0),
            ("tilt_range_deg", limits.tilt, 360.0),
        ] {
            check_range(&format!("{}[0]", field(name)), lo as f64, -limit, limit)?;
            check_range(&format!("{}[1]", field(name)), hi as f64, lo as f64, limit)?;
        }
        let [narrow, wide] = limits.zoom;
        check_range(
            &format!("{}[1]", field("zoom_range_deg")),
            wide as f64,
            0.5,
            120.0,
        )?;
        check_range(
            &format!("{}[0]", field("zoom_range_deg")),
            narrow as f64,
            0.5,
            wide as f64,
        )?;
        check_range(&field("field_ratio"), light.field_ratio as f64, 1.0, 3.0)?;
        check_positive(&field("intensity"), light.intensity as f64, 1e9)?;
        // At rest: pan and tilt 0 (or the nearest the ranges allow), widest, open,
        // full, the file's colour temperature or white.
        let white = light.kelvin.map_or(Vec3::ONE, kelvin_colour);
        let rest = State {
            channels: [
                0f32.clamp(limits.pan[0], limits.pan[1]),
                0f32.clamp(limits.tilt[0], limits.tilt[1]),
                wide,
                1.0,
                1.0,
                white.x,
                white.y,
                white.z,
                0.0,
                0.0,
            ],
            gobo: 0,
            prism_in: prism_at_rest,
        };
        let change = self.start.validate(&format!("{at}.start"), limits)?;
        let start = State {
            channels: std::array::from_fn(|c| change.channels[c].unwrap_or(rest.channels[c])),
            gobo: change.gobo.unwrap_or(0),
            prism_in: change.prism_in.unwrap_or(rest.prism_in),
        };
        let fixture = Fixture {
            name: self.name.clone(),
            position,
            axis,
            front,
            intensity: light.intensity,
            widest_zoom_deg: wide,
            zoom_scale: light.zoom_scale,
            field_ratio: light.field_ratio,
            falloff: self.falloff.into(),
            wheel: light.wheel,
            gobo_rotation_deg: self.gobo_rotation_deg,
            pan_range_deg: limits.pan,
            tilt_range_deg: limits.tilt,
            start,
            prism,
        };
        Ok((fixture, light.limits))
    }

    /// The light as the fixture's own keys give it.
    fn keyed(&self, at: &str, folder: &Path, sampling: Sampling) -> Result<Light> {
        if self.mode.is_some() {
            return Err(Error::Invalid(format!(
                "{at}.mode names a DMX mode of a GDTF file; give `gdtf` with it"
            )));
        }
        let intensity = self.intensity.ok_or_else(|| {
            Error::Invalid(format!(
                "{at}: `intensity` is missing (or give a `gdtf` file, which has it)"
            ))
        })?;
        let wheel = self
            .gobo_wheel
            .iter()
            .flatten()
            .map(|file| load_gobo(&folder.join(file), sampling))
            .collect::<Result<Vec<_>>>()?;
        Ok(Light {
            intensity,
            zoom_scale: 1.0,
            field_ratio: self.field_ratio.unwrap_or(DEFAULT_FIELD_RATIO),
            limits: Limits {
                pan: self.pan_range_deg.unwrap_or(DEFAULT_PAN),
                tilt: self.tilt_range_deg.unwrap_or(DEFAULT_TILT),
                zoom: self.zoom_range_deg.unwrap_or(DEFAULT_ZOOM),
                slots: wheel.len(),
                prism: false,
            },
            wheel,
            kelvin: None,
            prism: None,
        })
    }

    /// The light as the GDTF file `path` gives it in the fixture's `mode`: GDTF's beam
    /// and field angles (half and a tenth of the peak) turned into atmo's smooth edge,
    /// the intensity from the beam's luminous flux spread over that profile at the
    /// widest zoom.
    fn gdtf_light(
        &self,
        at: &str,
        unit: IntensityUnit,
        path: &Path,
        sampling: Sampling,
    ) -> Result<Light> {
        refuse_given(
            at,
            &[
                ("intensity", self.intensity.is_some()),
                ("pan_range_deg", self.pan_range_deg.is_some()),
                ("tilt_range_deg", self.tilt_range_deg.is_some()),
                ("zoom_range_deg", self.zoom_range_deg.is_some()),
                ("field_ratio", self.field_ratio.is_some()),
                ("gobo_wheel", self.gobo_wheel.is_some()),
            ],
            "a fixture from a GDTF file takes it from the file",
        )?;
        if unit != IntensityUnit::Candela {
            return Err(Error::Invalid(format!(
                "{at}.gdtf: a GDTF beam gives lumens, so the scene's unit must be \"cd\""
            )));
        }
        let mode = self.mode.as_deref().ok_or_else(|| {
            Error::Invalid(format!(
                "{at}: `mode` is missing: the GDTF file's DMX mode to use"
            ))
        })?;
        let file = read_gdtf(path, mode, sampling)?;
        // The file's prism, unless the scene gives the fixture its own.
        let prism = match (&file.prism, self.prism) {
            (Some(p), None) => Some(p.circular().map_err(|why| {
                Error::Invalid(format!("{at}.gdtf: GDTF file {}: {why}", path.display()))
            })?),
            _ => None,
        };
        let (beam, field) = gdtf::to_smooth_edge(file.beam_deg, file.field_deg);
        // atmo's beam at least a third of its field (the field ratio's limit).
        let beam = beam.max(field / 3.0).max(0.5);
        let field_ratio = (field / beam).max(1.0);
        // The zoom stays in the file's terms (its half-intensity beam angle).
        let zoom_scale = beam / file.beam_deg.max(1e-3);
        let zoom = file.zoom_range_deg.unwrap_or([file.beam_deg; 2]);
        let widest = zoom[1] * zoom_scale;
        let intensity = file.luminous_flux_lm
            / profile_solid_angle(
                0.5 * widest.to_radians(),
                (0.5 * widest * field_ratio)
                    .min(MEASURED_REACH_DEG)
                    .to_radians(),
                self.falloff.into(),
            );
        Ok(Light {
            intensity,
            zoom_scale,
            field_ratio,
            limits: Limits {
                pan: file.pan_range_deg.unwrap_or([0.0, 0.0]),
                tilt: file.tilt_range_deg.unwrap_or([0.0, 0.0]),
                zoom,
                slots: file.wheel.len(),
                prism: false,
            },
            wheel: file.wheel,
            kelvin: Some(file.kelvin),
            prism,
        })
    }
}

/// A GDTF file's fixture in `mode`.
#[cfg(feature = "gdtf")]
fn read_gdtf(path: &Path, mode: &str, sampling: Sampling) -> Result<gdtf::GdtfFixture> {
    let bytes = crate::files::read_bounded(path, "GDTF file", crate::files::DATA_LIMIT_BYTES)?;
    gdtf::read(&bytes, &path.display().to_string(), mode, sampling)
}

/// Without atmo's `gdtf` feature, GDTF files are refused with a message saying so.
#[cfg(not(feature = "gdtf"))]
fn read_gdtf(path: &Path, _mode: &str, _sampling: Sampling) -> Result<gdtf::GdtfFixture> {
    Err(Error::Invalid(format!(
        "GDTF file {}: fixtures from GDTF files need atmo's `gdtf` feature, which this build leaves out",
        path.display()
    )))
}

impl AttributesSpec {
    /// The change these attributes make on a fixture of `limits`, each checked
    /// against its range.
    fn validate(&self, at: &str, limits: &Limits) -> Result<Change> {
        let mut change = Change::default();
        // The fading attributes that are numbers: channel, value and range, checked in
        // this order (the colour between the dimmer and the gobo's speed).
        let numbers = [
            (0, self.pan_deg, limits.pan),
            (1, self.tilt_deg, limits.tilt),
            (2, self.zoom_deg, limits.zoom),
            (3, self.iris, [0.05, 1.0]),
            (4, self.dimmer, [0.0, 1.0]),
            (8, self.gobo_speed_dps, [-3600.0, 3600.0]),
            (9, self.prism_deg, [-3600.0, 3600.0]),
        ];
        let mut set = |list: &[(usize, Option<f32>, [f32; 2])]| {
            for &(c, value, [lo, hi]) in list {
                if let Some(v) = value {
                    check_range(
                        &format!("{at}.{}", CHANNELS[c]),
                        v as f64,
                        lo as f64,
                        hi as f64,
                    )?;
                    change.channels[c] = Some(v);
                }
            }
            Ok::<(), Error>(())
        };
        set(&numbers[..5])?;
        let colour = colour(at, self.color, (true, self.cmy), self.kelvin)?;
        set(&numbers[5..])?;
        if let Some(rgb) = colour {
            for c in 0..3 {
                change.channels[5 + c] = Some(rgb[c]);
            }
        }
        if let Some(slot) = self.gobo {
            let slots = limits.slots;
            if slot > slots {
                return Err(Error::out_of_range(
                    &format!("{at}.gobo"),
                    slot,
                    &format!("0 (open) to {slots} (the gobo_wheel's images)"),
                ));
            }
            change.gobo = Some(slot);
        }
        if let Some(prism_in) = self.prism_in {
            if !limits.prism {
                return Err(Error::Invalid(format!(
                    "{at}.prism_in: the fixture has no prism to put in or take out (give it \
                     `prism = {{ facets = 3, angle_deg = 9.0 }}`)"
                )));
            }
            change.prism_in = Some(prism_in);
        }
        Ok(change)
    }
}

/// The farthest off the axis a measured profile is drawn, degrees: the field of a
/// spotlight's square light map and shadow map must stay below 90 (`field_deg` below
/// 180); light a file gives beyond it is left out.
pub const MEASURED_REACH_DEG: f32 = 85.0;

/// A photometric file: IES LM-63, or EULUMDAT when `eulumdat`.
fn load_photometry(path: &Path, eulumdat: bool) -> Result<Photometry> {
    let what = if eulumdat {
        "EULUMDAT file"
    } else {
        "IES file"
    };
    let text = crate::files::read_text(path, what, crate::files::TEXT_LIMIT_BYTES)?;
    let origin = path.display().to_string();
    if eulumdat {
        Photometry::from_eulumdat(&text, &origin)
    } else {
        Photometry::from_ies(&text, &origin)
    }
}

/// The largest gobo image, pixels a side: four times a projector's finest gobo, and
/// 50 MB as texels.
pub const GOBO_MAX_SIDE: u32 = 4096;

/// A gobo from an image file (through the bounded reader).
fn load_gobo(path: &Path, sampling: Sampling) -> Result<Gobo> {
    let bytes = crate::files::read_bounded(path, "gobo image", crate::files::DATA_LIMIT_BYTES)?;
    gobo_from_image(&bytes, &path.display().to_string(), sampling)
}

/// A gobo from the bytes of an image file (PNG, or what the build's image features
/// read); `origin` names it in messages. The size is read from the header and checked
/// before anything is decoded: a small file can claim a huge image.
pub fn gobo_from_image(bytes: &[u8], origin: &str, sampling: Sampling) -> Result<Gobo> {
    use image::ImageDecoder as _;
    let bad = |e: image::ImageError| Error::Invalid(format!("gobo {origin}: {e}"));
    let decoder = image::ImageReader::new(std::io::Cursor::new(bytes))
        .with_guessed_format()
        .map_err(|e| Error::Invalid(format!("gobo {origin}: {e}")))?
        .into_decoder()
        .map_err(bad)?;
    let (width, height) = decoder.dimensions();
    if width.max(height) > GOBO_MAX_SIDE {
        return Err(Error::Invalid(format!(
            "gobo {origin}: {width} x {height} pixels is above the limit of {GOBO_MAX_SIDE} a \
             side; scale the image down"
        )));
    }
    // Decoding holds the image as the file stores it (up to 8 bytes a pixel), its
    // 8-bit RGB copy and the texels kept, 3 bytes a pixel each.
    crate::budget::check(
        &format!("gobo {origin} ({width} x {height})"),
        decoder.total_bytes() + 6 * width as u64 * height as u64,
        "the gobo image's size",
    )?;
    let image = image::DynamicImage::from_decoder(decoder)
        .map_err(bad)?
        .to_rgb8();
    Ok(Gobo::new(
        image.width() as usize,
        image.height() as usize,
        image.pixels().map(|p| p.0).collect(),
        sampling,
    ))
}

impl ObjectSpec {
    fn validate(&self, at: &str, folder: &Path) -> Result<Object> {
        let field = |name: &str| format!("{at}.{name}");
        let (shape, a) = match self {
            ObjectSpec::Plane {
                point,
                normal,
                albedo,
            } => (
                Shape::Plane {
                    point: vec3(&field("point"), *point)?,
                    normal: unit_vector(&field("normal"), *normal)?,
                },
                albedo,
            ),
            ObjectSpec::Rect {
                corner,
                edge_a,
                edge_b,
                albedo,
            } => {
                let (ea, eb) = (
                    vec3(&field("edge_a"), *edge_a)?,
                    vec3(&field("edge_b"), *edge_b)?,
                );
                if ea.cross(eb).length() < 1e-9 {
                    return Err(Error::Invalid(format!(
                        "{at}: edge_a and edge_b are zero or parallel: the rectangle has no area"
                    )));
                }
                (
                    Shape::Rect {
                        corner: vec3(&field("corner"), *corner)?,
                        edge_a: ea,
                        edge_b: eb,
                    },
                    albedo,
                )
            }
            ObjectSpec::Sphere {
                center,
                radius,
                albedo,
            } => {
                check_positive(&field("radius"), *radius as f64, 1e6)?;
                (
                    Shape::Sphere {
                        center: vec3(&field("center"), *center)?,
                        radius: *radius,
                    },
                    albedo,
                )
            }
            ObjectSpec::Box { min, max, albedo } => {
                let (min, max) = (vec3(&field("min"), *min)?, vec3(&field("max"), *max)?);
                if !min.cmplt(max).all() {
                    return Err(Error::out_of_range(
                        &field("max"),
                        format!("{max:?}"),
                        &format!("greater than {at}.min = {min:?} on every axis"),
                    ));
                }
                (Shape::Box(Aabb { min, max }), albedo)
            }
            ObjectSpec::Mesh {
                file,
                scale,
                rotate_y_deg,
                translate,
                albedo,
            } => {
                check_positive(&field("scale"), *scale as f64, 1e6)?;
                check_range(&field("rotate_y_deg"), *rotate_y_deg as f64, -360.0, 360.0)?;
                let translate = vec3(&field("translate"), *translate)?;
                let rotation = glam::Mat3::from_rotation_y(rotate_y_deg.to_radians());
                let mesh = load_obj(&folder.join(file), |p| rotation * (p * *scale) + translate)?;
                (Shape::Mesh(mesh), albedo)
            }
        };
        Ok(Object {
            shape,
            albedo: albedo(&field("albedo"), *a)?,
        })
    }
}

/// The triangles of an OBJ file (all its objects; polygons fanned into triangles;
/// materials ignored), each vertex mapped by `place`. Degenerate triangles are dropped;
/// a file without any triangle, with indices out of range or with non-finite
/// coordinates is an error, never a panic.
#[cfg(feature = "obj")]
pub fn load_obj(path: &Path, place: impl Fn(Vec3) -> Vec3) -> Result<Mesh> {
    let bytes = crate::files::read_bounded(path, "OBJ file", crate::files::DATA_LIMIT_BYTES)?;
    mesh_from_obj(&bytes, &path.display().to_string(), place)
}

/// [`load_obj`] from the bytes of an OBJ file; `origin` names it in messages.
#[cfg(feature = "obj")]
pub fn mesh_from_obj(bytes: &[u8], origin: &str, place: impl Fn(Vec3) -> Vec3) -> Result<Mesh> {
    let fail = |why: String| Error::Invalid(format!("OBJ file {origin}: {why}"));
    // The parsed lists, the triangles and their hierarchy hold a few times the text.
    crate::budget::check(
        &format!("the mesh of OBJ file {origin}"),
        4 * bytes.len() as u64,
        "the mesh's size",
    )?;
    let text = std::str::from_utf8(bytes).map_err(|e| fail(format!("not UTF-8 text ({e})")))?;
    check_obj_indices(text).map_err(fail)?;
    let options = tobj::LoadOptions {
        triangulate: true,
        ..Default::default()
    };
    let (models, _) = tobj::load_obj_buf(&mut std::io::Cursor::new(bytes), &options, |_| {
        Err(tobj::LoadError::OpenFileFailed)
    })
    .map_err(|e| fail(e.to_string()))?;
    let mut triangles = Vec::new();
    for model in &models {
        let (p, idx) = (&model.mesh.positions, &model.mesh.indices);
        let vertex = |i: u32| -> Result<Vec3> {
            let i = i as usize * 3;
            let v = p
                .get(i..i + 3)
                .ok_or_else(|| fail(format!("vertex index {} out of range", i / 3 + 1)))?;
            let v = place(Vec3::new(v[0], v[1], v[2]));
            if v.is_finite() {
                Ok(v)
            } else {
                Err(fail(format!(
                    "vertex {} is not finite where it is placed",
                    i / 3 + 1
                )))
            }
        };
        for t in idx.chunks_exact(3) {
            let [a, b, c] = [vertex(t[0])?, vertex(t[1])?, vertex(t[2])?];
            if (b - a).cross(c - a).length_squared() > 1e-20 {
                triangles.push([a, b, c]);
            }
        }
    }
    if triangles.is_empty() {
        return Err(fail("no triangles".into()));
    }
    Ok(Mesh::new(triangles))
}

/// Checks every index of the face and line elements (`f`, `l`) against the vertices,
/// texture coordinates and normals given before it, as OBJ counts them (from 1, or
/// back from the last with a minus sign): tobj turns an index out of range into an
/// arithmetic overflow (found by fuzzing: a panic in debug builds, a wrapped index in
/// release ones), so none reaches it. The message names the line.
#[cfg(feature = "obj")]
fn check_obj_indices(text: &str) -> std::result::Result<(), String> {
    let mut counts = [0i64; 3]; // positions, texture coordinates, normals
    for (k, line) in text.lines().enumerate() {
        let mut words = line.split_whitespace();
        match words.next() {
            Some("v") => counts[0] += 1,
            Some("vt") => counts[1] += 1,
            Some("vn") => counts[2] += 1,
            Some("f") | Some("l") => {
                for word in words {
                    for (kind, index) in word.split('/').enumerate().take(3) {
                        if index.is_empty() {
                            continue;
                        }
                        let n = counts[kind];
                        let ok = index
                            .parse::<i64>()
                            .is_ok_and(|i| (1..=n).contains(&i) || (-n..=-1).contains(&i));
                        if !ok {
                            let what = ["vertex", "texture coordinate", "normal"][kind];
                            return Err(format!(
                                "line {}: {what} index {index} is out of range: {n} given before it",
                                k + 1
                            ));
                        }
                    }
                }
            }
            _ => {}
        }
    }
    Ok(())
}

/// Without atmo's `obj` feature, OBJ meshes are refused with a message saying so.
#[cfg(not(feature = "obj"))]
pub fn load_obj(path: &Path, _place: impl Fn(Vec3) -> Vec3) -> Result<Mesh> {
    Err(Error::Invalid(format!(
        "OBJ file {}: meshes need atmo's `obj` feature, which this build leaves out",
        path.display()
    )))
}
