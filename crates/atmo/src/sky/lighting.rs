//! The light the sky and the sun put on a scene, in the form engines take: the sun as
//! a directional light (direction, colour, illuminance) and the sky as nine
//! spherical-harmonic coefficients of its radiance per linear-sRGB channel, from which
//! the irradiance on any surface follows (Ramamoorthi and Hanrahan 2001).
//!
//! The harmonics are the real basis in the world frame (x east, y up, z south), in
//! the order `(l, m)` = (0,0), (1,-1), (1,0), (1,1), (2,-2), (2,-1), (2,0), (2,1), (2,2):
//! `0.282095`, `0.488603 y`, `0.488603 z`, `0.488603 x`, `1.092548 xy`, `1.092548 yz`,
//! `0.315392 (3z^2 - 1)`, `1.092548 xz`, `0.546274 (x^2 - y^2)`. The coefficients are of
//! radiance (W m^-2 sr^-1 as linear sRGB); the irradiance on a surface with normal `n` is
//! `sum_lm A_l L_lm Y_lm(n)` with `A = (pi, 2pi/3, pi/4)` ([`irradiance`]).

use glam::Vec3;

use crate::atmosphere::spectrum::{srgb_luminance, SpectrumToRgb};
use crate::atmosphere::Atmosphere;
use crate::image::Frame;
use crate::view::Sun;

use super::envmap::equirect_direction;
use super::SkyPicture;

/// The luminous efficacy of radiation at 555 nm, lm/W: illuminance = 683 x Y.
pub const LUMENS_PER_WATT: f64 = 683.0;

/// Rows of the equirectangular map the harmonics are projected from: the sky's
/// nine coefficients change by under 1e-4 of the first from 128 to 512 rows.
pub const PROJECTION_ROWS: u32 = 128;

/// The band `l` of each of the nine harmonics, in the module docs' order.
pub const SH_BAND: [usize; 9] = [0, 1, 1, 1, 2, 2, 2, 2, 2];

/// `Y_00 = 1 / sqrt(4 pi)`, the constant harmonic: a radiance `c` from everywhere has
/// the coefficient `c / Y_00` and no other.
pub const SH_Y00: f64 = 0.282_095;

/// The nine real spherical harmonics at the unit direction `d` (module docs' order).
pub fn sh_basis(d: Vec3) -> [f64; 9] {
    let (x, y, z) = (d.x as f64, d.y as f64, d.z as f64);
    [
        SH_Y00,
        0.488_603 * y,
        0.488_603 * z,
        0.488_603 * x,
        1.092_548 * x * y,
        1.092_548 * y * z,
        0.315_392 * (3.0 * z * z - 1.0),
        1.092_548 * x * z,
        0.546_274 * (x * x - y * y),
    ]
}

/// Each pixel of an equirectangular map (`envmap` conventions): its direction (looking
/// out), its radiance and its solid angle, sr.
fn pixels_of(map: &Frame) -> impl Iterator<Item = (Vec3, Vec3, f64)> + '_ {
    let h = map.height;
    (0..h).flat_map(move |y| {
        let elevation =
            std::f64::consts::FRAC_PI_2 - std::f64::consts::PI * (y as f64 + 0.5) / h as f64;
        let solid_angle = (std::f64::consts::PI / h as f64).powi(2) * elevation.cos();
        (0..map.width).map(move |x| {
            let p = map.pixels[(y * map.width + x) as usize];
            (equirect_direction(x, y, h), p, solid_angle)
        })
    })
}

/// The radiance harmonics of an equirectangular map (`envmap` conventions), each pixel
/// weighted by its solid angle.
pub fn project_equirect(map: &Frame) -> [[f64; 3]; 9] {
    let mut sh = [[0.0; 3]; 9];
    for (d, p, solid_angle) in pixels_of(map) {
        for (s, b) in sh.iter_mut().zip(sh_basis(d)) {
            for (c, v) in s.iter_mut().zip(p.to_array()) {
                *c += b * solid_angle * v as f64;
            }
        }
    }
    sh
}

