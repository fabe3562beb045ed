//! Photometric files (IES LM-63 and EULUMDAT): no panic, no allocation past the counts'
//! limits; an accepted file gives finite candela >= 0 everywhere, a peak in
//! (0, MAX_CANDELA] and a reach within its vertical angles.
#![no_main]
use atmo::shafts::photometry::Photometry;
use libfuzzer_sys::fuzz_target;

mod common;

fuzz_target!(|data: &[u8]| {
    common::small_budget();
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    for p in [
        Photometry::from_ies(text, "fuzz"),
        Photometry::from_eulumdat(text, "fuzz"),
    ]
    .into_iter()
    .flatten()
    {
        assert!(p.peak() > 0.0 && p.peak() as f64 <= atmo::shafts::photometry::MAX_CANDELA);
        let reach = p.reach();
        assert!((0.0..=180.0).contains(&reach));
        for gamma in [0.0, 7.3, reach * 0.5, reach, 179.0] {
            for c in [-30.0, 0.0, 45.0, 91.0, 180.0, 269.0, 359.9, 725.0] {
                let cd = p.candela_at(gamma, c);
                assert!(cd.is_finite() && cd >= 0.0 && cd <= p.peak() * 1.0001, "{gamma} {c} {cd}");
            }
        }
    }
});
