//! `atmo sun`: where the sun is at a place and a time (NREL's SPA), and the sunlight
//! that reaches that point through an atmosphere, as one JSON object.

use anyhow::Result;
use atmo::sky::lighting::Sunlight;
use atmo::view::Sun;
use atmo::Error;
use clap::Args;
use serde_json::json;

use crate::args::{AtmosphereArgs, PlaceArgs};

#[derive(Args)]
pub struct SunArgs {
    #[command(flatten)]
    place: PlaceArgs,
    /// Altitude of the point above the ground (taken as sea level), metres.
    #[arg(long, default_value_t = 0.0)]
    altitude: f64,
    #[command(flatten)]
    medium: AtmosphereArgs,
}

pub fn run(args: SunArgs) -> Result<()> {
    let atmosphere = args.medium.load()?;
    let top = atmosphere.thickness_m();
    if !(args.altitude.is_finite() && (0.0..top).contains(&args.altitude)) {
        return Err(
            Error::out_of_range("--altitude", args.altitude, &format!("[0, {top}) m")).into(),
        );
    }
    let position = args.place.sun_position(args.altitude)?.ok_or_else(|| {
        Error::Invalid("atmo sun needs --latitude, --longitude and --time".into())
    })?;
    let sun = Sun::from_degrees(position.elevation_deg, position.azimuth_deg)?;
    let light = Sunlight::at(&atmosphere, args.altitude, sun);
    let out = json!({
        "latitude_deg": args.place.latitude,
        "longitude_deg": args.place.longitude,
        "time": args.place.time,
        "altitude_m": args.altitude,
        "elevation_deg": position.elevation_deg,
        "refracted_elevation_deg": position.refracted_elevation_deg,
        "azimuth_deg": position.azimuth_deg,
        "atmosphere": atmosphere.name,
        "sunlight": {
            "wavelengths_nm": atmosphere.wavelengths_nm,
            "direct_normal_irradiance_w_m2_nm": light.spectrum,
            "illuminance_lux": {"normal": light.normal_lux, "horizontal": light.horizontal_lux},
            "linear_srgb_colour": light.colour,
        },
    });
    outln!("{}", serde_json::to_string_pretty(&out)?);
    Ok(())
}
