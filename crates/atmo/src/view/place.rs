//! The sun from a place and a time: NREL's Solar Position Algorithm (Reda & Andreas
//! 2003/2008, stated to 0.0003 deg over -2000 to 6000), through the `solar-positioning`
//! crate, which is tested against the algorithm's published values; this module holds
//! atmo's conventions (azimuth clockwise from north, degrees at the edges) and its
//! validation. Users think in places and times, the methods in a [`Sun`].

use chrono::{DateTime, FixedOffset};
use solar_positioning::{Location, RefractionCorrection, SolarPositions};

use super::Sun;
use crate::error::{check_range, Error, Result};

/// Where on the Earth: WGS84 latitude and longitude, degrees (north and east positive),
/// and the altitude above sea level, m.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Place {
    /// Degrees north, in [-90, 90].
    pub latitude_deg: f64,
    /// Degrees east, in [-180, 180].
    pub longitude_deg: f64,
    /// Above sea level, m.
    pub altitude_m: f64,
}

/// The sun's topocentric position at a place and a time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SunPosition {
    /// Elevation of the sun's centre above the horizontal, geometric (no refraction), deg.
    pub elevation_deg: f64,
    /// The same as it is seen through a standard atmosphere (1010 hPa, 10 C), deg.
    pub refracted_elevation_deg: f64,
    /// Azimuth clockwise from north, deg, in [0, 360).
    pub azimuth_deg: f64,
}

impl SunPosition {
    /// The atmo [`Sun`] at the geometric position: the atmosphere's models bend no
    /// light, so the picture puts the sun where the geometry does.
    pub fn sun(&self) -> Sun {
        Sun::from_degrees(self.elevation_deg, self.azimuth_deg).expect("SPA's angles are in range")
    }
}

/// An RFC 3339 time with its offset (`2026-06-21T20:30:00+02:00`, or `Z`); anything
/// else, a time without an offset included, is refused naming `time`.
pub fn parse_time(text: &str) -> Result<DateTime<FixedOffset>> {
    DateTime::parse_from_rfc3339(text.trim()).map_err(|e| {
        Error::out_of_range(
            "time",
            text,
            &format!("an RFC 3339 time with its offset, e.g. 2026-06-21T20:30:00+02:00 ({e})"),
        )
    })
}

impl Place {
    /// Checks the fields: errors name `latitude`, `longitude`, `altitude_m`.
    pub fn validate(&self) -> Result<()> {
        check_range("latitude", self.latitude_deg, -90.0, 90.0)?;
        check_range("longitude", self.longitude_deg, -180.0, 180.0)?;
        check_range("altitude_m", self.altitude_m, -500.0, 1e5)
    }

    /// The sun seen from here at `time`. Delta T (terrestrial minus universal time) is
    /// Espenak and Meeus's estimate for the date, as the crate gives it; over 1950-2100
    /// its error moves the sun by well under 0.01 deg.
    pub fn sun_at(&self, time: DateTime<FixedOffset>) -> Result<SunPosition> {
        self.validate()?;
        let fail = |e: solar_positioning::Error| Error::Invalid(format!("sun position: {e}"));
        let delta_t = solar_positioning::delta_t::estimate_from_date_like(&time).map_err(fail)?;
        let prepared = SolarPositions::new()
            .for_time(&time, delta_t)
            .map_err(fail)?;
        let location = Location {
            latitude: self.latitude_deg,
            longitude: self.longitude_deg,
        };
        let at = |refraction| {
            prepared
                .at(location, self.altitude_m, refraction)
                .map_err(fail)
        };
        let geometric = at(None)?;
        let standard = RefractionCorrection::new(1010.0, 10.0).map_err(fail)?;
        let refracted = at(Some(standard))?;
        Ok(SunPosition {
            elevation_deg: geometric.elevation_angle(),
            refracted_elevation_deg: refracted.elevation_angle(),
            azimuth_deg: geometric.azimuth().rem_euclid(360.0),
        })
    }
}

