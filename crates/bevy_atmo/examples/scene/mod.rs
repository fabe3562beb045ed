//! What the examples and the tests share: a headless app with the plugin, whether
//! atmo has built what it draws, and the flight's plain with its towers.

#![allow(dead_code)] // each example and test uses its own part

use bevy::app::PluginsState;
use bevy::prelude::*;
use bevy::render::pipelined_rendering::PipelinedRenderingPlugin;
use bevy::render::RenderPlugin;
use bevy::window::ExitCondition;
use bevy::winit::WinitPlugin;
use bevy_atmo::prelude::*;

/// An app with Bevy's renderer on whatever adapter there is, no window, frames rendered
/// in order (no pipelined rendering, pipelines compiled when asked for), and the
/// plugin; its plugins finished, ready for `update`.
pub fn headless_app() -> App {
    let mut app = App::new();
    app.add_plugins(
        DefaultPlugins
            .set(WindowPlugin {
                primary_window: None,
                exit_condition: ExitCondition::DontExit,
                ..default()
            })
            .set(RenderPlugin {
                synchronous_pipeline_compilation: true,
                ..default()
            })
            .disable::<PipelinedRenderingPlugin>()
            .disable::<WinitPlugin>(),
    )
    .add_plugins(AtmoPlugin);
    // The renderer is made asynchronously: wait for it, then finish the plugins.
    while app.plugins_state() == PluginsState::Adding {
        bevy::tasks::tick_global_task_pools_on_main_thread();
    }
    app.finish();
    app.cleanup();
    app
}

/// The value after `flag` on the command line (`--frames 30`), if it is there.
pub fn option(flag: &str) -> Option<String> {
    let args: Vec<String> = std::env::args().collect();
    args.iter()
        .position(|a| a == flag)
        .and_then(|i| args.get(i + 1))
        .cloned()
}

/// Whether `flag` is on the command line (`--json`).
pub fn switch(flag: &str) -> bool {
    std::env::args().any(|a| a == flag)
}

/// Whether every sky and every cloud in `world` is ready and none is being built again
/// (their models are built on background threads: seconds).
pub fn built(world: &mut World) -> bool {
    let mut skies = world.query::<&AtmoSkyState>();
    let mut clouds = world.query::<&AtmoCloudsState>();
    skies.iter(world).all(|s| s.is_ready() && !s.is_building())
        && clouds.iter(world).all(|c| c.is_ready() && !c.is_building())
}

/// A plain 160 km across of `ground` at y = 0, and towers 120 m tall (half of them
/// below it) every 2 km out to 40 km, in three rows bending east.
pub fn plain_and_towers(world: &mut World, ground: StandardMaterial) {
    let mut meshes = world.resource_mut::<Assets<Mesh>>();
    let plain = meshes.add(Plane3d::default().mesh().size(160_000.0, 160_000.0));
    let tower = meshes.add(Cuboid::new(60.0, 240.0, 60.0));
    let mut materials = world.resource_mut::<Assets<StandardMaterial>>();
    let ground = materials.add(ground);
    let concrete = materials.add(StandardMaterial {
        base_color: Color::srgb(0.55, 0.53, 0.5),
        perceptual_roughness: 0.9,
        ..default()
    });
    world.spawn((Mesh3d(plain), MeshMaterial3d(ground)));
    for row in -1..=1 {
        for k in 1..=20 {
            let distance = 2000.0 * k as f32;
            world.spawn((
                Mesh3d(tower.clone()),
                MeshMaterial3d(concrete.clone()),
                Transform::from_xyz(row as f32 * 1500.0 + 0.3 * distance, 0.0, -distance),
            ));
        }
    }
}
