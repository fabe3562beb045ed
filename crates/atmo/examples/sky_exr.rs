//! The sky by the shell method (sky section 3) to a linear EXR: 7 km up, the sun 30 deg
//! high in the south-west, looking toward it.
//!
//! `cargo run --release -p atmo --example sky_exr -- sky.exr`

use atmo::sky::{SkyModel, SkyPicture, SkySettings, View};
use atmo::view::{Camera, Fov, Sun};
use atmo::Atmosphere;
use glam::Vec3;

fn main() -> atmo::Result<()> {
    let out = std::env::args().nth(1).unwrap_or_else(|| "sky.exr".into());
    let altitude_m = 7000.0;
    // Everything that does not depend on the sun, for one altitude: ~0.3 s.
    let model = SkyModel::new(&Atmosphere::earth(), &SkySettings::default(), altitude_m)?;
    // Then any sun with lookups only: a few milliseconds.
    let sun = Sun::from_degrees(30.0, 225.0)?;
    let eye = Vec3::new(0.0, altitude_m as f32, 0.0);
    let camera = Camera::yaw_pitch(eye, 225.0, 10.0, Fov::Vertical(70.0), (960, 540))?;
    let frame = SkyPicture::new(&model, sun).render(&View {
        camera,
        sun_disc: true,
    });
    // Linear radiance (the atmosphere's irradiance units per steradian); exposure and
    // tone map apply to .png only.
    frame.write(
        std::path::Path::new(&out),
        0.15,
        atmo::image::ToneMap::Exponential,
    )?;
    println!("wrote {out}");
    Ok(())
}
