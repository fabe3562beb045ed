//! The plugin's sky held to `atmo sky`'s: the same camera and sun drawn on the CPU
//! (`SkyPicture`, which the CLI renders), compared under the CLI's PNG display.

use std::sync::{Arc, OnceLock};

use crate::common::{app, around_the_box, atmo_camera, black_box, earth_model, radiance, settled};
use atmo::image::{Display, Frame, ToneMap};
use atmo::sky::{SkyPicture, SkylightTable, TableSettings, View};
use atmo::view::Sun;
use bevy::prelude::*;
use bevy_atmo::prelude::*;

/// The camera's altitude, m: the plugin builds its model for it.
const ALTITUDE_M: f32 = 1000.0;

/// `atmo sky`'s PNG display (its default exposure and tone map).
const DISPLAY: Display = Display {
    exposure: 0.15,
    tone: ToneMap::Exponential,
};

/// The sun and the view direction of the tests: the sun low in the picture's right
/// half, the view a little above the horizon.
fn sun() -> Sun {
    Sun::from_degrees(20.0, 200.0).unwrap()
}

fn looking() -> Vec3 {
    atmo::view::direction_of(170f64.to_radians(), 12f64.to_radians()).as_vec3()
}

/// The CPU's picture of the test's camera and sun, disc left out (its radiance is past
/// what an f16 target holds at this exposure).
fn reference() -> &'static Frame {
    static FRAME: OnceLock<Frame> = OnceLock::new();
    FRAME.get_or_init(|| {
        let model = earth_model(ALTITUDE_M);
        let view = View {
            camera: atmo_camera(looking()),
            sun_disc: false,
        };
        SkyPicture::new(&model, sun()).render(&view)
    })
}

/// The plugin's camera and sun for the test's view, with `msaa`, no aerial perspective
/// (tests/aerial.rs has it).
fn scene(msaa: Msaa) -> Option<App> {
    let sky = AtmoSky {
        sun_disc: false,
        aerial_perspective: false,
        ..AtmoSky::earth()
    };
    let eye = Vec3::new(0.0, ALTITUDE_M, 0.0);
    let mut app = app((
        sky,
        msaa,
        Transform::from_translation(eye).looking_to(looking(), Vec3::Y),
    ))?;
    app.world_mut().spawn((
        AtmoSun,
        Transform::default().looking_to(-sun().toward(), Vec3::Y),
    ));
    Some(app)
}

#[test]
fn the_sky_is_atmo_skys_for_the_same_camera_and_sun() {
    let Some(mut app) = scene(Msaa::Off) else {
        return;
    };
    let frame = radiance(&settled(&mut app));
    let e = frame.level_errors(reference(), DISPLAY).unwrap();
    eprintln!(
        "plugin vs atmo sky: RMS {:.3}, max {:.3} levels",
        e.rms, e.max
    );
    assert!(e.rms <= 0.5, "RMS {:.3} levels (bound 0.5)", e.rms);
    // Not a black picture matching a black one.
    let mean =
        frame.pixels.iter().map(|p| p.element_sum()).sum::<f32>() / frame.pixels.len() as f32;
    assert!(mean > 1.0, "mean radiance {mean}");
}

#[test]
fn with_msaa_4x_the_sky_fills_around_a_mesh_and_never_over_it() {
    let Some(mut app) = scene(Msaa::Sample4) else {
        return;
    };
    // A black box straight ahead, 200 m away, 40 m wide: about a tenth of the picture.
    let centre = Vec3::new(0.0, ALTITUDE_M, 0.0) + 200.0 * looking();
    black_box(app.world_mut(), centre, 40.0, looking());
    let frame = radiance(&settled(&mut app));
    // The box covers the centre: (20 / 180) / tan(22.5 deg) of the half-height, 27 %,
    // about +-14 pixels; inside +-10 it is black, outside +-18 the sky is atmo's.
    let outside = around_the_box(&frame, 10, 18);
    let e = frame.level_errors_over(reference(), DISPLAY, outside);
    eprintln!(
        "MSAA 4x, around the box: RMS {:.3}, max {:.3} levels",
        e.rms, e.max
    );
    assert!(e.rms <= 0.5, "RMS {:.3} levels (bound 0.5)", e.rms);
}

/// A coarse table (16 x 16 directions, 12 suns, 4 altitudes to 13 km) that builds in a
/// second or two.
fn coarse_table() -> SkylightTable {
    let settings = TableSettings {
        sky: atmo::sky::SkySettings {
            directions: 16,
            shells: 24,
            scattering_directions: 32,
            ..Default::default()
        },
        sun_steps: 12,
        altitude_steps: 4,
        ..TableSettings::default()
    };
    SkylightTable::precompute(&atmo::Atmosphere::earth(), &settings, &|_, _| {}).unwrap()
}

