//! Shafts of light (the shafts paper): a spotlight in stage haze cut by a sphere's
//! shadow, described in TOML as a scene file would, rendered by the sample planes.
//!
//! `cargo run --release -p atmo --example spotlights -- stage.png`

use atmo::shafts::{SamplePlanes, Scene};

/// One spotlight over a floor and a sphere, in metres, candela and 1/m.
const SCENE: &str = r#"
[camera]
position = [0.0, 1.4, 6.5]
look_at = [0.0, 1.1, 0.0]
fov_deg = 50.0
width = 720
height = 480

[haze]
extinction = 0.12
albedo = 0.9

[[spotlight]]
position = [-4.2, 3.0, -1.2]
aim = [0.6, 0.0, 0.2]
kelvin = 3200
intensity = 1500.0
beam_deg = 24.0
field_deg = 34.0

[[object]]
kind = "plane"
point = [0.0, 0.0, 0.0]
normal = [0.0, 1.0, 0.0]
albedo = 0.5

[[object]]
kind = "sphere"
center = [-0.7, 0.5, 0.0]
radius = 0.5
albedo = 0.7
"#;

fn main() -> atmo::Result<()> {
    let out = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "stage.png".into());
    let scene = Scene::from_toml_str(SCENE, "the example scene", std::path::Path::new("."))?;
    let frame = SamplePlanes::new(&scene).render();
    let display = scene.display;
    frame.write(std::path::Path::new(&out), display.exposure, display.tone)?;
    println!("wrote {out} ({})", scene.unit.radiance_unit());
    Ok(())
}
