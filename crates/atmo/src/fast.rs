//! Fast approximations the methods share, each written once here and mirrored in WGSL
//! by atmo-gpu (`shaders/functions.wgsl`), whose twin tests run both over a grid of
//! inputs. Same function on both sides: the horizon's and the beam's edges fall on the
//! same pixels on the CPU and the GPU.

/// `acos(x)` within 7e-5 rad for x in [-1, 1] (Abramowitz and Stegun 4.4.45), with no
/// library call, so loops over it vectorise; grid cells are 0.05 rad wide, so pictures
/// cannot tell it from the exact function.
#[inline]
pub fn fast_acos(x: f32) -> f32 {
    // Not `min`, which would turn NaN into 1: NaN in, NaN out.
    let a = x.abs();
    let a = if a > 1.0 { 1.0 } else { a };
    let r =
        (1.0 - a).sqrt() * (1.570_728_8 + a * (-0.212_114_4 + a * (0.074_261 - 0.018_729_3 * a)));
    if x < 0.0 {
        std::f32::consts::PI - r
    } else {
        r
    }
}

/// `atan(x)` for `x >= 0` within 2e-5 rad (0.001 degree): the off-axis angle in the beam's soft edge,
/// where `f32::atan` was a tenth of the frame time. Range-reduced to [0, 1] by
/// `atan x = pi/2 - atan(1/x)`, then a degree-9 odd minimax polynomial (Abramowitz and
/// Stegun 4.4.49).
#[inline]
pub fn fast_atan(x: f32) -> f32 {
    let (y, flip) = if x > 1.0 { (1.0 / x, true) } else { (x, false) };
    let y2 = y * y;
    let p = y
        * (0.999_866
            + y2 * (-0.330_299_5 + y2 * (0.180_141 + y2 * (-0.085_133_0 + y2 * 0.020_835_1))));
    if flip {
        std::f32::consts::FRAC_PI_2 - p
    } else {
        p
    }
}

/// `atan2(y, x)` in [-pi, pi] within 2e-5 rad, from [`fast_atan`] of the smaller
/// over the larger magnitude; 0 at the origin. The half-plane angle of a measured
/// spotlight's light map, looked up at every sub-sample.
#[inline]
pub fn fast_atan2(y: f32, x: f32) -> f32 {
    let (ax, ay) = (x.abs(), y.abs());
    if ax == 0.0 && ay == 0.0 {
        return 0.0;
    }
    let a = if ax >= ay {
        fast_atan(ay / ax)
    } else {
        std::f32::consts::FRAC_PI_2 - fast_atan(ax / ay)
    };
    let a = if x < 0.0 { std::f32::consts::PI - a } else { a };
    if y < 0.0 {
        -a
    } else {
        a
    }
}

/// A per-pixel offset in [0, 1) that neighbouring pixels spread evenly: Jimenez's
/// interleaved gradient noise (2014). The plane method shifts its sub-sample planes by
/// it (interleaved sampling, Keller and Heidrich 2001), so that a gobo's thin beams,
/// sampled too sparsely along the ray, give fine grain instead of bands.
#[inline]
pub fn interleaved_offset(x: u32, y: u32) -> f32 {
    let f = (0.067_110_56 * x as f32 + 0.005_837_15 * y as f32).fract();
    (52.982_918 * f).fract()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fast_acos_is_within_its_stated_error() {
        let worst = (0..=20_000)
            .map(|k| -1.0 + k as f32 / 10_000.0)
            .map(|x| (fast_acos(x) - x.acos()).abs())
            .fold(0.0, f32::max);
        assert!(worst < 7e-5, "{worst}");
        assert!(fast_acos(f32::NAN).is_nan());
    }

    #[test]
    fn fast_atan_is_within_its_stated_error() {
        let worst = (0..=100_000)
            .map(|k| k as f32 * 1e-4)
            .map(|x| (fast_atan(x) - x.atan()).abs())
            .fold(0.0, f32::max);
        assert!(worst < 2e-5, "{worst}");
    }

    #[test]
    fn fast_atan2_is_within_its_stated_error_in_every_quadrant() {
        let mut worst = 0.0f32;
        for k in 0..=3600 {
            let a = (k as f32 / 10.0 - 180.0).to_radians();
            for r in [1e-3f32, 0.7, 40.0] {
                let (y, x) = (r * a.sin(), r * a.cos());
                // As angles: at +-pi the two may pick either end.
                let d = (fast_atan2(y, x) - y.atan2(x)).abs();
                worst = worst.max(d.min(std::f32::consts::TAU - d));
            }
        }
        assert!(worst < 2e-5, "{worst}");
        assert_eq!(fast_atan2(0.0, 0.0), 0.0);
        assert!((fast_atan2(1.0, 0.0) - std::f32::consts::FRAC_PI_2).abs() < 1e-6);
        assert!((fast_atan2(-1.0, -1.0) + 0.75 * std::f32::consts::PI).abs() < 2e-5);
    }

    #[test]
    fn interleaved_offsets_lie_in_the_unit_interval_and_spread() {
        let v: Vec<f32> = (0..64)
            .flat_map(|y| (0..64).map(move |x| interleaved_offset(x, y)))
            .collect();
        assert!(v.iter().all(|&o| (0.0..1.0).contains(&o)));
        let mean = v.iter().sum::<f32>() / v.len() as f32;
        assert!((mean - 0.5).abs() < 0.02, "{mean}");
    }
}
