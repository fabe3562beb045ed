//! atmo renders light scattered in the air.
//!
//! - [`atmosphere`]: the medium (planet, densities, phase functions, optical depth,
//!   spectrum to colour).
//! - [`sky`]: the sky with multiple scattering by sampling shells and scattering maps
//!   (Iwasaki, Yanagita, Dobashi, Nishita 2004), cited as `sky (n)`, and the skylight
//!   table over sun and altitude compressed by SVD for real-time drawing
//!   ([`sky::table`]).
//! - [`shafts`]: shafts of light from spotlights in haze, with volumetric shadows and
//!   gobos, by sample planes (Dobashi, Yamamoto, Nishita 2002), cited as `shafts (n)`.
//! - [`clouds`]: particle clouds and the 3-D intensity buffer of the sun's light
//!   (Shimada, Shinya, Shiraishi, Harada 2008), cited as `clouds (n)`.
//! - [`reference`](mod@reference): slow, obviously-correct integrators the fast methods are tested
//!   against.
//! - [`image`]: float frame buffers, exposure, tone mapping, PNG/EXR written atomically.

pub mod atmosphere;
pub mod clouds;
pub mod error;
pub mod geometry;
pub mod image;
pub mod quadrature;
pub mod reference;
pub mod shafts;
pub mod sky;
pub mod view;

pub use atmosphere::Atmosphere;
pub use error::{Error, Result};
