//! The "conventional method" the sky paper speeds up: per view ray, numerical
//! integration of sky (2), with the optical depth toward the sun integrated afresh at
//! every point, and for the second order the nested integral of sky (10) over the
//! whole sphere of directions at every point along the ray.
//!
//! Geometry is plain Cartesian: the planet's centre at the origin, the viewpoint on the
//! z axis, the sun in the xz plane.

use glam::DVec3;

use crate::atmosphere::geometry::{
    distance_to_ground, distance_to_sphere_exit, sun_visible_fraction,
};
use crate::atmosphere::{Atmosphere, CONSTITUENTS};
use crate::quadrature::{fibonacci_sphere, gauss_legendre};
use crate::sky::shells::maps::MAX_CHANNELS;

/// Resolution of the reference integrator.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ReferenceSettings {
    /// 4-point Gauss-Legendre segments along each view ray.
    pub view_segments: usize,
    /// Segments along each path toward the sun.
    pub sun_segments: usize,
    /// Directions of the nested sphere integral (second order), a Fibonacci set.
    pub sphere_directions: usize,
    /// Segments along the view ray and along each nested ray for the second order.
    pub nested_segments: usize,
}

impl ReferenceSettings {
    /// Converged settings: doubling every count changes the sky by less than 0.1 %
    /// (checked by `doubling_the_reference_changes_little` and by `atmo bench sky`).
    pub const CONVERGED: ReferenceSettings = ReferenceSettings {
        view_segments: 48,
        sun_segments: 12,
        sphere_directions: 256,
        nested_segments: 12,
    };

    /// Every count doubled.
    pub fn doubled(&self) -> Self {
        ReferenceSettings {
            view_segments: 2 * self.view_segments,
            sun_segments: 2 * self.sun_segments,
            sphere_directions: 2 * self.sphere_directions,
            nested_segments: 2 * self.nested_segments,
        }
    }
}

/// The reference integrator for one atmosphere, viewpoint altitude and sun.
pub struct ReferenceSky<'a> {
    atmosphere: &'a Atmosphere,
    settings: ReferenceSettings,
    viewpoint: DVec3,
    sun: DVec3,
    sphere: Vec<DVec3>,
}

impl<'a> ReferenceSky<'a> {
    /// The sky at `altitude_m` with the sun at `sun_elevation` rad (azimuth 0).
    pub fn new(
        atmosphere: &'a Atmosphere,
        altitude_m: f64,
        sun_elevation: f64,
        settings: ReferenceSettings,
    ) -> Self {
        ReferenceSky {
            atmosphere,
            settings,
            viewpoint: DVec3::new(0.0, 0.0, atmosphere.bottom_radius_m + altitude_m),
            sun: DVec3::new(sun_elevation.cos(), 0.0, sun_elevation.sin()),
            sphere: fibonacci_sphere(settings.sphere_directions),
        }
    }

    /// Radiance per channel arriving at the viewpoint from the direction at
    /// `azimuth` from the sun and `elevation` (rad), of the orders `first..=last`
    /// (1 or 2).
    pub fn radiance(&self, azimuth: f64, elevation: f64, first: u32, last: u32) -> Vec<f64> {
        let d = DVec3::new(
            elevation.cos() * azimuth.cos(),
            elevation.cos() * azimuth.sin(),
            elevation.sin(),
        );
        let n = self.atmosphere.channels();
        let mut out = vec![0.0; n];
        if first <= 1 {
            self.single_scattering(self.viewpoint, d, self.settings.view_segments, &mut out);
        }
        if last >= 2 {
            self.second_order(self.viewpoint, d, &mut out);
        }
        out
    }

    /// Distance from `p` along `d` to the end of the atmosphere or the ground, and
    /// whether it is the ground.
    fn ray_end(&self, p: DVec3, d: DVec3) -> (f64, bool) {
        let r = p.length();
        let mu = (p.dot(d) / r).clamp(-1.0, 1.0);
        match distance_to_ground(r, mu, self.atmosphere.bottom_radius_m) {
            Some(t) => (t, true),
            None => (
                distance_to_sphere_exit(r, mu, self.atmosphere.top_radius_m),
                false,
            ),
        }
    }

    fn densities_at(&self, p: DVec3) -> [f64; CONSTITUENTS] {
        self.atmosphere
            .densities(self.atmosphere.altitude(p.length()))
    }

    /// Column densities from `p` along `d` over `length`, `segments` of Gauss-Legendre.
    fn columns(&self, p: DVec3, d: DVec3, length: f64, segments: usize) -> [f64; CONSTITUENTS] {
        let mut c = [0.0; CONSTITUENTS];
        gauss_legendre(0.0, length, segments, |t, w| {
            let rho = self.densities_at(p + t * d);
            for k in 0..CONSTITUENTS {
                c[k] += w * rho[k];
            }
        });
        c
    }

    /// Sunlight per channel reaching `p`: irradiance x transmittance x visible fraction.
    fn sunlight(&self, p: DVec3, out: &mut [f64]) {
        let r = p.length();
        let mu_s = p.dot(self.sun) / r;
        let a = self.atmosphere;
        let visible = sun_visible_fraction(r, mu_s, a.bottom_radius_m, a.sun_angular_radius);
        if visible == 0.0 {
            out.fill(0.0);
            return;
        }
        // The path toward the sun as if the ground were transparent: the visible
        // fraction above accounts for the planet.
        let length = distance_to_sphere_exit(r, mu_s, a.top_radius_m);
        let c = self.columns(p, self.sun, length, self.settings.sun_segments);
        for (k, o) in out.iter_mut().enumerate() {
            *o = a.solar_irradiance[k] * visible * (-a.optical_depth(&c, k)).exp();
        }
    }

