//! Argument groups shared by several commands.

use std::path::PathBuf;

use atmo::image::ToneMap;
use atmo::sky::{Order, SkySettings};
use atmo::view::place::{parse_time, Place, SunPosition};
use atmo::Atmosphere;
use atmo_view::sky::SkyParams;
use chrono::{DateTime, FixedOffset};
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

/// A picture of the sky: the sun, the viewpoint, the camera and the display; the still
/// `atmo sky` and the window `atmo view sky` take the same flags.
#[derive(Args)]
pub struct SkyPictureArgs {
    /// Sun elevation above the horizontal, degrees, in [-90, 90].
    #[arg(long, default_value_t = 30.0)]
    pub sun_elevation: f64,
    /// Sun azimuth, degrees clockwise from north.
    #[arg(long, default_value_t = 180.0)]
    pub sun_azimuth: f64,
    /// Viewpoint altitude above the ground, metres, below the top of the atmosphere.
    #[arg(long, default_value_t = 0.0)]
    pub altitude: f64,
    /// Image width, pixels.
    #[arg(long, default_value_t = 960)]
    pub width: u32,
    /// Image height, pixels.
    #[arg(long, default_value_t = 540)]
    pub height: u32,
    /// Camera azimuth, degrees clockwise from north (default: toward the sun).
    #[arg(long)]
    pub yaw: Option<f64>,
    /// Camera elevation, degrees.
    #[arg(long, default_value_t = 15.0)]
    pub pitch: f64,
    /// Vertical field of view, degrees.
    #[arg(long, default_value_t = 70.0)]
    pub fov: f64,
    /// The whole dome as a fisheye (zenith at the centre, north up, east left).
    #[arg(long)]
    pub fisheye: bool,
    /// Multiplies radiance before the tone map (PNG only); 0.15 suits a day sky,
    /// raise it for twilight.
    #[arg(long, default_value_t = 0.15)]
    pub exposure: f32,
    /// Tone map for PNG output.
    #[arg(long, value_enum, default_value_t = ToneMapArg::Exponential)]
    pub tone_map: ToneMapArg,
    /// Leave out the sun's disc.
    #[arg(long)]
    pub no_sun_disc: bool,
    #[command(flatten)]
    pub place: PlaceArgs,
}

/// Where and when: the sun from a place and a time instead of its angles.
#[derive(Args, Clone)]
pub struct PlaceArgs {
    /// Latitude, degrees north, in [-90, 90]; with --longitude and --time the sun is
    /// placed by NREL's SPA (overrides --sun-elevation and --sun-azimuth).
    #[arg(long, requires_all = ["longitude", "time"])]
    pub latitude: Option<f64>,
    /// Longitude, degrees east, in [-180, 180].
    #[arg(long, requires_all = ["latitude", "time"])]
    pub longitude: Option<f64>,
    /// The time, RFC 3339 with its offset: 2026-06-21T20:30:00+02:00 (or Z for UTC).
    #[arg(long, requires_all = ["latitude", "longitude"])]
    pub time: Option<String>,
}

impl PlaceArgs {
    /// The place (at `altitude_m` above sea level) and the time, if they are given.
    pub fn place_and_time(
        &self,
        altitude_m: f64,
    ) -> atmo::Result<Option<(Place, DateTime<FixedOffset>)>> {
        let (Some(latitude_deg), Some(longitude_deg), Some(time)) =
            (self.latitude, self.longitude, &self.time)
        else {
            return Ok(None);
        };
        let place = Place {
            latitude_deg,
            longitude_deg,
            altitude_m,
        };
        place.validate()?;
        Ok(Some((place, parse_time(time)?)))
    }

    /// The sun's position at the place and time, seen from `altitude_m` above sea
    /// level, if they are given.
    pub fn sun_position(&self, altitude_m: f64) -> atmo::Result<Option<SunPosition>> {
        self.place_and_time(altitude_m)?
            .map(|(place, time)| place.sun_at(time))
            .transpose()
    }
}

impl SkyPictureArgs {
    /// The parameters (the camera toward the sun unless `--yaw`; the sun from the place
    /// and time where they are given), not yet validated.
    pub fn params(&self) -> atmo::Result<SkyParams> {
        Ok(self.params_at(self.sun_position()?.as_ref()))
    }

    /// The sun's position at the place and time, seen from `--altitude`, if given.
    pub fn sun_position(&self) -> atmo::Result<Option<SunPosition>> {
        self.place.sun_position(self.altitude)
    }

