//! The plugin's aerial perspective held to atmo's: a black box and a grey one, unlit, a
//! few kilometres off, seen as `T L + S` with `T` and `S` of `SkyModel::aerial_along`
//! for the ray through each box's pixel, cut at the box's face.

use crate::common::{app, atmo_camera, earth_model, scale, settled, WIDTH};
use atmo::view::Sun;
use bevy::prelude::*;
use bevy_atmo::prelude::*;

const ALTITUDE_M: f32 = 1000.0;

/// The boxes: azimuth from the view's (deg), distance to the centre (m), half their
/// side (m), and their unlit colour.
const BOXES: [(f64, f32, f32, f32); 2] = [(-15.0, 3000.0, 300.0, 0.0), (15.0, 6000.0, 600.0, 0.5)];

/// Where the view looks: level, azimuth 170 deg; the sun at 20 deg, azimuth 200 deg.
const VIEW_AZIMUTH_DEG: f64 = 170.0;

fn sun() -> Sun {
    Sun::from_degrees(20.0, 200.0).unwrap()
}

fn toward(azimuth_deg: f64) -> Vec3 {
    atmo::view::direction_of(azimuth_deg.to_radians(), 0.0).as_vec3()
}

#[test]
fn a_box_fades_toward_the_sky_as_atmos_aerial_perspective_says() {
    let eye = Vec3::new(0.0, ALTITUDE_M, 0.0);
    let look = toward(VIEW_AZIMUTH_DEG);
    let Some(mut app) = app((
        AtmoSky {
            sun_disc: false,
            ..AtmoSky::earth()
        },
        Msaa::Off,
        Transform::from_translation(eye).looking_to(look, Vec3::Y),
    )) else {
        return;
    };
    app.world_mut().spawn((
        AtmoSun,
        Transform::default().looking_to(-sun().toward(), Vec3::Y),
    ));
    let world = app.world_mut();
    for (azimuth, distance, half, grey) in BOXES {
        let mesh = world
            .resource_mut::<Assets<Mesh>>()
            .add(Cuboid::from_length(2.0 * half));
        let material = world
            .resource_mut::<Assets<StandardMaterial>>()
            .add(StandardMaterial {
                base_color: Color::linear_rgb(grey, grey, grey),
                unlit: true,
                ..default()
            });
        let to_box = toward(VIEW_AZIMUTH_DEG + azimuth);
        world.spawn((
            Mesh3d(mesh),
            MeshMaterial3d(material),
            Transform::from_translation(eye + distance * to_box).looking_to(to_box, Vec3::Y),
        ));
    }
    let shot = settled(&mut app);

    let model = earth_model(ALTITUDE_M);
    let camera = atmo_camera(look);
    for (azimuth, distance, half, grey) in BOXES {
        let to_box = toward(VIEW_AZIMUTH_DEG + azimuth);
        let (x, y) = camera.pixel_of(distance * to_box).unwrap();
        let (x, y) = (x.floor() as u32, y.floor() as u32);
        let ray = camera.ray(x as f32 + 0.5, y as f32 + 0.5);
        // The face toward the eye, along this pixel's ray.
        let d = (distance - half) / ray.normalize().dot(to_box);
        let light = &model.aerial_along(sun(), ray, &[d.into()]).unwrap()[0];
        let (t, s) = light.rgb(model.atmosphere());
        let want = grey * t + s * scale();
        let p = shot[(y * WIDTH + x) as usize];
        let got = Vec3::new(p[0], p[1], p[2]);
        let error = (got - want).abs() / want;
        eprintln!(
            "box at {distance} m, pixel ({x}, {y}), face {d:.0} m: plugin {got}, atmo {want} \
             (T {t}, S {s}), off {error}"
        );
        assert!(
            error.max_element() <= 0.01,
            "box at {distance} m: plugin {got}, atmo {want}: off by {error} (bound 1 %)"
        );
    }
}
