//! The one camera of every method: a position and an orthonormal basis in the world
//! frame, a lens (pinhole or full-dome fisheye), an image size and supersampling.
//!
//! Sample planes are parallel to the screen (shafts 4.2), so the pinhole's natural ray is
//! the one whose component along the view axis is 1: the point at camera depth `z` on
//! the pixel's ray is `position + z * ray`.

use glam::{DVec3, Vec2, Vec3};

use super::direction_of;
use crate::error::{check_positive, check_range, Error, Result};
use crate::image::Frame;

/// The field of view of a pinhole, with the axis it spans.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Fov {
    /// Degrees across the image's height, in [0.01, 179].
    Vertical(f32),
    /// Degrees across the image's width, in [0.01, 179].
    Horizontal(f32),
}

impl Fov {
    /// `tan` of half the field of view across the width and the height of a
    /// `width` x `height` image (square pixels); an error naming `camera.fov_deg`.
    pub fn tan_halves(self, width: u32, height: u32) -> Result<(f32, f32)> {
        let (Fov::Vertical(deg) | Fov::Horizontal(deg)) = self;
        check_range("camera.fov_deg", deg as f64, 0.01, 179.0)?;
        let tan = (0.5 * deg.to_radians()).tan();
        let aspect = width as f32 / height as f32;
        Ok(match self {
            Fov::Vertical(_) => (tan * aspect, tan),
            Fov::Horizontal(_) => (tan, tan / aspect),
        })
    }
}

/// How the camera turns pixels into directions.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Lens {
    /// A pinhole, with `tan` of half the field of view across the width and the height.
    Pinhole {
        tan_half_width: f32,
        tan_half_height: f32,
    },
    /// An equidistant fisheye: the angle from the view axis grows with the distance from
    /// the image's centre, 90 deg at half the smaller side (the whole hemisphere in a
    /// circle); pixels outside the circle see nothing.
    Fisheye,
}

/// A camera in the world frame, validated.
#[derive(Debug, Clone, PartialEq)]
pub struct Camera {
    /// Eye position, m, world frame.
    pub position: Vec3,
    /// Unit view axis.
    pub forward: Vec3,
    /// Unit screen right.
    pub right: Vec3,
    /// Unit screen up.
    pub up: Vec3,
    /// Pinhole or fisheye.
    pub lens: Lens,
    /// Image width, pixels.
    pub width: u32,
    /// Image height, pixels.
    pub height: u32,
    /// Rays per pixel along each axis: `supersampling^2` rays on a regular grid,
    /// averaged (a box filter); 1 is one ray through the pixel centre.
    pub supersampling: u32,
    /// Nothing farther than this camera depth is drawn, m.
    pub far: f32,
}

impl Camera {
    /// A pinhole at `position` looking at `target`, rolled so that `up` is up on the
    /// screen; one ray a pixel, nothing clipped. Errors name `camera.look_at`,
    /// `camera.up`, `camera.fov_deg`, `width` or `height`.
    pub fn look_at(
        position: Vec3,
        target: Vec3,
        up: Vec3,
        fov: Fov,
        (width, height): (u32, u32),
    ) -> Result<Camera> {
        finite("camera.position", position)?;
        finite("camera.look_at", target)?;
        let forward = (target - position).try_normalize().ok_or_else(|| {
            Error::Invalid(format!(
                "camera.look_at = {target:?} equals camera.position: the camera has no view direction"
            ))
        })?;
        let right = forward.cross(up).try_normalize().ok_or_else(|| {
            Error::Invalid(format!(
                "camera.up = {up:?} is zero or parallel to the view direction {forward:?}"
            ))
        })?;
        Self::with_basis(position, forward, right, fov, (width, height))
    }

    /// A level pinhole at `position` looking toward azimuth `yaw_deg` (clockwise from
    /// north, in [-360, 360]) and elevation `pitch_deg` (in [-90, 90]), with no roll.
    pub fn yaw_pitch(
        position: Vec3,
        yaw_deg: f64,
        pitch_deg: f64,
        fov: Fov,
        size: (u32, u32),
    ) -> Result<Camera> {
        check_range("camera.yaw_deg", yaw_deg, -360.0, 360.0)?;
        check_range("camera.pitch_deg", pitch_deg, -90.0, 90.0)?;
        let yaw = yaw_deg.to_radians();
        let forward = direction_of(yaw, pitch_deg.to_radians());
        // Horizontal, to the right of the view: east when looking north.
        let right = DVec3::new(yaw.cos(), 0.0, yaw.sin());
        Self::with_basis(position, forward.as_vec3(), right.as_vec3(), fov, size)
    }

