//! The axes of the table's columns: sun elevations and viewpoint altitudes, sky (13)-(14),
//! spaced densest where the sky changes fastest.

/// One axis of the (sun elevation, altitude) grid: increasing values, both ends
/// included, spaced as a density asks (more points where the sky changes fastest).
#[derive(Debug, Clone, PartialEq)]
pub struct TableAxis {
    values: Vec<f64>,
}

/// Points of the fine grid on which [`TableAxis::with_density`] integrates the density.
const DENSITY_SAMPLES: usize = 1 << 16;

impl TableAxis {
    /// `count` points from `min` to `max` at `min + (max - min) u^power`,
    /// `u = i / (count - 1)`: even for `power = 1`, denser near `min` above it.
    pub fn power(min: f64, max: f64, count: usize, power: f64) -> Self {
        let values = (0..count)
            .map(|i| {
                let u = i as f64 / (count - 1) as f64;
                min + (max - min) * u.powf(power)
            })
            .collect();
        TableAxis { values }
    }

    /// `count` points from `min` to `max` with as many points per unit near `v` as
    /// `density(v)` says (relative): point `i` is where the integral of the density
    /// from `min` reaches `i / (count - 1)` of the whole.
    pub fn with_density(min: f64, max: f64, count: usize, density: impl Fn(f64) -> f64) -> Self {
        let h = (max - min) / DENSITY_SAMPLES as f64;
        let mut cumulative = vec![0.0; DENSITY_SAMPLES + 1];
        for k in 0..DENSITY_SAMPLES {
            let v = min + (k as f64 + 0.5) * h;
            cumulative[k + 1] = cumulative[k] + density(v) * h;
        }
        let total = cumulative[DENSITY_SAMPLES];
        let mut values: Vec<f64> = (0..count)
            .map(|i| {
                let target = total * i as f64 / (count - 1) as f64;
                let k = cumulative
                    .partition_point(|&c| c < target)
                    .clamp(1, DENSITY_SAMPLES);
                let (c0, c1) = (cumulative[k - 1], cumulative[k]);
                let f = if c1 > c0 {
                    (target - c0) / (c1 - c0)
                } else {
                    0.0
                };
                min + (k as f64 - 1.0 + f) * h
            })
            .collect();
        (values[0], values[count - 1]) = (min, max);
        TableAxis { values }
    }

    /// Grid points.
    pub fn count(&self) -> usize {
        self.values.len()
    }

    /// First grid value.
    pub fn min(&self) -> f64 {
        self.values[0]
    }

    /// Last grid value.
    pub fn max(&self) -> f64 {
        self.values[self.values.len() - 1]
    }

    /// The value of grid point `i`.
    pub fn value(&self, i: usize) -> f64 {
        self.values[i]
    }

    /// The grid interval `[value(i), value(i + 1)]` holding `v` and the weight of its
    /// upper end for linear interpolation (exactly 0 or 1 at grid points), or `None`
    /// outside `[min, max]`.
    pub fn locate(&self, v: f64) -> Option<(usize, f32)> {
        if !(v >= self.min() && v <= self.max()) {
            return None;
        }
        let n = self.values.len();
        let i = self.values.partition_point(|&x| x <= v).clamp(1, n - 1) - 1;
        let (a, b) = (self.values[i], self.values[i + 1]);
        Some((i, ((v - a) / (b - a)).clamp(0.0, 1.0) as f32))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn axes_locate_their_own_points_and_refuse_outside() {
        let dense = |v: f64| 1.0 + 4.0 * (-(v - 2.0f64).powi(2)).exp();
        let axes = [
            TableAxis::power(-0.2, 13.0, 9, 1.0),
            TableAxis::power(-0.2, 13.0, 9, 1.7),
            TableAxis::with_density(-0.2, 13.0, 9, dense),
        ];
        for axis in &axes {
            assert_eq!((axis.count(), axis.min(), axis.max()), (9, -0.2, 13.0));
            for i in 0..9 {
                let (j, w) = axis.locate(axis.value(i)).unwrap();
                assert!(w == 0.0 || w == 1.0, "{axis:?} {i}: {w}");
                assert_eq!(if w == 0.0 { j } else { j + 1 }, i);
            }
            let (j, w) = axis.locate(0.5 * (axis.value(3) + axis.value(4))).unwrap();
            assert_eq!(j, 3);
            assert!((w - 0.5).abs() < 1e-6);
            assert!(axis.locate(-0.21).is_none() && axis.locate(13.01).is_none());
            assert!(axis.locate(f64::NAN).is_none());
        }
        // The density puts the points where it is high: steps near 2 are ~5x shorter.
        let d = &axes[2];
        let steps: Vec<f64> = (0..8).map(|i| d.value(i + 1) - d.value(i)).collect();
        let near = (0..8)
            .find(|&i| d.value(i) <= 2.0 && d.value(i + 1) > 2.0)
            .unwrap();
        assert!(steps[near] * 3.0 < steps[7], "{steps:?}");
        assert!(steps.iter().all(|&s| s > 0.0), "{steps:?}");
    }
}
