//! Pictures of the sky: a camera's pixels turned into directions, looked up in the
//! skylight map (bilinear, sky 4.2), with the ground below the horizon and the sun's
//! disc.
//!
//! World frame: x east, y north, z up. Azimuths are measured clockwise from north
//! (toward east), elevations up from the horizontal.

use glam::{DVec3, Vec2, Vec3};
use rayon::prelude::*;

use super::table::SkylightTable;
use super::{sun_disc_radiance, DirectionGrid, SkyModel, SkylightMap, Sun};
use crate::atmosphere::geometry::horizon_dip;
use crate::atmosphere::optical_depth::transmittance_to_sun;
use crate::atmosphere::spectrum::SpectrumToRgb;
use crate::atmosphere::Atmosphere;
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
        self.camera(width, height)
            .direction(x, y)
            .map(|d| d.as_dvec3())
    }

    /// The per-frame constants that turn pixels into directions, in f32: a frame's
    /// millions of pixels need no more than the 1e-7 rad this resolves.
    fn camera(&self, width: u32, height: u32) -> Camera {
        let (w, h) = (width as f32, height as f32);
        match *self {
            Projection::Perspective { yaw, pitch, fov_y } => {
                let forward = direction_of(yaw, pitch);
                let right = DVec3::new(yaw.cos(), -yaw.sin(), 0.0);
                let up = right.cross(forward);
                let t = (0.5 * fov_y).tan();
                // Direction = forward + u right + v up, with u, v from the pixel centre.
                let right = (right * t * 2.0 / height as f64).as_vec3();
                let up = (up * t * 2.0 / height as f64).as_vec3();
                Camera::Perspective {
                    origin: forward.as_vec3() - right * (0.5 * w) + up * (0.5 * h),
                    right,
                    up,
                }
            }
            Projection::Fisheye => Camera::Fisheye {
                centre: Vec2::new(0.5 * w, 0.5 * h),
                radius: 0.5 * w.min(h),
            },
        }
    }
}

/// [`Projection`] prepared for one frame size.
enum Camera {
    /// Direction of pixel (x, y) = `origin + (x + 1/2) right - (y + 1/2) up`, normalised.
    Perspective { origin: Vec3, right: Vec3, up: Vec3 },
    /// Zenith angle proportional to the distance from `centre`, 90 deg at `radius`.
    Fisheye { centre: Vec2, radius: f32 },
}

impl Camera {
    #[inline]
    fn direction(&self, x: u32, y: u32) -> Option<Vec3> {
        let (px, py) = (x as f32 + 0.5, y as f32 + 0.5);
        match *self {
            Camera::Perspective { origin, right, up } => {
                Some((origin + px * right - py * up).normalize())
            }
            Camera::Fisheye { centre, radius } => {
                // North (+y) up and east (+x) to the left, as seen from below.
                let q = (centre - Vec2::new(px, py)) / radius;
                let rho = q.length();
                if rho > 1.0 {
                    return None;
                }
                let (sin_z, cos_z) = (rho * std::f32::consts::FRAC_PI_2).sin_cos();
                let horizontal = if rho > 0.0 { q / rho } else { Vec2::Y };
                Some(Vec3::new(horizontal.x * sin_z, horizontal.y * sin_z, cos_z))
            }
        }
    }
}

