//! Clouds lit by a moving sun, after Shimada, Shinya, Shiraishi and Harada, "Fast
//! rendering of dynamic clouds using GPU shaders" (cited as `clouds (n)`): a cloud is a
//! set of Gaussian particles ([`particles`], made by [`generator`]); the light reaching
//! every part of it is kept in a 3-D intensity buffer oriented to the sun ([`buffer`]),
//! filled in any particle order by the multiplicative form (7).
//!
//! [`harris`] is the baseline light pass the buffer is measured against; [`render`](mod@render)
//! draws the billboards (and the paper's own, [`paper_billboards`], the drawing's
//! baseline), lit by the sun through the buffer, by every order of it
//! ([`transfer`]'s table, [`diffusion`]'s solve or [`octaves`]) and by the sky
//! ([`sky_light`]); [`shadow`] is the cloud's shadow on the
//! ground; [`files`] reads and writes particles.

pub mod buffer;
pub mod diffusion;
pub mod files;
pub mod generator;
pub mod harris;
pub mod octaves;
pub mod particles;
pub mod render;
pub mod shadow;
pub mod sky_light;
pub mod transfer;
mod transfer_fitted;

pub use buffer::{IntensityBuffer, Splat};
pub use diffusion::{DiffuseLight, Diffusion};
pub use generator::Cumulus;
pub use octaves::Octaves;
pub use particles::Particle;
pub use render::{
    dims_the_sky, needs_depths, paper_billboards, render, render_with_depths, solve_for,
    AerialHaze, CloudLight, Scattering,
};
pub use shadow::CloudShadow;
pub use sky_light::{vertical_depths, SkyDimming, SkyLight};
pub use transfer::{CloudDepths, TransferTable};
