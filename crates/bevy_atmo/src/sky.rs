//! The sky a camera sees ([`AtmoSky`]): what it is drawn from, and the shell model
//! (sky 3) built for the camera's altitude on a background thread, again when the
//! camera has climbed or descended far enough, or when the settings change.

use std::path::PathBuf;
use std::sync::Arc;

use atmo::sky::aerial::{quadratic_slices, AerialRays};
use atmo::sky::{SkyModel, SkySettings, SkylightTable};
use atmo::Atmosphere;
use bevy::camera::Hdr;
use bevy::prelude::*;
use bevy::render::render_resource::TextureUsages;
use bevy::tasks::{futures::check_ready, AsyncComputeTaskPool, Task};

use crate::aerial;
use crate::skylight::SkyLight;

/// atmo's sky behind everything a 3-D camera draws: put it on the camera's entity.
///
/// The frame is Bevy's and atmo's alike: metres, +y up, -z north, +x east. The camera's
/// altitude is its height above [`AtmoSky::ground_level_m`].
///
/// Its plain fields can be edited in an inspector (`Reflect`); the atmosphere and the
/// source, atmo's own types, are not reflected.
#[derive(Component, Clone, Debug, Reflect)]
#[reflect(Component, Clone, Debug)]
#[require(Hdr)]
pub struct AtmoSky {
    /// The atmosphere (atmo's Earth by default: molecules, aerosols, ozone).
    #[reflect(ignore, default = "earth")]
    pub atmosphere: Arc<Atmosphere>,
    /// What the sky is drawn from.
    #[reflect(ignore, default = "every_order")]
    pub source: SkySource,
    /// The world y of altitude 0 (the ground), m.
    pub ground_level_m: f32,
    /// Whether the sun's disc is drawn.
    pub sun_disc: bool,
    /// Whether the meshes are seen through the air before them (aerial perspective),
    /// and out to how far, m: farther surfaces get the haze of this distance. From a
    /// model only (a table keeps no view rays).
    pub aerial_perspective: bool,
    pub aerial_far_m: f32,
    /// How the sky lights the scene (an environment map by default, or an ambient
    /// light), recomputed on a background thread (a few milliseconds) once the sun has
    /// moved by more than `sky_light_every_deg` degrees.
    pub sky_light: SkyLight,
    pub sky_light_every_deg: f32,
}

/// What a sky is drawn from.
#[derive(Clone, Debug)]
pub enum SkySource {
    /// The shell method's model (sky 3) with these settings (every order by default,
    /// `SkySettings::paper()` the paper's two). A model is of one altitude: it is
    /// built on a background thread for the camera's (a few seconds on two cores), and
    /// again once the camera is more than `rebuild_after_m` from it; the old one draws
    /// meanwhile, and nothing is drawn before the first is ready.
    Model {
        settings: SkySettings,
        rebuild_after_m: f32,
    },
    /// A skylight table (sky 4, `atmo precompute sky`): every altitude of its range
    /// (0 to 13 km by default) drawn continuously on the GPU, nothing rebuilt; above
    /// it, its highest altitude. Its atmosphere is the table's own.
    Table(Arc<SkylightTable>),
}

/// atmo's Earth, for a reflected [`AtmoSky`] made without one.
fn earth() -> Arc<Atmosphere> {
    AtmoSky::earth().atmosphere
}

/// The model of every order, for a reflected [`AtmoSky`] made without a source.
fn every_order() -> SkySource {
    AtmoSky::earth().source
}

impl AtmoSky {
    /// The Earth of atmo's defaults: every scattering order, ozone, a ground of albedo
    /// 0.1, from the shell model rebuilt every 500 m of altitude.
    pub fn earth() -> Self {
        AtmoSky {
            atmosphere: Arc::new(Atmosphere::earth()),
            source: SkySource::Model {
                settings: SkySettings::default(),
                rebuild_after_m: 500.0,
            },
            ground_level_m: 0.0,
            sun_disc: true,
            aerial_perspective: true,
            aerial_far_m: 60_000.0,
            sky_light: SkyLight::EnvironmentMap { size: 64 },
            sky_light_every_deg: 0.5,
        }
    }

