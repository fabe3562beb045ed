//! Geometry of straight rays in a spherical atmosphere.
//!
//! A ray starts at radius `r` (m, from the planet's centre) with `mu`, the cosine of
//! its zenith angle there. Everything follows from the triangle formed with the centre:
//! after a distance `t` the radius is `sqrt(r^2 + t^2 + 2 r mu t)`.

/// Radius in metres after travelling `t` metres along a ray that starts at `r` with `mu`.
#[inline]
pub fn radius_at(r: f64, mu: f64, t: f64) -> f64 {
    (r * r + t * t + 2.0 * r * mu * t).max(0.0).sqrt()
}

/// Distance in metres from radius `r` along `mu` to where the ray leaves the sphere of
/// radius `top` (with `r <= top`).
#[inline]
pub fn distance_to_sphere_exit(r: f64, mu: f64, top: f64) -> f64 {
    let disc = r * r * (mu * mu - 1.0) + top * top;
    (-r * mu + disc.max(0.0).sqrt()).max(0.0)
}

/// A ray whose closest approach to the planet's centre is within this many metres of
/// the ground grazes it and goes on: the horizon's own direction is the limit from above.
pub const GRAZE_M: f64 = 1e-3;

/// Distance in metres to the ground sphere of radius `bottom`, or `None` when the ray
/// misses (or only grazes, see [`GRAZE_M`]) the ground.
#[inline]
pub fn distance_to_ground(r: f64, mu: f64, bottom: f64) -> Option<f64> {
    let disc = r * r * (mu * mu - 1.0) + bottom * bottom;
    (mu < 0.0 && disc > 2.0 * bottom * GRAZE_M).then(|| (-r * mu - disc.sqrt()).max(0.0))
}

/// Cosine of the zenith angle of the horizon seen from radius `r`: rays with a smaller
/// `mu` hit the ground. It is `-sqrt(1 - (bottom/r)^2)`, minus the sine of the dip.
#[inline]
pub fn horizon_mu(r: f64, bottom: f64) -> f64 {
    -(1.0 - (bottom / r).powi(2)).max(0.0).sqrt()
}

/// The dip of the horizon below the horizontal seen from altitude `altitude_m`, in
/// radians: sky (15), `arccos(R / (R + h))` (the paper's text swaps the terms).
pub fn horizon_dip(bottom_radius_m: f64, altitude_m: f64) -> f64 {
    (bottom_radius_m / (bottom_radius_m + altitude_m))
        .clamp(-1.0, 1.0)
        .acos()
}

/// Fraction of the sun's disc above the horizon seen from radius `r`, for a sun at
/// zenith cosine `mu_s` and angular radius `sun_radius` (rad). Linear across the
/// disc's passage through the horizon, as Bruneton (2017) does, so twilight has no
/// hard edge.
#[inline]
pub fn sun_visible_fraction(r: f64, mu_s: f64, bottom: f64, sun_radius: f64) -> f64 {
    let sin_h = bottom / r;
    let cos_h = horizon_mu(r, bottom);
    let half_width = sin_h * sun_radius;
    ((mu_s - cos_h + half_width) / (2.0 * half_width)).clamp(0.0, 1.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    const R: f64 = 6_360_000.0;
    const TOP: f64 = 6_420_000.0;

    #[test]
    fn vertical_and_horizontal_rays() {
        // A vertical ray from the ground reaches the top after top - R.
        assert!((distance_to_sphere_exit(R, 1.0, TOP) - 60_000.0).abs() < 1e-6);
        // A horizontal ray from the ground: sqrt(top^2 - R^2).
        let expect = (TOP * TOP - R * R).sqrt();
        assert!((distance_to_sphere_exit(R, 0.0, TOP) - expect).abs() < 1e-6);
        // Straight down from 1 km reaches the ground after 1 km.
        assert!((distance_to_ground(R + 1000.0, -1.0, R).unwrap() - 1000.0).abs() < 1e-6);
        assert!(distance_to_ground(R + 1000.0, 0.0, R).is_none());
    }

    #[test]
    fn horizon_dip_at_13_km_is_about_3_7_degrees() {
        let dip = horizon_dip(R, 13_000.0).to_degrees();
        assert!((dip - 3.66).abs() < 0.05, "{dip}");
        // A ray just above the dip misses the ground, just below hits it.
        let r = R + 13_000.0;
        let mu_h = horizon_mu(r, R);
        assert!(distance_to_ground(r, mu_h + 1e-6, R).is_none());
        assert!(distance_to_ground(r, mu_h - 1e-6, R).is_some());
    }

    #[test]
    fn sun_fraction_goes_from_zero_to_one_across_the_horizon() {
        let r = R + 10.0;
        let mu_h = horizon_mu(r, R);
        let a = 0.004675;
        assert_eq!(sun_visible_fraction(r, mu_h - 0.01, R, a), 0.0);
        assert_eq!(sun_visible_fraction(r, mu_h + 0.01, R, a), 1.0);
        assert!((sun_visible_fraction(r, mu_h, R, a) - 0.5).abs() < 1e-9);
    }
}
