//! Shafts of light from spotlights in haze, after Dobashi, Yamamoto and Nishita, "An
//! accurate, fast method using graphics hardware for rendering shafts of light" (cited
//! as `shafts (n)`).
//!
//! What reaches the eye along a ray, shafts (1)-(3): the surface it meets, dimmed by the
//! haze, plus the light scattered toward the eye along the way,
//!
//! ```text
//! I_v = I_o exp(-sigma_t T) + integral_0^T H(t) I_l(t) g(alpha, s, t) dt
//! g   = sigma_s p(alpha) exp(-sigma_t (s + t)) / s^2
//! ```
//!
//! with `H` the light's visibility, `I_l` its intensity toward the point, `s` and `t`
//! the point's distances from the lamp and the eye (units and the paper's `rho`, `kappa`,
//! `K`: see [`haze`]). The modules follow the paper's pieces:
//!
//! - [`scene`]: the scene file (its camera is a [`crate::view::Camera`]); [`haze`], [`spotlight`] (beam, falloff, gobo
//!   as the projected light map), [`objects`] (planes, rectangles, spheres, boxes, OBJ
//!   meshes).
//! - [`edits`]: changes to a scene file by key (`--set`, the viewer's edits).
//! - [`photometry`]: measured profiles from IES LM-63 and EULUMDAT files.
//! - [`gdtf`]: fixtures from GDTF files (read with the `gdtf` feature).
//! - [`show`]: moving heads (pan, tilt, zoom, iris, colour, gobo wheel) and cues.
//! - [`shadow_map`]: `H` from a depth map per light (shafts 4.1).
//! - [`tables`]: the `F` and `h` tables of shafts (6).
//! - [`planes`]: the sample planes and sub-sample planes of shafts (5) and (7)-(9), the
//!   fast method.
//! - [`surface`]: the first term of shafts (1), shared by the fast method and the
//!   reference ([`crate::reference::shafts`]).

pub mod adaptive;
pub mod dmx;
pub mod edits;
pub mod gdtf;
#[cfg(feature = "gdtf")]
pub mod gdtf_body;
pub mod haze;
#[cfg(feature = "gdtf")]
pub mod mvr;
pub mod objects;
pub mod photometry;
pub mod planes;
pub mod scene;
pub mod shadow_map;
pub mod show;
pub mod spotlight;
pub mod surface;
pub mod tables;

use glam::Vec3;
use rayon::prelude::*;

pub use planes::SamplePlanes;
pub use scene::{Scene, SceneBuilder, SpotlightBuilder};

use crate::error::{check_range, Result};
use crate::fast::interleaved_offset;
use crate::image::Frame;
use crate::view::Camera;

/// The resolution of the plane method.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PlaneSettings {
    /// Sample planes `n` of shafts (5), parallel to the screen, evenly spaced through
    /// each light's lit volume.
    pub planes: u32,
    /// Sub-sample planes `m` per sample plane interval, shafts (9).
    pub sub_planes: u32,
    /// Texels along each side of a light's shadow map.
    pub shadow_map: u32,
    /// Whether the CPU computes the scattered light only where the picture needs it
    /// and interpolates between ([`adaptive`]; the default): on Fig. 6 a fifth of the
    /// pixels, within 0.1 level RMS of every pixel. `false` is the paper's method,
    /// every pixel computed (and what the GPU draws).
    pub adaptive: bool,
}

impl Default for PlaneSettings {
    /// The paper's 30 planes and 6 sub-planes (shafts 5.1); a 512^2 shadow map;
    /// adaptive sampling.
    fn default() -> Self {
        PlaneSettings {
            planes: 30,
            sub_planes: 6,
            shadow_map: 512,
            adaptive: true,
        }
    }
}

impl PlaneSettings {
    /// Checks every count against its allowed range.
    pub fn validate(&self) -> Result<()> {
        check_range("render.planes", self.planes as f64, 1.0, 4096.0)?;
        check_range("render.sub_planes", self.sub_planes as f64, 1.0, 256.0)?;
        check_range("render.shadow_map", self.shadow_map as f64, 16.0, 8192.0)
    }
}

/// A frame made by calling `shade(ray, offset)` on each camera ray (scaled to unit
/// length along the view axis, see [`Camera::ray`]) and averaging each pixel's rays;
/// rows in parallel, each pixel on its own, so the result does not depend on the thread
/// count. `offset` in [0, 1) is the pixel's [`interleaved_offset`].
pub fn render_rays(camera: &Camera, shade: impl Fn(Vec3, f32) -> Vec3 + Sync) -> Frame {
    let mut frame = Frame::new(camera.width, camera.height);
    let offsets = camera.subpixel_offsets();
    let weight = 1.0 / offsets.len() as f32;
    frame
        .pixels
        .par_chunks_mut(camera.width as usize)
        .enumerate()
        .for_each(|(y, row)| {
            for (x, pixel) in row.iter_mut().enumerate() {
                let offset = interleaved_offset(x as u32, y as u32);
                let sum: Vec3 = offsets
                    .iter()
                    .map(|(dx, dy)| shade(camera.ray(x as f32 + dx, y as f32 + dy), offset))
                    .sum();
                *pixel = sum * weight;
            }
        });
    frame
}
