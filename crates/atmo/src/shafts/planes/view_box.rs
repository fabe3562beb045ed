//! Where objects and lit volumes show on the camera's view plane, so a ray tries only
//! what it can meet.

use super::*;

/// A camera ray's point on the view plane at unit distance (`ray` unit length along
/// the view axis): its components along the camera's right and up.
#[inline]
pub(super) fn view_point(camera: &Camera, ray: Vec3) -> (f32, f32) {
    (ray.dot(camera.right), ray.dot(camera.up))
}

/// Where a box shows on the camera's view plane ([`view_point`]): a ray through a
/// point outside cannot meet it, as its picture in front of the eye is the hull of its
/// corners'.
#[derive(Debug, Clone, Copy)]
pub(super) struct ViewBox {
    pub(super) x: [f32; 2],
    pub(super) y: [f32; 2],
}

impl ViewBox {
    /// Everywhere: what an unbounded plane, or a box reaching to the eye's plane, gets.
    pub(super) const EVERYWHERE: ViewBox = ViewBox {
        x: [f32::NEG_INFINITY, f32::INFINITY],
        y: [f32::NEG_INFINITY, f32::INFINITY],
    };

    /// The box around `bounds`' corners seen by `camera`, widened by 1e-4 of a unit
    /// and of its coordinates (well above the rounding of a ray's point and of a hit
    /// test at the edge).
    pub(super) fn of(bounds: Option<Aabb>, camera: &Camera) -> ViewBox {
        let Some(bounds) = bounds else {
            return ViewBox::EVERYWHERE;
        };
        let widen = |x: f32, sign: f32| x + sign * 1e-4 * (1.0 + x.abs());
        bounds
            .corners()
            .into_iter()
            .try_fold(
                ViewBox {
                    x: [f32::INFINITY, f32::NEG_INFINITY],
                    y: [f32::INFINITY, f32::NEG_INFINITY],
                },
                |b, c| {
                    let d = c - camera.position;
                    let z = d.dot(camera.forward);
                    // A corner near or behind the eye's plane projects anywhere.
                    (z > 1e-3 * d.length()).then_some(())?;
                    let (x, y) = (d.dot(camera.right) / z, d.dot(camera.up) / z);
                    Some(ViewBox {
                        x: [b.x[0].min(widen(x, -1.0)), b.x[1].max(widen(x, 1.0))],
                        y: [b.y[0].min(widen(y, -1.0)), b.y[1].max(widen(y, 1.0))],
                    })
                },
            )
            .unwrap_or(ViewBox::EVERYWHERE)
    }

    #[inline]
    pub(super) fn holds(&self, (x, y): (f32, f32)) -> bool {
        x >= self.x[0] && x <= self.x[1] && y >= self.y[0] && y <= self.y[1]
    }
}
