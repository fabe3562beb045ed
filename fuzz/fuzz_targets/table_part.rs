//! Parts of a skylight table (`atmo precompute sky --part K/N`, read by `--merge`): no
//! panic, no allocation past the budget; an accepted part written again is the same
//! bytes (parse -> write -> parse).
#![no_main]
use atmo::sky::table::TablePart;
use libfuzzer_sys::fuzz_target;

mod common;

fuzz_target!(|data: &[u8]| {
    common::small_budget();
    let Ok(part) = TablePart::from_bytes(data, "fuzz") else { return };
    let bytes = part.to_bytes();
    let again = TablePart::from_bytes(&bytes, "written")
        .unwrap_or_else(|e| panic!("an accepted part did not read back: {e}"));
    assert_eq!(again.to_bytes(), bytes);
});
