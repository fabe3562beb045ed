//! Drawing from the table, sky 4.2: `t_k` interpolated bilinearly at the wanted sun
//! and altitude, then `T(theta, phi)` products summed per direction.

use glam::Vec3;

use super::{SkylightTable, TableFactors};
use crate::error::{Error, Result};

impl SkylightTable {
    /// The skylight map (linear sRGB, `[elevation][azimuth]` over [`SkylightTable::grid`])
    /// for a sun at `sun_elevation` rad seen from `altitude_m`.
    pub fn map(&self, sun_elevation: f64, altitude_m: f64) -> Result<Vec<Vec3>> {
        let mut out = vec![Vec3::ZERO; self.settings.sky.directions.pow(2)];
        self.map_into(sun_elevation, altitude_m, &mut out, &mut Vec::new())?;
        Ok(out)
    }

    /// [`SkylightTable::map`] into `out`, with `scratch` reused between calls: sky 4.2,
    /// bilinear interpolation of `t_k` and `T(theta, phi)` products per direction.
    /// Outside the table's sun or altitude range it is an error, never a clamp.
    pub fn map_into(
        &self,
        sun_elevation: f64,
        altitude_m: f64,
        out: &mut [Vec3],
        scratch: &mut Vec<f32>,
    ) -> Result<()> {
        let coefficients = self.coefficients(sun_elevation, altitude_m)?;
        self.factors.draw(&coefficients, scratch, out);
        Ok(())
    }

    /// The coefficients `t_k` of sky (17) for a sun at `sun_elevation` rad seen from
    /// `altitude_m`, bilinear in the table's grid, one per stored term: all a draw
    /// needs per frame besides the stored `s_k`. An error outside the table's ranges.
    pub fn coefficients(&self, sun_elevation: f64, altitude_m: f64) -> Result<Vec<f32>> {
        let (sun, altitude) = (self.sun_axis(), self.altitude_axis());
        let (s, ws) = sun.locate(sun_elevation).ok_or_else(|| {
            Error::out_of_range(
                "sun.elevation_deg",
                // Degrees to radians and back: round away the last bits.
                (sun_elevation.to_degrees() * 1e9).round() / 1e9,
                &format!(
                    "the table's [{}, {}]",
                    sun.min().to_degrees(),
                    sun.max().to_degrees()
                ),
            )
        })?;
        let (a, wa) = altitude.locate(altitude_m).ok_or_else(|| {
            Error::out_of_range(
                "altitude_m",
                altitude_m,
                &format!("the table's [{}, {}]", altitude.min(), altitude.max()),
            )
        })?;
        let m = sun.count();
        let corners = [
            (a * m + s, (1.0 - ws) * (1.0 - wa)),
            (a * m + s + 1, ws * (1.0 - wa)),
            ((a + 1) * m + s, (1.0 - ws) * wa),
            ((a + 1) * m + s + 1, ws * wa),
        ];
        Ok(self.factors.coefficients(&corners, m * altitude.count()))
    }

    /// The stored factors in the layout a draw runs over, for uploading to a GPU.
    pub fn factors(&self) -> TableFactors<'_> {
        TableFactors {
            s: &self.factors.s,
            order: &self.factors.order,
            used: &self.factors.used,
            directions: self.settings.sky.directions.pow(2),
        }
    }
}
