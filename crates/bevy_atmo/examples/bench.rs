//! The frame time of one scene drawn with bevy_atmo (atmo's every-order sky, alone, with
//! its aerial perspective, with its environment map light too, and with the aerial
//! perspective and a cumulus of 20,000 particles), against the same
//! scene without a sky and with Bevy's own `Atmosphere` (Hillaire 2020: its LUTs, sky
//! and aerial perspective), in the same run: a JSON line a case as `atmo bench --json`
//! prints, the ratio the baseline's time over atmo's.
//!
//! ```text
//! cargo run -p bevy_atmo --example bench -- [--frames N] [--size WxH] [--msaa N] [--json]
//! ```
//! Headless (no window): a plain with towers, a camera at 300 m rendering into an HDR
//! image with MSAA 4x and Bevy's tone mapping, the sun at 20 deg. Each frame is an
//! `App::update` then a wait for the GPU to finish it; the median of N frames (30) after
//! a warm-up (and, for atmo, once its model is built) is the figure.

use std::time::Instant;

use bevy::camera::{Exposure, RenderTarget};
use bevy::core_pipeline::tonemapping::Tonemapping;
use bevy::light::atmosphere::ScatteringMedium;
use bevy::light::Atmosphere;
use bevy::pbr::AtmosphereSettings;
use bevy::prelude::*;
use bevy::render::render_resource::TextureFormat;
use bevy::render::renderer::{RenderAdapterInfo, RenderDevice};
use bevy::render::RenderApp;
use bevy_atmo::prelude::*;

mod scene;

/// Whose sky the scene is drawn with: none (Bevy's clear colour), Bevy's Atmosphere,
/// or atmo's (with or without its aerial perspective, its environment map light and a
/// cloud).
#[derive(Clone, Copy)]
enum Sky {
    None,
    Bevy,
    Atmo {
        aerial: bool,
        light: bool,
        cloud: bool,
    },
}

fn main() {
    let value = scene::option;
    let frames: usize = value("--frames").map_or(30, |f| f.parse().expect("--frames: a count"));
    let (width, height) = value("--size").map_or((1280, 720), |s| {
        let (w, h) = s.split_once('x').expect("--size: WIDTHxHEIGHT");
        (
            w.parse().expect("--size: width"),
            h.parse().expect("--size: height"),
        )
    });
    let size = (width, height);
    let msaa: u32 = value("--msaa").map_or(4, |m| m.parse().expect("--msaa: 1, 2, 4 or 8"));
    let params = serde_json::json!({
        "width": width, "height": height, "msaa": msaa, "frames": frames,
        "sun_elevation_deg": 20, "altitude_m": 300,
    });
    let json = scene::switch("--json");
    let (none_ms, device) = median_frame_ms(Sky::None, frames, size, msaa);
    let none = "the same scene without a sky (Bevy's clear colour)";
    let cases = [
        (
            "bevy.sky",
            Sky::Atmo {
                aerial: false,
                light: false,
                cloud: false,
            },
            none,
        ),
        (
            "bevy.sky-and-haze",
            Sky::Atmo {
                aerial: true,
                light: false,
                cloud: false,
            },
            none,
        ),
        (
            "bevy.sky-haze-and-light",
            Sky::Atmo {
                aerial: true,
                light: true,
                cloud: false,
            },
            none,
        ),
        (
            "bevy.sky-haze-and-cloud",
            Sky::Atmo {
                aerial: true,
                light: false,
                cloud: true,
            },
            none,
        ),
    ];
    // What Bevy's Atmosphere draws (a sky and the haze on the scene) is the sky-and-haze
    // case's.
    let mut sky_and_haze_ms = 0.0;
    for (bench, sky, baseline) in cases {
        let atmo_ms = median_frame_ms(sky, frames, size, msaa).0;
        if bench == "bevy.sky-and-haze" {
            sky_and_haze_ms = atmo_ms;
        }
        report(json, bench, &params, &device, atmo_ms, baseline, none_ms);
    }
    // Last: Bevy's Atmosphere crashes lavapipe 22.3 (it runs on lavapipe 25:
    // scripts/lavapipe-25.sh).
    let (bevy_ms, _) = median_frame_ms(Sky::Bevy, frames, size, msaa);
    let baseline = "Bevy's Atmosphere (Hillaire 2020), its defaults: its sky and haze";
    report(
        json,
        "bevy.against-bevy-atmosphere",
        &params,
        &device,
        sky_and_haze_ms,
        baseline,
        bevy_ms,
    );
}

