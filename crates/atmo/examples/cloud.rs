//! A cumulus in front of the sky, lit and hazed by the Earth's atmosphere, every order:
//! `cargo run --release -p atmo --example cloud -- cloud.png`

use atmo::clouds::{Cumulus, Scattering, Splat};
use atmo::cloudscape::{Ambient, Cloudscape, CpuClouds};
use atmo::view::{Camera, Fov, Sun};
use glam::Vec3;

fn main() -> atmo::Result<()> {
    let out = std::env::args().nth(1).unwrap_or("cloud.png".into());
    let calm = Cumulus {
        particles: 20_000,
        ..Cumulus::default()
    }
    .generate();
    let scene = Cloudscape {
        calm,
        resolution: 128,
        forward: 0.0,
        splat: Splat::Pieces,
        phase: atmo::atmosphere::PhaseFunction::CloudMie,
        scattering: Scattering::SOLVE, // every order; Scattering::SINGLE is the paper's
        ambient: Ambient::Sky,
        sky: true,
        ground_albedo: None,
    };
    let particles = scene.blown(0.0);
    let centre = Cloudscape::centre_of(&particles);
    let eye = centre + Vec3::new(-1500.0, -300.0, 2500.0);
    let camera = Camera::look_at(eye, centre, Vec3::Y, Fov::Vertical(40.0), (960, 540))?;
    let sun = Sun::from_degrees(25.0, 40.0)?;
    let mut clouds = CpuClouds::new(scene.resolution);
    clouds.light(&particles, sun.toward(), scene.forward, scene.splat)?;
    let sky = scene.sky_around(&particles, &camera)?;
    let shadow = scene.shadow(&particles, sun, 256)?;
    let (light, behind) = scene.lighting(sky.as_ref(), shadow.as_ref(), sun, &camera)?;
    let frame = clouds.draw(&particles, &camera, &light, behind.as_ref())?;
    frame.write(out.as_ref(), 0.15, atmo::image::ToneMap::Exponential)
}
