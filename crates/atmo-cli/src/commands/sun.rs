//! `atmo sun`: where the sun is at a place and a time (NREL's SPA), and the sunlight
//! that reaches that point through an atmosphere, as one JSON object.

use anyhow::Result;
use atmo::atmosphere::spectrum::{srgb_luminance, SpectrumToRgb};
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

/// The luminous efficacy of radiation at 555 nm, lm/W: illuminance = 683 x Y.
const LUMENS_PER_WATT: f64 = 683.0;

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
    let spectrum = atmosphere.direct_sunlight(args.altitude, position.elevation_deg.to_radians());
    let rgb = SpectrumToRgb::new(&atmosphere.wavelengths_nm)
        .rgb(&spectrum.iter().map(|&e| e as f32).collect::<Vec<_>>());
    // Y of the spectrum (the converter integrates the CIE curves into linear sRGB).
    let rgb = rgb.map(f64::from);
    let y = srgb_luminance(rgb);
    let normal_lux = LUMENS_PER_WATT * y;
    let horizontal_lux = normal_lux * position.elevation_deg.to_radians().sin().max(0.0);
    let colour = if y > 0.0 {
        rgb.map(|c| c / y)
    } else {
        [0.0; 3]
    };
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
            "direct_normal_irradiance_w_m2_nm": spectrum,
            "illuminance_lux": {"normal": normal_lux, "horizontal": horizontal_lux},
            "linear_srgb_colour": colour,
        },
    });
    println!("{}", serde_json::to_string_pretty(&out)?);
    Ok(())
}
