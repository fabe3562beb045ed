//! OBJ meshes: no panic, no allocation past the budget; an accepted mesh has triangles,
//! all of finite vertices.
#![no_main]
use libfuzzer_sys::fuzz_target;

mod common;

fuzz_target!(|data: &[u8]| {
    common::small_budget();
    let Ok(mesh) = atmo::shafts::scene::mesh_from_obj(data, "fuzz", |p| p) else { return };
    assert!(!mesh.is_empty());
    assert!(mesh.triangles().iter().flatten().all(|v| v.is_finite()));
});
