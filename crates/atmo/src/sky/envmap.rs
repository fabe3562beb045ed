//! Environment maps: the whole sphere of directions around the viewpoint (sky, ground,
//! the sun's disc if asked) as linear radiance, for engines to light and reflect with.
//!
//! Conventions, in the world frame of [`crate::view`] (x east, y up, z south):
//!
//! - **Equirectangular**, `2N x N`: column `u = (x + 0.5) / 2N` is the azimuth clockwise
//!   from north, `360 u` deg (north at both edges, east a quarter of the way in, south
//!   in the middle); row `v = (y + 0.5) / N` the elevation `90 - 180 v` deg (zenith on
//!   top).
//! - **Cubemap**, six `N x N` faces in the order +X, -X, +Y, -Y, +Z, -Z (east, west, up,
//!   down, south, north), each oriented as in the OpenGL and Vulkan cube-map rules (which
//!   KTX2 follows): on face +X, for instance, pixels run toward -z to the right and
//!   toward -y downward ([`cube_direction`]).

use glam::Vec3;

use crate::error::{check_range, Result};
use crate::image::Frame;

use super::SkyPicture;

/// What kind of environment map.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum EnvmapKind {
    /// One `2N x N` latitude-longitude picture.
    Equirect,
    /// Six `N x N` faces.
    Cubemap,
}

/// The faces of a cubemap in order, as file-name suffixes.
pub const CUBE_FACES: [&str; 6] = ["px", "nx", "py", "ny", "pz", "nz"];

/// The world direction (unit) through the centre of pixel (`x`, `y`) of an
/// equirectangular map `height` rows high.
pub fn equirect_direction(x: u32, y: u32, height: u32) -> Vec3 {
    let azimuth = std::f32::consts::TAU * (x as f32 + 0.5) / (2 * height) as f32;
    let elevation =
        std::f32::consts::FRAC_PI_2 - std::f32::consts::PI * (y as f32 + 0.5) / height as f32;
    let (sin_e, cos_e) = elevation.sin_cos();
    let (sin_a, cos_a) = azimuth.sin_cos();
    Vec3::new(cos_e * sin_a, sin_e, -cos_e * cos_a)
}

/// The world direction (unit) through the centre of pixel (`x`, `y`) of cube face
/// `face` (0 to 5 in [`CUBE_FACES`] order) `size` pixels a side.
pub fn cube_direction(face: usize, x: u32, y: u32, size: u32) -> Vec3 {
    let a = 2.0 * (x as f32 + 0.5) / size as f32 - 1.0;
    let b = 2.0 * (y as f32 + 0.5) / size as f32 - 1.0;
    let d = match face {
        0 => Vec3::new(1.0, -b, -a),
        1 => Vec3::new(-1.0, -b, a),
        2 => Vec3::new(a, 1.0, b),
        3 => Vec3::new(a, -1.0, -b),
        4 => Vec3::new(a, -b, 1.0),
        _ => Vec3::new(-a, -b, -1.0),
    };
    d.normalize()
}

/// Checks an environment map's size `n` (rows of an equirectangular map, or a cube
/// face's side): in range, and the map's frames ([`Frame::BYTES_PER_PIXEL`]) within
/// the run's memory budget; errors name the field `envmap size`.
pub fn check_size(kind: EnvmapKind, n: u32) -> Result<()> {
    check_range("envmap size", n as f64, 4.0, 8192.0)?;
    let side = n as u64;
    let (what, pixels) = match kind {
        EnvmapKind::Equirect => (format!("a {} x {n} map", 2 * n), 2 * side * side),
        EnvmapKind::Cubemap => (format!("six {n} x {n} cube faces"), 6 * side * side),
    };
    crate::budget::check(&what, pixels * Frame::BYTES_PER_PIXEL, "envmap size")
}

impl SkyPicture {
    /// The equirectangular map, `2 height x height`, linear sRGB radiance.
    pub fn equirect(&self, height: u32, sun_disc: bool) -> Frame {
        let pixel = std::f32::consts::PI / height as f32;
        self.render_directions(2 * height, height, pixel, sun_disc, |x, y| {
            equirect_direction(x, y, height)
        })
    }

    /// The six faces of the cubemap, `size x size` each, in [`CUBE_FACES`] order.
    pub fn cubemap(&self, size: u32, sun_disc: bool) -> Vec<Frame> {
        let pixel = std::f32::consts::FRAC_PI_2 / size as f32;
        (0..6)
            .map(|face| {
                self.render_directions(size, size, pixel, sun_disc, |x, y| {
                    cube_direction(face, x, y, size)
                })
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn equirect_directions_follow_the_convention() {
        let h = 90;
        // Pixel centres sit half a pixel (1 deg here) from the exact angles.
        let close = |a: Vec3, b: Vec3| (a - b).length() < 0.05;
        // The middle of the top row is near the zenith, the bottom near the nadir.
        assert!(close(equirect_direction(90, 0, h), Vec3::Y));
        assert!(close(equirect_direction(90, h - 1, h), -Vec3::Y));
        // On the horizon row: north at the left edge, east at a quarter, south half-way.
        let row = h / 2;
        assert!(close(equirect_direction(0, row, h), -Vec3::Z));
        assert!(close(equirect_direction(45, row, h), Vec3::X));
        assert!(close(equirect_direction(90, row, h), Vec3::Z));
        assert!(close(equirect_direction(135, row, h), -Vec3::X));
    }

    #[test]
    fn cube_faces_cover_the_sphere_as_opengl_does() {
        let n = 64;
        let centres = [Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z];
        for (face, centre) in centres.iter().enumerate() {
            assert!((cube_direction(face, n / 2, n / 2, n) - *centre).length() < 0.05);
        }
        // OpenGL's table: on +X, s runs toward -z and t toward -y.
        let top_left = cube_direction(0, 0, 0, n);
        assert!(top_left.z > 0.5 && top_left.y > 0.5, "{top_left}");
        // On +Y (up), t runs toward +z (south): the bottom row faces south.
        assert!(cube_direction(2, n / 2, n - 1, n).z > 0.5);
        // Every direction belongs to exactly the face whose axis dominates it.
        for (face, centre) in centres.iter().enumerate() {
            for (x, y) in [(0, 0), (n - 1, 3), (20, n - 1)] {
                let d = cube_direction(face, x, y, n);
                let major = d.abs().max_element();
                assert!((d.dot(*centre) - major).abs() < 1e-6, "{face} {x} {y}");
            }
        }
    }
}