/// The mean radiance of an equirectangular map (`envmap` conventions, width twice the
/// height) over the cell of the sphere nearest each of the unit `directions` (looking
/// out), each pixel weighted by its solid angle: a quadrature's values where its nodes
/// are `directions` (a cloud's transfer solve carries the sky in along them). A
/// direction no pixel's centre falls nearest, in a map coarser than the directions,
/// reads the pixel it points into.
pub fn cell_means(map: &Frame, directions: &[Vec3]) -> Vec<Vec3> {
    debug_assert_eq!(map.width, 2 * map.height, "an equirectangular map");
    let nearest = |d: Vec3| {
        let mut best = (0, f32::NEG_INFINITY);
        for (i, w) in directions.iter().enumerate() {
            if w.dot(d) > best.1 {
                best = (i, w.dot(d));
            }
        }
        best.0
    };
    let mut sums = vec![(Vec3::ZERO, 0.0f32); directions.len()];
    for (d, p, solid_angle) in pixels_of(map) {
        let (sum, weight) = &mut sums[nearest(d)];
        *sum += p * solid_angle as f32;
        *weight += solid_angle as f32;
    }
    sums.iter()
        .zip(directions)
        .map(|(&(sum, weight), &d)| {
            if weight > 0.0 {
                sum / weight
            } else {
                map.pixels[equirect_pixel(d, map.height) as usize]
            }
        })
        .collect()
}

/// The index of the pixel of an equirectangular map `height` rows high that the unit
/// `d` points into ([`equirect_direction`]'s inverse).
fn equirect_pixel(d: Vec3, height: u32) -> u32 {
    let width = 2 * height;
    let elevation = d.y.clamp(-1.0, 1.0).asin();
    let azimuth = d.x.atan2(-d.z).rem_euclid(std::f32::consts::TAU);
    let y =
        ((std::f32::consts::FRAC_PI_2 - elevation) / std::f32::consts::PI * height as f32) as u32;
    let x = (azimuth / std::f32::consts::TAU * width as f32) as u32;
    y.min(height - 1) * width + x.min(width - 1)
}

/// Irradiance (linear sRGB, W m^-2) on a surface with unit normal `normal` from
/// radiance harmonics `sh`: the cosine lobe's convolution `A_l` per band.
pub fn irradiance(sh: &[[f64; 3]; 9], normal: Vec3) -> [f64; 3] {
    let a = [
        std::f64::consts::PI,
        2.0 * std::f64::consts::PI / 3.0,
        std::f64::consts::PI / 4.0,
    ];
    let basis = sh_basis(normal);
    let mut e = [0.0; 3];
    for k in 0..9 {
        for (c, e) in e.iter_mut().enumerate() {
            *e += a[SH_BAND[k]] * sh[k][c] * basis[k];
        }
    }
    e
}

/// The sunlight reaching a point: spectral and as an engine's directional light.
#[derive(Debug, Clone, PartialEq)]
pub struct Sunlight {
    /// Unit vector toward the sun, world frame.
    pub direction: [f64; 3],
    /// Irradiance on a surface facing the sun per wavelength, W m^-2 nm^-1.
    pub spectrum: Vec<f64>,
    /// Illuminance on a surface facing the sun and on a horizontal one, lux.
    pub normal_lux: f64,
    pub horizontal_lux: f64,
    /// The colour as linear sRGB with luminance 1 (0 at night).
    pub colour: [f64; 3],
}

impl Sunlight {
    /// The sunlight at `altitude_m` in `atmosphere` from `sun`: the solar irradiance
    /// through the transmittance along the sun's ray, times the disc's visible part.
    pub fn at(atmosphere: &Atmosphere, altitude_m: f64, sun: Sun) -> Self {
        let spectrum = atmosphere.direct_sunlight(altitude_m, sun.elevation());
        let rgb = SpectrumToRgb::for_atmosphere(atmosphere)
            .rgb(&spectrum.iter().map(|&e| e as f32).collect::<Vec<_>>())
            .map(f64::from);
        let y = srgb_luminance(rgb);
        let normal_lux = LUMENS_PER_WATT * y;
        Sunlight {
            direction: sun.toward().as_dvec3().to_array(),
            spectrum,
            normal_lux,
            horizontal_lux: normal_lux * sun.elevation().sin().max(0.0),
            colour: if y > 0.0 {
                rgb.map(|c| c / y)
            } else {
                [0.0; 3]
            },
        }
    }
}

/// The cosine-weighted integral of an equirectangular map's radiance over the
/// hemisphere facing up (world y): the irradiance on a horizontal surface, exactly
/// (to the map's resolution), which nine harmonics give only roughly: a sky's bright
/// horizon band is smeared into it (docs/sky.md).
pub fn irradiance_up(map: &Frame) -> [f64; 3] {
    let h = map.height;
    let mut e = [0.0; 3];
    for y in 0..h / 2 {
        let elevation =
            std::f64::consts::FRAC_PI_2 - std::f64::consts::PI * (y as f64 + 0.5) / h as f64;
        let weight = (std::f64::consts::PI / h as f64).powi(2) * elevation.cos() * elevation.sin();
        for p in &map.pixels[(y * map.width) as usize..((y + 1) * map.width) as usize] {
            for (e, v) in e.iter_mut().zip(p.to_array()) {
                *e += weight * v as f64;
            }
        }
    }
    e
}

