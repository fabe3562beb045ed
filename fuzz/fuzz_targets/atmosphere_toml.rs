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
    // Read as TOML, not searched for "inf": a description may hold those letters (the
    // fuzzer found "coeftcinfie").
    let value: toml::Value = toml::from_str(&written)
        .unwrap_or_else(|e| panic!("atmo wrote TOML that does not parse: {e}\n{written}"));
    assert!(finite(&value), "{written}");
    let again = atmo::Atmosphere::from_toml_str(&written, "written")
        .unwrap_or_else(|e| panic!("an accepted atmosphere did not read back: {e}\n{written}"));
    assert_eq!(again.to_toml(), written);
});

/// Whether every number in `value` is finite.
fn finite(value: &toml::Value) -> bool {
    match value {
        toml::Value::Float(x) => x.is_finite(),
        toml::Value::Array(items) => items.iter().all(finite),
        toml::Value::Table(table) => table.values().all(finite),
        _ => true,
    }
}
