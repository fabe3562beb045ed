//! A flight over a checkered plain toward rows of towers and cumulus clouds: atmo's
//! every-order sky behind them, the sun as Bevy's directional light (its colour and
//! illuminance from atmo), the aerial perspective fading the far towers into the sky's
//! own colour, and the clouds lit by the same sun and sky.
//!
//! ```text
//! cargo run --release -p bevy_atmo --example flight
//! cargo run --release -p bevy_atmo --example flight -- --screenshot flight.png
//! ```
//! W/S: forward and back; A/D: turn; R/F: climb and descend (the sky is rebuilt for a
//! new altitude every 500 m, in the background); Up/Down and Left/Right: the sun's
//! elevation and azimuth. `--screenshot FILE` saves the window once the sky is built
//! and exits.

use bevy::camera::Exposure;
use bevy::core_pipeline::tonemapping::Tonemapping;
use bevy::prelude::*;
use bevy::render::render_resource::{Extent3d, TextureDimension, TextureFormat};
use bevy::render::view::screenshot::{save_to_disk, Screenshot};
use bevy_atmo::prelude::*;

mod scene;

/// The camera's height above the plain at the start, m.
const START_ALTITUDE_M: f32 = 300.0;

fn main() {
    let screenshot = std::env::args().skip_while(|a| a != "--screenshot").nth(1);
    App::new()
        .add_plugins(DefaultPlugins.set(WindowPlugin {
            primary_window: Some(Window {
                title: "atmo in Bevy: flight".into(),
                resolution: (1280, 720).into(),
                ..default()
            }),
            ..default()
        }))
        .add_plugins(AtmoPlugin)
        .insert_resource(Shot(screenshot, 0))
        .insert_resource(SunAngles {
            elevation_deg: 20.0,
            azimuth_deg: 120.0,
        })
        .add_systems(Startup, setup)
        .add_systems(Update, (fly, move_sun, screenshot_when_built))
        .run();
}

/// The sun's place on the sky, degrees (azimuth clockwise from north, -z).
#[derive(Resource)]
struct SunAngles {
    elevation_deg: f32,
    azimuth_deg: f32,
}

/// Where to save a screenshot, and the frames the sky has been ready for.
#[derive(Resource)]
struct Shot(Option<String>, u32);

fn setup(world: &mut World) {
    world.spawn((
        Camera3d::default(),
        AtmoSky::earth(),
        Exposure { ev100: 13.0 },
        Tonemapping::AcesFitted,
        Projection::Perspective(PerspectiveProjection {
            fov: 50f32.to_radians(),
            far: 200_000.0,
            ..default()
        }),
        Transform::from_xyz(0.0, START_ALTITUDE_M, 0.0)
            .looking_to(Vec3::new(0.3, -0.06, -1.0), Vec3::Y),
    ));
    world.spawn((AtmoSun, DirectionalLight::default(), Transform::default()));
    // Two cumulus ahead: the paper's largest, and a smaller one nearer and to the left.
    for (particles, seed, width, at) in [
        (60_134, 1, 1200.0, Vec3::new(3500.0, 1400.0, -9000.0)),
        (20_000, 7, 700.0, Vec3::new(-1200.0, 1200.0, -5000.0)),
    ] {
        let cumulus = atmo::clouds::Cumulus {
            particles,
            seed,
            width,
            base: 0.0,
            ..default()
        };
        world.spawn((
            AtmoClouds::from_particles(cumulus.generate()),
            Transform::from_translation(at),
        ));
    }
    // Fields of 1.25 km: a checker texture of nearest texels over the plain.
    let checker = world
        .resource_mut::<Assets<Image>>()
        .add(checker_image(256, 128));
    let ground = StandardMaterial {
        base_color_texture: Some(checker),
        perceptual_roughness: 0.95,
        ..default()
    };
    scene::plain_and_towers(world, ground);
}

/// A `texels` square checker of `cells` x `cells` fields, in two greens and browns.
fn checker_image(texels: u32, cells: u32) -> Image {
    let side = texels / cells;
    let mut data = Vec::with_capacity((texels * texels * 4) as usize);
    for y in 0..texels {
        for x in 0..texels {
            let dark = ((x / side) + (y / side)).is_multiple_of(2);
            let rgb = if dark { [62, 82, 40] } else { [112, 104, 70] };
            data.extend_from_slice(&[rgb[0], rgb[1], rgb[2], 255]);
        }
    }
    let mut image = Image::new(
        Extent3d {
            width: texels,
            height: texels,
            depth_or_array_layers: 1,
        },
        TextureDimension::D2,
        data,
        TextureFormat::Rgba8UnormSrgb,
        default(),
    );
    image.sampler = bevy::image::ImageSampler::nearest();
    image
}

/// W/S forward and back, A/D turn, R/F up and down: a flight at 250 m/s.
fn fly(
    keys: Res<ButtonInput<KeyCode>>,
    time: Res<Time>,
    mut camera: Single<&mut Transform, With<Camera3d>>,
) {
    let dt = time.delta_secs();
    let forward = camera.forward().with_y(0.0).normalize_or_zero();
    let mut step = Vec3::ZERO;
    for (key, direction) in [
        (KeyCode::KeyW, forward),
        (KeyCode::KeyS, -forward),
        (KeyCode::KeyR, Vec3::Y),
        (KeyCode::KeyF, -Vec3::Y),
    ] {
        if keys.pressed(key) {
            step += direction;
        }
    }
    camera.translation += 250.0 * dt * step;
    camera.translation.y = camera.translation.y.max(2.0);
    let turn = keys.pressed(KeyCode::KeyA) as i32 - keys.pressed(KeyCode::KeyD) as i32;
    camera.rotate_y(0.6 * dt * turn as f32);
}

/// Up/Down and Left/Right move the sun at 5 degrees a second.
fn move_sun(
    keys: Res<ButtonInput<KeyCode>>,
    time: Res<Time>,
    mut angles: ResMut<SunAngles>,
    mut sun: Single<&mut Transform, With<AtmoSun>>,
) {
    let rate = 5.0 * time.delta_secs();
    let axis = |plus, minus| (keys.pressed(plus) as i32 - keys.pressed(minus) as i32) as f32;
    angles.elevation_deg = (angles.elevation_deg
        + rate * axis(KeyCode::ArrowUp, KeyCode::ArrowDown))
    .clamp(-10.0, 90.0);
    angles.azimuth_deg += rate * axis(KeyCode::ArrowRight, KeyCode::ArrowLeft);
    let toward = atmo::view::direction_of(
        f64::from(angles.azimuth_deg).to_radians(),
        f64::from(angles.elevation_deg).to_radians(),
    )
    .as_vec3();
    // The light travels away from the sun; straight up, any "up" will do.
    let up = if toward.y.abs() > 0.999 {
        Vec3::Z
    } else {
        Vec3::Y
    };
    **sun = Transform::default().looking_to(-toward, up);
}

/// With `--screenshot FILE`: saves the window ten frames after the sky and the clouds
/// are built, then exits once it is written.
fn screenshot_when_built(world: &mut World) {
    let Some(path) = world.resource::<Shot>().0.clone() else {
        return;
    };
    if !scene::built(world) {
        return;
    }
    let mut shot = world.resource_mut::<Shot>();
    shot.1 += 1;
    let frames = shot.1;
    if frames == 10 {
        world
            .spawn(Screenshot::primary_window())
            .observe(save_to_disk(path));
    }
    if frames == 40 {
        world.write_message(AppExit::Success);
    }
}
