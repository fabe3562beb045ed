//! EXR pictures (`atmo compare`'s input): no panic, no decoding past the pictures'
//! limits or the budget; an accepted picture has one pixel per width x height.
#![no_main]
use libfuzzer_sys::fuzz_target;

mod common;

fuzz_target!(|data: &[u8]| {
    common::small_budget();
    let Ok(frame) = atmo::image::Frame::exr_from_bytes(data, "fuzz") else { return };
    assert!(frame.width.max(frame.height) <= 16384);
    assert_eq!(frame.pixels.len(), frame.width as usize * frame.height as usize);
});
