//! The sun ([`AtmoSun`]): a `DirectionalLight` whose direction places the sun in the
//! sky, and whose colour and illuminance atmo sets to the sunlight at the camera.

use atmo::sky::lighting::Sunlight;
use atmo::view::Sun;
use bevy::prelude::*;

use crate::sky::AtmoSky;

/// Marks the `DirectionalLight` that is the sun. Its direction (the way its light
/// travels: the entity's forward, -z) puts the sun in every [`AtmoSky`]; atmo sets its
/// colour and illuminance (lux on a surface facing the sun) to the sunlight reaching the
/// first active sky camera through the atmosphere: dimmer and redder toward the
/// horizon, none once the sun has set.
#[derive(Component, Clone, Copy, Debug, Default, Reflect)]
#[reflect(Component, Default)]
#[require(DirectionalLight)]
pub struct AtmoSun;

/// The sun this frame, for the render world: `None` without an [`AtmoSun`].
#[derive(Resource, Clone, Copy, Debug, Default)]
pub(crate) struct SunNow(pub Option<Sun>);

/// Places the sun from the [`AtmoSun`] light and sets the light to the sunlight at the
/// first active sky camera (lowest `Camera::order`).
pub(crate) fn light_the_sun(
    mut suns: Query<(&GlobalTransform, &mut DirectionalLight), With<AtmoSun>>,
    cameras: Query<(&AtmoSky, &GlobalTransform, &Camera)>,
    mut now: ResMut<SunNow>,
) {
    let mut lights = suns.iter_mut();
    let Some((transform, mut light)) = lights.next() else {
        now.0 = None;
        return;
    };
    if lights.next().is_some() {
        warn_once!("bevy_atmo: more than one AtmoSun; the first found is the sun");
    }
    // A light's transform is never degenerate after propagation; a zero scale would be.
    let Ok(sun) = Sun::from_toward(transform.back().as_vec3()) else {
        now.0 = None;
        return;
    };
    now.0 = Some(sun);
    let first = cameras
        .iter()
        .filter(|(_, _, camera)| camera.is_active)
        .min_by_key(|(_, _, camera)| camera.order);
    let Some((sky, eye, _)) = first else {
        return;
    };
    let sunlight = Sunlight::at(&sky.atmosphere, sky.altitude_m(eye.translation().y), sun);
    let [r, g, b] = sunlight.colour.map(|c| c as f32);
    let (color, illuminance) = (Color::linear_rgb(r, g, b), sunlight.normal_lux as f32);
    // Written only when it changes: Bevy re-extracts a changed light.
    if light.color != color || light.illuminance != illuminance {
        light.color = color;
        light.illuminance = illuminance;
    }
}
