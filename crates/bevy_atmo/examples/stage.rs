//! A stage in haze: three moving spotlights (one through a gobo) sweep over a floor,
//! their beams scattered by atmo's sample planes (shafts), a sphere and a truss cutting
//! shadows into them; Bevy lights the surfaces with the same spotlights.
//!
//! ```text
//! cargo run --release -p bevy_atmo --example stage
//! cargo run --release -p bevy_atmo --example stage -- --screenshot stage.png
//! ```
//! Space pauses the lights. `--screenshot FILE` saves the window after a few frames
//! and exits.

use std::f32::consts::PI;
use std::path::Path;

use bevy::camera::{ClearColorConfig, Exposure};
use bevy::core_pipeline::tonemapping::Tonemapping;
use bevy::light::GlobalAmbientLight;
use bevy::prelude::*;
use bevy::render::view::screenshot::{save_to_disk, Screenshot};
use bevy_atmo::prelude::*;

/// The room: 16 m wide, 12 deep, 7 high, the haze filling it.
const ROOM: Vec3 = Vec3::new(16.0, 7.0, 12.0);

fn main() {
    let screenshot = std::env::args().skip_while(|a| a != "--screenshot").nth(1);
    App::new()
        .add_plugins(DefaultPlugins.set(WindowPlugin {
            primary_window: Some(Window {
                title: "atmo in Bevy: stage".into(),
                resolution: (960, 540).into(),
                ..default()
            }),
            ..default()
        }))
        .add_plugins(AtmoPlugin)
        // A dim house light: the room shows where the beams do not reach.
        .insert_resource(GlobalAmbientLight {
            brightness: 3.0,
            ..GlobalAmbientLight::NONE
        })
        .insert_resource(Shot(screenshot, 0))
        .insert_resource(Show {
            time_s: 1.2,
            playing: true,
        })
        .add_systems(Startup, setup)
        .add_systems(Update, (play, sweep, screenshot_after_a_while).chain())
        .run();
}

/// The show's clock, s, and whether it runs.
#[derive(Resource)]
struct Show {
    time_s: f32,
    playing: bool,
}

/// Where to save a screenshot, and the frames drawn.
#[derive(Resource)]
struct Shot(Option<String>, u32);

/// A moving head: where it hangs and how it sweeps (a phase of the show's clock).
#[derive(Component)]
struct Head {
    at: Vec3,
    phase: f32,
}

