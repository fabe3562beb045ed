//! A cloud (the clouds paper): a generated cumulus lit by the sun through the 3-D
//! intensity buffer, drawn as billboards, with sunlight and skylight from the sky
//! module's atmosphere.
//!
//! `cargo run --release -p atmo --example cloud -- cloud.png`

use atmo::atmosphere::PhaseFunction;
use atmo::clouds::{render, Cumulus, Haze, IntensityBuffer, Lighting, Scattering, SkyLight, Splat};
use atmo::sky::{Daylight, SkySettings};
use atmo::view::{Camera, Fov, Sun};
use atmo::Atmosphere;
use glam::Vec3;

fn main() -> atmo::Result<()> {
    let out = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "cloud.png".into());
    let particles = Cumulus {
        particles: 20_000,
        ..Cumulus::default()
    }
    .generate();
    let sun = Sun::from_degrees(25.0, 40.0)?;
    // The sun's transmittance inside the cloud, in a 128^3 buffer oriented to the sun.
    let buffer = IntensityBuffer::new(&particles, sun.toward(), 128, 0.0, Splat::Pieces)?;
    // The sky's light at the cloud's height.
    let centre = particles.iter().map(|p| p.position).sum::<Vec3>() / particles.len() as f32;
    let daylight = Daylight::new(
        &Atmosphere::earth(),
        &SkySettings::default(),
        centre.y as f64,
    )?;
    let light = Lighting {
        to_sun: sun.toward(),
        sun: daylight.sunlight(sun),
        ambient: SkyLight::from_harmonics(&daylight.skylight(sun)),
        phase: PhaseFunction::CloudMie,
        haze: Haze::CLEAR,
        // Every order of scattering (Scattering::SINGLE: the paper's single scattering).
        scattering: Scattering::MULTIPLE,
    };
    let eye = centre + Vec3::new(-1500.0, -300.0, 2500.0);
    let camera = Camera::look_at(eye, centre, Vec3::Y, Fov::Vertical(40.0), (960, 540))?;
    let frame = render(&particles, &buffer, &camera, &light, None)?;
    frame.write(
        std::path::Path::new(&out),
        0.15,
        atmo::image::ToneMap::Exponential,
    )?;
    println!("wrote {out}");
    Ok(())
}
