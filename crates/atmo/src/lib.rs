//! atmo renders light scattered in the air: the sky with multiple scattering, shafts of
//! light from spotlights in haze, and clouds lit by the sun, each after a paper and
//! validated against a slow, obviously-correct reference ([`reference`](mod@reference)).
//!
//! The three methods stand side by side on a shared floor: [`view`] (the world frame,
//! the [`Sun`](view::Sun), the [`Camera`](view::Camera)), [`atmosphere`] (the medium and
//! every phase function), [`geometry`] (rays, boxes, meshes) and [`image`] (frames,
//! tone maps, files). None of the methods imports another; [`cloudscape`] puts the
//! clouds in the sky's sky, the one place two meet, above both. docs/architecture.md
//! draws the layers.
//!
//! # The sky ([`sky`]): Iwasaki, Yanagita, Dobashi, Nishita 2004, cited `sky (n)`
//!
//! ```
//! use atmo::sky::{SkyModel, SkyPicture, SkySettings, View};
//! use atmo::view::{Camera, Fov, Sun};
//!
//! let coarse = SkySettings { shells: 12, directions: 24, ..SkySettings::default() };
//! let model = SkyModel::new(&atmo::Atmosphere::earth(), &coarse, 2000.0)?; // 2 km up
//! let camera = Camera::yaw_pitch(glam::Vec3::ZERO, 180.0, 20.0, Fov::Vertical(60.0), (64, 36))?;
//! let sun = Sun::from_degrees(25.0, 180.0)?; // in the south
//! let frame = SkyPicture::new(&model, sun).render(&View { camera, sun_disc: true });
//! assert_eq!((frame.width, frame.height), (64, 36));
//! # Ok::<(), atmo::Error>(())
//! ```
//!
//! # Shafts of light ([`shafts`]): Dobashi, Yamamoto, Nishita 2002, cited `shafts (n)`
//!
//! ```
//! use atmo::shafts::{SamplePlanes, Scene};
//!
//! let scene = Scene::from_toml_str(r#"
//!     camera = { position = [0, 1.5, 6], look_at = [0, 1, 0], fov_deg = 50, width = 48, height = 32 }
//!     haze = { extinction = 0.1, albedo = 0.9 }
//!     [[spotlight]]
//!     position = [0, 4, 0]
//!     aim = [0, 0, 0]
//!     intensity = 1000.0
//!     beam_deg = 20.0
//!     field_deg = 30.0
//! "#, "an example", std::path::Path::new("."))?;
//! let frame = SamplePlanes::new(&scene).render(); // radiance in cd/m^2
//! assert!(frame.pixels.iter().any(|p| p.x > 0.0)); // the beam shows in the haze
//! # Ok::<(), atmo::Error>(())
//! ```
//!
//! # Clouds ([`clouds`]): Shimada, Shinya, Shiraishi, Harada 2008, cited `clouds (n)`
//!
//! ```
//! use atmo::atmosphere::PhaseFunction;
//! use atmo::clouds::{render, Cumulus, AerialHaze, IntensityBuffer, CloudLight, Scattering, SkyLight, Splat};
//! use atmo::view::{Camera, Fov, Sun};
//! use glam::Vec3;
//!
//! let particles = Cumulus { particles: 300, ..Cumulus::default() }.generate();
//! let sun = Sun::from_degrees(30.0, 40.0)?;
//! let buffer = IntensityBuffer::new(&particles, sun.toward(), 32, 0.0, Splat::Pieces)?;
//! let light = CloudLight { to_sun: sun.toward(), sun: Vec3::ONE,
//!                        ambient: SkyLight::uniform(Vec3::splat(0.05)),
//!                        phase: PhaseFunction::CloudMie, haze: AerialHaze::CLEAR,
//!                        scattering: Scattering::SOLVE };
//! let centre = particles.iter().map(|p| p.position).sum::<Vec3>() / particles.len() as f32;
//! let camera = Camera::look_at(centre + Vec3::new(0.0, 0.0, 4000.0), centre, Vec3::Y,
//!                              Fov::Vertical(40.0), (48, 32))?;
//! let frame = render(&particles, &buffer, &camera, &light, None)?;
//! assert!(frame.pixels[16 * 48 + 24].x > 0.0); // the cloud's middle is lit
//! # Ok::<(), atmo::Error>(())
//! ```
//!
//! `examples/` holds a whole program for each (`cargo run --release -p atmo --example
//! sky_exr`, `sky_table`, `stage`, `cloud`). Cargo features (all on by default) leave
//! out what a user does not need: `table` (the skylight table, with faer), `png`, `exr`
//! and `obj` (OBJ meshes in shafts scenes).

pub mod atmosphere;
pub mod budget;
pub mod clouds;
pub mod cloudscape;
pub mod error;
pub mod fast;
pub mod files;
pub mod geometry;
pub mod image;
pub mod lanes;
pub mod quadrature;
pub mod reference;
pub mod shafts;
pub mod sky;
pub mod view;

pub use atmosphere::Atmosphere;
pub use error::{Error, Result};
