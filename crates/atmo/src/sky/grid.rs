//! The grid of view directions of a skylight map, sky (11)-(12).
//!
//! Azimuth `theta` is measured from the sun's vertical plane, from 0 (toward the sun)
//! to pi (away from it): the sky is symmetric about that plane. Elevation `phi` runs
//! from `elevation_min` (below the horizontal, the horizon's dip seen from altitude,
//! sky (15)) to `elevation_max`. Unlike sky (11), `theta_i = pi i / (L - 1)` includes
//! both ends, so directions near the anti-solar point interpolate instead of
//! extrapolating.

/// Grid points over (azimuth from the sun, elevation), both ends included.
#[derive(Debug, Clone, PartialEq)]
pub struct DirectionGrid {
    /// Points in azimuth, over [0, pi].
    pub azimuths: usize,
    /// Points in elevation, over [elevation_min, elevation_max].
    pub elevations: usize,
    /// Lowest elevation, rad.
    pub elevation_min: f64,
    /// Highest elevation, rad.
    pub elevation_max: f64,
}

impl DirectionGrid {
    /// A grid of `azimuths` x `elevations` points.
    pub fn new(azimuths: usize, elevations: usize, elevation_min: f64, elevation_max: f64) -> Self {
        DirectionGrid {
            azimuths: azimuths.max(2),
            elevations: elevations.max(2),
            elevation_min,
            elevation_max,
        }
    }

    /// Azimuth from the sun of column `i`, rad.
    pub fn azimuth(&self, i: usize) -> f64 {
        std::f64::consts::PI * i as f64 / (self.azimuths - 1) as f64
    }

    /// Elevation of row `j`, rad.
    pub fn elevation(&self, j: usize) -> f64 {
        self.elevation_min
            + (self.elevation_max - self.elevation_min) * j as f64 / (self.elevations - 1) as f64
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grid_covers_its_ends() {
        let g = DirectionGrid::new(5, 4, -0.1, 1.5);
        assert_eq!(g.azimuth(0), 0.0);
        assert_eq!(g.azimuth(4), std::f64::consts::PI);
        assert!((g.elevation(0) + 0.1).abs() < 1e-15 && (g.elevation(3) - 1.5).abs() < 1e-15);
    }
}
