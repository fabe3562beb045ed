//! A scene built in Rust rather than read from a file: each method sets what a key of
//! the scene file sets, and [`SceneBuilder::build`] checks the values with the same
//! code as a file's, so a builder and a file of the same values give the same scene
//! and the same messages (naming the key, `spotlight[0].beam_deg`).
//!
//! ```
//! use atmo::shafts::{SamplePlanes, Scene, SpotlightBuilder};
//! use glam::Vec3;
//!
//! let scene = Scene::builder(Vec3::new(0.0, 1.5, 6.0), Vec3::new(0.0, 1.0, 0.0), 50.0, (48, 32))
//!     .haze(0.1, 0.9)
//!     .spotlight(SpotlightBuilder::new(Vec3::new(0.0, 4.0, 0.0), Vec3::ZERO)
//!         .intensity(1000.0)
//!         .beam(20.0, 30.0))
//!     .sphere(Vec3::new(0.0, 1.0, 0.0), 0.5, 0.6)
//!     .plane(Vec3::ZERO, Vec3::Y, 0.3)
//!     .build()?;
//! let frame = SamplePlanes::new(&scene).render(); // radiance in cd/m^2
//! assert!(frame.pixels.iter().any(|p| p.x > 0.0));
//! # Ok::<(), atmo::Error>(())
//! ```

use super::*;

/// A scene's values, set in Rust ([`Scene::builder`]).
pub struct SceneBuilder {
    spec: SceneSpec,
    folder: PathBuf,
}

/// A spotlight's values ([`SceneBuilder::spotlight`]): the keys of a `[[spotlight]]`.
pub struct SpotlightBuilder {
    spec: SpotlightSpec,
}

impl Scene {
    /// A scene seen from `position` looking at `look_at` (m, world frame: +y up) with a
    /// vertical field of view of `fov_deg`, `size` pixels; clear air, no lights, no
    /// objects until the builder adds them.
    pub fn builder(position: Vec3, look_at: Vec3, fov_deg: f32, size: (u32, u32)) -> SceneBuilder {
        SceneBuilder {
            spec: SceneSpec {
                camera: CameraSpec {
                    position: position.to_array(),
                    look_at: look_at.to_array(),
                    up: y_up(),
                    fov_deg,
                    fov_axis: FovAxis::default(),
                    width: size.0,
                    height: size.1,
                    supersampling: one(),
                    far_m: default_far(),
                },
                haze: HazeSpec {
                    extinction: 0.0,
                    albedo: one_f(),
                    phase: PhaseSpec::default(),
                    bounds: None,
                },
                render: RenderSpec::default(),
                display: DisplaySpec::default(),
                spotlight: Vec::new(),
                object: Vec::new(),
                fixture: Vec::new(),
                cue: Vec::new(),
                mvr: None,
            },
            folder: PathBuf::from("."),
        }
    }
}

impl SceneBuilder {
    /// Haze of `extinction` 1/m and single-scattering `albedo` (`haze.extinction`,
    /// `haze.albedo`), filling all space.
    pub fn haze(mut self, extinction: f32, albedo: f32) -> Self {
        self.spec.haze.extinction = extinction;
        self.spec.haze.albedo = albedo;
        self
    }

    /// Rays a pixel along each axis (`camera.supersampling`).
    pub fn supersampling(mut self, rays: u32) -> Self {
        self.spec.camera.supersampling = rays;
        self
    }

    /// Sample planes and sub-planes of the plane method (`render.planes`,
    /// `render.sub_planes`).
    pub fn planes(mut self, planes: u32, sub_planes: u32) -> Self {
        self.spec.render.planes = planes;
        self.spec.render.sub_planes = sub_planes;
        self
    }

    /// The exposure of 8-bit pictures (`display.exposure`).
    pub fn exposure(mut self, exposure: f32) -> Self {
        self.spec.display.exposure = exposure;
        self
    }

    /// Where relative paths (a spotlight's gobo) start; default the working folder.
    pub fn folder(mut self, folder: impl Into<PathBuf>) -> Self {
        self.folder = folder.into();
        self
    }

    /// A spotlight (`[[spotlight]]`).
    pub fn spotlight(mut self, light: SpotlightBuilder) -> Self {
        self.spec.spotlight.push(light.spec);
        self
    }

    /// An infinite plane through `point` facing `normal`, of grey `albedo`.
    pub fn plane(mut self, point: Vec3, normal: Vec3, albedo: f32) -> Self {
        self.spec.object.push(ObjectSpec::Plane {
            point: point.to_array(),
            normal: normal.to_array(),
            albedo: AlbedoSpec::Grey(albedo),
        });
        self
    }

    /// A sphere of `radius` m about `center`, of grey `albedo`.
    pub fn sphere(mut self, center: Vec3, radius: f32, albedo: f32) -> Self {
        self.spec.object.push(ObjectSpec::Sphere {
            center: center.to_array(),
            radius,
            albedo: AlbedoSpec::Grey(albedo),
        });
        self
    }

    /// An axis-aligned box from `min` to `max`, of grey `albedo`.
    pub fn cuboid(mut self, min: Vec3, max: Vec3, albedo: f32) -> Self {
        self.spec.object.push(ObjectSpec::Box {
            min: min.to_array(),
            max: max.to_array(),
            albedo: AlbedoSpec::Grey(albedo),
        });
        self
    }

    /// The scene, every value checked as a file's are (the message names its key).
    pub fn build(self) -> Result<Scene> {
        Scene::from_spec(self.spec, &self.folder)
    }
}

impl SpotlightBuilder {
    /// A lamp at `position` aimed at `aim` (m), 1,000 cd, beam 20 deg and field 30 deg,
    /// white.
    pub fn new(position: Vec3, aim: Vec3) -> SpotlightBuilder {
        SpotlightBuilder {
            spec: SpotlightSpec {
                position: position.to_array(),
                aim: Some(aim.to_array()),
                direction: None,
                up: None,
                color: None,
                kelvin: None,
                intensity: Some(1000.0),
                dimmer: one_f(),
                intensity_unit: candela(),
                beam_deg: Some(20.0),
                field_deg: Some(30.0),
                falloff: None,
                profile: None,
                gobo: None,
                gobo_sampling: SamplingSpec::default(),
            },
        }
    }

    /// Luminous intensity on the axis, cd (`intensity`).
    pub fn intensity(mut self, candela: f32) -> Self {
        self.spec.intensity = Some(candela);
        self
    }

    /// The beam and field angles, full, degrees (`beam_deg`, `field_deg`).
    pub fn beam(mut self, beam_deg: f32, field_deg: f32) -> Self {
        self.spec.beam_deg = Some(beam_deg);
        self.spec.field_deg = Some(field_deg);
        self
    }

    /// A linear RGB colour (`color`).
    pub fn color(mut self, rgb: Vec3) -> Self {
        self.spec.color = Some(rgb.to_array());
        self
    }

    /// A black body's colour, K (`kelvin`).
    pub fn kelvin(mut self, kelvin: f32) -> Self {
        self.spec.kelvin = Some(kelvin);
        self
    }

    /// The dimmer, 0 to 1 (`dimmer`).
    pub fn dimmer(mut self, dimmer: f32) -> Self {
        self.spec.dimmer = dimmer;
        self
    }

    /// A gobo image (`gobo`), relative to the scene's folder ([`SceneBuilder::folder`]).
    pub fn gobo(mut self, path: impl Into<PathBuf>) -> Self {
        self.spec.gobo = Some(path.into());
        self
    }
}