/// An equirectangular map's radiance averaged over the sphere, `(1 / 4 pi) integral L
/// dw`, each row weighted by its solid angle.
pub fn mean_radiance(map: &Frame) -> [f64; 3] {
    let h = map.height;
    let mut sum = [0.0; 3];
    for y in 0..h {
        let elevation =
            std::f64::consts::FRAC_PI_2 - std::f64::consts::PI * (y as f64 + 0.5) / h as f64;
        let solid_angle = (std::f64::consts::PI / h as f64).powi(2) * elevation.cos();
        for p in &map.pixels[(y * map.width) as usize..((y + 1) * map.width) as usize] {
            for (s, v) in sum.iter_mut().zip(p.to_array()) {
                *s += solid_angle * v as f64;
            }
        }
    }
    sum.map(|s| s / (4.0 * std::f64::consts::PI))
}

/// The light on a scene at the viewpoint: the sun, and the sky (without the sun's
/// disc; with the ground below the horizon where the picture has it).
#[derive(Debug, Clone, PartialEq)]
pub struct Lighting {
    pub sun: Sunlight,
    /// `[coefficient][rgb]`, the sky's radiance harmonics.
    pub sky_sh9: [[f64; 3]; 9],
    /// The sky's irradiance on a horizontal surface, linear sRGB W m^-2, integrated.
    pub sky_irradiance_up: [f64; 3],
}

impl Lighting {
    /// The lighting of `picture` (the sky of `sun` at `altitude_m` in `atmosphere`).
    pub fn new(picture: &SkyPicture, atmosphere: &Atmosphere, altitude_m: f64, sun: Sun) -> Self {
        let map = picture.equirect(PROJECTION_ROWS, false);
        Lighting {
            sun: Sunlight::at(atmosphere, altitude_m, sun),
            sky_sh9: project_equirect(&map),
            sky_irradiance_up: irradiance_up(&map),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_uniform_sky_projects_onto_the_first_harmonic_only() {
        let mut map = Frame::new(256, 128);
        map.pixels.fill(Vec3::new(1.0, 2.0, 3.0));
        let sh = project_equirect(&map);
        // The integral of Y_00 over the sphere: 0.282095 x 4 pi.
        let want = 0.282_095 * 4.0 * std::f64::consts::PI;
        for c in 0..3 {
            assert!(
                (sh[0][c] / (c + 1) as f64 - want).abs() < 1e-3 * want,
                "{sh:?}"
            );
            for s in &sh[1..] {
                assert!(s[c].abs() < 1e-3 * want, "{sh:?}");
            }
        }
        // A uniform radiance L puts pi L on any surface, and is its own mean.
        let e = irradiance(&sh, Vec3::new(0.3, 0.9, 0.1).normalize());
        assert!((e[1] - 2.0 * std::f64::consts::PI).abs() < 1e-2, "{e:?}");
        let mean = mean_radiance(&map);
        assert!((mean[2] - 3.0).abs() < 1e-3, "{mean:?}");
    }

    #[test]
    fn a_radiance_from_above_only_lights_upward_surfaces() {
        // Radiance max(y, 0): irradiance up is 2 pi / 3, down 0 (to the SH's precision).
        let h = 128;
        let mut map = Frame::new(2 * h, h);
        for y in 0..h {
            for x in 0..2 * h {
                let d = equirect_direction(x, y, h);
                map.pixels[(y * 2 * h + x) as usize] = Vec3::splat(d.y.max(0.0));
            }
        }
        let sh = project_equirect(&map);
        let (up, down) = (irradiance(&sh, Vec3::Y)[0], irradiance(&sh, -Vec3::Y)[0]);
        let want = 2.0 * std::f64::consts::PI / 3.0;
        assert!(
            (up - want).abs() < 0.03 * want && down.abs() < 0.03 * want,
            "{up} {down}"
        );
        // Its mean over the sphere: (1 / 4 pi) 2 pi (1/2) = 1/4.
        let mean = mean_radiance(&map)[0];
        assert!((mean - 0.25).abs() < 1e-3, "{mean}");
    }
}