fn setup(
    mut commands: Commands,
    mut meshes: ResMut<Assets<Mesh>>,
    mut materials: ResMut<Assets<StandardMaterial>>,
) {
    let (w, h, d) = (ROOM.x, ROOM.y, ROOM.z);
    commands.spawn((
        Camera3d::default(),
        AtmoHaze {
            extinction: 0.08,
            bounds: Some((
                Vec3::new(-w / 2.0, 0.0, -d / 2.0),
                Vec3::new(w / 2.0, h, d / 2.0),
            )),
            ..AtmoHaze::default()
        },
        Camera {
            clear_color: ClearColorConfig::Custom(Color::BLACK),
            ..default()
        },
        Exposure { ev100: 4.5 },
        Tonemapping::AcesFitted,
        Projection::Perspective(PerspectiveProjection {
            fov: 60f32.to_radians(),
            ..default()
        }),
        Transform::from_xyz(0.0, 2.4, d / 2.0 - 0.3)
            .looking_at(Vec3::new(0.0, 3.0, -d / 2.0), Vec3::Y),
    ));
    let surface = |materials: &mut Assets<StandardMaterial>, grey: f32| {
        materials.add(StandardMaterial {
            base_color: Color::linear_rgb(grey, grey, grey),
            perceptual_roughness: 0.9,
            ..default()
        })
    };
    let floor = surface(&mut materials, 0.3);
    let wall = surface(&mut materials, 0.5);
    let steel = surface(&mut materials, 0.15);
    commands.spawn((
        Mesh3d(meshes.add(Plane3d::default().mesh().size(w, d))),
        MeshMaterial3d(floor),
    ));
    commands.spawn((
        Mesh3d(meshes.add(Plane3d::new(Vec3::Z, Vec2::ONE).mesh().size(w, h))),
        MeshMaterial3d(wall.clone()),
        Transform::from_xyz(0.0, h / 2.0, -d / 2.0),
    ));
    commands.spawn((
        Mesh3d(meshes.add(Sphere::new(0.8).mesh().ico(4).expect("a small ico sphere"))),
        MeshMaterial3d(wall),
        Transform::from_xyz(1.5, 0.8, -2.0),
    ));
    // A truss over the stage: a 10 m beam of two chords and their struts on two legs.
    let truss_at = Vec3::new(0.0, 4.2, 0.1);
    let mut bar = |length: f32, along: Vec3| {
        let size = Vec3::splat(0.08) + along * (length - 0.08);
        meshes.add(Cuboid::from_size(size))
    };
    let chord = bar(10.0, Vec3::X);
    let strut = bar(0.6, Vec3::Y);
    let leg = bar(4.2, Vec3::Y);
    for y in [0.0, 0.6] {
        commands.spawn((
            Mesh3d(chord.clone()),
            MeshMaterial3d(steel.clone()),
            Transform::from_translation(truss_at + Vec3::Y * y),
        ));
    }
    for k in 0..=16 {
        let x = -5.0 + 10.0 * k as f32 / 16.0;
        commands.spawn((
            Mesh3d(strut.clone()),
            MeshMaterial3d(steel.clone()),
            Transform::from_translation(truss_at + Vec3::new(x, 0.3, 0.0))
                .with_rotation(Quat::from_rotation_z(if k % 2 == 0 { 0.5 } else { -0.5 })),
        ));
    }
    for x in [-5.0, 5.0] {
        commands.spawn((
            Mesh3d(leg.clone()),
            MeshMaterial3d(steel.clone()),
            Transform::from_xyz(x, 2.1, truss_at.z),
        ));
    }
    // Three heads above the truss, warm, white and cool, each 6000 cd on its axis; the
    // white one projects a gobo of spokes.
    let spokes = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/gobos/spokes.png");
    let gobo = AtmoBeam::default()
        .with_gobo(&spokes)
        .expect("the repository's gobo");
    for (k, colour) in [
        Color::srgb(1.0, 0.75, 0.5),
        Color::WHITE,
        Color::srgb(0.6, 0.75, 1.0),
    ]
    .into_iter()
    .enumerate()
    {
        let at = Vec3::new(-4.0 + 4.0 * k as f32, 6.5, 1.0);
        commands.spawn((
            if k == 1 {
                gobo.clone()
            } else {
                AtmoBeam::default()
            },
            SpotLight {
                color: colour,
                intensity: 6000.0 * 4.0 * PI,
                range: 30.0,
                inner_angle: 8f32.to_radians(),
                outer_angle: 13f32.to_radians(),
                shadow_maps_enabled: true,
                ..default()
            },
            Head {
                at,
                phase: 2.1 * k as f32,
            },
            Transform::from_translation(at),
        ));
    }
}

/// Space pauses and restarts the show's clock.
fn play(keys: Res<ButtonInput<KeyCode>>, time: Res<Time>, mut show: ResMut<Show>) {
    if keys.just_pressed(KeyCode::Space) {
        show.playing = !show.playing;
    }
    if show.playing {
        show.time_s += time.delta_secs();
    }
}

/// Each head sweeps its beam over the stage: a slow figure of eight on the floor.
fn sweep(show: Res<Show>, mut heads: Query<(&Head, &mut Transform)>) {
    let t = 0.35 * show.time_s;
    for (head, mut transform) in &mut heads {
        let (a, b) = (t + head.phase, 2.0 * (t + head.phase));
        let target = Vec3::new(head.at.x * 0.4 + 3.0 * a.sin(), 0.0, -2.0 + 1.5 * b.sin());
        *transform = Transform::from_translation(head.at).looking_at(target, Vec3::Y);
    }
}

/// With `--screenshot FILE`: saves the window at the tenth frame (the lights paused
/// from the first), then exits once it is written.
fn screenshot_after_a_while(
    mut commands: Commands,
    mut shot: ResMut<Shot>,
    mut show: ResMut<Show>,
    mut exit: MessageWriter<AppExit>,
) {
    let Some(path) = shot.0.clone() else {
        return;
    };
    show.playing = false;
    shot.1 += 1;
    if shot.1 == 10 {
        commands
            .spawn(Screenshot::primary_window())
            .observe(save_to_disk(path));
    }
    if shot.1 == 20 {
        exit.write(AppExit::Success);
    }
}