    /// The whole dome from `position`: a fisheye looking straight up, north at the top of
    /// the picture and east to the left (as seen from below).
    pub fn dome(position: Vec3, (width, height): (u32, u32)) -> Result<Camera> {
        finite("camera.position", position)?;
        Frame::check_size(width, height)?;
        Ok(Camera {
            position,
            forward: Vec3::Y,
            right: Vec3::NEG_X,
            up: Vec3::NEG_Z,
            lens: Lens::Fisheye,
            width,
            height,
            supersampling: 1,
            far: f32::INFINITY,
        })
    }

    fn with_basis(
        position: Vec3,
        forward: Vec3,
        right: Vec3,
        fov: Fov,
        (width, height): (u32, u32),
    ) -> Result<Camera> {
        finite("camera.position", position)?;
        Frame::check_size(width, height)?;
        let (tan_half_width, tan_half_height) = fov.tan_halves(width, height)?;
        Ok(Camera {
            position,
            forward,
            right,
            up: right.cross(forward),
            lens: Lens::Pinhole {
                tan_half_width,
                tan_half_height,
            },
            width,
            height,
            supersampling: 1,
            far: f32::INFINITY,
        })
    }

    /// The camera with `k` x `k` rays a pixel, `k` in [1, 16] (`camera.supersampling`).
    pub fn with_supersampling(self, k: u32) -> Result<Camera> {
        check_range("camera.supersampling", k as f64, 1.0, 16.0)?;
        Ok(Camera {
            supersampling: k,
            ..self
        })
    }

    /// The camera drawing nothing beyond camera depth `far_m` in (0, 1e7] (`camera.far_m`).
    pub fn with_far(self, far_m: f32) -> Result<Camera> {
        check_positive("camera.far_m", far_m as f64, 1e7)?;
        Ok(Camera { far: far_m, ..self })
    }

    /// The pinhole's `tan` of half the field of view across the width and the height; an
    /// error for a fisheye, which `method` cannot draw.
    pub fn pinhole(&self, method: &str) -> Result<(f32, f32)> {
        match self.lens {
            Lens::Pinhole {
                tan_half_width,
                tan_half_height,
            } => Ok((tan_half_width, tan_half_height)),
            Lens::Fisheye => Err(Error::Invalid(format!(
                "camera.lens = fisheye: {method} draws through a pinhole camera only"
            ))),
        }
    }

    /// The pinhole ray through the image point `(x, y)` in pixels (0,0 the top-left
    /// corner of the top-left pixel), scaled so that its component along the view axis
    /// is 1. For a fisheye, the direction of [`PixelBasis::direction`] (unscaled, NaN
    /// outside the circle).
    #[inline]
    pub fn ray(&self, x: f32, y: f32) -> Vec3 {
        match self.lens {
            Lens::Pinhole {
                tan_half_width,
                tan_half_height,
            } => {
                let sx = (2.0 * x / self.width as f32 - 1.0) * tan_half_width;
                let sy = (1.0 - 2.0 * y / self.height as f32) * tan_half_height;
                self.forward + sx * self.right + sy * self.up
            }
            Lens::Fisheye => self.pixel_basis().direction_at(x, y).unwrap_or(Vec3::NAN),
        }
    }

    /// Where the world point `p` shows in a pinhole's picture: the image point `(x, y)`
    /// whose [`Camera::ray`] passes through it, pixels from the top-left corner; `None`
    /// behind the camera (or on its plane) and through a fisheye.
    pub fn pixel_of(&self, p: Vec3) -> Option<(f32, f32)> {
        let Lens::Pinhole {
            tan_half_width,
            tan_half_height,
        } = self.lens
        else {
            return None;
        };
        let d = p - self.position;
        let z = d.dot(self.forward);
        (z > 0.0).then(|| {
            let sx = d.dot(self.right) / (z * tan_half_width);
            let sy = d.dot(self.up) / (z * tan_half_height);
            (
                (sx + 1.0) * 0.5 * self.width as f32,
                (1.0 - sy) * 0.5 * self.height as f32,
            )
        })
    }

    /// Offsets in pixels of the rays of one pixel, from its top-left corner.
    pub fn subpixel_offsets(&self) -> Vec<(f32, f32)> {
        let k = self.supersampling;
        (0..k * k)
            .map(|i| {
                (
                    ((i % k) as f32 + 0.5) / k as f32,
                    ((i / k) as f32 + 0.5) / k as f32,
                )
            })
            .collect()
    }

    /// Camera depth of the world point `p`, m (distance along the view axis).
    #[inline]
    pub fn depth(&self, p: Vec3) -> f32 {
        (p - self.position).dot(self.forward)
    }

