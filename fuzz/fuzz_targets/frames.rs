//! An animation folder's manifest and a frame (`atmo assemble`, and a chunk's run
//! deciding which frames are whole): the manifest's JSON, a NUL byte, then the frame
//! file's bytes. No panic, no allocation past the budget; an accepted frame is the
//! manifest's width x height of 8-bit RGB.
#![no_main]
use libfuzzer_sys::fuzz_target;

mod common;

fuzz_target!(|data: &[u8]| {
    common::small_budget();
    let split = data.iter().position(|&b| b == 0).unwrap_or(data.len());
    let Ok(text) = std::str::from_utf8(&data[..split]) else { return };
    let Ok(manifest) = atmo_cli::Manifest::parse(text, "fuzz") else { return };
    let frame = data.get(split + 1..).unwrap_or_default();
    if let Ok(rgb) = atmo_cli::frame_from_bytes(frame, "frame", &manifest) {
        assert_eq!(rgb.len(), 3 * manifest.width as usize * manifest.height as usize);
    }
});
