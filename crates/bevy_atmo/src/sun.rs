//! The sun ([`AtmoSun`]): a `DirectionalLight` whose direction places the sun in the
//! sky, and whose colour and illuminance atmo sets to the sunlight at the camera.

use atmo::sky::lighting::Sunlight;
use atmo::view::place::Place;
use atmo::view::Sun;
use bevy::prelude::*;
use chrono::{DateTime, FixedOffset};

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

/// The sun of a place and a time (NREL's solar position algorithm, atmo's `atmo sun`):
/// put beside [`AtmoSun`], it turns the light to the sun's geometric position at `time`
/// seen from `place`, whenever either changes (advance `time` to move the sun through a
/// day). North is -z, east +x.
#[derive(Component, Clone, Debug)]
#[require(AtmoSun)]
pub struct AtmoSunAt {
    pub place: Place,
    pub time: DateTime<FixedOffset>,
}

impl AtmoSunAt {
    /// The sun at `time` (RFC 3339 with its offset, `2026-06-21T20:30:00+02:00`) seen
    /// from `latitude_deg` north and `longitude_deg` east at sea level; errors name the
    /// field.
    pub fn new(latitude_deg: f64, longitude_deg: f64, time: &str) -> atmo::Result<Self> {
        let place = Place {
            latitude_deg,
            longitude_deg,
            altitude_m: 0.0,
        };
        place.validate()?;
        Ok(AtmoSunAt {
            place,
            time: atmo::view::place::parse_time(time)?,
        })
    }
}

/// Turns each [`AtmoSunAt`] light to its sun when its place or time changed.
pub(crate) fn place_the_sun(mut suns: Query<(&AtmoSunAt, &mut Transform), Changed<AtmoSunAt>>) {
    for (at, mut transform) in &mut suns {
        match at.place.sun_at(at.time) {
            Ok(position) => {
                let toward = position.sun().toward();
                // The light travels away from the sun; straight up, any "up" will do.
                let up = if toward.y.abs() > 0.999 {
                    Vec3::Z
                } else {
                    Vec3::Y
                };
                transform.look_to(-toward, up);
            }
            Err(e) => error!("AtmoSunAt: {e}"),
        }
    }
}

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
    let Some((sky, eye)) = first_sky_camera(&cameras) else {
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

/// The first active sky camera (lowest `Camera::order`): the one the sun's light and
/// the clouds' are made for.
pub(crate) fn first_sky_camera<'a>(
    cameras: &'a Query<(&AtmoSky, &GlobalTransform, &Camera)>,
) -> Option<(&'a AtmoSky, &'a GlobalTransform)> {
    cameras
        .iter()
        .filter(|(_, _, camera)| camera.is_active)
        .min_by_key(|(_, _, camera)| camera.order)
        .map(|(sky, eye, _)| (sky, eye))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_place_and_a_time_turn_the_light_to_the_suns_position() {
        let at = AtmoSunAt::new(48.1, 11.6, "2026-06-21T19:00:00+02:00").unwrap();
        let want = at.place.sun_at(at.time).unwrap();
        let mut app = App::new();
        app.add_systems(Update, place_the_sun);
        let sun = app.world_mut().spawn((at, Transform::default())).id();
        app.update();
        let transform = app.world().get::<Transform>(sun).unwrap();
        // Toward the sun is the light's back; an evening sun in Munich is low in the
        // north-west.
        let got = Sun::from_toward(*transform.back()).unwrap();
        assert!(
            (got.elevation().to_degrees() - want.elevation_deg).abs() < 1e-3,
            "{got:?}"
        );
        let azimuth = got.azimuth().to_degrees().rem_euclid(360.0);
        assert!(
            (azimuth - want.azimuth_deg).abs() < 1e-3,
            "{azimuth} vs {want:?}"
        );
        assert!(want.elevation_deg > 0.0 && want.elevation_deg < 20.0);
        assert!(want.azimuth_deg > 270.0 && want.azimuth_deg < 320.0);
    }
}