/// Prints a case: a line of JSON as `atmo bench --json` prints, or a sentence.
fn report(
    json: bool,
    bench: &str,
    params: &serde_json::Value,
    device: &str,
    median_ms: f64,
    baseline: &str,
    baseline_median_ms: f64,
) {
    let ratio = baseline_median_ms / median_ms;
    if json {
        let line = serde_json::json!({
            "bench": bench,
            "command": "cargo run -p bevy_atmo --example bench -- --json",
            "params": params,
            "device": device,
            "median_ms": median_ms,
            "baseline": baseline,
            "baseline_median_ms": baseline_median_ms,
            "ratio": ratio,
        });
        println!("{line}");
    } else {
        println!("{bench} on {device}: {median_ms:.2} ms a frame; {baseline}: {baseline_median_ms:.2} ms (ratio {ratio:.3})");
    }
    use std::io::Write as _;
    let _ = std::io::stdout().flush();
}

/// The median time of `frames` frames of the scene with `sky`, ms, and the adapter's name
/// and driver.
fn median_frame_ms(sky: Sky, frames: usize, size: (u32, u32), msaa: u32) -> (f64, String) {
    let mut app = scene::headless_app();
    scene(app.world_mut(), sky, size, msaa);
    let render = app.sub_app(RenderApp).world();
    let device = render.resource::<RenderDevice>().clone();
    let info = render.resource::<RenderAdapterInfo>();
    let adapter = format!("{} ({})", info.name, info.driver_info);
    let frame = |app: &mut App| {
        let start = Instant::now();
        app.update();
        device
            .wgpu_device()
            .poll(bevy::render::render_resource::PollType::wait_indefinitely())
            .expect("the GPU finished the frame");
        start.elapsed().as_secs_f64() * 1e3
    };
    // Warm-up: pipelines, and atmo's models (built on a background thread).
    let mut ready = 0;
    while ready < 10 {
        frame(&mut app);
        let built = scene::built(app.world_mut());
        ready = if built { ready + 1 } else { 0 };
        assert!(app.should_exit().is_none(), "the renderer stopped the app");
    }
    let mut times: Vec<f64> = (0..frames).map(|_| frame(&mut app)).collect();
    times.sort_by(f64::total_cmp);
    (times[times.len() / 2], adapter)
}

/// The scene: the flight's plain and towers, the sun at 20 deg, and the camera at 300 m
/// with `sky`.
fn scene(world: &mut World, sky: Sky, (width, height): (u32, u32), msaa: u32) {
    let image = Image::new_target_texture(width, height, TextureFormat::Rgba8UnormSrgb, None);
    let image = world.resource_mut::<Assets<Image>>().add(image);
    let mut camera = world.spawn((
        Camera3d::default(),
        RenderTarget::Image(image.into()),
        Exposure { ev100: 13.0 },
        Tonemapping::AcesFitted,
        Msaa::from_samples(msaa),
        Transform::from_xyz(0.0, 300.0, 0.0).looking_to(Vec3::new(0.3, -0.06, -1.0), Vec3::Y),
    ));
    let toward_sun = atmo::view::direction_of(120f64.to_radians(), 20f64.to_radians()).as_vec3();
    let sun = Transform::default().looking_to(-toward_sun, Vec3::Y);
    match sky {
        Sky::None => {
            world.spawn((DirectionalLight::default(), sun));
        }
        Sky::Atmo {
            aerial,
            light,
            cloud,
        } => {
            let earth = AtmoSky::earth();
            camera.insert(AtmoSky {
                aerial_perspective: aerial,
                sky_light: if light {
                    earth.sky_light
                } else {
                    SkyLight::Off
                },
                ..earth
            });
            world.spawn((AtmoSun, sun));
            if cloud {
                // The flight's nearer cumulus, in view ahead.
                world.spawn((
                    AtmoClouds::cumulus(20_000),
                    Transform::from_xyz(-1200.0, 1200.0, -5000.0),
                ));
            }
        }
        Sky::Bevy => {
            camera.insert(AtmosphereSettings::default());
            let medium = world
                .resource_mut::<Assets<ScatteringMedium>>()
                .add(ScatteringMedium::default());
            world.spawn(Atmosphere::earth(medium));
            world.spawn((
                DirectionalLight {
                    illuminance: bevy::light::light_consts::lux::RAW_SUNLIGHT,
                    ..default()
                },
                sun,
            ));
        }
    }
    scene::plain_and_towers(
        world,
        StandardMaterial {
            base_color: Color::srgb(0.3, 0.35, 0.2),
            perceptual_roughness: 0.95,
            ..default()
        },
    );
}