    /// Marches from `p` along `d`: calls `visit(point, transmittance from p, weight)` at
    /// every node, and returns the end point, whether it is the ground, and the
    /// transmittance to it.
    fn march(
        &self,
        p: DVec3,
        d: DVec3,
        segments: usize,
        mut visit: impl FnMut(DVec3, &[f64], f64),
    ) -> (DVec3, bool, Vec<f64>) {
        let a = self.atmosphere;
        let n = a.channels();
        let (length, ground) = self.ray_end(p, d);
        let h = length / segments as f64;
        let mut columns = [0.0; CONSTITUENTS];
        let mut transmittance = vec![0.0; n];
        for s in 0..segments {
            let start = p + (s as f64 * h) * d;
            gauss_legendre(0.0, h, 1, |t, w| {
                // Optical depth from the segment's start to the node, integrated afresh.
                let partial = self.columns(start, d, t, 1);
                let total: [f64; CONSTITUENTS] = std::array::from_fn(|k| columns[k] + partial[k]);
                for (k, tr) in transmittance.iter_mut().enumerate() {
                    *tr = (-a.optical_depth(&total, k)).exp();
                }
                visit(start + t * d, &transmittance, w);
            });
            let whole = self.columns(start, d, h, 1);
            for k in 0..CONSTITUENTS {
                columns[k] += whole[k];
            }
        }
        for (k, tr) in transmittance.iter_mut().enumerate() {
            *tr = (-a.optical_depth(&columns, k)).exp();
        }
        (p + length * d, ground, transmittance)
    }

    /// Single scattering arriving at `p` from direction `d`, plus the sunlit ground if
    /// the ray ends on it; added to `out`.
    fn single_scattering(&self, p: DVec3, d: DVec3, segments: usize, out: &mut [f64]) {
        let a = self.atmosphere;
        let n = a.channels();
        let nu = d.dot(self.sun);
        let (p_r, p_m) = (a.rayleigh.phase.eval(nu), a.mie.phase.eval(nu));
        let mut sun = [0.0; MAX_CHANNELS];
        let (end, ground, t_end) = self.march(p, d, segments, |q, tr, w| {
            self.sunlight(q, &mut sun[..n]);
            let rho = self.densities_at(q);
            for k in 0..n {
                let scattering = a.rayleigh.scattering_per_m[k] * rho[0] * p_r
                    + a.mie.scattering_per_m[k] * rho[1] * p_m;
                out[k] += w * tr[k] * sun[k] * scattering;
            }
        });
        if ground && a.ground_albedo > 0.0 {
            let mu_s = end.normalize().dot(self.sun);
            if mu_s > 0.0 {
                self.sunlight(end, &mut sun[..n]);
                for k in 0..n {
                    out[k] += t_end[k] * a.ground_albedo / std::f64::consts::PI * sun[k] * mu_s;
                }
            }
        }
    }

    /// Second-order scattering arriving at `p` from `d`: at every node, Rayleigh (and,
    /// if its phase is set, aerosol) scattering of the single-scattered light arriving
    /// from every direction of the sphere, sky (10).
    fn second_order(&self, p: DVec3, d: DVec3, out: &mut [f64]) {
        let a = self.atmosphere;
        let n = a.channels();
        let weight = 4.0 * std::f64::consts::PI / self.sphere.len() as f64;
        let mut incoming = vec![0.0; n];
        self.march(p, d, self.settings.nested_segments, |q, tr, w| {
            let rho = self.densities_at(q);
            let mut source = [0.0; MAX_CHANNELS];
            for omega in &self.sphere {
                incoming.fill(0.0);
                self.single_scattering(q, *omega, self.settings.nested_segments, &mut incoming);
                let phase = a.rayleigh.phase.eval(omega.dot(d));
                for k in 0..n {
                    source[k] += weight * phase * incoming[k];
                }
            }
            for k in 0..n {
                out[k] += w * tr[k] * a.rayleigh.scattering_per_m[k] * rho[0] * source[k];
            }
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn zero_density_gives_no_sky() {
        let mut a = Atmosphere::earth();
        a.rayleigh
            .scattering_per_m
            .iter_mut()
            .for_each(|b| *b = 0.0);
        a.mie.scattering_per_m.iter_mut().for_each(|b| *b = 0.0);
        let sky = ReferenceSky::new(&a, 100.0, 0.5, ReferenceSettings::CONVERGED);
        assert!(sky.radiance(0.3, 0.4, 1, 1).iter().all(|&v| v == 0.0));
    }

    #[test]
    fn optically_thin_zenith_matches_the_closed_form() {
        // A thin Rayleigh-only atmosphere, sun at the zenith, looking up: the radiance
        // is E p(1) beta H (1 - exp(-top/H)) to first order in the optical depth.
        let mut a = Atmosphere::earth();
        a.mie.scattering_per_m.iter_mut().for_each(|b| *b = 0.0);
        a.mie.extinction_per_m.iter_mut().for_each(|b| *b = 0.0);
        a.rayleigh
            .scattering_per_m
            .iter_mut()
            .for_each(|b| *b = 1e-9);
        a.rayleigh.extinction_per_m = a.rayleigh.scattering_per_m.clone();
        let sky = ReferenceSky::new(
            &a,
            0.0,
            std::f64::consts::FRAC_PI_2,
            ReferenceSettings::CONVERGED,
        );
        let got = sky.radiance(0.0, std::f64::consts::FRAC_PI_2, 1, 1);
        let h = a.rayleigh.scale_height_m;
        let want = a.solar_irradiance[0]
            * a.rayleigh.phase.eval(1.0)
            * 1e-9
            * h
            * (1.0 - (-a.thickness_m() / h).exp());
        assert!((got[0] / want - 1.0).abs() < 1e-4, "{} vs {want}", got[0]);
    }
}
