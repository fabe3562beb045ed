//! GDTF fixture files (a zip of description.xml and wheel images): no panic, no
//! allocation past the budget (entries are checked against it before they are read);
//! an accepted fixture has beam and field angles in (0, 180], a flux in
//! (0, MAX_FLUX_LM], a colour temperature in [1000, 40000] K, ordered ranges, and a prism of unit beams that is atmo's circular prism or refused.
#![no_main]
use atmo::shafts::show::Prism;
use atmo::shafts::spotlight::Sampling;
use libfuzzer_sys::fuzz_target;

mod common;

fuzz_target!(|data: &[u8]| {
    common::small_budget();
    for mode in ["Standard", "Basic"] {
        let Ok(f) = atmo::shafts::gdtf::read(data, "fuzz", mode, Sampling::Nearest) else {
            continue;
        };
        // The ranges a luminaire's beam has (each refused past them, naming it).
        assert!(f.beam_deg > 0.0 && f.beam_deg <= 180.0);
        assert!(f.field_deg > 0.0 && f.field_deg <= 180.0);
        assert!(f.luminous_flux_lm > 0.0 && f.luminous_flux_lm <= atmo::shafts::gdtf::MAX_FLUX_LM);
        assert!((1000.0..=40000.0).contains(&f.kelvin));
        if let Some([narrow, wide]) = f.zoom_range_deg {
            assert!(narrow > 0.0 && wide <= 180.0);
        }
        for [lo, hi] in [f.pan_range_deg, f.tilt_range_deg, f.zoom_range_deg].into_iter().flatten() {
            assert!(lo <= hi);
        }
        for g in &f.wheel {
            let (width, height) = g.size();
            assert_eq!(g.srgb().len(), width * height);
        }
        if let Some(prism) = &f.prism {
            // Facets are unit beams; a circular prism's numbers are in atmo's ranges.
            assert!(prism.facets.iter().all(|d| (d.length() - 1.0).abs() < 1e-4));
            if let Ok(p) = prism.circular() {
                let [fewest, most] = Prism::FACETS;
                assert!((fewest..=most).contains(&p.facets));
                assert!((0.0..=Prism::MAX_ANGLE_DEG).contains(&p.angle_deg));
            }
        }
    }
});
