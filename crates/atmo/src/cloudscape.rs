//! A cloud scene: the clouds method ([`crate::clouds`]) in the sky method's sky
//! ([`crate::sky`]), assembled once for every program that draws one (the CLI, the
//! window, a user's own). The methods do not import each other; this layer above them
//! knows both: the particles and how they are lit and drawn, the sunlight coloured by
//! the atmosphere down to the cloud, the sky's light on the droplets, the sky behind
//! the cloud, the air in front of it and the ground under its shadow.
//!
//! [`Cloudscape`] holds what the picture is made of; [`CpuClouds`] keeps what does not
//! change between frames on the CPU (the intensity buffer, updated in place, and the
//! particles' depths in the cloud); `atmo_gpu::cloudscape` chooses between it and the
//! GPU's twin and keeps the rest (the sun's shadow, the sky around the cloud).
//!
//! ```
//! use atmo::cloudscape::{Ambient, Cloudscape, CpuClouds};
//! use atmo::clouds::{Cumulus, Scattering, Splat};
//! use atmo::atmosphere::PhaseFunction;
//! use atmo::view::{Camera, Fov, Sun};
//! use glam::Vec3;
//!
//! let scene = Cloudscape {
//!     calm: Cumulus { particles: 300, ..Cumulus::default() }.generate(),
//!     resolution: 32,
//!     forward: 0.0,
//!     splat: Splat::Pieces,
//!     phase: PhaseFunction::CloudMie,
//!     scattering: Scattering::MULTIPLE,
//!     ambient: Ambient::Rgb(Vec3::splat(0.02)),
//!     sky: false,
//!     ground_albedo: None,
//! };
//! let particles = scene.blown(0.0);
//! let centre = Cloudscape::centre_of(&particles);
//! let camera = Camera::look_at(centre + Vec3::new(0.0, 0.0, 4000.0), centre, Vec3::Y,
//!                              Fov::Vertical(40.0), (48, 32))?;
//! let sun = Sun::from_degrees(30.0, 40.0)?;
//! let mut clouds = CpuClouds::new(scene.resolution);
//! clouds.light(&particles, sun.toward(), scene.forward, scene.splat)?;
//! let (light, behind) = scene.lighting(None, None, sun, &camera)?;
//! let frame = clouds.draw(&particles, &camera, &light, behind.as_ref())?;
//! assert!(frame.pixels[16 * 48 + 24].x > 0.0); // the cloud's middle is lit
//! # Ok::<(), atmo::Error>(())
//! ```

use std::cell::{Ref, RefCell};

use glam::Vec3;

use crate::atmosphere::PhaseFunction;
use crate::clouds::buffer::{IntensityBuffer, Splat};
use crate::clouds::render::{
    needs_depths, render_with_depths, solve_for, AerialHaze, CloudLight, Scattering,
};
use crate::clouds::shadow::{CloudShadow, Ground};
use crate::clouds::DiffuseLight;
use crate::clouds::{CloudDepths, Particle, SkyLight};
use crate::error::Result;
use crate::image::Frame;
use crate::sky::{Daylight, SkyModel, SkyPicture, SkySettings, View};
use crate::view::{Camera, Sun};
use crate::Atmosphere;

/// Where the light the droplets scatter from around them comes from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Ambient {
    /// A radiance from every direction alike, linear sRGB (none: zero).
    Rgb(Vec3),
    /// The sky's radiance all around the cloud (the ground's below); needs the sky.
    Sky,
}

/// What a cloud picture is made of, checked by whoever built it: the particles, how
/// the light pass fills the buffer, how the droplets scatter, and the light around.
#[derive(Debug, Clone)]
pub struct Cloudscape {
    /// The particles before any wind.
    pub calm: Vec<Particle>,
    /// Intensity buffer voxels along each axis.
    pub resolution: usize,
    /// The part of scattered light taken to go on along the light (the paper's
    /// p(l,l)/4pi), in [0, 1]; 0 with every order.
    pub forward: f32,
    /// How particles enter the buffer.
    pub splat: Splat,
    /// The droplets' phase function toward the eye.
    pub phase: PhaseFunction,
    /// Single scattering, or every order and by which model.
    pub scattering: Scattering,
    /// The light from around the cloud; [`Ambient::Sky`] needs [`Cloudscape::sky`].
    pub ambient: Ambient,
    /// The cloud in front of the sky (the Earth atmosphere at its default settings),
    /// lit by sunlight coloured by the atmosphere and hazed by the air in front.
    pub sky: bool,
    /// The ground's reflectance under the cloud: with the sky, its ground's albedo
    /// (the atmosphere's where `None`); without, a painted ground where given.
    pub ground_albedo: Option<f32>,
}

