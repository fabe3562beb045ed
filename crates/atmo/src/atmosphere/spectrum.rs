//! From radiance at a few wavelengths to linear sRGB.
//!
//! The spectrum between the sampled wavelengths is taken as piecewise linear (held
//! constant beyond the first and last), integrated against the CIE 1931 2-degree
//! colour-matching functions from 360 to 830 nm, and the XYZ result converted to linear
//! sRGB (D65). The matching functions are the multi-lobe Gaussian fit of Wyman, Sloan
//! and Shirley (2013, JCGT 2(2)), within about 1 % of the tabulated CIE data: close
//! enough for a sky, and 30 lines instead of a 471-row table.

/// Piecewise Gaussian with different widths left and right of the mean.
fn lobe(lambda: f64, mean: f64, left: f64, right: f64) -> f64 {
    let s = if lambda < mean { left } else { right };
    let t = (lambda - mean) / s;
    (-0.5 * t * t).exp()
}

/// CIE 1931 x-bar, y-bar, z-bar at `lambda` nm (Wyman-Sloan-Shirley multi-lobe fit).
pub fn cie_1931(lambda: f64) -> [f64; 3] {
    let x = 1.056 * lobe(lambda, 599.8, 37.9, 31.0) + 0.362 * lobe(lambda, 442.0, 16.0, 26.7)
        - 0.065 * lobe(lambda, 501.1, 20.4, 26.2);
    let y = 0.821 * lobe(lambda, 568.8, 46.9, 40.5) + 0.286 * lobe(lambda, 530.9, 16.3, 31.1);
    let z = 1.217 * lobe(lambda, 437.0, 11.8, 36.0) + 0.681 * lobe(lambda, 459.0, 26.0, 13.8);
    [x, y, z]
}

/// XYZ to linear sRGB primaries, D65 white (IEC 61966-2-1).
const XYZ_TO_SRGB: [[f64; 3]; 3] = [
    [3.2404542, -1.5371385, -0.4985314],
    [-0.9692660, 1.8760108, 0.0415560],
    [0.0556434, -0.2040259, 1.0572252],
];

/// The colour of a black body at `kelvin` (Planck's law integrated against the CIE 1931
/// functions from 360 to 830 nm), in linear sRGB scaled to luminance Y = 1. Colours
/// outside the sRGB gamut (deep red below about 1900 K) are clipped to it.
pub fn blackbody_srgb(kelvin: f64) -> [f64; 3] {
    // Planck's law up to constant factors: lambda^-5 / (exp(c2 / (lambda T)) - 1).
    const C2: f64 = 1.438_776_9e-2; // m K
    let mut xyz = [0.0f64; 3];
    for step in 360..=830 {
        let lambda = step as f64 * 1e-9;
        let planck = lambda.powi(-5) / (C2 / (lambda * kelvin)).exp_m1();
        let cmf = cie_1931(step as f64);
        for c in 0..3 {
            xyz[c] += planck * cmf[c];
        }
    }
    let rgb: [f64; 3] = std::array::from_fn(|r| {
        (0..3)
            .map(|c| XYZ_TO_SRGB[r][c] * xyz[c] / xyz[1])
            .sum::<f64>()
            .max(0.0)
    });
    let luminance = srgb_luminance(rgb);
    rgb.map(|v| v / luminance)
}

/// The luminance `Y` of a linear-sRGB colour (the Y row of sRGB's matrix to XYZ).
#[inline]
pub fn srgb_luminance(rgb: [f64; 3]) -> f64 {
    0.2126 * rgb[0] + 0.7152 * rgb[1] + 0.0722 * rgb[2]
}

/// A linear map from radiance at the atmosphere's wavelengths to linear sRGB.
#[derive(Debug, Clone)]
pub struct SpectrumToRgb {
    /// `weights[rgb][channel]`: contribution of each sampled wavelength to each primary.
    pub(crate) weights: [Vec<f32>; 3],
}

impl SpectrumToRgb {
    /// The map for samples at `wavelengths_nm` (increasing).
    pub fn new(wavelengths_nm: &[f64]) -> Self {
        let n = wavelengths_nm.len();
        let mut xyz = vec![[0.0f64; 3]; n];
        // 1 nm steps; each step's radiance is a hat-function mix of the samples.
        for step in 360..=830 {
            let lambda = step as f64;
            let cmf = cie_1931(lambda);
            let k = wavelengths_nm.partition_point(|&w| w <= lambda);
            let hat: Vec<(usize, f64)> = if k == 0 {
                vec![(0, 1.0)]
            } else if k == n {
                vec![(n - 1, 1.0)]
            } else {
                let (a, b) = (wavelengths_nm[k - 1], wavelengths_nm[k]);
                let f = (lambda - a) / (b - a);
                vec![(k - 1, 1.0 - f), (k, f)]
            };
            for (i, h) in hat {
                for c in 0..3 {
                    xyz[i][c] += h * cmf[c];
                }
            }
        }
        let weights = std::array::from_fn(|rgb| {
            xyz.iter()
                .map(|w| (0..3).map(|c| XYZ_TO_SRGB[rgb][c] * w[c]).sum::<f64>() as f32)
                .collect()
        });
        SpectrumToRgb { weights }
    }