#[test]
fn a_table_sky_follows_the_camera_up_with_no_rebuild() {
    let table = Arc::new(coarse_table());
    let sky = AtmoSky {
        atmosphere: Arc::new(table.atmosphere().clone()),
        source: SkySource::Table(table.clone()),
        sun_disc: false,
        aerial_perspective: false,
        sky_light: SkyLight::Off,
        ..AtmoSky::earth()
    };
    let Some(mut app) = app((
        sky,
        Msaa::Off,
        Transform::from_xyz(0.0, 500.0, 0.0).looking_to(looking(), Vec3::Y),
    )) else {
        return;
    };
    app.world_mut().spawn((
        AtmoSun,
        Transform::default().looking_to(-sun().toward(), Vec3::Y),
    ));
    let view = View {
        camera: atmo_camera(looking()),
        sun_disc: false,
    };
    let mut pictures = Vec::new();
    for altitude in [500.0f32, 9000.0] {
        let mut cameras = app.world_mut().query::<(&mut Transform, &AtmoSky)>();
        for (mut transform, _) in cameras.iter_mut(app.world_mut()) {
            transform.translation.y = altitude;
        }
        // The read-back lags the frame: let the old pictures pass first.
        for _ in 0..5 {
            app.update();
        }
        let frame = radiance(&settled(&mut app));
        let want = SkyPicture::from_table(&table, sun(), altitude.into())
            .unwrap()
            .render(&view);
        let e = frame.level_errors(&want, DISPLAY).unwrap();
        eprintln!(
            "table sky at {altitude} m: RMS {:.3}, max {:.3} levels",
            e.rms, e.max
        );
        assert!(
            e.rms <= 0.5,
            "at {altitude} m: RMS {:.3} levels (bound 0.5)",
            e.rms
        );
        pictures.push(frame);
    }
    // The climb changed the sky: a picture of one altitude would not pass at the other.
    let apart = pictures[0].level_errors(&pictures[1], DISPLAY).unwrap();
    assert!(
        apart.rms > 5.0,
        "500 m and 9 km differ by only {:.2} levels RMS",
        apart.rms
    );
}

#[test]
fn switching_msaa_and_the_orders_live_remakes_the_passes_without_errors() {
    // MSAA off, then 4x (the passes are remade for the new sample count), the disc on
    // (nothing rebuilt), then the paper's two orders (the model is rebuilt): each picture
    // settles with no GPU error.
    let Some(mut app) = scene(Msaa::Off) else {
        return;
    };
    let first = radiance(&settled(&mut app));
    let mut cameras = app.world_mut().query::<(&mut Msaa, &mut AtmoSky)>();
    for (mut msaa, _) in cameras.iter_mut(app.world_mut()) {
        *msaa = Msaa::Sample4;
    }
    for _ in 0..5 {
        app.update();
    }
    let multisampled = radiance(&settled(&mut app));
    let e = multisampled.level_errors(&first, DISPLAY).unwrap();
    assert!(e.rms <= 0.1, "MSAA 4x against off: RMS {:.3} levels", e.rms);
    // The sun's disc switched on needs no new model.
    let mut cameras = app.world_mut().query::<&mut AtmoSky>();
    for mut sky in cameras.iter_mut(app.world_mut()) {
        sky.sun_disc = true;
    }
    app.update();
    let mut states = app.world_mut().query::<&AtmoSkyState>();
    let building = states.iter(app.world()).any(|s| s.is_building());
    assert!(!building, "the disc switched on rebuilt the model");
    let mut cameras = app.world_mut().query::<&mut AtmoSky>();
    for mut sky in cameras.iter_mut(app.world_mut()) {
        sky.source = SkySource::Model {
            settings: atmo::sky::SkySettings::paper(),
            rebuild_after_m: 500.0,
        };
        sky.sun_disc = false;
    }
    for _ in 0..5 {
        app.update();
    }
    let paper = radiance(&settled(&mut app));
    eprintln!("MSAA 4x against off: RMS {:.3} levels", e.rms);
    // Two orders leave out the light of the higher ones: a darker sky.
    let mean = |f: &Frame| f.pixels.iter().map(|p| p.element_sum()).sum::<f32>();
    assert!(
        mean(&paper) < 0.97 * mean(&first),
        "the paper's orders {} against every order {}",
        mean(&paper),
        mean(&first)
    );
}
