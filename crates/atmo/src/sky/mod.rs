//! The sky with multiple scattering (Iwasaki, Yanagita, Dobashi, Nishita 2004), cited as
//! `sky (n)`, in the paper's two halves:
//!
//! - [`shells`], section 3: the shell method. [`SkyModel`] holds everything about one
//!   viewpoint altitude that does not depend on the sun, then gives the skylight map of
//!   any sun with lookups only.
//! - `table` (feature `table`, on by default), section 4: `SkylightTable`, the maps of every sun elevation and
//!   altitude compressed by SVD, drawn in well under a millisecond (docs/sky-table.md).
//!
//! [`SkyPicture`] turns either into pictures through a [`crate::view::Camera`], with the
//! ground below the horizon and the sun's disc. The sky's own frame (x east, y north,
//! z up) is internal: cameras and suns are in the world frame of [`crate::view`].
//! [`Daylight`] is the sky's light on things in the air, such as clouds.
//!
//! ```
//! use atmo::sky::{SkyModel, SkyPicture, SkySettings, View};
//! use atmo::view::{Camera, Fov, Sun};
//! use atmo::Atmosphere;
//!
//! // A coarse model (the defaults are the paper's 40 shells and 64 x 64 directions).
//! let settings = SkySettings { shells: 12, directions: 24, ..SkySettings::default() };
//! let model = SkyModel::new(&Atmosphere::earth(), &settings, 1000.0)?; // 1 km up
//! let sun = Sun::from_degrees(20.0, 135.0)?; // south-east, 20 deg up
//! let camera = Camera::yaw_pitch(glam::Vec3::ZERO, 135.0, 10.0, Fov::Vertical(60.0), (64, 36))?;
//! let frame = SkyPicture::new(&model, sun).render(&View { camera, sun_disc: true });
//! // Linear sRGB radiance; the middle of the picture looks near the sun: bright.
//! assert!(frame.pixels.iter().all(|p| p.min_element() >= 0.0));
//! # Ok::<(), atmo::Error>(())
//! ```

pub mod aerial;
pub mod daylight;
pub mod envmap;
pub mod frame;
pub mod grid;
pub mod lighting;
pub mod probe;
pub mod shells;
#[cfg(feature = "table")]
pub mod table;

pub use daylight::Daylight;
pub use frame::{SkyPicture, View};
pub use grid::DirectionGrid;
pub use shells::{Order, ShellLight, SkyModel, SkySettings, SkylightMap, ViewRays};
#[cfg(feature = "table")]
pub use table::{SkylightTable, TableSettings};
