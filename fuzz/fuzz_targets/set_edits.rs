//! `--set KEY=VALUE` edits of a scene file (the first line the edit, the rest the
//! file): no panic, no allocation past the budget; an accepted edit gives a file that
//! reads back as TOML with the value where the key says.
#![no_main]
use atmo::shafts::edits::{Document, Edit};
use libfuzzer_sys::fuzz_target;

mod common;

fuzz_target!(|data: &[u8]| {
    common::small_budget();
    let Ok(text) = std::str::from_utf8(data) else { return };
    let (line, file) = text.split_once('\n').unwrap_or((text, ""));
    let Ok(edit) = Edit::parse(line) else { return };
    let Ok(edited) = Document::edited(file, "fuzz", std::slice::from_ref(&edit)) else {
        return;
    };
    let again = Document::parse(&edited.to_string(), "fuzz").expect("an edited file reads back");
    let got = again.get(&edit.key).map(|v| v.to_string());
    match &edit.value {
        Some(_) => assert!(got.is_some(), "{} is not set", edit.key),
        None => assert!(got.is_none(), "{} is still there", edit.key),
    }
});
