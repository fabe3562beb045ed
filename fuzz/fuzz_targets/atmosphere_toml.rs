//! Atmosphere TOML: no panic; what is accepted is finite, and what atmo writes of it
//! reads back to the same text (tables embed it).
#![no_main]
use libfuzzer_sys::fuzz_target;

mod common;

fuzz_target!(|data: &[u8]| {
    common::small_budget();
    let Ok(text) = std::str::from_utf8(data) else { return };
    let Ok(atmosphere) = atmo::Atmosphere::from_toml_str(text, "fuzz") else { return };
    let written = atmosphere.to_toml();
    assert!(!written.contains("NaN") && !written.contains("inf"), "{written}");
    let again = atmo::Atmosphere::from_toml_str(&written, "written")
        .unwrap_or_else(|e| panic!("an accepted atmosphere did not read back: {e}\n{written}"));
    assert_eq!(again.to_toml(), written);
});
