//! Clouds as entities ([`AtmoClouds`]): atmo's particle clouds (clouds 2.1), placed by
//! the entity's transform, lit by the [`crate::AtmoSun`] through the sky camera's
//! atmosphere: the sunlight and the sky's light at the cloud's height from a sky model
//! built there on a background thread (sky 3), again when the cloud has moved 500 m up
//! or down or the sky's atmosphere changed.

use std::path::Path;
use std::sync::Arc;

use atmo::atmosphere::PhaseFunction;
use atmo::clouds::{Cumulus, Particle, Scattering, SkyLight};
use atmo::cloudscape::Cloudscape;
use atmo::sky::{Daylight, SkySettings};
use atmo::view::Sun;
use atmo::Atmosphere;
use bevy::prelude::*;
use bevy::render::sync_world::SyncToRenderWorld;
use bevy::tasks::{futures::check_ready, AsyncComputeTaskPool, Task};

use crate::sky::{same_atmosphere, AtmoSky, SkySource};
use crate::sun::{first_sky_camera, SunNow};

/// How far a cloud moves up or down before the light at its height is made again, m.
const RELIGHT_AFTER_M: f64 = 500.0;

/// A cloud of particles in the sky of every [`AtmoSky`] camera: put it on an entity
/// whose transform places it (translation and rotation; the scale is not applied).
///
/// Drawn after the opaque meshes with their depth: a mesh in front hides the cloud, a
/// mesh inside it fades into it. The light scattered more than once is atmo's transfer
/// solve by default (`atmo clouds`' default: the nearest its path tracer).
///
/// Reflected (an inspector edits its resolution) but for the particles, the scattering
/// and the phase function, atmo's own types.
#[derive(Component, Clone, Debug, Reflect)]
#[reflect(Component, Clone, Debug)]
#[require(Transform, SyncToRenderWorld)]
pub struct AtmoClouds {
    /// The particles, in the entity's frame (m).
    #[reflect(ignore, default = "no_particles")]
    pub particles: Arc<[Particle]>,
    /// Intensity buffer voxels along each axis (clouds 3.3): 128 by default; the paper
    /// draws its largest cloud through 256.
    pub resolution: usize,
    /// Single scattering, or every order and by which model.
    #[reflect(ignore, default = "every_order")]
    pub scattering: Scattering,
    /// The droplets' phase function toward the eye.
    #[reflect(ignore, default = "cloud_mie")]
    pub phase: PhaseFunction,
}

/// No particles, for a reflected [`AtmoClouds`] made without them.
fn no_particles() -> Arc<[Particle]> {
    Arc::new([])
}

/// Every order by the transfer solve, `atmo clouds`' default.
fn every_order() -> Scattering {
    Scattering::SOLVE
}

/// The droplets' Mie phase function.
fn cloud_mie() -> PhaseFunction {
    PhaseFunction::CloudMie
}

impl AtmoClouds {
    /// atmo's generated cumulus of `particles` particles (the paper's largest has
    /// 60,134; 1.2 km wide), its flat base's centre at the entity's origin.
    pub fn cumulus(particles: usize) -> Self {
        AtmoClouds::from_particles(
            Cumulus {
                particles,
                base: 0.0,
                ..Cumulus::default()
            }
            .generate(),
        )
    }

    /// A particle file (`atmo clouds --particles`: CSV or atmo's binary), its particles
    /// where the file puts them relative to the entity; errors name the file.
    pub fn from_file(path: &Path) -> atmo::Result<Self> {
        let albedo = Cumulus::default().albedo;
        Ok(AtmoClouds::from_particles(atmo::clouds::files::read(
            path, albedo,
        )?))
    }

    /// `particles` drawn with atmo's defaults.
    pub fn from_particles(particles: Vec<Particle>) -> Self {
        AtmoClouds {
            particles: particles.into(),
            resolution: 128,
            scattering: every_order(),
            phase: cloud_mie(),
        }
    }
}

/// The sky model the light at a cloud comes from: the atmosphere and settings of the
/// sky camera, at the cloud's altitude.
#[derive(Clone)]
struct Recipe {
    atmosphere: Arc<Atmosphere>,
    settings: SkySettings,
    altitude_m: f64,
}

impl Recipe {
    /// Whether a model made from `self` serves `other`: the same sky, near enough.
    fn serves(&self, other: &Recipe) -> bool {
        same_atmosphere(&self.atmosphere, &other.atmosphere)
            && self.settings == other.settings
            && (self.altitude_m - other.altitude_m).abs() <= RELIGHT_AFTER_M
    }
}