impl Cloudscape {
    /// The particles carried `seconds` by a sheared breeze: 6 m/s at the cloud's base
    /// and 1 m/s faster for each 100 m up, toward +x and a little +z (east, a little
    /// south). The wind's picture at any time, the same whether reached at once or
    /// frame by frame.
    pub fn blown(&self, seconds: f32) -> Vec<Particle> {
        let base = self
            .calm
            .iter()
            .map(|p| p.position.y)
            .fold(f32::INFINITY, f32::min);
        self.calm
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

    /// The particles' mean position, m.
    pub fn centre_of(particles: &[Particle]) -> Vec3 {
        particles.iter().map(|p| p.position).sum::<Vec3>() / particles.len() as f32
    }

    /// The sky around `particles` seen from `camera`, where the picture has one.
    pub fn sky_around(&self, particles: &[Particle], camera: &Camera) -> Result<Option<SkyAround>> {
        self.sky
            .then(|| SkyAround::new(particles, camera, self.ground_albedo))
            .transpose()
    }

    /// Whether the picture shows the ground (with the sky, or a painted ground), and so
    /// the cloud's shadow on it.
    pub fn shows_ground(&self) -> bool {
        self.sky || self.ground_albedo.is_some()
    }

    /// The cloud's shadow for `sun` on a map of `resolution` texels a side, where the
    /// picture shows the ground: made with each light pass.
    pub fn shadow(
        &self,
        particles: &[Particle],
        sun: Sun,
        resolution: usize,
    ) -> Result<Option<CloudShadow>> {
        self.shows_ground()
            .then(|| CloudShadow::new(particles, sun.toward(), resolution))
            .transpose()
    }

    /// Sunlight and sky light at the cloud for `sun`, and what `camera` sees behind it:
    /// the sky and the ground (where the picture has them), the ground under the
    /// cloud's `shadow`.
    pub fn lighting(
        &self,
        sky: Option<&SkyAround>,
        shadow: Option<&CloudShadow>,
        sun: Sun,
        camera: &Camera,
    ) -> Result<(CloudLight, Option<Frame>)> {
        let (sunlight, ambient, haze, mut background) = match (sky, self.ambient) {
            (None, Ambient::Rgb(rgb)) => {
                (Vec3::ONE, SkyLight::uniform(rgb), AerialHaze::CLEAR, None)
            }
            (None, Ambient::Sky) => {
                return Err(crate::Error::Invalid(
                    "the sky's light on the cloud (ambient = sky) needs the sky".into(),
                ))
            }
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
        let light = CloudLight {
            to_sun: sun.toward(),
            sun: sunlight,
            ambient,
            phase: self.phase,
            haze,
            scattering: self.scattering,
        };
        Ok((light, background))
    }
}

/// The sky around a cloud (Earth atmosphere, default settings): its light at the
/// cloud's mean height, and the sky behind it and the air in front of it from the
/// camera's height.
pub struct SkyAround {
    at_cloud: Daylight,
    at_camera: SkyModel,
    /// The cloud's centre, m, world frame.
    centre: Vec3,
}

impl SkyAround {
    /// The sky around `particles` seen from `camera`, over a ground of `ground_albedo`
    /// (the Earth atmosphere's where not given).
    pub fn new(
        particles: &[Particle],
        camera: &Camera,
        ground_albedo: Option<f32>,
    ) -> Result<SkyAround> {
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
            centre: Cloudscape::centre_of(particles),
        })
    }

    /// The cloud's particles moved (the wind): the air in front is measured to their
    /// new centre; the light at their height is kept.
    pub fn moved(&mut self, particles: &[Particle]) {
        self.centre = Cloudscape::centre_of(particles);
    }

    /// The world frame's height `y` m as an altitude the sky module takes: inside
    /// `atmosphere`.
    fn altitude(atmosphere: &Atmosphere, y: f64) -> f64 {
        y.clamp(
            0.0,
            atmosphere.top_radius_m - atmosphere.bottom_radius_m - 1.0,
        )
    }

    /// For `sun`: the sun's irradiance at the cloud (RGB, through the atmosphere), the
    /// sky's radiance all around it (its ambient light), the air in front of the cloud,
    /// and the sky behind it as `camera` sees it.
    fn at(&self, sun: Sun, camera: &Camera) -> Result<(Vec3, SkyLight, AerialHaze, Frame)> {
        let view = View {
            camera: camera.clone(),
            sun_disc: true,
        };
        let background = SkyPicture::new(&self.at_camera, sun).render(&view);
        Ok((
            self.at_cloud.sunlight(sun),
            SkyLight::from_map(&self.at_cloud.skylight_map(sun)),
            haze_before(&self.at_camera, sun, self.centre - camera.position)?,
            background,
        ))
    }
}

/// The air in front of a cloud `to_cloud` (m, world frame) from the eye of `model` for
/// `sun`: the aerial perspective at that distance and direction (every order the model
/// carries), linear sRGB.
pub fn haze_before(model: &SkyModel, sun: Sun, to_cloud: Vec3) -> Result<AerialHaze> {
    let distance = to_cloud.length() as f64;
    let light = model.aerial_along(sun, to_cloud, &[distance])?;
    let (transmittance, inscatter) = light[0].rgb(model.atmosphere());
    Ok(AerialHaze {
        transmittance,
        inscatter,
    })
}

