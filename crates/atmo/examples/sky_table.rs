//! The real-time sky (sky section 4): a small skylight table precomputed once, then a
//! sunset drawn from it, each map in well under a millisecond. A flight simulator keeps
//! the table in a file (`SkylightTable::write`, `atmo precompute sky`) and draws from it
//! every frame.
//!
//! `cargo run --release -p atmo --example sky_table -- sunset.png`

use std::time::Instant;

use atmo::sky::{SkyPicture, SkySettings, SkylightTable, TableSettings, View};
use atmo::view::{Camera, Fov, Sun};
use atmo::Atmosphere;
use glam::Vec3;

fn main() -> atmo::Result<()> {
    let out = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "sunset.png".into());
    // A coarse table (the defaults, the paper's grids, take about 40 s to precompute).
    let settings = TableSettings {
        sky: SkySettings {
            shells: 16,
            directions: 32,
            ..SkySettings::default()
        },
        sun_steps: 24,
        altitude_steps: 4,
        ..TableSettings::default()
    };
    let table = SkylightTable::precompute(&Atmosphere::earth(), &settings, &|_, _| {})?;
    let (sun, altitude_m) = (Sun::from_degrees(3.0, 260.0)?, 2500.0);
    let start = Instant::now();
    let picture = SkyPicture::from_table(&table, sun, altitude_m)?;
    println!(
        "map from the table in {:.3} ms",
        start.elapsed().as_secs_f64() * 1e3
    );
    let eye = Vec3::new(0.0, altitude_m as f32, 0.0);
    let camera = Camera::yaw_pitch(eye, 260.0, 5.0, Fov::Vertical(60.0), (960, 540))?;
    let frame = picture.render(&View {
        camera,
        sun_disc: true,
    });
    frame.write(
        std::path::Path::new(&out),
        0.3,
        atmo::image::ToneMap::Exponential,
    )?;
    println!("wrote {out}");
    Ok(())
}