    /// The per-frame constants that turn pixel centres into directions, in f32: a
    /// frame's millions of pixels need no more than the 1e-7 rad this resolves.
    pub fn pixel_basis(&self) -> PixelBasis {
        let (w, h) = (self.width as f32, self.height as f32);
        match self.lens {
            Lens::Pinhole {
                tan_half_width,
                tan_half_height,
            } => {
                // Direction = forward + u right + v up, with u, v from the pixel centre.
                let right = self.right * (2.0 * tan_half_width / w);
                let up = self.up * (2.0 * tan_half_height / h);
                PixelBasis::Perspective {
                    origin: self.forward - right * (0.5 * w) + up * (0.5 * h),
                    right,
                    up,
                }
            }
            Lens::Fisheye => PixelBasis::Fisheye {
                centre: Vec2::new(0.5 * w, 0.5 * h),
                radius: 0.5 * w.min(h),
                forward: self.forward,
                right: self.right,
                up: self.up,
            },
        }
    }
}

/// Refuses a point with a NaN or infinite coordinate, naming `field`.
fn finite(field: &str, p: Vec3) -> Result<()> {
    if p.is_finite() {
        Ok(())
    } else {
        Err(Error::Invalid(format!("{field} = {p:?} is not finite")))
    }
}

/// A [`Camera`]'s lens prepared for one frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PixelBasis {
    /// Direction of pixel (x, y) = `origin + (x + 1/2) right - (y + 1/2) up` (not unit).
    Perspective { origin: Vec3, right: Vec3, up: Vec3 },
    /// Angle from `forward` proportional to the distance from `centre` (pixels), 90 deg
    /// at `radius`, toward the screen's `right` and `up`.
    Fisheye {
        centre: Vec2,
        radius: f32,
        forward: Vec3,
        right: Vec3,
        up: Vec3,
    },
}

impl PixelBasis {
    /// The same basis with every vector mapped by `f`, a rotation: how a method with a
    /// frame of its own (the sky's) takes the camera in.
    pub fn rotated(self, f: impl Fn(Vec3) -> Vec3) -> PixelBasis {
        match self {
            PixelBasis::Perspective { origin, right, up } => PixelBasis::Perspective {
                origin: f(origin),
                right: f(right),
                up: f(up),
            },
            PixelBasis::Fisheye {
                centre,
                radius,
                forward,
                right,
                up,
            } => PixelBasis::Fisheye {
                centre,
                radius,
                forward: f(forward),
                right: f(right),
                up: f(up),
            },
        }
    }

    /// The angle a pixel spans at the centre of the picture, rad.
    pub fn pixel_angle(&self) -> f32 {
        match *self {
            // |up| is the tangent step of one pixel at the centre.
            PixelBasis::Perspective { up, .. } => up.length().atan(),
            PixelBasis::Fisheye { radius, .. } => std::f32::consts::FRAC_PI_2 / radius,
        }
    }

    /// The direction (not unit) through the centre of pixel (x, y), or `None` outside
    /// the fisheye's circle.
    #[inline]
    pub fn direction(&self, x: u32, y: u32) -> Option<Vec3> {
        self.direction_at(x as f32 + 0.5, y as f32 + 0.5)
    }

