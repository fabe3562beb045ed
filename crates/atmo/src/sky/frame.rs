//! Pictures of the sky: a camera's pixels turned into directions, looked up in the
//! skylight map (bilinear, sky 4.2), with the ground below the horizon and the sun's
//! disc.
//!
//! World frame: x east, y north, z up. Azimuths are measured clockwise from north
//! (toward east), elevations up from the horizontal.

use glam::{DVec3, Vec3};
use rayon::prelude::*;

use super::{SkyModel, SkylightMap, Sun};
use crate::atmosphere::geometry::horizon_dip;
use crate::atmosphere::spectrum::SpectrumToRgb;
use crate::error::{check_range, Result};
use crate::image::Frame;

/// How pixels map to directions.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Projection {
    /// A pinhole camera looking at azimuth `yaw` and elevation `pitch` (rad), with
    /// vertical field of view `fov_y` (rad).
    Perspective { yaw: f64, pitch: f64, fov_y: f64 },
    /// The whole dome in a circle: zenith at the centre, the horizontal at the rim,
    /// equidistant in zenith angle, north up and east to the left (as seen from below).
    Fisheye,
}

impl Projection {
    /// A perspective camera from degrees, validated.
    pub fn perspective_degrees(yaw: f64, pitch: f64, fov_y: f64) -> Result<Self> {
        check_range("yaw (deg)", yaw, -360.0, 360.0)?;
        check_range("pitch (deg)", pitch, -90.0, 90.0)?;
        check_range("fov (deg)", fov_y, 1.0, 179.0)?;
        Ok(Projection::Perspective {
            yaw: yaw.to_radians(),
            pitch: pitch.to_radians(),
            fov_y: fov_y.to_radians(),
        })
    }

    /// World direction through the centre of pixel (x, y) of a `width` x `height`
    /// image, or `None` outside the fisheye's circle.
    pub fn direction(&self, x: u32, y: u32, width: u32, height: u32) -> Option<DVec3> {
        let (w, h) = (width as f64, height as f64);
        let (px, py) = (x as f64 + 0.5, y as f64 + 0.5);
        match *self {
            Projection::Perspective { yaw, pitch, fov_y } => {
                let forward = direction_of(yaw, pitch);
                let right = DVec3::new(yaw.cos(), -yaw.sin(), 0.0);
                let up = right.cross(forward);
                let t = (0.5 * fov_y).tan();
                let u = (2.0 * px / w - 1.0) * t * w / h;
                let v = (1.0 - 2.0 * py / h) * t;
                Some((forward + u * right + v * up).normalize())
            }
            Projection::Fisheye => {
                let radius = 0.5 * w.min(h);
                let (dx, dy) = ((px - 0.5 * w) / radius, (py - 0.5 * h) / radius);
                let rho = (dx * dx + dy * dy).sqrt();
                if rho > 1.0 {
                    return None;
                }
                let zenith = rho * std::f64::consts::FRAC_PI_2;
                let azimuth = (-dx).atan2(-dy);
                Some(direction_of(azimuth, std::f64::consts::FRAC_PI_2 - zenith))
            }
        }
    }
}

/// Unit vector at `azimuth` (clockwise from north) and `elevation`, rad.
pub fn direction_of(azimuth: f64, elevation: f64) -> DVec3 {
    let (sa, ca) = azimuth.sin_cos();
    let (se, ce) = elevation.sin_cos();
    DVec3::new(sa * ce, ca * ce, se)
}

/// What to draw and how big.
#[derive(Debug, Clone, Copy)]
pub struct View {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Camera.
    pub projection: Projection,
    /// Whether to draw the sun's disc.
    pub sun_disc: bool,
}

/// The skylight map and the ground map of one sun, in linear sRGB, ready to sample.
pub struct SkyPicture {
    sky: SkylightMap,
    sky_rgb: Vec<Vec3>,
    ground: SkylightMap,
    ground_rgb: Vec<Vec3>,
    dip: f64,
    sun: Sun,
    sun_rgb: Vec3,
    sun_cos_radius: f64,
}

