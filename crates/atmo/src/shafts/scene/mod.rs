//! The scene file: camera, haze, spotlights and objects in physical units (TOML, see
//! docs/shafts.md for every key and convention). Parsed with `deny_unknown_fields` so a
//! misspelt key is an error with its line and column, validated once here into the
//! types the renderers use, with messages naming the field and its allowed range.

use std::path::{Path, PathBuf};

use glam::Vec3;
use serde::Deserialize;

use super::dmx;
use super::gdtf;
use super::haze::Haze;
use super::objects::{Object, Objects};
use super::photometry::Photometry;
use super::shadow_map::ShadowMap;
use super::show::{profile_solid_angle, Change, Cue, Fixture, Prism, Show, State, CHANNELS};
use super::spotlight::{light_frame, Falloff, Gobo, Profile, Sampling, Spotlight};
use super::PlaneSettings;
use crate::atmosphere::phase::PhaseFunction;
use crate::atmosphere::spectrum::blackbody_srgb;
use crate::error::{check_positive, check_range, from_toml, Error, Result};
use crate::geometry::{Aabb, Mesh, Shape};
use crate::image::{Display, ToneMap};
use crate::view::{Camera, Fov};

mod assets;
mod build;
mod builder;
#[cfg(feature = "gdtf")]
mod mvr;
mod spec;

#[cfg(feature = "obj")]
pub use assets::mesh_from_obj;
use assets::*;
pub use assets::{
    gobo_from_image, load_gobo, load_obj, load_photometry, GOBO_MAX_SIDE, MEASURED_REACH_DEG,
};
use build::*;
pub use builder::{SceneBuilder, SpotlightBuilder};
use spec::*;

/// A validated scene: everything a renderer needs.
#[derive(Debug, Clone)]
pub struct Scene {
    /// The camera: a pinhole, as scene files make it (the sample planes are parallel to
    /// its screen, shafts 4.2).
    pub camera: Camera,
    /// The haze.
    pub haze: Haze,
    /// The fixed spotlights; the moving heads are the [`Scene::show`]'s, and
    /// [`Scene::lights`] gives both.
    pub spotlights: Vec<Spotlight>,
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
    /// What the scene's gobos, photometric files, GDTF fixtures and meshes hold, bytes:
    /// counted beside the shadow maps and the picture in [`Scene::validate_planes`].
    pub files_bytes: u64,
    /// The moving heads and their cues, posed at one time of the show
    /// ([`Scene::at_time`]; its start as loaded).
    pub show: Show,
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

impl Scene {
    /// Loads and validates the scene file at `path`; gobo and OBJ paths in it are
    /// relative to its folder.
    pub fn from_file(path: &Path) -> Result<Scene> {
        Scene::from_text_at(&Scene::read_text(path)?, path)
    }

    /// The text of the scene file at `path` (through the bounded reader); for an MVR
    /// file (`.mvr`), the scene atmo makes around its rig ([`mvr_scene_text`]).
    pub fn read_text(path: &Path) -> Result<String> {
        let is_mvr = path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("mvr"));
        if is_mvr {
            return mvr_scene_text(path);
        }
        crate::files::read_toml(path, "scene file")
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
        Scene::from_spec(from_toml(text, origin)?, folder)
    }

