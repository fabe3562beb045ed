//! Argument groups shared by several commands.

use std::path::PathBuf;

use atmo::image::ToneMap;
use atmo::sky::SkySettings;
use atmo::Atmosphere;
use clap::{Args, ValueEnum};

#[derive(Clone, Copy, ValueEnum)]
pub enum ToneMapArg {
    Exponential,
    Aces,
    Clamp,
}

impl From<ToneMapArg> for ToneMap {
    fn from(t: ToneMapArg) -> Self {
        match t {
            ToneMapArg::Exponential => ToneMap::Exponential,
            ToneMapArg::Aces => ToneMap::Aces,
            ToneMapArg::Clamp => ToneMap::Clamp,
        }
    }
}

/// Which atmosphere: a file, or an embedded preset; ozone on or off.
#[derive(Args)]
pub struct AtmosphereArgs {
    /// Atmosphere TOML file (see docs/atmospheres.md); default: the `--preset`.
    #[arg(long, value_name = "FILE.toml")]
    pub atmosphere: Option<PathBuf>,
    /// Embedded atmosphere: `earth` (measured coefficients) or `paper`.
    #[arg(long, default_value = "earth")]
    pub preset: String,
    /// Switch on the atmosphere's ozone layer.
    #[arg(long)]
    pub ozone: bool,
}

/// The shell method's settings (sky 3).
#[derive(Args)]
pub struct ShellArgs {
    /// Highest scattering order: 1, 2 (the paper) or 3.
    #[arg(long, default_value_t = 2)]
    order: u32,
    /// Sampling shells (paper: 40).
    #[arg(long, default_value_t = SkySettings::default().shells)]
    shells: usize,
    /// View directions per axis L of the skylight map (sky (11)-(12); paper: 64).
    #[arg(long, default_value_t = SkySettings::default().directions)]
    directions: usize,
    /// Directions of the higher-order quadrature (paper: 15).
    #[arg(long, default_value_t = SkySettings::default().scattering_directions)]
    scattering_directions: usize,
    /// Let aerosols scatter the higher orders too (the paper: Rayleigh only).
    #[arg(long)]
    multiple_mie: bool,
}

impl ShellArgs {
    /// The settings, not yet validated.
    pub fn settings(&self) -> SkySettings {
        SkySettings {
            shells: self.shells,
            directions: self.directions,
            scattering_directions: self.scattering_directions,
            order: self.order,
            multiple_mie: self.multiple_mie,
            ..SkySettings::default()
        }
    }
}

impl AtmosphereArgs {
    /// The atmosphere from `--atmosphere` or `--preset`, with `--ozone` applied.
    pub fn load(&self) -> atmo::Result<Atmosphere> {
        let atmosphere = match &self.atmosphere {
            Some(path) => Atmosphere::from_toml_file(path)?,
            None => Atmosphere::preset(&self.preset)?,
        };
        if self.ozone {
            atmosphere.with_ozone(true)
        } else {
            Ok(atmosphere)
        }
    }
}
