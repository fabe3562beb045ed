//! The plugin's clouds held to `atmo clouds`' CPU picture: the same particles, camera
//! and sun, lit by the same sky, in front of the same sky, with MSAA 4x and a mesh in
//! front of the cloud.

use crate::common::{
    app, around_the_box, atmo_camera, black_box, radiance, settled, HEIGHT, WIDTH,
};
use atmo::clouds::render::CloudLight;
use atmo::clouds::{Cumulus, Particle, Splat};
use atmo::cloudscape::{haze_before, CpuClouds};
use atmo::image::{Display, ToneMap};
use atmo::sky::{Daylight, SkyPicture, SkySettings, View};
use atmo::view::{Camera as AtmoCamera, Fov, Sun};
use bevy::prelude::*;
use bevy_atmo::prelude::*;

/// The camera's place, m.
const EYE: Vec3 = Vec3::new(0.0, 1000.0, 0.0);

/// Where the cloud's base is centred, m: 1.5 km north of the camera, 500 m above it.
const CLOUD: Vec3 = Vec3::new(0.0, 1500.0, -1500.0);

/// The comparison's display: the cloud's bright side near the top of the range.
const DISPLAY: Display = Display {
    exposure: 0.02,
    tone: ToneMap::Exponential,
};

/// The sun behind the camera, to its right, 35 deg up.
fn sun() -> Sun {
    Sun::from_degrees(35.0, 150.0).unwrap()
}

/// A 400 m cumulus of 1,500 particles, its base's centre at the origin.
fn particles() -> Vec<Particle> {
    Cumulus {
        particles: 1500,
        width: 400.0,
        base: 0.0,
        ..Cumulus::default()
    }
    .generate()
}

fn looking() -> Vec3 {
    (CLOUD + Vec3::Y * 150.0 - EYE).normalize()
}

/// The CPU's picture: the sky of the camera's altitude, the cloud over it lit by the
/// sky of the cloud's, through the air in front of it (the plugin's light).
fn reference() -> atmo::image::Frame {
    let sun = sun();
    let earth = atmo::Atmosphere::earth();
    let model = atmo::sky::SkyModel::new(&earth, &settings(), EYE.y.into()).unwrap();
    let view = View {
        camera: atmo_camera(looking()),
        sun_disc: false,
    };
    let sky = SkyPicture::new(&model, sun).render(&view);
    let placed: Vec<Particle> = particles()
        .into_iter()
        .map(|p| Particle {
            position: p.position + CLOUD,
            ..p
        })
        .collect();
    let centre = atmo::cloudscape::Cloudscape::centre_of(&placed);
    let daylight = Daylight::new(&earth, &settings(), centre.y.into()).unwrap();
    let clouds = AtmoClouds::from_particles(Vec::new());
    let light = CloudLight {
        to_sun: sun.toward(),
        sun: daylight.sunlight(sun),
        ambient: atmo::clouds::SkyLight::from_map(&daylight.skylight_map(sun)),
        phase: clouds.phase,
        haze: haze_before(&model, sun, centre - EYE).unwrap(),
        scattering: clouds.scattering,
    };
    let camera = AtmoCamera::look_at(
        EYE,
        EYE + looking(),
        Vec3::Y,
        Fov::Vertical(45.0),
        (WIDTH, HEIGHT),
    )
    .unwrap();
    let mut cpu = CpuClouds::new(RESOLUTION);
    cpu.light(&placed, sun.toward(), 0.0, Splat::Pieces)
        .unwrap();
    cpu.draw(&placed, &camera, &light, Some(&sky)).unwrap()
}

/// Every order on a coarse model (a fraction of a second to build, where the
/// default's takes seconds): the plugin's sky and its light at the cloud are made with
/// the sky camera's settings, the reference's with the same.
fn settings() -> SkySettings {
    SkySettings {
        directions: 16,
        shells: 24,
        scattering_directions: 32,
        ..SkySettings::default()
    }
}

/// Intensity buffer voxels a side, the plugin's and the CPU's.
const RESOLUTION: usize = 64;

#[test]
fn the_cloud_is_atmo_clouds_behind_a_mesh_with_msaa_4x() {
    let sky = AtmoSky {
        sun_disc: false,
        aerial_perspective: false,
        sky_light: SkyLight::Off,
        source: SkySource::Model {
            settings: settings(),
            rebuild_after_m: 500.0,
        },
        ..AtmoSky::earth()
    };
    let Some(mut app) = app((
        sky,
        Msaa::Sample4,
        Transform::from_translation(EYE).looking_to(looking(), Vec3::Y),
    )) else {
        return;
    };
    let world = app.world_mut();
    world.spawn((
        AtmoSun,
        Transform::default().looking_to(-sun().toward(), Vec3::Y),
    ));
    world.spawn((
        AtmoClouds {
            resolution: RESOLUTION,
            ..AtmoClouds::from_particles(particles())
        },
        Transform::from_translation(CLOUD),
    ));
    // A black box straight ahead, 200 m away and 20 m wide, in front of the cloud.
    black_box(world, EYE + 200.0 * looking(), 20.0, looking());
    let frame = radiance(&settled(&mut app));
    let want = reference();
    if let Ok(dir) = std::env::var("ATMO_TEST_PICTURES") {
        let dir = std::path::Path::new(&dir);
        frame
            .write(&dir.join("bevy-clouds.png"), DISPLAY.exposure, DISPLAY.tone)
            .unwrap();
        want.write(&dir.join("atmo-clouds.png"), DISPLAY.exposure, DISPLAY.tone)
            .unwrap();
    }
    // The box: (10 / 200) / tan(22.5 deg) of the half-height, 12 %, about +-6.5
    // pixels; inside +-4 it is black, outside +-9 the picture is atmo's.
    let outside = around_the_box(&frame, 4, 9);
    let (cx, cy) = (WIDTH / 2, HEIGHT / 2);
    // The cloud is there: far brighter than the sky around it.
    let (middle, corner) = (want.pixels[(cy * WIDTH + cx + 14) as usize], want.pixels[0]);
    assert!(
        middle.y > 3.0 * corner.y,
        "cloud {middle} against sky {corner}"
    );
    let e = frame.level_errors_over(&want, DISPLAY, outside);
    eprintln!(
        "plugin vs atmo clouds, MSAA 4x, around the box: RMS {:.3}, max {:.3} levels",
        e.rms, e.max
    );
    assert!(e.rms <= 1.0, "RMS {:.3} levels (bound 1)", e.rms);
}