    /// The scene a file's values describe, checked (each message names the key), its
    /// relative paths from `folder`: what a file and a [`SceneBuilder`] both become.
    fn from_spec(mut spec: SceneSpec, folder: &Path) -> Result<Scene> {
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
        let assets = Assets::new(folder);
        let mut spotlights: Vec<Spotlight> = Vec::with_capacity(spec.spotlight.len());
        for (i, l) in spec.spotlight.iter().enumerate() {
            let light = l.validate(&format!("spotlight[{i}]"), unit, &assets)?;
            spotlights.push(share_profile(&spotlights, light));
        }
        let mut list = spec
            .object
            .iter()
            .enumerate()
            .map(|(i, o)| o.validate(&format!("object[{i}]"), &assets))
            .collect::<Result<Vec<_>>>()?;
        // The rig's fixtures after the file's own (their GDTF files inside the MVR's
        // path, which is among the scene's files instead).
        let mvr_file = spec.mvr.as_ref().map(|m| m.file.clone());
        if let Some(m) = &spec.mvr {
            let rig = load_mvr(m, &assets, &spec.fixture)?;
            spec.fixture.extend(rig.fixtures);
            list.extend(rig.objects);
        }
        let show = show(&spec, unit, &assets)?;
        let wheels = spec
            .fixture
            .iter()
            .flat_map(|f| f.gobo_wheel.iter().flatten().chain(f.gdtf.iter()))
            .filter(|f| mvr_file.as_ref().is_none_or(|m| !f.starts_with(m)))
            .chain(mvr_file.as_ref());
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
        let mut scene = Scene {
            camera,
            haze,
            spotlights,
            objects: Objects { list },
            planes,
            display,
            unit,
            files: gobos
                .chain(wheels)
                .chain(meshes)
                .map(|f| folder.join(f))
                .collect(),
            files_bytes: assets.held(),
            show,
        };
        scene.pose_bodies(false);
        scene.validate_planes()?;
        Ok(scene)
    }

    /// Every light of the scene now: the fixed spotlights, then the show's heads as
    /// posed. A light's index in this order names it to the renderers (its shadow map,
    /// its sample planes).
    pub fn lights(&self) -> impl ExactSizeIterator<Item = &Spotlight> + Clone {
        Lights {
            fixed: self.spotlights.iter(),
            heads: self.show.lights().iter(),
        }
    }

    /// How many lights [`Scene::lights`] gives.
    pub fn light_count(&self) -> usize {
        self.spotlights.len() + self.show.lights().len()
    }

    /// The scene at `time_s` seconds into its show: its moving heads posed as its cues
    /// have them then (the fixed spotlights do not change).
    pub fn at_time(&mut self, time_s: f32) {
        self.show.at_time(time_s);
        self.pose_bodies(true);
    }

    /// The heads in `states` (one per fixture, with its gobo's turn, degrees), as a
    /// desk drives them ([`Show::drive`]), at `time_s`, their bodies with them.
    pub fn drive(&mut self, time_s: f32, states: &[(State, f32)]) {
        self.show.drive(time_s, states);
        self.pose_bodies(true);
    }

    /// The fixtures' bodies put where the show has the heads now: the last objects,
    /// one a fixture that shows its body, after the scene's own (`replace`: those of
    /// the last pose are there to be replaced; false only as the scene is made).
    fn pose_bodies(&mut self, replace: bool) {
        if replace {
            let n = self.show.fixtures.iter().filter(|f| f.body).count();
            let keep = self.objects.list.len().saturating_sub(n);
            self.objects.list.truncate(keep);
        }
        self.objects.list.extend(self.show.bodies());
    }

    /// The farthest camera depth drawn, m: the camera's far plane, or, where it has none
    /// (`Camera::look_at` makes an infinite one; a scene file always gives `far_m`), as
    /// far as the haze can send light to the eye ([`Haze::reach`]). The sample planes
    /// need a finite one: rays that meet nothing end there.
    pub fn far_m(&self) -> f32 {
        if self.camera.far.is_finite() {
            self.camera.far
        } else {
            self.haze.reach(self.camera.position)
        }
    }

    /// Checks the plane settings, and that the shadow maps they make for these lights
    /// fit the run's memory budget ([`crate::budget`]); again after a caller changes
    /// them.
    pub fn validate_planes(&self) -> Result<()> {
        self.planes.validate()?;
        self.beside_files(|| self.check_buffers())
    }

