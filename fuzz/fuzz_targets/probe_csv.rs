//! `--probe` direction files: no panic; accepted directions are finite with elevations
//! in [-90, 90].
#![no_main]
use libfuzzer_sys::fuzz_target;

mod common;

fuzz_target!(|data: &[u8]| {
    common::small_budget();
    let Ok(text) = std::str::from_utf8(data) else { return };
    let Ok(directions) = atmo::sky::probe::parse_directions(text, "fuzz") else { return };
    assert!(!directions.is_empty());
    for (a, e) in directions {
        assert!(a.is_finite() && (-90.0..=90.0).contains(&e));
    }
});
