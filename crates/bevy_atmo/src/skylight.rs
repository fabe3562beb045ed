//! The sky's light on the scene: each sky camera's `AmbientLight` set to the light the
//! whole sky (without the sun's disc) puts on a horizontal surface, so that what the
//! sun does not reach is lit as the sky says. Recomputed on a background thread when
//! the sun has moved by more than [`AtmoSky::sky_light_every_deg`] or the sky changed.

use atmo::atmosphere::spectrum::srgb_luminance;
use atmo::sky::lighting::{irradiance_up, LUMENS_PER_WATT, PROJECTION_ROWS};
use atmo::sky::SkyPicture;
use atmo::view::Sun;
use bevy::prelude::*;
use bevy::tasks::{futures::check_ready, AsyncComputeTaskPool, Task};

use crate::sky::{AtmoSky, AtmoSkyState, ReadySky};
use crate::sun::SunNow;

/// A camera's sky light: the sun and sky it was computed for, and the one under way.
#[derive(Component, Default)]
pub(crate) struct SkyLightState {
    lit: Option<(Sun, u64)>,
    building: Option<Task<atmo::Result<AmbientLight>>>,
}

/// The ambient light of a sky: a surface of albedo `a` under a sky whose irradiance on a
/// horizontal surface is `E` reflects `a E / pi`, which Bevy's ambient term gives for a
/// brightness (cd/m^2) of `683 Y(E) / pi` and the colour of `E`.
fn ambient_of(picture: &SkyPicture) -> AmbientLight {
    let e = irradiance_up(&picture.equirect(PROJECTION_ROWS, false));
    let y = srgb_luminance(e).max(0.0);
    let [r, g, b] = e.map(|c| if y > 0.0 { (c / y) as f32 } else { 0.0 });
    AmbientLight {
        color: Color::linear_rgb(r, g, b),
        brightness: (LUMENS_PER_WATT * y / std::f64::consts::PI) as f32,
        ..default()
    }
}

/// The angle between two suns, degrees.
fn degrees_between(a: Sun, b: Sun) -> f64 {
    let cos = a.toward().as_dvec3().dot(b.toward().as_dvec3());
    cos.clamp(-1.0, 1.0).acos().to_degrees()
}

/// Starts the sky light of each camera whose sky changed or whose sun moved far enough;
/// puts the finished ones on the cameras as their `AmbientLight`.
pub(crate) fn light_the_scene(
    mut commands: Commands,
    sun: Res<SunNow>,
    mut cameras: Query<(
        Entity,
        &AtmoSky,
        &AtmoSkyState,
        &GlobalTransform,
        Option<&mut SkyLightState>,
    )>,
) {
    for (entity, sky, state, transform, light) in &mut cameras {
        let Some(mut light) = light else {
            commands.entity(entity).insert(SkyLightState::default());
            continue;
        };
        if let Some(done) = light.building.as_mut().and_then(check_ready) {
            light.building = None;
            match done {
                Ok(ambient) => {
                    commands.entity(entity).insert(ambient);
                }
                Err(e) => error!("atmo's sky light: {e}"),
            }
        }
        let (Some(sun), Some(ready), true) = (sun.0, state.ready.clone(), sky.sky_light) else {
            continue;
        };
        let stale = light.lit.is_none_or(|(lit, generation)| {
            generation != state.generation
                || degrees_between(lit, sun) > f64::from(sky.sky_light_every_deg)
        });
        if !stale || light.building.is_some() {
            continue;
        }
        light.lit = Some((sun, state.generation));
        let altitude = sky.altitude_m(transform.translation().y);
        light.building = Some(AsyncComputeTaskPool::get().spawn(async move {
            let picture = match ready {
                ReadySky::Model(model, _) => SkyPicture::new(&model, sun),
                ReadySky::Table(table) => {
                    let top = table.settings().max_altitude_m;
                    SkyPicture::from_table(&table, sun, altitude.min(top))?
                }
            };
            Ok(ambient_of(&picture))
        }));
    }
}
