//! The table's error bound: what "an error of epsilon" on the display means (sky 4.1:
//! at most 1/255 on an 8-bit display).

use glam::Vec3;

use super::CHANNELS;
use crate::image::{srgb_decode, srgb_encode, Display};

/// The term counts aim this fraction below `epsilon`, so rounding in the inverse display
/// transform can never carry an error over the bound.
const BOUND_MARGIN: f32 = 1e-3;

/// What "an error of epsilon" means: the difference of the values a display is sent
/// for the table's and the directly computed radiance, channel by channel (linear sRGB
/// radiance times `display.exposure`, through `display.tone`, then sRGB-encoded if
/// `srgb`), in [0, 1]: 1/255 is one step of an 8-bit frame buffer.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ErrorBound {
    /// Largest difference of displayed values, in (0, 1).
    pub epsilon: f32,
    /// Exposure and tone map of the display.
    pub display: Display,
    /// Whether values are compared after sRGB encoding (what an 8-bit sRGB image holds)
    /// or before it (a linear frame buffer, as the paper's 8-bit values).
    pub srgb: bool,
}

impl ErrorBound {
    /// The value displayed for linear radiance `x`.
    #[inline]
    fn shown(&self, x: f32) -> f32 {
        let v = self.display.tone.apply(x * self.display.exposure);
        if self.srgb {
            srgb_encode(v)
        } else {
            v
        }
    }

    /// The linear radiance shown as `d` in [0, 1); `None` from 1 up, where every tone
    /// map saturates.
    fn radiance(&self, d: f32) -> Option<f32> {
        let v = if self.srgb {
            srgb_decode(d.max(0.0))
        } else {
            d.max(0.0)
        };
        (d < 1.0).then(|| self.display.tone.invert(v) / self.display.exposure)
    }

    /// The display error of `approx` against `exact` (linear radiance), in units of epsilon.
    #[inline]
    pub fn error(&self, approx: f32, exact: f32) -> f32 {
        (self.shown(approx) - self.shown(exact)).abs() / self.epsilon
    }

    /// The largest [`ErrorBound::error`] over two maps, channel by channel.
    pub fn max_error(&self, approx: &[Vec3], exact: &[Vec3]) -> f32 {
        approx
            .iter()
            .zip(exact)
            .flat_map(|(a, e)| (0..CHANNELS).map(move |c| self.error(a[c], e[c])))
            .fold(0.0, f32::max)
    }

    /// The interval of linear radiance shown within `epsilon (1 - margin)` of `exact`.
    pub(super) fn interval(&self, exact: f32) -> (f32, f32) {
        let eps = self.epsilon * (1.0 - BOUND_MARGIN);
        let d = self.shown(exact);
        let lo = if d - eps > 0.0 {
            self.radiance(d - eps).unwrap_or(f32::INFINITY)
        } else {
            f32::NEG_INFINITY
        };
        let hi = self.radiance(d + eps).unwrap_or(f32::INFINITY);
        (lo, hi)
    }
}
