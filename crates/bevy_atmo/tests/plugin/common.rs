//! A headless Bevy app with the plugin, rendering into an image that is read back: what
//! every test of the plugin shares.

use std::time::{Duration, Instant};

use bevy::camera::{Exposure, RenderTarget};
use bevy::core_pipeline::tonemapping::{DebandDither, Tonemapping};
use bevy::prelude::*;
use bevy::render::gpu_readback::{Readback, ReadbackComplete};
use bevy::render::render_resource::{TextureFormat, TextureUsages};

use crate::scene;

/// The picture's size: rows of 64 f32 RGBA pixels are 1024 bytes, a whole number of
/// wgpu's 256-byte copy rows, so the read-back has no padding.
pub const WIDTH: u32 = 192;
pub const HEIGHT: u32 = 108;

/// The camera's exposure: EV100 14 (a bright day), so a day sky is written near 0.3.
pub const EXPOSURE: Exposure = Exposure { ev100: 14.0 };

/// What the last read-back gave: RGBA f32 pixels, row-major.
#[derive(Resource, Default)]
struct Shot(Option<Vec<[f32; 4]>>);

/// Whether there is an adapter to render on. Without one a test says it skipped, as
/// atmo-gpu's do (a line `atmo-test: skipped TEST: WHY` past the capture), and passes;
/// in CI (`CI=true`) it fails instead, so a broken driver install cannot pass.
fn adapter() -> bool {
    match atmo_gpu::Gpu::new(None) {
        Ok(_) => true,
        Err(atmo_gpu::GpuError::NoAdapter { .. })
            if std::env::var("CI").as_deref() != Ok("true") =>
        {
            use std::io::Write as _;
            let test = std::thread::current()
                .name()
                .unwrap_or("a test")
                .to_string();
            let why = "no GPU adapter (install mesa-vulkan-drivers)";
            let _ = writeln!(std::io::stderr(), "atmo-test: skipped {test}: {why}");
            false
        }
        Err(e) => panic!("GPU setup failed: {e}"),
    }
}

/// An app with Bevy's renderer on whatever adapter there is (no window, frames rendered
/// in order), the plugin, and a camera with `camera` (plus the test's exposure, no tone
/// map, no dithering) rendering into an RGBA f32 image read back every frame; `None`
/// where there is no adapter outside CI ([`adapter`]).
pub fn app(camera: impl Bundle) -> Option<App> {
    if !adapter() {
        return None;
    }
    let mut app = scene::headless_app();
    app.init_resource::<Shot>();
    let mut image = Image::new_target_texture(WIDTH, HEIGHT, TextureFormat::Rgba32Float, None);
    image.texture_descriptor.usage |= TextureUsages::COPY_SRC;
    let image = app.world_mut().resource_mut::<Assets<Image>>().add(image);
    app.world_mut().spawn((
        Camera3d::default(),
        RenderTarget::Image(image.clone().into()),
        EXPOSURE,
        Tonemapping::None,
        DebandDither::Disabled,
        camera,
    ));
    app.world_mut().spawn(Readback::texture(image)).observe(
        |read: On<ReadbackComplete>, mut shot: ResMut<Shot>| {
            let pixels: &[[f32; 4]] = bytemuck::cast_slice(&read.data);
            shot.0 = Some(pixels.to_vec());
        },
    );
    Some(app)
}

/// Updates `app` until every sky and cloud has been ready for a few frames (its model is built on
/// a background thread: seconds; the GPU's copy is made a frame later, the read-back
/// comes a frame or two after that) and two read-backs in a row agree, and returns the
/// picture; panics after two minutes, or when the renderer has asked the app to exit
/// (a GPU error).
pub fn settled(app: &mut App) -> Vec<[f32; 4]> {
    let start = Instant::now();
    let mut last: Option<Vec<[f32; 4]>> = None;
    let mut ready_frames = 0;
    loop {
        app.update();
        assert!(
            app.should_exit().is_none(),
            "the renderer stopped the app (a GPU error; see the log)"
        );
        let done = scene::built(app.world_mut());
        ready_frames = if done { ready_frames + 1 } else { 0 };
        let shot = app.world_mut().resource_mut::<Shot>().0.take();
        if let (Some(shot), true) = (shot, ready_frames > 4) {
            if last.as_ref() == Some(&shot) {
                return shot;
            }
            last = Some(shot);
        }
        assert!(
            start.elapsed() < Duration::from_secs(120),
            "no settled picture after two minutes"
        );
        std::thread::sleep(Duration::from_millis(5));
    }
}

/// Luminance per radiance (683 lm/W) times the camera's exposure: what the plugin
/// multiplies atmo's radiance by.
pub fn scale() -> f32 {
    atmo::sky::lighting::LUMENS_PER_WATT as f32 * EXPOSURE.exposure()
}

/// A read-back as atmo's radiance.
pub fn radiance(shot: &[[f32; 4]]) -> atmo::image::Frame {
    let mut frame = atmo::image::Frame::new(WIDTH, HEIGHT);
    for (p, s) in frame.pixels.iter_mut().zip(shot) {
        *p = Vec3::new(s[0], s[1], s[2]) / scale();
    }
    frame
}

/// atmo's Earth at `altitude_m`, every order: what `AtmoSky::earth()` builds.
pub fn earth_model(altitude_m: f32) -> atmo::sky::SkyModel {
    let settings = atmo::sky::SkySettings::default();
    atmo::sky::SkyModel::new(&atmo::Atmosphere::earth(), &settings, altitude_m.into()).unwrap()
}

/// atmo's camera for a Bevy camera looking along `look` (y up) with Bevy's default
/// vertical field of view (45 deg), at the origin, of the test picture's size.
pub fn atmo_camera(look: Vec3) -> atmo::view::Camera {
    let fov = atmo::view::Fov::Vertical(45.0);
    atmo::view::Camera::look_at(Vec3::ZERO, look, Vec3::Y, fov, (WIDTH, HEIGHT)).unwrap()
}

/// Spawns a black unlit cube of `side` m at `centre`, facing `look`.
pub fn black_box(world: &mut World, centre: Vec3, side: f32, look: Vec3) {
    let mesh = world
        .resource_mut::<Assets<Mesh>>()
        .add(Cuboid::new(side, side, side));
    let material = world
        .resource_mut::<Assets<StandardMaterial>>()
        .add(StandardMaterial {
            base_color: Color::BLACK,
            unlit: true,
            ..default()
        });
    world.spawn((
        Mesh3d(mesh),
        MeshMaterial3d(material),
        Transform::from_translation(centre).looking_to(look, Vec3::Y),
    ));
}

/// Of a picture with a box in its middle, asserts that the pixels within `inside` of
/// the middle (in x and y) are black, and returns those farther than `outside`.
pub fn around_the_box(frame: &atmo::image::Frame, inside: i32, outside: i32) -> Vec<usize> {
    let (cx, cy) = (WIDTH as i32 / 2, HEIGHT as i32 / 2);
    let mut around = Vec::new();
    for y in 0..HEIGHT as i32 {
        for x in 0..WIDTH as i32 {
            let (dx, dy) = ((x - cx).abs(), (y - cy).abs());
            let i = (y * WIDTH as i32 + x) as usize;
            if dx.max(dy) <= inside {
                assert_eq!(frame.pixels[i], Vec3::ZERO, "pixel ({x}, {y}) of the box");
            } else if dx.max(dy) > outside {
                around.push(i);
            }
        }
    }
    around
}