impl Place {
    /// The span of the local day of `time` (midnight to midnight in its offset) when the
    /// sun's centre is at least `above_deg` high, to the minute: sunrise and sunset for
    /// about -0.83 deg (refraction and the disc's radius). Refused when the sun stays
    /// below all day; the whole day when it never goes below.
    pub fn daylight(
        &self,
        time: DateTime<FixedOffset>,
        above_deg: f64,
    ) -> Result<(DateTime<FixedOffset>, DateTime<FixedOffset>)> {
        let midnight = time
            .date_naive()
            .and_hms_opt(0, 0, 0)
            .and_then(|t| t.and_local_timezone(*time.offset()).single())
            .ok_or_else(|| Error::Invalid(format!("time {time}: no local midnight")))?;
        let mut up = Vec::new();
        for minute in 0..=24 * 60 {
            let t = midnight + chrono::Duration::minutes(minute);
            if self.sun_at(t)?.elevation_deg >= above_deg {
                up.push(t);
            }
        }
        match (up.first(), up.last()) {
            (Some(&rise), Some(&set)) => Ok((rise, set)),
            _ => Err(Error::Invalid(format!(
                "on {} the sun stays below {above_deg} deg at latitude {}",
                time.date_naive(),
                self.latitude_deg
            ))),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The SPA paper's example (Reda & Andreas, table A4.1): Golden, Colorado,
    /// 2003-10-17 12:30:30 -07:00, with Delta T = 67 s, 820 hPa and 11 C: topocentric
    /// zenith 50.11162 deg (refracted), azimuth 194.34024 deg. Here Delta T is the
    /// estimate (about 64.5 s for 2003) and the refraction is the standard one; both
    /// move the sun by far less than the 0.01 deg asked of it.
    #[test]
    fn the_published_example_is_reproduced() {
        let golden = Place {
            latitude_deg: 39.742476,
            longitude_deg: -105.1786,
            altitude_m: 1830.14,
        };
        let time = parse_time("2003-10-17T12:30:30-07:00").unwrap();
        let sun = golden.sun_at(time).unwrap();
        assert!((sun.azimuth_deg - 194.34024).abs() < 0.01, "{sun:?}");
        // Refraction at 820 hPa, 11 C differs from the standard 1010 hPa, 10 C by ~0.003 deg.
        assert!(
            (90.0 - sun.refracted_elevation_deg - 50.11162).abs() < 0.01,
            "{sun:?}"
        );
        assert!(sun.refracted_elevation_deg > sun.elevation_deg);
        let s = sun.sun();
        assert!((s.elevation().to_degrees() - sun.elevation_deg).abs() < 1e-9);
    }

    #[test]
    fn places_and_times_are_checked() {
        assert!(parse_time("2026-06-21T12:00:00")
            .unwrap_err()
            .to_string()
            .starts_with("time = 2026-06-21T12:00:00 is out of range"));
        assert_eq!(
            parse_time("2026-06-21T10:00:00Z").unwrap(),
            parse_time("2026-06-21T12:00:00+02:00").unwrap()
        );
        let bad = Place {
            latitude_deg: 91.0,
            longitude_deg: 0.0,
            altitude_m: 0.0,
        };
        assert!(bad
            .validate()
            .unwrap_err()
            .to_string()
            .starts_with("latitude = 91"));
    }

    /// Paris on the June solstice: sunrise 05:47, sunset 21:58 local time (the published
    /// times, for the disc's top edge with refraction: -0.833 deg); polar night refused.
    #[test]
    fn the_day_runs_from_sunrise_to_sunset() {
        let paris = Place {
            latitude_deg: 48.8566,
            longitude_deg: 2.3522,
            altitude_m: 0.0,
        };
        let (rise, set) = paris
            .daylight(parse_time("2026-06-21T12:00:00+02:00").unwrap(), -0.833)
            .unwrap();
        let minutes = |t: DateTime<FixedOffset>| {
            use chrono::Timelike;
            t.hour() * 60 + t.minute()
        };
        assert!(minutes(rise).abs_diff(5 * 60 + 47) <= 2, "{rise}");
        assert!(minutes(set).abs_diff(21 * 60 + 58) <= 2, "{set}");
        let north = Place {
            latitude_deg: 80.0,
            ..paris
        };
        let e = north
            .daylight(parse_time("2026-12-21T12:00:00Z").unwrap(), -0.833)
            .unwrap_err();
        assert!(e.to_string().contains("stays below"), "{e}");
    }

    /// Solstice noon at the equator and at the Arctic circle, and the sun setting in the
    /// west: coarse truths the algorithm must keep.
    #[test]
    fn the_sun_is_where_the_seasons_put_it() {
        let at = |lat: f64, lon: f64, t: &str| {
            Place {
                latitude_deg: lat,
                longitude_deg: lon,
                altitude_m: 0.0,
            }
            .sun_at(parse_time(t).unwrap())
            .unwrap()
        };
        // June solstice, local solar noon at Greenwich: declination +23.44.
        let noon = at(0.0, 0.0, "2026-06-21T12:02:00Z");
        assert!(
            (noon.elevation_deg - (90.0 - 23.44)).abs() < 0.1,
            "{noon:?}"
        );
        assert!((noon.azimuth_deg - 0.0).abs() < 1.0 || (noon.azimuth_deg - 360.0).abs() < 1.0);
        // Midnight sun on the Arctic circle: just above the horizon, due north.
        let midnight = at(66.57, 0.0, "2026-06-21T00:02:00Z");
        assert!(midnight.elevation_deg.abs() < 0.6, "{midnight:?}");
        assert!((midnight.azimuth_deg - 180.0).abs() > 170.0, "{midnight:?}");
        // An evening in Paris: low in the west-north-west.
        let evening = at(48.85, 2.35, "2026-06-21T21:00:00+02:00");
        assert!((0.0..10.0).contains(&evening.elevation_deg), "{evening:?}");
        assert!((290.0..320.0).contains(&evening.azimuth_deg), "{evening:?}");
    }
}
