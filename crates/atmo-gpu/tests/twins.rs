//! Twin tests: every WGSL function that mirrors a Rust one (functions.wgsl) run on the
//! GPU over a grid of inputs and compared with the Rust, function by function, so a
//! slip in either copy shows here and not as a faint difference in some picture.

mod common;

use atmo::atmosphere::PhaseFunction;
use atmo::image::ToneMap;
use atmo_gpu::display::tone_code;
use atmo_gpu::wgsl::evaluate;
use common::gpu;

/// `n + 1` evenly spaced values over [a, b], as the x of each input.
fn grid(a: f32, b: f32, n: usize) -> Vec<[f32; 4]> {
    (0..=n)
        .map(|k| [a + (b - a) * k as f32 / n as f32, 0.0, 0.0, 0.0])
        .collect()
}

/// The largest difference between the GPU's `expression` and `rust` over `inputs`,
/// after `scale` (1 for absolute differences, the value for relative ones).
fn worst(
    gpu: &atmo_gpu::Gpu,
    expression: &str,
    inputs: &[[f32; 4]],
    rust: impl Fn([f32; 4]) -> f32,
    relative: bool,
) -> f32 {
    let on_gpu = evaluate(gpu, expression, inputs).unwrap();
    assert_eq!(on_gpu.len(), inputs.len());
    inputs
        .iter()
        .zip(&on_gpu)
        .map(|(v, g)| {
            let r = rust(*v);
            let d = (g - r).abs();
            if relative {
                d / r.abs().max(1e-30)
            } else {
                d
            }
        })
        .fold(0.0, f32::max)
}

#[test]
fn fast_acos_and_fast_atan_match_the_rust() {
    let Some(gpu) = gpu() else { return };
    let acos = worst(
        &gpu,
        "fast_acos(v.x)",
        &grid(-1.0, 1.0, 4000),
        |v| atmo::fast::fast_acos(v[0]),
        false,
    );
    assert!(acos < 2e-6, "fast_acos: {acos}");
    let atan = worst(
        &gpu,
        "fast_atan(v.x)",
        &grid(0.0, 20.0, 4000),
        |v| atmo::fast::fast_atan(v[0]),
        false,
    );
    assert!(atan < 2e-6, "fast_atan: {atan}");
    // Around the circle at three radii, and the origin.
    let points: Vec<[f32; 4]> = (0..=720)
        .flat_map(|k| {
            let a = (k as f32 * 0.5 - 180.0).to_radians();
            [1e-3f32, 0.8, 30.0].map(|r| [r * a.cos(), r * a.sin(), 0.0, 0.0])
        })
        .chain([[0.0; 4]])
        .collect();
    let atan2 = worst(
        &gpu,
        "fast_atan2(v.y, v.x)",
        &points,
        |v| atmo::fast::fast_atan2(v[1], v[0]),
        false,
    );
    assert!(atan2 < 4e-6, "fast_atan2: {atan2}");
}

#[test]
fn erf_matches_the_rust() {
    let Some(gpu) = gpu() else { return };
    let e = worst(
        &gpu,
        "erf(v.x)",
        &grid(-4.0, 4.0, 4000),
        |v| atmo::clouds::particles::erf(v[0] as f64) as f32,
        false,
    );
    // The GPU's exp is not correctly rounded; the CPU's erf runs in f64.
    assert!(e < 1e-6, "erf: {e}");
}

#[test]
fn interleaved_offsets_match_the_rust() {
    let Some(gpu) = gpu() else { return };
    let inputs: Vec<[f32; 4]> = (0..64u32)
        .flat_map(|y| (0..64u32).map(move |x| [x as f32, y as f32, 0.0, 0.0]))
        .collect();
    let e = worst(
        &gpu,
        "interleaved_offset(u32(v.x), u32(v.y))",
        &inputs,
        |v| atmo::fast::interleaved_offset(v[0] as u32, v[1] as u32),
        false,
    );
    // fract(52.98 f) multiplies the last bit of f by 53; a wrap at 1 would show as ~1.
    assert!(e < 1e-5, "interleaved_offset: {e}");
}

#[test]
fn every_phase_function_matches_the_rust() {
    let Some(gpu) = gpu() else { return };
    let cosines = grid(-1.0, 1.0, 2000);
    for phase in [
        PhaseFunction::Rayleigh,
        PhaseFunction::PaperMie,
        PhaseFunction::HenyeyGreenstein { g: 0.76 },
        PhaseFunction::HenyeyGreenstein { g: -0.3 },
        PhaseFunction::CornetteShanks { g: 0.8 },
        PhaseFunction::PaperHaze { exponent: 16.0 },
        PhaseFunction::CloudMie,
    ] {
        let (kind, p) = phase.code();
        let expression = format!("phase_function({kind}u, {:?}, v.x)", p as f32);
        let e = worst(&gpu, &expression, &cosines, |v| phase.eval_f32(v[0]), true);
        assert!(e < 1e-5, "{phase:?}: relative {e}");
    }
}

#[test]
fn tone_maps_and_the_srgb_encoding_match_the_rust() {
    let Some(gpu) = gpu() else { return };
    let exposed = grid(-1.0, 20.0, 2100);
    for tone in [ToneMap::Clamp, ToneMap::Exponential, ToneMap::Aces] {
        let expression = format!("tone_map({}u, v.x)", tone_code(tone));
        let e = worst(&gpu, &expression, &exposed, |v| tone.apply(v[0]), false);
        // A 255th of a level at most: the display's rounding never flips.
        assert!(e < 2e-6, "{tone:?}: {e}");
    }
    let linear = grid(0.0, 1.0, 2000);
    let e = worst(
        &gpu,
        "srgb_encode(v.x)",
        &linear,
        |v| atmo::image::srgb_encode(v[0]),
        false,
    );
    assert!(e < 2e-6, "srgb_encode: {e}");
}

#[test]
fn the_prelude_carries_every_phase_code() {
    let prelude = atmo_gpu::wgsl::prelude();
    for (name, code) in PhaseFunction::CODES {
        assert!(
            prelude.contains(&format!("const PHASE_{name}: u32 = {code}u;")),
            "{name} missing from {prelude}"
        );
    }
    assert!(prelude.contains("const FOOTPRINT: f32 = 3.5;"), "{prelude}");
    assert!(prelude.contains(&format!(
        "const OBJECT_MESH: u32 = {}u;",
        atmo_gpu::wgsl::OBJECT_MESH
    )));
}
