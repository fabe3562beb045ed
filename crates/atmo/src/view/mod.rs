//! The shared floor of the three methods: the one world frame, the [`Sun`] and the
//! [`Camera`].
//!
//! # The world frame
//!
//! Every method works in one frame: **right-handed, +y up, metres**, with x toward the
//! east and z toward the south (so -z is north, the way a camera looking "into the
//! screen" looks north). The origin is on the ground; for the sky, `y` is the altitude
//! above the planet's surface. Azimuths are measured clockwise from north toward east,
//! elevations up from the horizontal, both in degrees at the edges (files, the command
//! line) and in radians inside.
//!
//! The sky's planet-centred frame (z up) is an internal detail of [`crate::sky`]; a
//! shafts scene is in this frame as its file writes it; clouds are in it as they are.
//!
//! ```
//! use atmo::view::{direction_of, Sun};
//! let sun = Sun::from_degrees(30.0, 90.0)?; // 30 deg up, due east
//! let toward = sun.toward();
//! assert!((toward.y - 0.5).abs() < 1e-6 && toward.x > 0.8);
//! assert!((direction_of(0.0, 0.0) - glam::DVec3::NEG_Z).length() < 1e-12); // north
//! # Ok::<(), atmo::Error>(())
//! ```

mod camera;
pub mod input;
#[cfg(feature = "place")]
pub mod place;

pub use camera::{Camera, Fov, Lens, PixelBasis};

use glam::{DVec3, Vec3};

use crate::error::{check_range, Error, Result};

/// The unit world vector at `azimuth` (clockwise from north) and `elevation`, rad.
pub fn direction_of(azimuth: f64, elevation: f64) -> DVec3 {
    let (sa, ca) = azimuth.sin_cos();
    let (se, ce) = elevation.sin_cos();
    DVec3::new(sa * ce, se, -ca * ce)
}

/// The sun, as seen from the scene: its position on the sky, which every method turns
/// into the unit vector **toward the sun** ([`Sun::toward`]), the direction opposite to
/// the one its light travels in.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sun {
    /// Elevation above the horizontal, rad, in [-pi/2, pi/2].
    elevation: f64,
    /// Azimuth, rad, clockwise from north toward east.
    azimuth: f64,
}

impl Sun {
    /// A sun at `elevation_deg` in [-90, 90] and `azimuth_deg` in [-360, 360] (clockwise
    /// from north), validated: errors name `sun.elevation_deg` and `sun.azimuth_deg`.
    pub fn from_degrees(elevation_deg: f64, azimuth_deg: f64) -> Result<Self> {
        check_range("sun.elevation_deg", elevation_deg, -90.0, 90.0)?;
        check_range("sun.azimuth_deg", azimuth_deg, -360.0, 360.0)?;
        Ok(Sun {
            elevation: elevation_deg.to_radians(),
            azimuth: azimuth_deg.to_radians(),
        })
    }

    /// The same sun at `elevation`, rad, clamped to [-pi/2, pi/2] (a sun moving through
    /// a sequence).
    pub fn with_elevation(self, elevation: f64) -> Self {
        let limit = std::f64::consts::FRAC_PI_2;
        Sun {
            elevation: elevation.clamp(-limit, limit),
            ..self
        }
    }

    /// The sun in the direction `toward` (any non-zero length, world frame); an error
    /// naming `sun.direction` when it is zero or not finite.
    pub fn from_toward(toward: Vec3) -> Result<Self> {
        let d = toward.as_dvec3().try_normalize().ok_or_else(|| {
            Error::Invalid(format!(
                "sun.direction = {toward:?} has no direction: give a finite, non-zero vector"
            ))
        })?;
        Ok(Sun {
            elevation: d.y.clamp(-1.0, 1.0).asin(),
            azimuth: d.x.atan2(-d.z),
        })
    }

    /// Elevation above the horizontal, rad.
    pub fn elevation(&self) -> f64 {
        self.elevation
    }

    /// Azimuth clockwise from north, rad.
    pub fn azimuth(&self) -> f64 {
        self.azimuth
    }

    /// The unit world vector toward the sun.
    pub fn toward(&self) -> Vec3 {
        direction_of(self.azimuth, self.elevation).as_vec3()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_frame_is_right_handed_with_y_up_x_east_and_z_south() {
        let east = direction_of(90f64.to_radians(), 0.0);
        let north = direction_of(0.0, 0.0);
        let up = direction_of(0.0, 90f64.to_radians());
        assert!((east - DVec3::X).length() < 1e-12);
        assert!((up - DVec3::Y).length() < 1e-12);
        // Right-handed: east x up = south = +z.
        assert!((east.cross(up) - DVec3::Z).length() < 1e-12);
        assert!((north + DVec3::Z).length() < 1e-12);
    }

    #[test]
    fn a_sun_survives_the_round_trip_through_its_direction() {
        for (e, a) in [(30.0, 0.0), (-5.0, 200.0), (89.0, -45.0), (0.5, 90.0)] {
            let sun = Sun::from_degrees(e, a).unwrap();
            let back = Sun::from_toward(sun.toward() * 3.0).unwrap();
            assert!((back.elevation() - sun.elevation()).abs() < 1e-6, "{e} {a}");
            // The azimuths' difference, folded into [-pi, pi].
            let tau = std::f64::consts::TAU;
            let da = (back.azimuth() - sun.azimuth() + 0.5 * tau).rem_euclid(tau) - 0.5 * tau;
            assert!(da.abs() < 1e-6, "{e} {a}: {da}");
        }
    }

    #[test]
    fn bad_suns_name_their_field() {
        let e = Sun::from_degrees(91.0, 0.0).unwrap_err().to_string();
        assert!(
            e.contains("sun.elevation_deg") && e.contains("[-90, 90]"),
            "{e}"
        );
        let e = Sun::from_degrees(0.0, 400.0).unwrap_err().to_string();
        assert!(e.contains("sun.azimuth_deg"), "{e}");
        let e = Sun::from_toward(Vec3::ZERO).unwrap_err().to_string();
        assert!(e.contains("sun.direction"), "{e}");
    }
}
