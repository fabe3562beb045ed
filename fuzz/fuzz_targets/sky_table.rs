//! Skylight table files: no panic, no allocation past the budget; an accepted table
//! written again is the same bytes, and reads back equal (parse -> write -> parse).
#![no_main]
use libfuzzer_sys::fuzz_target;

mod common;

fuzz_target!(|data: &[u8]| {
    common::small_budget();
    let Ok(table) = atmo::sky::table::SkylightTable::from_bytes(data, "fuzz") else { return };
    let bytes = table.to_bytes();
    let again = atmo::sky::table::SkylightTable::from_bytes(&bytes, "written")
        .unwrap_or_else(|e| panic!("an accepted table did not read back: {e}"));
    assert_eq!(again, table);
    assert_eq!(again.to_bytes(), bytes);
});
