//! `atmo clouds --scene FILE` (the file's text): no panic, no allocation past the
//! budget; every key becomes a flag of `atmo clouds` or a refusal naming it, and what
//! the flags say is read as the command line would read it.
#![no_main]
use libfuzzer_sys::fuzz_target;

mod common;

fuzz_target!(|data: &[u8]| {
    common::small_budget();
    let Ok(text) = std::str::from_utf8(data) else { return };
    match atmo_cli::parse_clouds_scene(text, &[]) {
        Ok(_) | Err(atmo_cli::Refused::Clap(_)) => {}
        Err(atmo_cli::Refused::Input(message)) => {
            assert!(message.contains("--"), "a refusal names the flag or the scene: {message}")
        }
    }
});
