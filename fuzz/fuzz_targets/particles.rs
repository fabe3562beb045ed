//! Particle files, CSV and binary (the first byte chooses): no panic; every accepted
//! particle is finite and inside the ranges the arithmetic holds.
#![no_main]
use atmo::clouds::files;
use libfuzzer_sys::fuzz_target;

mod common;

fuzz_target!(|data: &[u8]| {
    common::small_budget();
    let Some((&first, rest)) = data.split_first() else { return };
    let parsed = if first % 2 == 0 {
        let mut bytes = b"ATMOPART".to_vec();
        bytes.extend_from_slice(rest);
        files::parse_binary(&bytes, "fuzz")
    } else {
        let Ok(text) = std::str::from_utf8(rest) else { return };
        files::parse_csv(text, "fuzz", 0.99)
    };
    for p in parsed.iter().flatten() {
        assert!(p.position.is_finite() && p.position.abs().max_element() <= files::MAX_POSITION_M);
        assert!(p.radius > 0.0 && p.radius <= files::MAX_RADIUS_M);
        assert!(p.density >= 0.0 && p.density * p.radius <= files::MAX_DENSITY_RADIUS);
        assert!((0.0..=1.0).contains(&p.albedo));
    }
});
