//! The light the plugin puts on a scene: the sun's `DirectionalLight` and the sky's
//! `AmbientLight`, against atmo's `Sunlight` and the sky's irradiance, and against what
//! daylight measures.

use crate::common::{app, earth_model, settled};
use atmo::atmosphere::spectrum::srgb_luminance;
use atmo::sky::lighting::{irradiance_up, Sunlight, PROJECTION_ROWS};
use atmo::sky::SkyPicture;
use atmo::view::Sun;
use atmo::Atmosphere;
use bevy::prelude::*;
use bevy_atmo::prelude::*;

const ALTITUDE_M: f32 = 1000.0;

#[test]
fn the_sun_and_the_sky_light_the_scene_as_atmo_says() {
    let sun = Sun::from_degrees(20.0, 200.0).unwrap();
    let eye = Vec3::new(0.0, ALTITUDE_M, 0.0);
    let sky = AtmoSky {
        sky_light: SkyLight::Ambient,
        ..AtmoSky::earth()
    };
    let Some(mut app) = app((
        sky,
        Msaa::Off,
        Transform::from_translation(eye).looking_to(Vec3::NEG_Z, Vec3::Y),
    )) else {
        return;
    };
    let light = app
        .world_mut()
        .spawn((
            AtmoSun,
            Transform::default().looking_to(-sun.toward(), Vec3::Y),
        ))
        .id();
    let ambient = camera_gets::<AmbientLight>(&mut app);

    // The sun: atmo's sunlight at the camera, 60 to 100 klux at 20 deg.
    let want = Sunlight::at(&Atmosphere::earth(), ALTITUDE_M.into(), sun);
    let got = app.world().get::<DirectionalLight>(light).unwrap();
    assert!(
        (f64::from(got.illuminance) / want.normal_lux - 1.0).abs() < 1e-5,
        "{} lux vs {}",
        got.illuminance,
        want.normal_lux
    );
    assert!(
        (60e3..100e3).contains(&got.illuminance),
        "{} lux",
        got.illuminance
    );
    let colour = got.color.to_linear();
    let want_colour = want.colour.map(|c| c as f32);
    assert!(
        (Vec3::new(colour.red, colour.green, colour.blue) - Vec3::from(want_colour))
            .abs()
            .max_element()
            < 1e-5,
        "{colour:?} vs {want_colour:?}"
    );

    // The sky: a horizontal surface of albedo a reflects a E / pi, E the sky's irradiance
    // on it; a clear sky with the sun at 20 deg gives some 5 to 10 klux (less in cleaner
    // air: atmo's Earth from 1 km gives 5.5), bluish. The range catches a lost pi or 683.
    let picture = SkyPicture::new(&earth_model(ALTITUDE_M), sun);
    let e = irradiance_up(&picture.equirect(PROJECTION_ROWS, false));
    let lux = 683.0 * srgb_luminance(e);
    let brightness = f64::from(ambient.brightness);
    eprintln!(
        "sun {} lux, sky {lux:.0} lux on a horizontal surface, ambient {brightness:.0} cd/m^2",
        got.illuminance
    );
    assert!(
        (brightness / (lux / std::f64::consts::PI) - 1.0).abs() < 1e-4,
        "ambient {brightness} cd/m^2, the sky's {lux} lux / pi"
    );
    assert!(
        (3e3..15e3).contains(&lux),
        "the sky's {lux} lux on a horizontal surface"
    );
    let sky = ambient.color.to_linear();
    assert!(sky.blue > sky.red, "a clear sky's light is bluish: {sky:?}");
}

/// Updates `app` until its camera has a `T` (the sky's light is made on a background
/// thread once the sky is ready), and returns it.
fn camera_gets<T: Component + Clone>(app: &mut App) -> T {
    settled(app);
    for _ in 0..2000 {
        app.update();
        let mut cameras = app.world_mut().query::<&T>();
        if let Some(found) = cameras.iter(app.world()).next() {
            return found.clone();
        }
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    panic!("the camera never got its sky light");
}

#[test]
fn the_sky_becomes_an_environment_map_the_right_way_round() {
    // The sun low in the south: Bevy looks the north (world -z) up on the cube's +z face
    // (its cubemaps are left-handed), which must hold the darker, northern sky (the
    // upper halves of the two faces differ by 23 %; the wrong way round, the other way).
    let sun = Sun::from_degrees(10.0, 180.0).unwrap();
    let Some(mut app) = app((
        AtmoSky::earth(),
        Msaa::Off,
        Transform::from_xyz(0.0, ALTITUDE_M, 0.0).looking_to(Vec3::NEG_Z, Vec3::Y),
    )) else {
        return;
    };
    app.world_mut().spawn((
        AtmoSun,
        Transform::default().looking_to(-sun.toward(), Vec3::Y),
    ));
    let map = camera_gets::<bevy::light::GeneratedEnvironmentMapLight>(&mut app);
    assert_eq!(map.intensity, 683.0, "radiance in W m^-2 sr^-1 to cd/m^2");
    let mut cameras = app.world_mut().query::<&AmbientLight>();
    let ambient = cameras
        .iter(app.world())
        .next()
        .expect("the global ambient overridden");
    assert_eq!(ambient.brightness, 0.0);
    let images = app.world().resource::<Assets<Image>>();
    let image = images.get(&map.environment_map).expect("the sky's cubemap");
    let size = image.texture_descriptor.size.width as usize;
    let data = image.data.as_ref().expect("kept in the main world");
    // The mean luminance of the upper half of face `face` (0 to 5: +x -x +y -y +z -z).
    let upper_half = |face: usize| {
        let texel = |i: usize| {
            let at = |c: usize| {
                let b = &data[8 * i + 2 * c..8 * i + 2 * c + 2];
                half::f16::from_le_bytes([b[0], b[1]]).to_f32()
            };
            0.2126 * at(0) + 0.7152 * at(1) + 0.0722 * at(2)
        };
        let start = face * size * size;
        (start..start + size * size / 2).map(texel).sum::<f32>() / (size * size / 2) as f32
    };
    let (north, south) = (upper_half(4), upper_half(5));
    eprintln!("north {north}, south {south} (W m^-2 sr^-1, luminance)");
    assert!(
        north > 0.0 && south > 1.1 * north,
        "north {north}, south {south}"
    );
    // Up is up: the zenith face is sky, the nadir face ground (dimmer, the sun's side
    // aside).
    assert!(
        upper_half(2) > upper_half(3),
        "zenith {} nadir {}",
        upper_half(2),
        upper_half(3)
    );
}
