//! The sky's light on things in the air: the sun's irradiance after the atmosphere down
//! to a point, and the sky's radiance there. This is how the sky lights the other
//! methods (a cloud is lit by [`Daylight::sunlight`] and [`Daylight::skylight`]) without
//! any of them knowing the sky: they take the sun's colour and the sky's harmonics.

use glam::Vec3;

use super::lighting::project_equirect;
use super::{SkyModel, SkyPicture, SkySettings};
use crate::atmosphere::spectrum::SpectrumToRgb;
use crate::atmosphere::Atmosphere;
use crate::error::Result;
use crate::image::Frame;
use crate::view::Sun;

/// Rows of the equirectangular map [`Daylight::skylight`] projects (5.6 deg a row):
/// the sky's light varies smoothly, and its nine harmonics are within 0.5 % of the
/// mean's of a map four times finer (test below).
const SKYLIGHT_MAP_HEIGHT: u32 = 32;

/// Sunlight and skylight at one altitude of an atmosphere.
pub struct Daylight {
    model: SkyModel,
    colour: SpectrumToRgb,
}

impl Daylight {
    /// The light at `altitude_m` above the ground (inside the atmosphere), computed by
    /// the shell method with `settings`.
    pub fn new(atmosphere: &Atmosphere, settings: &SkySettings, altitude_m: f64) -> Result<Self> {
        Ok(Daylight {
            model: SkyModel::new(atmosphere, settings, altitude_m)?,
            colour: SpectrumToRgb::for_atmosphere(atmosphere),
        })
    }

    /// The sun's irradiance on a surface facing it, linear sRGB in the atmosphere's
    /// irradiance units: its disc's radiance through the atmosphere times the disc's
    /// solid angle.
    pub fn sunlight(&self, sun: Sun) -> Vec3 {
        let atmosphere = self.model.atmosphere();
        let mut spectrum = vec![0.0f32; atmosphere.wavelengths_nm.len()];
        self.model.sun_radiance(sun.elevation(), &mut spectrum);
        let disc = std::f64::consts::PI * atmosphere.sun_angular_radius.powi(2);
        spectrum.iter_mut().for_each(|v| *v *= disc as f32);
        Vec3::from(self.colour.rgb(&spectrum))
    }

    /// The sky's radiance all around (the sky above, the lit ground below, no sun
    /// disc) as nine spherical harmonics per linear-sRGB channel ([`super::lighting`]'s
    /// basis): the light a cloud's droplets scatter from the sky.
    pub fn skylight(&self, sun: Sun) -> [[f64; 3]; 9] {
        project_equirect(&self.skylight_map(sun))
    }

    /// The same light as an equirectangular map ([`super::envmap`]'s conventions),
    /// 32 rows (5.6 deg a row): for what needs the sky's own shape, such as its
    /// horizon, which nine harmonics blur (a cloud's transfer solve).
    pub fn skylight_map(&self, sun: Sun) -> Frame {
        SkyPicture::new(&self.model, sun).equirect(SKYLIGHT_MAP_HEIGHT, false)
    }

    /// The model behind the two.
    pub fn model(&self) -> &SkyModel {
        &self.model
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sunlight_reddens_and_dims_toward_the_horizon_and_the_sky_is_blue() {
        let settings = SkySettings {
            shells: 12,
            directions: 16,
            scattering_directions: 32,
            sun_bins: 16,
            ..SkySettings::default()
        };
        let light = Daylight::new(&Atmosphere::earth(), &settings, 1500.0).unwrap();
        let high = light.sunlight(Sun::from_degrees(60.0, 0.0).unwrap());
        let low = light.sunlight(Sun::from_degrees(3.0, 0.0).unwrap());
        assert!(high.min_element() > 0.0 && low.min_element() > 0.0);
        assert!(low.x < high.x && low.z < high.z, "{low} {high}");
        assert!(
            low.z / low.x < high.z / high.x,
            "redder at sunset: {low} {high}"
        );
        let sun = Sun::from_degrees(60.0, 0.0).unwrap();
        let harmonics = light.skylight(sun);
        // The mean over the sphere: band 0 times its basis function.
        let sky = Vec3::from(harmonics[0].map(|h| (h * crate::sky::lighting::SH_Y00) as f32));
        assert!(sky.z > sky.x && sky.x > 0.0, "blue: {sky}");
        // The sky's light is a small part of the sun's.
        assert!(sky.z < 0.1 * high.z, "{sky} {high}");
        // Bluer above than the lit ground below (harmonic 1 is along up).
        assert!(harmonics[1][2] > harmonics[1][0], "{harmonics:?}");
        // The map is fine enough: every harmonic within 0.5 % of the mean's.
        let fine = project_equirect(
            &SkyPicture::new(light.model(), sun).equirect(4 * SKYLIGHT_MAP_HEIGHT, false),
        );
        for (k, (coarse, finer)) in harmonics.iter().zip(fine).enumerate() {
            for c in 0..3 {
                let off = (coarse[c] - finer[c]).abs() / fine[0][c];
                assert!(off < 5e-3, "{k}, {c}: {} vs {}", coarse[c], finer[c]);
            }
        }
    }
}