    /// The map for `atmosphere`'s spectrum: its fitted weights to XYZ where it has them
    /// ([`crate::Atmosphere::colour`]), else the piecewise-linear spectrum of
    /// [`SpectrumToRgb::new`].
    pub fn for_atmosphere(atmosphere: &crate::Atmosphere) -> Self {
        match &atmosphere.colour {
            None => SpectrumToRgb::new(&atmosphere.wavelengths_nm),
            Some(xyz) => {
                let n = atmosphere.wavelengths_nm.len();
                let weights = std::array::from_fn(|rgb| {
                    (0..n)
                        .map(|i| {
                            (0..3).map(|c| XYZ_TO_SRGB[rgb][c] * xyz[c][i]).sum::<f64>() as f32
                        })
                        .collect()
                });
                SpectrumToRgb { weights }
            }
        }
    }

    /// Linear sRGB of the spectrum `radiance` (one value a wavelength).
    #[inline]
    pub fn rgb(&self, radiance: &[f32]) -> [f32; 3] {
        std::array::from_fn(|c| {
            self.weights[c]
                .iter()
                .zip(radiance)
                .map(|(w, l)| w * l)
                .sum()
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn y_bar_peaks_near_555_nm_with_unit_height() {
        let peak = (380..780).max_by(|a, b| {
            cie_1931(*a as f64)[1]
                .partial_cmp(&cie_1931(*b as f64)[1])
                .unwrap()
        });
        let peak = peak.unwrap();
        assert!((550..=560).contains(&peak), "{peak}");
        assert!((cie_1931(555.0)[1] - 1.0).abs() < 0.02);
    }

    #[test]
    fn black_bodies_go_from_orange_through_white_to_blue() {
        let tungsten = blackbody_srgb(3200.0);
        let daylight = blackbody_srgb(6500.0);
        let sky = blackbody_srgb(12000.0);
        assert!(
            tungsten[0] > tungsten[1] && tungsten[1] > tungsten[2],
            "{tungsten:?}"
        );
        assert!(sky[2] > sky[1] && sky[1] > sky[0], "{sky:?}");
        // 6500 K is close to D65, the sRGB white (within the fit's 1-3 %).
        for c in daylight {
            assert!((c - 1.0).abs() < 0.06, "{daylight:?}");
        }
        for rgb in [tungsten, daylight, sky] {
            let y = srgb_luminance(rgb);
            assert!((y - 1.0).abs() < 1e-9);
        }
    }

    #[test]
    fn flat_spectrum_is_nearly_neutral_and_blue_is_blue() {
        let wl = [420.0, 470.0, 520.0, 570.0, 620.0, 670.0];
        let m = SpectrumToRgb::new(&wl);
        let white = m.rgb(&[1.0; 6]);
        // Illuminant E (flat) in linear sRGB at Y = 1 is about (1.205, 0.948, 0.909).
        let y = 0.2126 * white[0] + 0.7152 * white[1] + 0.0722 * white[2];
        for (got, want) in white.iter().zip([1.205, 0.948, 0.909]) {
            assert!((got / y - want).abs() < 0.03, "{white:?}");
        }
        let sky: Vec<f32> = wl.iter().map(|l| (500.0 / *l as f32).powi(4)).collect();
        let rgb = m.rgb(&sky);
        assert!(rgb[2] > rgb[1] && rgb[1] > rgb[0], "{rgb:?}");
    }

    #[test]
    fn colour_rows_of_srgbs_primaries_give_the_channels_themselves() {
        // An atmosphere whose three "wavelengths" are an RGB renderer's channels (Bevy's,
        // bevy_atmo's accuracy example) gives XYZ rows that are sRGB's primaries (blue,
        // green, red, as the wavelengths increase): its picture is the channels.
        let text = r#"
name = "rgb"
bottom_radius_m = 6360000.0
top_radius_m = 6460000.0
sun_angular_radius_deg = 0.2667
wavelengths_nm = [440.0, 550.0, 680.0]
solar_irradiance = 1.0
[rayleigh]
scale_height_m = 8000.0
scattering_per_m = [33.1e-6, 13.558e-6, 5.802e-6]
phase = { kind = "rayleigh" }
[mie]
scale_height_m = 1200.0
scattering_per_m = 3.996e-6
phase = { kind = "henyey-greenstein", g = 0.8 }
[colour]
x = [0.1804375, 0.3575761, 0.4124564]
y = [0.0721750, 0.7151522, 0.2126729]
z = [0.9503041, 0.1191920, 0.0193339]
"#;
        let atmosphere = crate::Atmosphere::from_toml_str(text, "test").unwrap();
        let m = SpectrumToRgb::for_atmosphere(&atmosphere);
        for (channel, rgb) in [(0, 2), (1, 1), (2, 0)] {
            let mut radiance = [0.0f32; 3];
            radiance[channel] = 1.0;
            let got = m.rgb(&radiance);
            for (c, v) in got.iter().enumerate() {
                let want = if c == rgb { 1.0 } else { 0.0 };
                assert!((v - want).abs() < 1e-5, "channel {channel}: {got:?}");
            }
        }
    }
}
