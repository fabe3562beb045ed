//! Sampling shells (sky 3.2, Fig. 2) and the rays that cross them.
//!
//! The shells are spheres centred on the planet at which the scattered light is
//! sampled; the integral of sky (2) along a ray becomes a sum over the points where
//! the ray crosses them. The shells are denser near the ground, where the air and the
//! aerosols are dense and thin: altitude `h_k = thickness * (k / (K - 1))^p`.

use crate::atmosphere::geometry::GRAZE_M;
use crate::atmosphere::Atmosphere;

/// Exponent `p` of the shell spacing: 2 puts the first shell 37 m above the ground and
/// spaces them 3 km apart at the top, for 40 shells in 60 km.
pub const SHELL_SPACING_EXPONENT: f64 = 2.0;

/// The radii of the sampling shells, increasing, from the ground to the top of the
/// atmosphere, plus one shell through each viewpoint so that view rays start on one.
#[derive(Debug, Clone)]
pub struct SamplingShells {
    radii: Vec<f64>,
}

impl SamplingShells {
    /// `count` shells (at least 2: the ground and the top) and the viewpoints'
    /// (altitudes in m, each within the atmosphere).
    pub fn new(atmosphere: &Atmosphere, count: usize, viewpoint_altitudes_m: &[f64]) -> Self {
        let thickness = atmosphere.thickness_m();
        let mut radii: Vec<f64> = (0..count)
            .map(|k| {
                let u = k as f64 / (count - 1) as f64;
                atmosphere.bottom_radius_m + thickness * u.powf(SHELL_SPACING_EXPONENT)
            })
            .collect();
        for &h in viewpoint_altitudes_m {
            let r_v = atmosphere.bottom_radius_m + h;
            let at = radii.partition_point(|&r| r < r_v);
            let near = |k: usize| k < radii.len() && (radii[k] - r_v).abs() < 0.5;
            if !(near(at) || (at > 0 && near(at - 1))) {
                radii.insert(at, r_v);
            }
        }
        SamplingShells { radii }
    }

    /// Index of the shell through the viewpoint at `altitude_m` (one of those the
    /// shells were made with), or `None`.
    pub fn index_of(&self, atmosphere: &Atmosphere, altitude_m: f64) -> Option<usize> {
        let r_v = atmosphere.bottom_radius_m + altitude_m;
        let at = self.radii.partition_point(|&r| r < r_v);
        [at, at.wrapping_sub(1)]
            .into_iter()
            .find(|&k| k < self.radii.len() && (self.radii[k] - r_v).abs() < 0.5)
    }

    /// Shell radii in metres, increasing; the first is the ground, the last the top.
    pub fn radii(&self) -> &[f64] {
        &self.radii
    }

    /// Number of shells, the viewpoint's included.
    pub fn len(&self) -> usize {
        self.radii.len()
    }

    /// The points where the ray from shell `origin` with zenith cosine `mu` crosses the
    /// shells, in order along the ray, starting with the origin itself (distance 0).
    /// Returns (shell index, distance m) pairs and whether the ray ends on the ground.
    pub fn crossings(&self, origin: usize, mu: f64, out: &mut Vec<(u16, f64)>) -> bool {
        out.clear();
        let r0 = self.radii[origin];
        out.push((origin as u16, 0.0));
        let bottom = self.radii[0];
        let b = r0 * mu;
        let c = r0 * r0 * (1.0 - mu * mu); // squared perigee radius
        let dist = |j: usize, sign: f64| -b + sign * (self.radii[j].powi(2) - c).max(0.0).sqrt();
        if mu >= 0.0 {
            for j in origin + 1..self.radii.len() {
                out.push((j as u16, dist(j, 1.0)));
            }
            return false;
        }
        let perigee = c.sqrt();
        let hits_ground = perigee < bottom - GRAZE_M;
        // Down through the shells below the origin that the ray reaches ...
        let mut lowest = origin;
        for j in (0..origin).rev() {
            if !hits_ground && self.radii[j] <= perigee + GRAZE_M {
                break;
            }
            out.push((j as u16, dist(j, -1.0)));
            lowest = j;
        }
        if hits_ground {
            return true;
        }
        // ... and up again from the lowest one to the top.
        for j in lowest..self.radii.len() {
            out.push((j as u16, dist(j, 1.0)));
        }
        false
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::atmosphere::geometry::horizon_mu;

    fn shells(h: f64) -> (SamplingShells, usize) {
        let a = Atmosphere::earth();
        let s = SamplingShells::new(&a, 40, &[h]);
        let v = s.index_of(&a, h).unwrap();
        (s, v)
    }

    #[test]
    fn shells_are_denser_near_the_ground_and_include_the_viewpoint() {
        let (s, v) = shells(7000.0);
        assert_eq!(s.len(), 41);
        let r = s.radii();
        assert!(r.windows(2).all(|w| w[1] > w[0]));
        assert!(r[1] - r[0] < 0.1 * (r[40] - r[39]));
        assert_eq!(r[v], 6_360_000.0 + 7000.0);
        // A viewpoint on the ground reuses the ground shell.
        assert_eq!(shells(0.0).0.len(), 40);
        // Several viewpoints, each on its own shell, found again.
        let a = Atmosphere::earth();
        let many = SamplingShells::new(&a, 40, &[0.0, 500.0, 7000.0, 7000.0]);
        assert_eq!(many.len(), 42);
        assert_eq!(many.radii()[many.index_of(&a, 500.0).unwrap()], 6_360_500.0);
        assert_eq!(many.index_of(&a, 0.0), Some(0));
        assert_eq!(many.index_of(&a, 1234.0), None);
    }

    #[test]
    fn upward_ray_crosses_every_shell_above_once() {
        let (s, v) = shells(7000.0);
        let mut out = Vec::new();
        assert!(!s.crossings(v, 0.3, &mut out));
        assert_eq!(out.len(), s.len() - v);
        assert!(out.windows(2).all(|w| w[1].1 > w[0].1));
        assert_eq!(out.last().unwrap().0 as usize, s.len() - 1);
    }

    #[test]
    fn downward_rays_hit_the_ground_or_come_back_up() {
        let (s, v) = shells(13000.0);
        let mut out = Vec::new();
        let r0 = s.radii()[v];
        let mu_h = horizon_mu(r0, s.radii()[0]);
        assert!(s.crossings(v, -0.5, &mut out));
        assert_eq!(out.last().unwrap().0, 0);
        assert!((out.last().unwrap().1 - 13000.0 / 0.5).abs() < 100.0);
        assert!(!s.crossings(v, mu_h + 1e-4, &mut out));
        assert!(out.windows(2).all(|w| w[1].1 > w[0].1), "{out:?}");
        assert_eq!(out.last().unwrap().0 as usize, s.len() - 1);
        // Each crossing lies on its shell.
        for &(j, t) in &out {
            let r = crate::atmosphere::geometry::radius_at(r0, mu_h + 1e-4, t);
            assert!((r - s.radii()[j as usize]).abs() < 0.05, "{j}: {r}");
        }
    }
}