/// The sun's light at a cloud: the sun it is for, its irradiance (linear sRGB,
/// W m^-2) and the sky's radiance all around.
#[derive(Clone, Copy, Debug)]
pub(crate) struct CloudSun {
    pub sun: Sun,
    pub sunlight: Vec3,
    pub skylight: SkyLight,
}

/// A cloud in the making (the plugin adds it beside [`AtmoClouds`]): its particles in
/// the world, and the light at its height.
#[derive(Component, Default)]
pub struct AtmoCloudsState {
    /// The particles in the world frame, their mean position (m), and a count that
    /// changes when they do.
    pub(crate) particles: Option<Arc<[Particle]>>,
    pub(crate) centre: Vec3,
    pub(crate) generation: u64,
    daylight: Option<(Arc<Daylight>, Recipe)>,
    building: Option<(Task<atmo::Result<Daylight>>, Recipe)>,
    /// The last build failed (its error logged): none is tried until the sky changes.
    failed: Option<Recipe>,
    pub(crate) lit: Option<CloudSun>,
}

impl AtmoCloudsState {
    /// Whether the cloud is lit and can be drawn (false until the light at its height
    /// is first made: seconds).
    pub fn is_ready(&self) -> bool {
        self.particles.is_some() && self.lit.is_some()
    }

    /// Whether the light at the cloud's height is being made.
    pub fn is_building(&self) -> bool {
        self.building.is_some()
    }
}

/// A cloud, as its systems see it.
type CloudParts<'a> = (
    Entity,
    Ref<'a, AtmoClouds>,
    Ref<'a, GlobalTransform>,
    Option<&'a mut AtmoCloudsState>,
);

/// Places each cloud's particles in the world, starts the light at its height where
/// none serves it, takes the lights that are done, and lights it by this frame's sun.
pub(crate) fn light_the_clouds(
    mut commands: Commands,
    mut clouds: Query<CloudParts>,
    cameras: Query<(&AtmoSky, &GlobalTransform, &Camera)>,
    sun: Res<SunNow>,
) {
    let sky = first_sky_camera(&cameras).map(|(sky, _)| sky);
    for (entity, cloud, transform, state) in &mut clouds {
        let Some(mut state) = state else {
            commands.entity(entity).insert(AtmoCloudsState::default());
            continue;
        };
        if cloud.particles.is_empty() {
            warn_once!("bevy_atmo: an AtmoClouds without particles draws nothing");
            continue;
        }
        if state.particles.is_none() || cloud.is_changed() || transform.is_changed() {
            let (_, rotation, translation) = transform.to_scale_rotation_translation();
            let placed: Arc<[Particle]> = cloud
                .particles
                .iter()
                .map(|p| Particle {
                    position: translation + rotation * p.position,
                    ..*p
                })
                .collect();
            state.centre = Cloudscape::centre_of(&placed);
            state.particles = Some(placed);
            state.generation += 1;
        }
        let Some(sky) = sky else { continue };
        let wanted = Recipe {
            atmosphere: sky.atmosphere.clone(),
            settings: match &sky.source {
                SkySource::Model { settings, .. } => settings.clone(),
                SkySource::Table(_) => SkySettings::default(),
            },
            altitude_m: sky.altitude_m(state.centre.y),
        };
        if let Some(done) = state
            .building
            .as_mut()
            .and_then(|(task, _)| check_ready(task))
        {
            let (_, recipe) = state.building.take().expect("checked above");
            match done {
                Ok(daylight) => {
                    state.daylight = Some((Arc::new(daylight), recipe));
                    state.lit = None;
                }
                Err(e) => {
                    error!("atmo's light at a cloud: {e}");
                    state.failed = Some(recipe);
                }
            }
        }
        let served = |recipe: Option<&Recipe>| recipe.is_some_and(|r| r.serves(&wanted));
        let under_way = served(state.building.as_ref().map(|(_, r)| r));
        if !served(state.daylight.as_ref().map(|(_, r)| r))
            && !under_way
            && !served(state.failed.as_ref())
        {
            let recipe = wanted.clone();
            let task = AsyncComputeTaskPool::get().spawn(async move {
                Daylight::new(&recipe.atmosphere, &recipe.settings, recipe.altitude_m)
            });
            state.building = Some((task, wanted));
        }
        let (Some((daylight, _)), Some(sun)) = (&state.daylight, sun.0) else {
            continue;
        };
        if state.lit.is_none_or(|lit| lit.sun != sun) {
            let lit = CloudSun {
                sun,
                sunlight: daylight.sunlight(sun),
                skylight: SkyLight::from_map(&daylight.skylight_map(sun)),
            };
            state.lit = Some(lit);
        }
    }
}