    /// The sky of a skylight table file written by `atmo precompute sky`; its errors
    /// name the file and what is wrong with it.
    pub fn from_table_file(path: impl Into<PathBuf>) -> atmo::Result<Self> {
        let table = SkylightTable::read(&path.into())?;
        Ok(AtmoSky {
            atmosphere: Arc::new(table.atmosphere().clone()),
            source: SkySource::Table(Arc::new(table)),
            ..AtmoSky::earth()
        })
    }

    /// The camera's altitude for a camera at world height `y`, m (never below 0).
    pub fn altitude_m(&self, y: f32) -> f64 {
        f64::from(y - self.ground_level_m).max(0.0)
    }
}

/// The sky ready to draw for a camera, as the render world takes it: a model with the
/// view rays of its aerial perspective where it has one, or a table.
#[derive(Clone)]
pub(crate) enum ReadySky {
    Model(Arc<SkyModel>, Option<Arc<AerialRays>>),
    Table(Arc<SkylightTable>),
}

impl ReadySky {
    /// The altitude a camera at `altitude_m` sees drawn: a table's top above its range
    /// (a table holds no higher sky); a model draws from its own altitude whatever this.
    pub(crate) fn drawn_altitude(&self, altitude_m: f64) -> f64 {
        match self {
            ReadySky::Model(..) => altitude_m,
            ReadySky::Table(table) => altitude_m.min(table.settings().max_altitude_m),
        }
    }
}

/// A model and its aerial perspective's view rays, as a build gives them.
type Built = atmo::Result<(SkyModel, Option<AerialRays>)>;

/// What a camera's sky is made from: a change to any of it makes the sky again; the
/// other fields of [`AtmoSky`] are read as they are each frame.
#[derive(Clone)]
struct Recipe {
    atmosphere: Arc<Atmosphere>,
    /// The model's settings, or the table (the same one, not an equal one).
    source: Result<SkySettings, Arc<SkylightTable>>,
    /// The aerial perspective's reach, m, where it is drawn.
    aerial_far_m: Option<f32>,
}

impl Recipe {
    fn of(sky: &AtmoSky) -> Self {
        Recipe {
            atmosphere: sky.atmosphere.clone(),
            source: match &sky.source {
                SkySource::Model { settings, .. } => Ok(settings.clone()),
                SkySource::Table(table) => Err(table.clone()),
            },
            aerial_far_m: sky.aerial_perspective.then_some(sky.aerial_far_m),
        }
    }
}

impl PartialEq for Recipe {
    fn eq(&self, other: &Self) -> bool {
        let source = match (&self.source, &other.source) {
            (Ok(a), Ok(b)) => a == b,
            (Err(a), Err(b)) => Arc::ptr_eq(a, b),
            _ => false,
        };
        source
            && self.aerial_far_m == other.aerial_far_m
            && same_atmosphere(&self.atmosphere, &other.atmosphere)
    }
}

/// Whether two atmospheres are the same: one shared, or equal (a cheap test first).
pub(crate) fn same_atmosphere(a: &Arc<Atmosphere>, b: &Arc<Atmosphere>) -> bool {
    Arc::ptr_eq(a, b) || a == b
}

/// A sky camera's sky in the making (the plugin adds it beside [`AtmoSky`]): the sky
/// drawn now, the model being built, and a count that changes whenever what is drawn
/// does (so the GPU's copy is remade).
#[derive(Component, Default)]
pub struct AtmoSkyState {
    pub(crate) ready: Option<ReadySky>,
    pub(crate) generation: u64,
    /// The build under way (always of `recipe`) and the altitude it is for, m.
    building: Option<(Task<Built>, f64)>,
    /// Whether the model drawn now is of `recipe` (not while an old one draws after the
    /// settings changed): another camera of that recipe may share it.
    current: bool,
    /// What the sky is made from; `None` before the first.
    recipe: Option<Recipe>,
    /// The recipe changed since the last model was started.
    stale: bool,
    /// The last build failed (its error logged): none is tried until the settings change.
    failed: bool,
}

impl AtmoSkyState {
    /// Whether a sky is ready to draw (false until the first model is built).
    pub fn is_ready(&self) -> bool {
        self.ready.is_some()
    }

