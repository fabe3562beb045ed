//! MVR files (`[mvr]` in a scene): the zip, GeneralSceneDescription.xml, symbols and
//! 3DS meshes. No panic, no allocation past the budget; an accepted rig's fixtures are
//! placed with unit axes in its frame and its triangles are finite.
#![no_main]
use libfuzzer_sys::fuzz_target;

mod common;

fuzz_target!(|data: &[u8]| {
    common::small_budget();
    if let Ok(rig) = atmo::shafts::mvr::read(data, "fuzz.mvr") {
        for f in &rig.fixtures {
            assert!(f.origin.is_finite());
            assert!((f.axis.length() - 1.0).abs() < 1e-3 && (f.front.length() - 1.0).abs() < 1e-3);
        }
        assert!(rig.triangles.iter().flatten().all(|p| p.is_finite()));
    }
});
