//! The pinhole camera of a shafts scene. Sample planes are parallel to its screen
//! (shafts 4.2), so the natural ray is the one whose component along the view axis is
//! 1: the point at camera depth `z` on the pixel's ray is `position + z * ray`.

use glam::Vec3;

/// A pinhole camera, validated.
#[derive(Debug, Clone, PartialEq)]
pub struct Camera {
    /// Eye position, m.
    pub position: Vec3,
    /// Unit view axis.
    pub forward: Vec3,
    /// Unit screen right.
    pub right: Vec3,
    /// Unit screen up.
    pub up: Vec3,
    /// `tan` of half the horizontal field of view.
    pub tan_half_width: f32,
    /// `tan` of half the vertical field of view.
    pub tan_half_height: f32,
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
    /// A camera at `position` looking at `target`, rolled so that `up` is up on the
    /// screen; `tan_half` the tangents of half the field of view across the width and
    /// the height; one ray a pixel, nothing clipped. `None` when `target` is `position`
    /// or `up` is zero or along the view.
    pub fn look_at(
        position: Vec3,
        target: Vec3,
        up: Vec3,
        (tan_half_width, tan_half_height): (f32, f32),
        (width, height): (u32, u32),
    ) -> Option<Camera> {
        let forward = (target - position).try_normalize()?;
        let right = forward.cross(up).try_normalize()?;
        Some(Camera {
            position,
            forward,
            right,
            up: right.cross(forward),
            tan_half_width,
            tan_half_height,
            width,
            height,
            supersampling: 1,
            far: f32::INFINITY,
        })
    }

    /// The ray through the image point `(x, y)` in pixels (0,0 the top-left corner of
    /// the top-left pixel), scaled so that its component along the view axis is 1.
    #[inline]
    pub fn ray(&self, x: f32, y: f32) -> Vec3 {
        let sx = (2.0 * x / self.width as f32 - 1.0) * self.tan_half_width;
        let sy = (1.0 - 2.0 * y / self.height as f32) * self.tan_half_height;
        self.forward + sx * self.right + sy * self.up
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
}