/// `acos(x)` within 7e-5 rad for x in [-1, 1] (Abramowitz and Stegun 4.4.45), several
/// times faster than the library call; grid cells are 0.05 rad wide, so the picture
/// cannot tell.
#[inline]
fn fast_acos(x: f32) -> f32 {
    let a = x.abs().min(1.0);
    let r =
        (1.0 - a).sqrt() * (1.570_728_8 + a * (-0.212_114_4 + a * (0.074_261 - 0.018_729_3 * a)));
    if x < 0.0 {
        std::f32::consts::PI - r
    } else {
        r
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

/// Radiance over a grid of directions, linear sRGB.
struct RgbGrid {
    grid: DirectionGrid,
    rgb: Vec<Vec3>,
}

impl RgbGrid {
    fn of_map(map: &SkylightMap, colour: &SpectrumToRgb) -> Self {
        RgbGrid {
            grid: map.grid.clone(),
            rgb: map.to_rgb(colour).into_iter().map(Vec3::from).collect(),
        }
    }
}

/// The skylight map of one sun (and, from a model, the ground map), in linear sRGB,
/// ready to sample.
pub struct SkyPicture {
    sky: RgbGrid,
    /// Directions below `ground_below`: the ground map of a model; a table has none,
    /// and those pixels stay black.
    ground: Option<RgbGrid>,
    /// Elevation below which the ground map applies, rad.
    ground_below: f64,
    /// Horizontal unit vector toward the sun's azimuth.
    sun_horizontal: Vec2,
    sun_direction: Vec3,
    sun_rgb: Vec3,
    sun_cos_radius: f32,
}

impl SkyPicture {
    /// Computes the maps of `model` for `sun`.
    pub fn new(model: &SkyModel, sun: Sun) -> Self {
        let atmosphere = model.atmosphere();
        let colour = SpectrumToRgb::new(&atmosphere.wavelengths_nm);
        let mut sun_spectrum = vec![0.0; atmosphere.channels()];
        model.sun_radiance(sun.elevation, &mut sun_spectrum);
        Self::with_maps(
            atmosphere,
            sun,
            RgbGrid::of_map(&model.skylight_map(sun.elevation), &colour),
            Some(RgbGrid::of_map(&model.ground_map(sun.elevation), &colour)),
            -horizon_dip(atmosphere.bottom_radius_m, model.altitude_m()),
            colour.rgb(&sun_spectrum),
        )
    }

    /// Draws the skylight map of `sun` seen from `altitude_m` from `table` (sky 4.2);
    /// an error outside the table's ranges. Below the table's lowest elevation (the
    /// horizon's dip at its highest altitude) the picture is black.
    pub fn from_table(table: &SkylightTable, sun: Sun, altitude_m: f64) -> Result<Self> {
        let map = table.map(sun.elevation, altitude_m)?;
        Ok(Self::from_table_map(table, sun, altitude_m, map))
    }

    /// A picture of `map`, a skylight map of `table` for `sun` at `altitude_m`.
    pub fn from_table_map(
        table: &SkylightTable,
        sun: Sun,
        altitude_m: f64,
        map: Vec<Vec3>,
    ) -> Self {
        let atmosphere = table.atmosphere();
        let colour = SpectrumToRgb::new(&atmosphere.wavelengths_nm);
        let mut sun_spectrum = vec![0.0; atmosphere.channels()];
        let r = atmosphere.bottom_radius_m + altitude_m;
        transmittance_to_sun(atmosphere, r, sun.elevation.sin(), &mut sun_spectrum);
        sun_disc_radiance(atmosphere, &mut sun_spectrum);
        let grid = table.grid();
        let ground_below = grid.elevation_min;
        Self::with_maps(
            atmosphere,
            sun,
            RgbGrid { grid, rgb: map },
            None,
            ground_below,
            colour.rgb(&sun_spectrum),
        )
    }

    fn with_maps(
        atmosphere: &Atmosphere,
        sun: Sun,
        sky: RgbGrid,
        ground: Option<RgbGrid>,
        ground_below: f64,
        sun_rgb: [f32; 3],
    ) -> Self {
        let (sin_a, cos_a) = sun.azimuth.sin_cos();
        SkyPicture {
            sky,
            ground,
            ground_below,
            sun_horizontal: Vec2::new(sin_a as f32, cos_a as f32),
            sun_direction: direction_of(sun.azimuth, sun.elevation).as_vec3(),
            sun_rgb: Vec3::from(sun_rgb),
            sun_cos_radius: atmosphere.sun_angular_radius.cos() as f32,
        }
    }

    /// Linear sRGB radiance seen along the world direction `d`.
    pub fn radiance(&self, d: DVec3, sun_disc: bool) -> Vec3 {
        self.radiance_f32(d.normalize().as_vec3(), sun_disc)
    }

    /// [`SkyPicture::radiance`] for a unit vector in f32, the per-pixel path.
    #[inline]
    fn radiance_f32(&self, d: Vec3, sun_disc: bool) -> Vec3 {
        let elevation = (std::f32::consts::FRAC_PI_2 - fast_acos(d.z)) as f64;
        let horizontal = Vec2::new(d.x, d.y);
        let length = horizontal.length();
        // The azimuth from the sun's, folded into [0, pi] (the sky is symmetric).
        let relative = if length > 1e-6 {
            fast_acos(horizontal.dot(self.sun_horizontal) / length) as f64
        } else {
            0.0
        };
        let map = if elevation >= self.ground_below {
            Some(&self.sky)
        } else {
            self.ground.as_ref()
        };
        let mut rgb = map.map_or(Vec3::ZERO, |m| m.grid.bilinear(&m.rgb, relative, elevation));
        if sun_disc && d.dot(self.sun_direction) >= self.sun_cos_radius {
            rgb += self.sun_rgb;
        }
        rgb.max(Vec3::ZERO)
    }

    /// Renders `view`, rows in parallel.
    pub fn render(&self, view: &View) -> Frame {
        let mut frame = Frame::new(view.width, view.height);
        self.render_into(view, &mut frame);
        frame
    }

    /// Renders `view` into `frame` (of the view's size), rows in parallel.
    pub fn render_into(&self, view: &View, frame: &mut Frame) {
        let camera = view.projection.camera(view.width, view.height);
        frame
            .pixels
            .par_chunks_mut(view.width as usize)
            .enumerate()
            .for_each(|(y, row)| {
                for (x, p) in row.iter_mut().enumerate() {
                    *p = camera
                        .direction(x as u32, y as u32)
                        .map_or(Vec3::ZERO, |d| self.radiance_f32(d, view.sun_disc));
                }
            });
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
        assert!((d - want).length() < 1e-6, "{d} {want}");
        // Pixels to the right are clockwise (toward larger azimuth).
        let right = p.direction(100, 50, 101, 101).unwrap();
        assert!(right.x.atan2(right.y) > d.x.atan2(d.y));
    }

    #[test]
    fn fast_acos_is_within_its_stated_error() {
        let worst = (0..=20_000)
            .map(|k| -1.0 + k as f32 / 10_000.0)
            .map(|x| (fast_acos(x) - x.acos()).abs())
            .fold(0.0, f32::max);
        assert!(worst < 7e-5, "{worst}");
    }

    #[test]
    fn perspective_pixels_match_the_pinhole_formula() {
        let p = Projection::perspective_degrees(30.0, 20.0, 60.0).unwrap();
        let (yaw, pitch, t) = (
            30f64.to_radians(),
            20f64.to_radians(),
            30f64.to_radians().tan(),
        );
        let forward = direction_of(yaw, pitch);
        let right = DVec3::new(yaw.cos(), -yaw.sin(), 0.0);
        let up = right.cross(forward);
        for (x, y) in [(0, 0), (319, 0), (100, 179), (319, 179)] {
            let u = (2.0 * (x as f64 + 0.5) / 320.0 - 1.0) * t * 320.0 / 180.0;
            let v = (1.0 - 2.0 * (y as f64 + 0.5) / 180.0) * t;
            let want = (forward + u * right + v * up).normalize();
            let got = p.direction(x, y, 320, 180).unwrap();
            assert!((got - want).length() < 1e-6, "({x}, {y}): {got} {want}");
        }
    }

    #[test]
    fn fisheye_centre_is_the_zenith_and_north_is_up() {
        let p = Projection::Fisheye;
        assert!((p.direction(50, 50, 101, 101).unwrap().z - 1.0).abs() < 1e-6);
        let north = p.direction(50, 0, 101, 101).unwrap();
        assert!(north.y > 0.99, "{north}");
        let east = p.direction(0, 50, 101, 101).unwrap();
        assert!(east.x > 0.99, "{east}");
        assert!(p.direction(0, 0, 101, 101).is_none());
    }
}