/// The clouds on the CPU: the intensity buffer (none before the first light pass;
/// updated in place after it) and the particles' depths in the cloud, kept while the
/// particles stay (the sky's light inside the cloud and the transfer table read them).
pub struct CpuClouds {
    buffer: Option<IntensityBuffer>,
    resolution: usize,
    depths: KeptDepths,
    /// Light passes made, and the transfer solve for the last one (with the light it
    /// was made for), made when a picture first needs it and kept to start the next.
    passes: usize,
    solved: RefCell<Option<KeptSolve>>,
}

/// A transfer solve and what it was made for: the light pass it read and the light.
struct KeptSolve {
    pass: usize,
    light: CloudLight,
    diffuse: DiffuseLight,
}

impl CpuClouds {
    /// Clouds to be lit through a buffer of `resolution` voxels a side.
    pub fn new(resolution: usize) -> CpuClouds {
        CpuClouds {
            buffer: None,
            resolution,
            depths: KeptDepths::default(),
            passes: 0,
            solved: RefCell::new(None),
        }
    }

    /// The intensity buffer, once lit.
    pub fn buffer(&self) -> Option<&IntensityBuffer> {
        self.buffer.as_ref()
    }

    /// The buffer of `particles` (which may have moved) lit from `to_sun`.
    pub fn light(
        &mut self,
        particles: &[Particle],
        to_sun: Vec3,
        forward: f32,
        splat: Splat,
    ) -> Result<()> {
        self.passes += 1;
        match &mut self.buffer {
            Some(buffer) => buffer.update(particles, to_sun, forward, splat),
            None => {
                self.buffer = Some(IntensityBuffer::new(
                    particles,
                    to_sun,
                    self.resolution,
                    forward,
                    splat,
                )?);
                Ok(())
            }
        }
    }

    /// The picture of `particles` through `camera` lit by `light` over `background`;
    /// an error before the first light pass.
    pub fn draw(
        &self,
        particles: &[Particle],
        camera: &Camera,
        light: &CloudLight,
        background: Option<&Frame>,
    ) -> Result<Frame> {
        let buffer = self.buffer.as_ref().ok_or_else(|| {
            crate::Error::Invalid("the clouds were drawn before their light pass".into())
        })?;
        let none = CloudDepths::default();
        let depths = needs_depths(light)
            .then(|| self.depths.of(particles))
            .transpose()?;
        let depths = depths.as_deref().unwrap_or(&none);
        let diffuse = self.solve(particles, buffer, light)?;
        let diffuse = diffuse.as_ref().map(|kept| &kept.diffuse);
        render_with_depths(
            particles, depths, buffer, diffuse, camera, light, background,
        )
    }

    /// The transfer solve `light` draws with (none if it draws with none), made again
    /// only after a light pass or for another sun or phase, from the last one.
    fn solve(
        &self,
        particles: &[Particle],
        buffer: &IntensityBuffer,
        light: &CloudLight,
    ) -> Result<Option<Ref<'_, KeptSolve>>> {
        if light.scattering.diffusion().is_none() {
            return Ok(None);
        }
        let fresh = |kept: &KeptSolve| {
            kept.pass == self.passes
                && kept.light.to_sun == light.to_sun
                && kept.light.phase == light.phase
                && kept.light.scattering == light.scattering
        };
        if !self.solved.borrow().as_ref().is_some_and(fresh) {
            let previous = self.solved.borrow_mut().take();
            let diffuse = solve_for(
                particles,
                buffer,
                light,
                previous.as_ref().map(|k| &k.diffuse),
            )?
            .expect("a solve was asked for");
            *self.solved.borrow_mut() = Some(KeptSolve {
                pass: self.passes,
                light: *light,
                diffuse,
            });
        }
        Ok(Some(Ref::map(self.solved.borrow(), |kept| {
            kept.as_ref().expect("made above")
        })))
    }

    /// How many times the particles' depths were made: once for each new set of
    /// particles a picture that needs them was drawn of.
    pub fn depths_made(&self) -> usize {
        self.depths.made.get()
    }
}

/// The particles' depths in the cloud ([`CloudDepths`]) and the particles they were
/// made for: they depend on the particles alone, so frames of the same particles under a
/// moving sun or camera make them once.
#[derive(Default)]
struct KeptDepths {
    kept: RefCell<Option<(Vec<Particle>, CloudDepths)>>,
    /// Times they were made.
    made: std::cell::Cell<usize>,
}

impl KeptDepths {
    /// The depths of `particles`, made again only where they are not those last given.
    fn of(&self, particles: &[Particle]) -> Result<Ref<'_, CloudDepths>> {
        let stale = self
            .kept
            .borrow()
            .as_ref()
            .is_none_or(|(kept, _)| kept != particles);
        if stale {
            *self.kept.borrow_mut() = Some((particles.to_vec(), CloudDepths::of(particles)?));
            self.made.set(self.made.get() + 1);
        }
        Ok(Ref::map(self.kept.borrow(), |kept| {
            &kept.as_ref().expect("made above").1
        }))
    }
}
