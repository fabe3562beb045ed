//! Shafts scene TOML (gobo and OBJ paths relative to the project's scenes/, so the
//! seeds load whole): no panic, no allocation past the budget; an accepted scene holds
//! only finite numbers, and so does its show posed at any time.
#![no_main]
use libfuzzer_sys::fuzz_target;

mod common;

fuzz_target!(|data: &[u8]| {
    common::small_budget();
    let Ok(text) = std::str::from_utf8(data) else { return };
    let folder = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes");
    let Ok(mut scene) = atmo::shafts::Scene::from_toml_str(text, "fuzz", &folder) else { return };
    let c = &scene.camera;
    assert!(c.position.is_finite() && c.width > 0 && c.height > 0);
    let end = scene.show.duration();
    for t in [0.0, 0.37 * end, end, end + 1.0] {
        scene.at_time(t);
        for light in scene.lights() {
            assert!(light.position.is_finite() && light.intensity.is_finite());
            assert!(light.intensity.min_element() >= 0.0);
            assert!(light.light_from_world.is_finite() && light.field_half < 1.5708);
        }
    }
    assert!(scene.haze.extinction.is_finite() && scene.haze.albedo.is_finite());
});
