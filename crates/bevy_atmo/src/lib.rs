//! atmo in Bevy: the every-order sky behind a 3-D camera and the sun as a
//! `DirectionalLight` lit through the atmosphere, drawn on Bevy's own device by
//! atmo-gpu's passes.
//!
//! ```no_run
//! use bevy::prelude::*;
//! use bevy_atmo::prelude::*;
//!
//! fn setup(mut commands: Commands) {
//!     // The sky behind everything the camera draws, from its altitude (its y, m).
//!     commands.spawn((Camera3d::default(), AtmoSky::earth(), Transform::from_xyz(0.0, 2.0, 0.0)));
//!     // The sun: atmo sets the light's colour and illuminance; its direction moves the sun.
//!     commands.spawn((
//!         AtmoSun,
//!         Transform::from_xyz(0.0, 0.0, 0.0).looking_to(Vec3::new(0.3, -0.5, 1.0), Vec3::Y),
//!     ));
//! }
//!
//! App::new()
//!     .add_plugins((DefaultPlugins, AtmoPlugin))
//!     .add_systems(Startup, setup)
//!     .run();
//! ```
//!
//! Units are Bevy's physical ones: the sky is written as luminance (atmo's radiance,
//! W m^-2 sr^-1 as linear sRGB, times 683 lm/W) times the camera's exposure, the sun's
//! illuminance in lux; with Bevy's default exposure (EV100 9.7) a midday sky is far
//! over white, so a daylight scene sets `Exposure::SUNLIGHT` on its camera as it would
//! for Bevy's own Atmosphere. docs/bevy.md says what the plugin does and does not do.

mod aerial;
mod beam_pass;
mod beams;
mod cloud_pass;
mod clouds;
mod render;
mod sky;
mod skylight;
mod sun;

use bevy::core_pipeline::core_3d::{main_opaque_pass_3d, main_transparent_pass_3d};
use bevy::core_pipeline::schedule::Core3d;
use bevy::prelude::*;
use bevy::render::{ExtractSchedule, Render, RenderApp, RenderStartup, RenderSystems};
use bevy::transform::TransformSystems;

pub use beams::{AtmoBeam, AtmoHaze};
pub use clouds::{AtmoClouds, AtmoCloudsState};
pub use sky::{AtmoSky, AtmoSkyState, SkySource};
pub use skylight::SkyLight;
pub use sun::{AtmoSun, AtmoSunAt};

/// What a Bevy program imports to use atmo.
pub mod prelude {
    pub use crate::{
        AtmoBeam, AtmoClouds, AtmoCloudsState, AtmoHaze, AtmoPlugin, AtmoSky, AtmoSkyState,
        AtmoSun, AtmoSunAt, SkyLight, SkySource,
    };
}

/// Adds atmo's sky and sun to an app with Bevy's renderer.
#[derive(Default)]
pub struct AtmoPlugin;

impl Plugin for AtmoPlugin {
    fn build(&self, app: &mut App) {
        app.init_resource::<sun::SunNow>()
            .init_resource::<beams::Beams>()
            .register_type::<AtmoSun>()
            .register_type::<AtmoSky>()
            .register_type::<AtmoClouds>()
            .register_type::<AtmoHaze>()
            .register_type::<AtmoBeam>()
            .add_systems(
                PostUpdate,
                (
                    sky::build_skies,
                    sun::light_the_sun,
                    skylight::light_the_scene,
                    clouds::light_the_clouds,
                    beams::gather_beams,
                )
                    .chain()
                    .after(TransformSystems::Propagate),
            )
            // Before the transforms propagate, so the light turns in the same frame.
            .add_systems(
                PostUpdate,
                sun::place_the_sun.before(TransformSystems::Propagate),
            );
        let Some(render_app) = app.get_sub_app_mut(RenderApp) else {
            return;
        };
        render_app
            .init_resource::<beam_pass::ExtractedBeams>()
            .add_systems(RenderStartup, render::init_gpu)
            .add_systems(
                ExtractSchedule,
                (
                    render::extract_skies,
                    cloud_pass::extract_clouds,
                    beam_pass::extract_beams,
                ),
            )
            .add_systems(
                Render,
                (cloud_pass::prepare_clouds, beam_pass::prepare_beams)
                    .in_set(RenderSystems::PrepareResources),
            )
            // After the views' depth textures exist (made in PrepareResources).
            .add_systems(
                Render,
                (render::prepare_skies, cloud_pass::prepare_view_clouds)
                    .chain()
                    .in_set(RenderSystems::PrepareBindGroups),
            )
            .add_systems(
                Core3d,
                (render::draw_sky, beam_pass::draw_beams)
                    .chain()
                    .after(main_opaque_pass_3d)
                    .before(main_transparent_pass_3d),
            );
    }
}