    /// The parameters with the sun at `position` where there is one (from
    /// [`SkyPictureArgs::sun_position`]), else at `--sun-elevation`/`--sun-azimuth`.
    pub fn params_at(&self, position: Option<&SunPosition>) -> SkyParams {
        let (sun_elevation, sun_azimuth) = match position {
            Some(p) => (p.elevation_deg, p.azimuth_deg),
            None => (self.sun_elevation, self.sun_azimuth),
        };
        SkyParams {
            sun_elevation_deg: sun_elevation,
            sun_azimuth_deg: sun_azimuth,
            altitude_m: self.altitude,
            yaw_deg: self.yaw.unwrap_or(sun_azimuth),
            pitch_deg: self.pitch,
            fov_deg: self.fov,
            fisheye: self.fisheye,
            sun_disc: !self.no_sun_disc,
            exposure: self.exposure,
            tone: self.tone_map.into(),
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
    /// Switch on the atmosphere's ozone layer where its file has it off (the embedded
    /// `earth` has it on).
    #[arg(long, conflicts_with = "no_ozone")]
    pub ozone: bool,
    /// Switch the ozone layer off (with `--order 2`: the paper's model of the Earth).
    #[arg(long)]
    pub no_ozone: bool,
    /// The ground's Lambertian albedo, 0 (black) to 1, instead of the atmosphere's
    /// (`earth`: 0.1); it lights the ground and every scattering order above the first.
    #[arg(long, value_name = "ALBEDO")]
    pub ground_albedo: Option<f64>,
}

/// The shell method's settings (sky 3).
#[derive(Args)]
pub struct ShellArgs {
    /// Highest scattering order: 1 to 60 (the paper: 2), or "all" (orders are added
    /// until the next adds under 0.1 % anywhere; aerosols then scatter every order too).
    /// Default: all, or 2 with `--preset paper`.
    #[arg(long, value_name = "N|all")]
    order: Option<Order>,
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
    /// Longest interval between samples along a ray, metres (longer ones are split);
    /// raise it for planets far larger than the Earth.
    #[arg(long, value_name = "METRES", default_value_t = SkySettings::default().max_interval_m)]
    max_interval: f64,
}

impl ShellArgs {
    /// The highest order: `--order`, else every order, or the paper's 2 for the
    /// paper's atmosphere.
    fn order(&self, medium: &AtmosphereArgs) -> Order {
        self.order.unwrap_or(if medium.is_paper() {
            SkySettings::paper().order
        } else {
            SkySettings::default().order
        })
    }

    /// The flags that give these settings for the atmosphere `medium`, for a still
    /// command.
    pub fn flags(&self, medium: &AtmosphereArgs) -> String {
        let mut out = format!(
            "--order {} --shells {} --directions {} --scattering-directions {}",
            self.order(medium),
            self.shells,
            self.directions,
            self.scattering_directions
        );
        if self.multiple_mie {
            out.push_str(" --multiple-mie");
        }
        if self.max_interval != SkySettings::default().max_interval_m {
            out.push_str(&format!(" --max-interval {}", self.max_interval));
        }
        out
    }

    /// The settings for the atmosphere `medium`, not yet validated.
    pub fn settings(&self, medium: &AtmosphereArgs) -> SkySettings {
        let order = self.order(medium);
        SkySettings {
            shells: self.shells,
            directions: self.directions,
            scattering_directions: self.scattering_directions,
            order,
            multiple_mie: self.multiple_mie || order == Order::All,
            max_interval_m: self.max_interval,
            ..SkySettings::default()
        }
    }
}

impl AtmosphereArgs {
    /// The flags that choose this atmosphere, for a still command.
    pub fn flags(&self) -> String {
        let mut out = match &self.atmosphere {
            Some(path) => format!("--atmosphere {}", path.display()),
            None => format!("--preset {}", self.preset),
        };
        if self.ozone {
            out.push_str(" --ozone");
        }
        if self.no_ozone {
            out.push_str(" --no-ozone");
        }
        if let Some(albedo) = self.ground_albedo {
            out.push_str(&format!(" --ground-albedo {albedo}"));
        }
        out
    }

    /// The atmosphere from `--atmosphere` or `--preset`, with `--ozone`, `--no-ozone`
    /// and `--ground-albedo` applied.
    pub fn load(&self) -> atmo::Result<Atmosphere> {
        let mut atmosphere = match &self.atmosphere {
            Some(path) => Atmosphere::from_toml_file(path)?,
            None => Atmosphere::preset(&self.preset)?,
        };
        if let Some(albedo) = self.ground_albedo {
            if !(0.0..=1.0).contains(&albedo) {
                return Err(atmo::Error::out_of_range(
                    "--ground-albedo",
                    albedo,
                    "[0, 1]",
                ));
            }
            atmosphere.ground_albedo = albedo;
        }
        if self.ozone {
            atmosphere.with_ozone(true)
        } else if self.no_ozone {
            atmosphere.with_ozone(false)
        } else {
            Ok(atmosphere)
        }
    }

    /// Whether this is the embedded paper's atmosphere (which takes the paper's order).
    pub fn is_paper(&self) -> bool {
        self.atmosphere.is_none() && self.preset == "paper"
    }
}

/// `K/N` with 1 <= K <= N (part K of N, counted as people count), as (K - 1, N).
pub fn parse_part(s: &str) -> Result<(usize, usize), String> {
    let (k, n) = s
        .split_once('/')
        .ok_or_else(|| format!("`{s}`: write the part as K/N, e.g. 3/16"))?;
    let number = |t: &str| t.trim().parse::<usize>().map_err(|e| format!("`{t}`: {e}"));
    let (k, n) = (number(k)?, number(n)?);
    if !(1..=n).contains(&k) {
        return Err(format!("part {k} of {n}: K runs from 1 to N"));
    }
    Ok((k - 1, n))
}