    /// Whether a model is being built (the first, or one for a new altitude or new
    /// settings).
    pub fn is_building(&self) -> bool {
        self.building.is_some()
    }
}

/// A sky camera, as the builds see it.
type SkyCameraParts<'a> = (
    Entity,
    Ref<'a, AtmoSky>,
    &'a GlobalTransform,
    Option<&'a mut AtmoSkyState>,
    Option<&'a mut Camera3d>,
);

/// A model one camera has made, or is making, that another of the same recipe near
/// the same altitude takes rather than building its own.
struct Shared {
    recipe: Recipe,
    /// The model's altitude, m.
    altitude_m: f64,
    /// The model and its view rays; `None` while it is being built.
    model: Option<(Arc<SkyModel>, Option<Arc<AerialRays>>)>,
}

/// Starts a model for each camera whose sky has none, whose recipe changed (a build
/// under way for the old one is dropped), or which left its model's altitude; takes
/// the models that are done. Cameras share: one whose sky another camera of the same
/// recipe has made, or is making, within its `rebuild_after_m` takes that model (a
/// split screen or a mirror's camera builds nothing of its own).
pub(crate) fn build_skies(mut commands: Commands, mut cameras: Query<SkyCameraParts>) {
    let mut shared: Vec<Shared> = cameras
        .iter()
        .filter_map(|(.., state, _)| state)
        .filter_map(|state| Some((state, state.recipe.as_ref()?)))
        .flat_map(|(state, recipe)| {
            let made = match &state.ready {
                Some(ReadySky::Model(model, rays)) if state.current => Some(Shared {
                    recipe: recipe.clone(),
                    altitude_m: model.altitude_m(),
                    model: Some((model.clone(), rays.clone())),
                }),
                _ => None,
            };
            let making = state.building.as_ref().map(|(_, altitude_m)| Shared {
                recipe: recipe.clone(),
                altitude_m: *altitude_m,
                model: None,
            });
            made.into_iter().chain(making)
        })
        .collect();
    for (entity, sky, transform, state, camera) in &mut cameras {
        // The aerial pass reads the depth buffer.
        let binding = TextureUsages::TEXTURE_BINDING.bits();
        if let Some(mut camera) = camera.filter(|c| c.depth_texture_usages.0 & binding == 0) {
            camera.depth_texture_usages.0 |= binding;
        }
        let Some(mut state) = state else {
            commands.entity(entity).insert(AtmoSkyState {
                recipe: Some(Recipe::of(&sky)),
                stale: true,
                ..default()
            });
            continue;
        };
        // A change to the sky's disc or its light, say, makes no new model.
        if sky.is_changed() && state.recipe.as_ref() != Some(&Recipe::of(&sky)) {
            state.recipe = Some(Recipe::of(&sky));
            state.building = None;
            state.current = false;
            state.stale = true;
            state.failed = false;
        }
        let settings = match &sky.source {
            SkySource::Table(table) => {
                if state.stale {
                    state.stale = false;
                    state.ready = Some(ReadySky::Table(table.clone()));
                    state.generation += 1;
                }
                continue;
            }
            SkySource::Model {
                settings,
                rebuild_after_m,
            } => (settings, f64::from(*rebuild_after_m)),
        };
        if let Some(done) = state
            .building
            .as_mut()
            .and_then(|(task, ..)| check_ready(task))
        {
            state.building = None;
            match done {
                Ok((model, rays)) => {
                    state.ready = Some(ReadySky::Model(Arc::new(model), rays.map(Arc::new)));
                    state.current = true;
                    state.generation += 1;
                }
                Err(e) => {
                    error!("atmo's sky model: {e}");
                    state.failed = true;
                }
            }
        }
        let altitude = sky.altitude_m(transform.translation().y);
        let far = match &state.ready {
            Some(ReadySky::Model(model, _)) => (model.altitude_m() - altitude).abs() > settings.1,
            _ => true,
        };
        if (state.stale || far) && state.building.is_none() && !state.failed {
            let recipe = state.recipe.clone().expect("set with the state");
            let near =
                |s: &&Shared| s.recipe == recipe && (s.altitude_m - altitude).abs() <= settings.1;
            match shared.iter().find(near).map(|s| &s.model) {
                // Another camera's model: taken as it is.
                Some(Some((model, rays))) => {
                    state.stale = false;
                    state.ready = Some(ReadySky::Model(model.clone(), rays.clone()));
                    state.current = true;
                    state.generation += 1;
                }
                // Another camera's build under way: taken once it is done.
                Some(None) => {}
                None => {
                    state.stale = false;
                    let (atmosphere, settings) = (sky.atmosphere.clone(), settings.0.clone());
                    let far_m = sky
                        .aerial_perspective
                        .then_some(f64::from(sky.aerial_far_m));
                    let task = AsyncComputeTaskPool::get().spawn(async move {
                        let model = SkyModel::new(&atmosphere, &settings, altitude)?;
                        let slices = far_m.map(|far| quadratic_slices(aerial::SLICES, far));
                        let rays = slices
                            .map(|s| model.aerial_rays(aerial::ROWS, &s))
                            .transpose()?;
                        Ok((model, rays))
                    });
                    shared.push(Shared {
                        recipe,
                        altitude_m: altitude,
                        model: None,
                    });
                    state.building = Some((task, altitude));
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use bevy::reflect::{FromReflect, GetPath};

    #[test]
    fn an_inspector_edits_the_plain_fields_and_keeps_the_rest() {
        let mut sky = AtmoSky {
            source: SkySource::Model {
                settings: SkySettings::paper(),
                rebuild_after_m: 200.0,
            },
            ..AtmoSky::earth()
        };
        *sky.path_mut::<bool>("sun_disc").unwrap() = false;
        *sky.path_mut::<f32>("aerial_far_m").unwrap() = 20_000.0;
        assert!(!sky.sun_disc && sky.aerial_far_m == 20_000.0);
        assert!(
            sky.reflect_path("atmosphere").is_err(),
            "atmo's atmosphere reflected"
        );
        // Made from its reflection, the unreflected fields take the defaults.
        let made = AtmoSky::from_reflect(&sky).unwrap();
        assert_eq!((made.sun_disc, made.aerial_far_m), (false, 20_000.0));
        let SkySource::Model { settings, .. } = made.source else {
            panic!("a table")
        };
        assert_eq!(settings, SkySettings::default());
    }

    #[test]
    fn cameras_of_one_sky_near_one_altitude_share_one_model() {
        // Two cameras 200 m apart (within the 500 m a model holds) build one model and
        // draw it both; a third 2 km higher builds its own.
        let mut app = App::new();
        app.add_plugins(TaskPoolPlugin::default());
        app.add_systems(Update, build_skies);
        let sky = AtmoSky {
            source: SkySource::Model {
                settings: SkySettings {
                    shells: 8,
                    directions: 8,
                    scattering_directions: 16,
                    sun_bins: 8,
                    ..SkySettings::default()
                },
                rebuild_after_m: 500.0,
            },
            aerial_perspective: false,
            ..AtmoSky::earth()
        };
        let at = |y: f32| GlobalTransform::from_translation(Vec3::new(0.0, y, 0.0));
        let cameras =
            [1000.0, 1200.0, 3000.0].map(|y| app.world_mut().spawn((sky.clone(), at(y))).id());
        let mut states = app.world_mut().query::<&AtmoSkyState>();
        for _ in 0..2 {
            app.update();
        }
        let building = states.iter(app.world()).filter(|s| s.is_building()).count();
        assert_eq!(
            building, 2,
            "one build for the two cameras near 1 km, one at 3 km"
        );
        let start = std::time::Instant::now();
        while !states.iter(app.world()).all(AtmoSkyState::is_ready) {
            assert!(start.elapsed().as_secs() < 300, "the models never came");
            std::thread::sleep(std::time::Duration::from_millis(20));
            app.update();
        }
        let model = |camera: Entity| match &app.world().get::<AtmoSkyState>(camera).unwrap().ready {
            Some(ReadySky::Model(model, _)) => model.clone(),
            _ => panic!("no model"),
        };
        let [low, near, high] = cameras.map(model);
        assert!(Arc::ptr_eq(&low, &near), "the two near 1 km share");
        assert!(!Arc::ptr_eq(&low, &high));
        assert_eq!((low.altitude_m(), high.altitude_m()), (1000.0, 3000.0));
    }
}
