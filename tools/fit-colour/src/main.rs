//! Fits the `earth` preset's weights from its six wavelengths to CIE XYZ (the
//! `[colour]` table of `crates/atmo/presets/earth.toml`) to the same atmosphere sampled
//! at 48 wavelengths (`earth-spectral`), whose colour is taken as the truth: the sky's
//! radiance at the six wavelengths is nearly a function of a few smooth spectral shapes
//! (Rayleigh's lambda^-4, the sun's spectrum, ozone's Chappuis band), so three rows of
//! six weights can give its chromaticity far better than a piecewise-linear spectrum
//! between the samples (docs/sky.md, "Colour").
//!
//! Over altitudes 0, 3, 6 and 12 km, ozone on and off, suns from -4 to 85 deg and a
//! grid of directions (the ground below the horizon included), each XYZ row is fitted
//! by least squares weighted by 1 / Y^2 (so every direction's chromaticity counts, dim
//! or bright). Prints the table to paste into earth.toml, and the fit's du'v' on
//! altitudes and suns it did not see.
//!
//! `cargo run --release -p atmo-fit-colour` (about a minute on two cores).

use atmo::atmosphere::spectrum::SpectrumToRgb;
use atmo::sky::{SkyModel, SkySettings};
use atmo::Atmosphere;
use faer::linalg::solvers::Solve;

/// Sky directions (azimuth from the sun, elevation), rad.
fn directions() -> Vec<(f64, f64)> {
    let mut dirs = Vec::new();
    for e in [
        -10.0f64, -2.0, 0.5, 2.0, 5.0, 10.0, 20.0, 35.0, 55.0, 75.0, 89.0,
    ] {
        for a in [0.0f64, 15.0, 40.0, 70.0, 100.0, 140.0, 180.0] {
            dirs.push((a.to_radians(), e.to_radians()));
        }
    }
    dirs
}

/// Pairs of (the six-wavelength radiance, the 48-wavelength XYZ) at `altitude_m` for
/// `suns` (deg), ozone on or off.
fn samples(altitude_m: f64, ozone: bool, suns: &[f64]) -> Vec<(Vec<f64>, [f64; 3])> {
    let settings = SkySettings {
        shells: 20,
        directions: 32,
        ..SkySettings::default()
    };
    let mut six = Atmosphere::earth().with_ozone(ozone).unwrap();
    six.colour = None;
    let many = Atmosphere::preset("earth-spectral")
        .unwrap()
        .with_ozone(ozone)
        .unwrap();
    let m6 = SkyModel::new(&six, &settings, altitude_m).unwrap();
    let m48 = SkyModel::new(&many, &settings, altitude_m).unwrap();
    let reference = xyz_of(&many);
    let dirs = directions();
    let mut out = Vec::new();
    for &sun in suns {
        let l6 = m6.radiance_along(sun.to_radians(), &dirs);
        let l48 = m48.radiance_along(sun.to_radians(), &dirs);
        for (a, b) in l6.iter().zip(&l48) {
            let xyz = apply(&reference, b);
            if xyz[1] > 0.0 {
                out.push((a.iter().map(|&v| v as f64).collect(), xyz));
            }
        }
    }
    out
}

/// The piecewise-linear map of `atmosphere`'s wavelengths to XYZ (rows X, Y, Z).
fn xyz_of(atmosphere: &Atmosphere) -> [Vec<f64>; 3] {
    // SpectrumToRgb's sRGB weights taken back to XYZ (sRGB to XYZ, D65).
    const SRGB_TO_XYZ: [[f64; 3]; 3] = [
        [0.4124564, 0.3575761, 0.1804375],
        [0.2126729, 0.7151522, 0.0721750],
        [0.0193339, 0.1191920, 0.9503041],
    ];
    let rgb = SpectrumToRgb::new(&atmosphere.wavelengths_nm);
    let n = atmosphere.wavelengths_nm.len();
    std::array::from_fn(|c| {
        (0..n)
            .map(|i| {
                let column: [f32; 3] = {
                    let mut unit = vec![0.0f32; n];
                    unit[i] = 1.0;
                    rgb.rgb(&unit)
                };
                (0..3).map(|k| SRGB_TO_XYZ[c][k] * column[k] as f64).sum()
            })
            .collect()
    })
}

fn apply(rows: &[Vec<f64>; 3], radiance: &[f32]) -> [f64; 3] {
    std::array::from_fn(|c| {
        rows[c]
            .iter()
            .zip(radiance)
            .map(|(w, l)| w * *l as f64)
            .sum()
    })
}

/// u'v' of XYZ.
fn uv(x: [f64; 3]) -> (f64, f64) {
    let d = x[0] + 15.0 * x[1] + 3.0 * x[2];
    (4.0 * x[0] / d, 9.0 * x[1] / d)
}

fn main() {
    let train_suns = [
        -4.0, -1.0, 0.5, 1.5, 3.0, 5.0, 8.0, 12.0, 18.0, 25.0, 35.0, 50.0, 65.0, 85.0,
    ];
    let mut train = Vec::new();
    for altitude in [0.0, 3000.0, 6000.0, 12000.0] {
        for ozone in [true, false] {
            train.extend(samples(altitude, ozone, &train_suns));
        }
    }
    let n = train[0].0.len();
    let rows: [Vec<f64>; 3] = std::array::from_fn(|c| {
        let a = faer::Mat::<f64>::from_fn(train.len(), n, |r, i| train[r].0[i] / train[r].1[1]);
        let b = faer::Mat::<f64>::from_fn(train.len(), 1, |r, _| train[r].1[c] / train[r].1[1]);
        let ata = a.transpose() * &a;
        let atb = a.transpose() * &b;
        let x = ata
            .llt(faer::Side::Lower)
            .expect("positive definite")
            .solve(&atb);
        (0..n).map(|i| x[(i, 0)]).collect()
    });
    let list = |v: &[f64]| {
        v.iter()
            .map(|x| format!("{x:.6}"))
            .collect::<Vec<_>>()
            .join(", ")
    };
    println!(
        "[colour]\nx = [{}]\ny = [{}]\nz = [{}]",
        list(&rows[0]),
        list(&rows[1]),
        list(&rows[2])
    );
    // Held out: altitudes and suns the fit did not see.
    for (altitude, ozone) in [(1000.0, true), (8000.0, true), (1000.0, false)] {
        let test = samples(altitude, ozone, &[2.0, 10.0, 30.0]);
        let mut d: Vec<f64> = test
            .iter()
            .map(|(l, x)| {
                let fit: [f64; 3] =
                    std::array::from_fn(|c| rows[c].iter().zip(l).map(|(w, v)| w * v).sum());
                let ((u1, v1), (u2, v2)) = (uv(fit), uv(*x));
                ((u1 - u2).powi(2) + (v1 - v2).powi(2)).sqrt()
            })
            .collect();
        d.sort_by(|a, b| a.total_cmp(b));
        eprintln!(
            "held out, {altitude} m, ozone {ozone}: du'v' median {:.5}, 95 % {:.5}, max {:.5}",
            d[d.len() / 2],
            d[d.len() * 95 / 100],
            d[d.len() - 1]
        );
    }
}