    /// The direction (not unit) through the image point `(px, py)`, pixels from the
    /// top-left corner, or `None` outside the fisheye's circle.
    #[inline]
    pub fn direction_at(&self, px: f32, py: f32) -> Option<Vec3> {
        match *self {
            PixelBasis::Perspective { origin, right, up } => Some(origin + px * right - py * up),
            PixelBasis::Fisheye {
                centre,
                radius,
                forward,
                right,
                up,
            } => {
                let q = Vec2::new(px - centre.x, centre.y - py) / radius;
                let rho = q.length();
                if rho > 1.0 {
                    return None;
                }
                let (sin_z, cos_z) = (rho * std::f32::consts::FRAC_PI_2).sin_cos();
                let across = if rho > 0.0 { q / rho } else { Vec2::Y };
                Some(cos_z * forward + (sin_z * across.x) * right + (sin_z * across.y) * up)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: Vec3, b: Vec3, tol: f32) -> bool {
        (a - b).length() < tol
    }

    #[test]
    fn a_pinhole_sees_its_target_in_the_middle_and_the_fov_at_the_edges() {
        let cam = Camera::look_at(
            Vec3::new(1.0, 2.0, 3.0),
            Vec3::new(1.0, 2.0, -7.0),
            Vec3::Y,
            Fov::Vertical(90.0),
            (200, 100),
        )
        .unwrap();
        assert!(close(cam.ray(100.0, 50.0), Vec3::NEG_Z, 1e-6));
        // Top edge: 45 deg up; right edge: tan = 2 (aspect 2).
        assert!(close(cam.ray(100.0, 0.0), Vec3::new(0.0, 1.0, -1.0), 1e-6));
        assert!(close(cam.ray(200.0, 50.0), Vec3::new(2.0, 0.0, -1.0), 1e-6));
        assert_eq!(cam.depth(Vec3::new(5.0, 0.0, -1.0)), 4.0);
        // The horizontal axis: 90 deg across the width.
        let wide = Camera::look_at(
            Vec3::ZERO,
            Vec3::NEG_Z,
            Vec3::Y,
            Fov::Horizontal(90.0),
            (200, 100),
        );
        assert!(close(
            wide.unwrap().ray(200.0, 0.0),
            Vec3::new(1.0, 0.5, -1.0),
            1e-6
        ));
    }

    #[test]
    fn the_pixel_basis_gives_the_pinholes_rays_at_pixel_centres() {
        let cam = Camera::yaw_pitch(Vec3::ZERO, 35.0, 12.0, Fov::Vertical(60.0), (64, 48)).unwrap();
        let basis = cam.pixel_basis();
        for (x, y) in [(0, 0), (63, 47), (20, 31)] {
            let a = basis.direction(x, y).unwrap().normalize();
            let b = cam.ray(x as f32 + 0.5, y as f32 + 0.5).normalize();
            assert!(close(a, b, 1e-5), "{x} {y}: {a} {b}");
        }
        // No roll: screen right is horizontal.
        assert!(cam.right.y.abs() < 1e-7 && cam.up.y > 0.0);
    }

    #[test]
    fn a_point_shows_where_the_pinholes_ray_through_it_comes_from() {
        let cam = Camera::yaw_pitch(
            Vec3::new(1.0, 2.0, 3.0),
            35.0,
            12.0,
            Fov::Vertical(60.0),
            (64, 48),
        )
        .unwrap();
        for (x, y) in [(0.0, 0.0), (63.5, 47.5), (20.25, 31.75), (-10.0, 60.0)] {
            let p = cam.position + 7.0 * cam.ray(x, y);
            let (px, py) = cam.pixel_of(p).unwrap();
            assert!(
                (px - x).abs() < 1e-3 && (py - y).abs() < 1e-3,
                "{x} {y}: {px} {py}"
            );
        }
        assert!(cam.pixel_of(cam.position - cam.forward).is_none());
        let dome = Camera::dome(Vec3::ZERO, (101, 101)).unwrap();
        assert!(dome.pixel_of(Vec3::Y).is_none());
    }

    #[test]
    fn the_dome_puts_the_zenith_in_the_middle_north_on_top_and_east_left() {
        let cam = Camera::dome(Vec3::ZERO, (101, 101)).unwrap();
        let b = cam.pixel_basis();
        assert!(close(b.direction(50, 50).unwrap(), Vec3::Y, 1e-6));
        let top = b.direction_at(50.5, 0.0).unwrap();
        assert!(close(top, Vec3::NEG_Z, 1e-6), "{top}");
        let left = b.direction_at(0.0, 50.5).unwrap();
        assert!(close(left, Vec3::X, 1e-6), "{left}");
        assert!(b.direction(0, 0).is_none());
        assert!(cam
            .pinhole("shafts")
            .unwrap_err()
            .to_string()
            .contains("camera.lens"));
    }

    #[test]
    fn bad_cameras_name_their_field() {
        let e = |r: Result<Camera>| r.unwrap_err().to_string();
        let at = |t, up, fov| Camera::look_at(Vec3::ZERO, t, up, fov, (10, 10));
        assert!(e(at(Vec3::ZERO, Vec3::Y, Fov::Vertical(40.0))).contains("camera.look_at"));
        let nan = Vec3::new(f32::NAN, 0.0, 0.0);
        assert!(e(at(nan, Vec3::Y, Fov::Vertical(40.0))).contains("camera.look_at = Vec3(NaN"));
        assert!(e(Camera::dome(nan, (10, 10))).contains("camera.position"));
        assert!(e(at(Vec3::Y, Vec3::Y, Fov::Vertical(40.0))).contains("camera.up"));
        assert!(e(at(Vec3::X, Vec3::Y, Fov::Vertical(180.0))).contains("camera.fov_deg"));
        let yaw = Camera::yaw_pitch(Vec3::ZERO, 0.0, 95.0, Fov::Vertical(40.0), (10, 10));
        assert!(e(yaw).contains("camera.pitch_deg"));
        let cam = at(Vec3::X, Vec3::Y, Fov::Vertical(40.0)).unwrap();
        assert!(e(cam.clone().with_supersampling(0)).contains("camera.supersampling"));
        assert!(e(cam.with_far(-1.0)).contains("camera.far_m"));
    }
}
