//! `atmo view --script` files: no panic, no allocation past the budget; an accepted
//! script's events are one a line at most, their numbers finite, each edit's value
//! within a line's limit, and every edit is listed among its parameters.
#![no_main]
use atmo::view::input::{Input, Script, SCRIPT_LINE_BYTES};
use libfuzzer_sys::fuzz_target;

mod common;

fuzz_target!(|data: &[u8]| {
    common::small_budget();
    let Ok(text) = std::str::from_utf8(data) else { return };
    let Ok(script) = Script::parse(text, "fuzz") else { return };
    let lines = text.lines().count() as u64;
    let mut events = 0;
    for frame in 0..=lines.min(64) {
        for input in script.at(frame) {
            events += 1;
            match input {
                Input::Drag(dx, dy) => assert!(dx.is_finite() && dy.is_finite()),
                Input::Aim(_, x, y) => assert!(x.is_finite() && y.is_finite()),
                Input::Set(name, value) => {
                    assert!(!name.is_empty() && name.len() + value.len() <= SCRIPT_LINE_BYTES);
                    assert!(script.parameters().any(|p| p == name));
                }
                Input::Key(_) => {}
            }
        }
    }
    assert!(events <= lines, "{events} events from {lines} lines");
});