    /// Runs `work` with what the scene's files hold counted in its budget checks
    /// ([`crate::budget::beside`]): the checks of buffers made for the scene.
    pub fn beside_files<T>(&self, work: impl FnOnce() -> T) -> T {
        crate::budget::beside(self.files_bytes, assets::FILES, work)
    }

    /// The budget checks of [`Scene::validate_planes`].
    fn check_buffers(&self) -> Result<()> {
        // Each light's shadow map, on the CPU or on the GPU, at the time of the show
        // with the most (every prism in).
        let most = self.spotlights.len() + self.show.most_lights();
        let maps = most as u64 * ShadowMap::bytes(self.planes.shadow_map as usize);
        crate::budget::check(
            &format!("{most} shadow maps of {}^2", self.planes.shadow_map),
            maps,
            "render.shadow_map (--shadow-map) or the number of spotlights",
        )?;
        // And the picture's buffers beside them (a frame was charged 12 bytes a pixel,
        // a third of what the plane method holds).
        let (width, height) = (self.camera.width, self.camera.height);
        crate::budget::check(
            &format!("{most} shadow maps and a {width} x {height} picture's buffers"),
            maps + width as u64 * height as u64 * PLANES_BYTES_PER_PIXEL,
            "camera.width and camera.height",
        )
    }
}

/// What the plane method holds a pixel of its picture, bytes: the frame, the
/// scattered light and the grid it is interpolated over, the surfaces seen. Measured
/// from outside at 34 (peak resident size over 2.8 M more pixels of
/// spotlight-sphere.toml, adaptive); charged at 40.
pub const PLANES_BYTES_PER_PIXEL: u64 = 40;

/// `light` holding the profile of the first of `before` with an equal one, and its
/// intensity map where the two are equal: a file is read once ([`Assets`]), but each
/// light tabulates its map again (200 lights sharing an IES file held 200 copies of
/// it, 120 MB), and two files may hold the same profile. Done as each light is built,
/// so only one copy is ever extra.
fn share_profile(before: &[Spotlight], mut light: Spotlight) -> Spotlight {
    let Profile::Measured(photometry) = &light.profile else {
        return light;
    };
    let same = before
        .iter()
        .find(|b| matches!(&b.profile, Profile::Measured(p) if p == photometry));
    if let Some(first) = same {
        light.profile = first.profile.clone();
        if first.intensity_map == light.intensity_map {
            light.intensity_map = first.intensity_map.clone();
        }
    }
    light
}

/// [`Scene::lights`]: the fixed spotlights then the heads, with a known length (a
/// `Chain` of two slices has none).
#[derive(Clone)]
struct Lights<'a> {
    fixed: std::slice::Iter<'a, Spotlight>,
    heads: std::slice::Iter<'a, Spotlight>,
}

impl<'a> Iterator for Lights<'a> {
    type Item = &'a Spotlight;

    fn next(&mut self) -> Option<&'a Spotlight> {
        self.fixed.next().or_else(|| self.heads.next())
    }

    fn size_hint(&self) -> (usize, Option<usize>) {
        let n = self.fixed.len() + self.heads.len();
        (n, Some(n))
    }
}

impl ExactSizeIterator for Lights<'_> {}

/// The rig of `[mvr]`, its fixtures named apart from the file's `fixtures`.
#[cfg(feature = "gdtf")]
fn load_mvr(m: &MvrSpec, assets: &Assets, fixtures: &[FixtureSpec]) -> Result<mvr::Rig> {
    let taken: Vec<String> = fixtures.iter().map(|f| f.name.clone()).collect();
    m.load(assets, &taken)
}

/// Without atmo's `gdtf` feature, `[mvr]` is refused with a message saying so.
#[cfg(not(feature = "gdtf"))]
fn load_mvr(m: &MvrSpec, _: &Assets, _: &[FixtureSpec]) -> Result<MvrRig> {
    Err(Error::Invalid(format!(
        "mvr.file {}: MVR rigs need atmo's `gdtf` feature, which this build leaves out",
        m.file.display()
    )))
}

