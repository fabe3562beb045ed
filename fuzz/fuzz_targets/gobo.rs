//! Gobo images: no panic, no decoding of an image past the size limit or the budget;
//! an accepted gobo has one texel per pixel.
#![no_main]
use atmo::shafts::spotlight::Sampling;
use libfuzzer_sys::fuzz_target;

mod common;

fuzz_target!(|data: &[u8]| {
    common::small_budget();
    let Ok(gobo) = atmo::shafts::scene::gobo_from_image(data, "fuzz", Sampling::Bilinear) else {
        return;
    };
    let side = atmo::shafts::scene::GOBO_MAX_SIDE as usize;
    let (width, height) = gobo.size();
    assert!(width.max(height) <= side);
    assert_eq!(gobo.srgb().len(), width * height);
    assert!(gobo.sample(0.3, -0.2).is_finite());
});