impl SkyPicture {
    /// Computes the maps of `model` for `sun`.
    pub fn new(model: &SkyModel, sun: Sun) -> Self {
        let atmosphere = model.atmosphere();
        let colour = SpectrumToRgb::new(&atmosphere.wavelengths_nm);
        let to_vec = |m: &SkylightMap| {
            m.to_rgb(&colour)
                .into_iter()
                .map(Vec3::from)
                .collect::<Vec<_>>()
        };
        let sky = model.skylight_map(sun.elevation);
        let ground = model.ground_map(sun.elevation);
        let mut sun_spectrum = vec![0.0; atmosphere.channels()];
        model.sun_radiance(sun.elevation, &mut sun_spectrum);
        SkyPicture {
            sky_rgb: to_vec(&sky),
            ground_rgb: to_vec(&ground),
            sky,
            ground,
            dip: horizon_dip(atmosphere.bottom_radius_m, model.altitude_m()),
            sun,
            sun_rgb: Vec3::from(colour.rgb(&sun_spectrum)),
            sun_cos_radius: atmosphere.sun_angular_radius.cos(),
        }
    }

    /// Linear sRGB radiance seen along the world direction `d`.
    pub fn radiance(&self, d: DVec3, sun_disc: bool) -> Vec3 {
        let elevation = d.z.clamp(-1.0, 1.0).asin();
        let azimuth = d.x.atan2(d.y);
        let mut relative = (azimuth - self.sun.azimuth).rem_euclid(std::f64::consts::TAU);
        if relative > std::f64::consts::PI {
            relative = std::f64::consts::TAU - relative;
        }
        let mut rgb = if elevation >= -self.dip {
            self.sky.grid.bilinear(&self.sky_rgb, relative, elevation)
        } else {
            self.ground
                .grid
                .bilinear(&self.ground_rgb, relative, elevation)
        };
        if sun_disc
            && d.dot(direction_of(self.sun.azimuth, self.sun.elevation)) >= self.sun_cos_radius
        {
            rgb += self.sun_rgb;
        }
        rgb.max(Vec3::ZERO)
    }

    /// Renders `view`, rows in parallel.
    pub fn render(&self, view: &View) -> Frame {
        let mut frame = Frame::new(view.width, view.height);
        frame
            .pixels
            .par_chunks_mut(view.width as usize)
            .enumerate()
            .for_each(|(y, row)| {
                for (x, p) in row.iter_mut().enumerate() {
                    if let Some(d) =
                        view.projection
                            .direction(x as u32, y as u32, view.width, view.height)
                    {
                        *p = self.radiance(d, view.sun_disc);
                    }
                }
            });
        frame
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn perspective_centre_looks_along_yaw_and_pitch() {
        let p = Projection::perspective_degrees(90.0, 10.0, 60.0).unwrap();
        let d = p.direction(50, 50, 101, 101).unwrap();
        let want = direction_of(90f64.to_radians(), 10f64.to_radians());
        assert!((d - want).length() < 1e-9, "{d} {want}");
        // Pixels to the right are clockwise (toward larger azimuth).
        let right = p.direction(100, 50, 101, 101).unwrap();
        assert!(right.x.atan2(right.y) > d.x.atan2(d.y));
    }

    #[test]
    fn fisheye_centre_is_the_zenith_and_north_is_up() {
        let p = Projection::Fisheye;
        assert!((p.direction(50, 50, 101, 101).unwrap().z - 1.0).abs() < 1e-9);
        let north = p.direction(50, 0, 101, 101).unwrap();
        assert!(north.y > 0.99, "{north}");
        let east = p.direction(0, 50, 101, 101).unwrap();
        assert!(east.x > 0.99, "{east}");
        assert!(p.direction(0, 0, 101, 101).is_none());
    }
}