/// What a rig adds, where MVR files cannot be read.
#[cfg(not(feature = "gdtf"))]
struct MvrRig {
    fixtures: Vec<FixtureSpec>,
    objects: Vec<Object>,
}

/// The scene atmo makes around the MVR file at `path` when it is given as the scene:
/// the camera in front of the rig (MVR's -y, atmo's +z) looking at it, haze filling its
/// bounds and a metre more, a floor under it, its fixtures lit where atmo can light them
/// and drawn dark where it cannot (`keep_dark`; a scene file's `[mvr]` can `replace`
/// their GDTF files instead, docs/previz.md).
#[cfg(feature = "gdtf")]
pub fn mvr_scene_text(path: &Path) -> Result<String> {
    let origin = path.display().to_string();
    let bytes = crate::files::read_bounded(path, "MVR file", crate::files::DATA_LIMIT_BYTES)?;
    let rig = crate::shafts::mvr::read(&bytes, &origin)?;
    let points = rig
        .triangles
        .iter()
        .flatten()
        .copied()
        .chain(rig.fixtures.iter().map(|f| f.origin));
    let (mut lo, mut hi) = points.fold(
        (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
        |(lo, hi), p| (lo.min(p), hi.max(p)),
    );
    if lo.x > hi.x {
        (lo, hi) = (Vec3::new(-5.0, 0.0, -5.0), Vec3::new(5.0, 6.0, 5.0));
    }
    lo.y = lo.y.min(0.0);
    let size = (hi - lo).max(Vec3::splat(1.0));
    let look_at = Vec3::new(
        0.5 * (lo.x + hi.x),
        lo.y + 0.35 * size.y,
        0.5 * (lo.z + hi.z),
    );
    let position = look_at + Vec3::new(0.0, 0.15 * size.y, 0.5 * size.z + 1.1 * size.x.max(size.y));
    let (box_lo, box_hi) = (lo - Vec3::new(1.0, 0.0, 1.0), hi + Vec3::ONE);
    let name = path
        .file_name()
        .map(|n| {
            n.to_string_lossy()
                .replace('\\', "\\\\")
                .replace('"', "\\\"")
        })
        .unwrap_or_default();
    let v = |p: Vec3| format!("[{:.3}, {:.3}, {:.3}]", p.x, p.y, p.z);
    Ok(format!(
        "# The scene atmo makes around {name}: its {fixtures} fixtures and its truss and \
         scenery,\n# seen from the front; copy it to a file to change the camera or the haze.\n\
         [camera]\nposition = {position}\nlook_at = {look_at}\nfov_deg = 50.0\nwidth = 1280\n\
         height = 720\nfar_m = {far:.1}\n\n[haze]\nextinction = 0.03\nalbedo = 0.9\n\
         phase = {{ kind = \"paper\", exponent = 16 }}\nbox = {{ min = {box_lo}, max = {box_hi} }}\n\n\
         [display]\nexposure = 0.05\n\n[render]\nshadow_map = 256\n\n\
         [mvr]\nfile = \"{name}\"\nkeep_dark = true\n\n\
         [[object]]\nkind = \"plane\"\npoint = [0.0, {floor:.3}, 0.0]\nnormal = [0.0, 1.0, 0.0]\nalbedo = 0.3\n",
        fixtures = rig.fixtures.len(),
        position = v(position),
        look_at = v(look_at),
        far = 4.0 * size.max_element() + (position - look_at).length(),
        box_lo = v(box_lo),
        box_hi = v(box_hi),
        floor = lo.y,
    ))
}

/// Without atmo's `gdtf` feature, an MVR file as the scene is refused with a message
/// saying so.
#[cfg(not(feature = "gdtf"))]
pub fn mvr_scene_text(path: &Path) -> Result<String> {
    Err(Error::Invalid(format!(
        "{}: MVR rigs need atmo's `gdtf` feature, which this build leaves out",
        path.display()
    )))
}
