//! The "conventional method" the sky paper speeds up: per view ray, numerical
//! integration of sky (2), with the optical depth toward the sun integrated afresh at
//! every point, and for the second order the nested integral of sky (10) over the
//! whole sphere of directions at every point along the ray.
//!
//! For every order, [`ReferenceSky::multiple_scattering`] is a Monte Carlo path tracer
//! of orders 2 and above (molecules and aerosols at every event, a Lambertian ground,
//! next-event estimation toward the sun), independent of the shell method: it shares
//! only the atmosphere's coefficients and densities with it.
//!
//! Geometry is plain Cartesian: the planet's centre at the origin, the viewpoint on the
//! z axis, the sun in the xz plane.

use glam::DVec3;

use crate::atmosphere::geometry::{
    distance_to_ground, distance_to_sphere_exit, sun_visible_fraction,
};
use crate::atmosphere::{Atmosphere, CONSTITUENTS};
use crate::clouds::generator::SplitMix64;
use crate::quadrature::{fibonacci_sphere, gauss_legendre};
use crate::reference::sampling::{mean_and_error, sample_cosine, PhaseSampler};
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
        let d = direction(azimuth, elevation);
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

    /// Single scattering (no ground) between the viewpoint and the point at `distance`
    /// m along the direction at `azimuth` from the sun and `elevation` (rad), and the
    /// transmittance to it, per channel: the aerial perspective of order 1.
    pub fn aerial_single(
        &self,
        azimuth: f64,
        elevation: f64,
        distance: f64,
    ) -> (Vec<f64>, Vec<f64>) {
        let d = direction(azimuth, elevation);
        let mut inscatter = vec![0.0; self.atmosphere.channels()];
        let segments = self.settings.view_segments;
        let (_, _, transmittance) =
            self.single_along(self.viewpoint, d, segments, distance, &mut inscatter);
        (transmittance, inscatter)
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

    /// Marches from `p` along `d` up to `limit` m: calls `visit(point, transmittance
    /// from p, weight)` at every node, and returns the end point, whether it is the
    /// ground, and the transmittance to it.
    fn march(
        &self,
        p: DVec3,
        d: DVec3,
        segments: usize,
        limit: f64,
        mut visit: impl FnMut(DVec3, &[f64], f64),
    ) -> (DVec3, bool, Vec<f64>) {
        let a = self.atmosphere;
        let n = a.channels();
        let (end, ground) = self.ray_end(p, d);
        let (length, ground) = (end.min(limit), ground && end <= limit);
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
        let (end, ground, t_end) = self.single_along(p, d, segments, f64::INFINITY, out);
        if ground && a.ground_albedo > 0.0 {
            let mu_s = end.normalize().dot(self.sun);
            if mu_s > 0.0 {
                let mut sun = [0.0; MAX_CHANNELS];
                self.sunlight(end, &mut sun[..n]);
                for k in 0..n {
                    out[k] += t_end[k] * a.ground_albedo / std::f64::consts::PI * sun[k] * mu_s;
                }
            }
        }
    }

    /// Single scattering in the air arriving at `p` from direction `d` within `limit`
    /// m, added to `out`; returns what [`Self::march`] does.
    fn single_along(
        &self,
        p: DVec3,
        d: DVec3,
        segments: usize,
        limit: f64,
        out: &mut [f64],
    ) -> (DVec3, bool, Vec<f64>) {
        let a = self.atmosphere;
        let n = a.channels();
        let nu = d.dot(self.sun);
        let (p_r, p_m) = (a.rayleigh.phase.eval(nu), a.mie.phase.eval(nu));
        let mut sun = [0.0; MAX_CHANNELS];
        self.march(p, d, segments, limit, |q, tr, w| {
            self.sunlight(q, &mut sun[..n]);
            let rho = self.densities_at(q);
            for k in 0..n {
                let scattering = a.rayleigh.scattering_per_m[k] * rho[0] * p_r
                    + a.mie.scattering_per_m[k] * rho[1] * p_m;
                out[k] += w * tr[k] * sun[k] * scattering;
            }
        })
    }

    /// Second-order scattering arriving at `p` from `d`: at every node, Rayleigh (and,
    /// if its phase is set, aerosol) scattering of the single-scattered light arriving
    /// from every direction of the sphere, sky (10).
    fn second_order(&self, p: DVec3, d: DVec3, out: &mut [f64]) {
        let a = self.atmosphere;
        let n = a.channels();
        let weight = 4.0 * std::f64::consts::PI / self.sphere.len() as f64;
        let mut incoming = vec![0.0; n];
        self.march(
            p,
            d,
            self.settings.nested_segments,
            f64::INFINITY,
            |q, tr, w| {
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
            },
        );
    }
}

/// The unit direction at `azimuth` from the sun and `elevation` (rad), in the
/// reference's frame (the sun in the xz plane, z up).
fn direction(azimuth: f64, elevation: f64) -> DVec3 {
    DVec3::new(
        elevation.cos() * azimuth.cos(),
        elevation.cos() * azimuth.sin(),
        elevation.sin(),
    )
}

/// Steps of the march that finds where a path's next collision is.
const FREE_FLIGHT_STEPS: usize = 96;

/// The most events along one path; the Russian roulette ends nearly all before.
const MAX_EVENTS: usize = 200;

impl ReferenceSky<'_> {
    /// Orders 2 and above arriving at the viewpoint from the direction at `azimuth`
    /// from the sun and `elevation` (rad), per channel: the mean over `paths` paths per
    /// channel and its standard error. The paths start at the eye; at each event
    /// (scattering by molecules or aerosols, or reflection by a Lambertian ground of
    /// the atmosphere's albedo) from the first on, the sunlight scattered toward the
    /// eye is added from the second on (next-event estimation, the disc's visible
    /// fraction as in single scattering); directions are sampled from the phase
    /// function of the species that scatters (or the cosine), distances by free flight
    /// (the first forced into the atmosphere), and a Russian roulette ends the paths
    /// without bias. The same `seed` gives the same numbers.
    pub fn multiple_scattering(
        &self,
        azimuth: f64,
        elevation: f64,
        paths: usize,
        seed: u64,
    ) -> (Vec<f64>, Vec<f64>) {
        let d = direction(azimuth, elevation);
        let n = self.atmosphere.channels();
        let a = self.atmosphere;
        let samplers = [
            PhaseSampler::new(a.rayleigh.phase),
            PhaseSampler::new(a.mie.phase),
        ];
        let (mut mean, mut error) = (vec![0.0; n], vec![0.0; n]);
        for c in 0..n {
            let mut rng = SplitMix64::new(seed ^ (c as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15));
            (mean[c], error[c]) =
                mean_and_error((0..paths).map(|_| self.path(d, c, &samplers, &mut rng)));
        }
        (mean, error)
    }

    /// One path's estimate of orders >= 2 in channel `c`, leaving the eye along `d`.
    fn path(&self, d: DVec3, c: usize, samplers: &[PhaseSampler; 2], rng: &mut SplitMix64) -> f64 {
        let a = self.atmosphere;
        let mut sun = [0.0; MAX_CHANNELS];
        let (mut p, mut w) = (self.viewpoint, d);
        let (mut weight, mut total) = (1.0, 0.0);
        for event in 1..=MAX_EVENTS {
            let (length, ground) = self.ray_end(p, w);
            // The first flight is forced to collide in the air (weight 1 - T): light
            // that leaves along the view ray adds nothing to orders >= 2 ... unless the
            // ray ends on the ground, which is then a possible event like any other.
            let force = event == 1 && !ground;
            let (hit, t_end) = self.free_flight(p, w, length, c, force, rng);
            if force {
                weight *= 1.0 - t_end;
            }
            match hit {
                Some(t) => {
                    let q = p + t * w;
                    let rho = self.densities_at(q);
                    let scatter_r = a.rayleigh.scattering_per_m[c] * rho[0];
                    let scatter_m = a.mie.scattering_per_m[c] * rho[1];
                    let extinction = a.optical_depth(&rho, c);
                    weight *= (scatter_r + scatter_m) / extinction;
                    if event >= 2 {
                        self.sunlight(q, &mut sun[..a.channels()]);
                        let nu = w.dot(self.sun);
                        let phase = (scatter_r * a.rayleigh.phase.eval(nu)
                            + scatter_m * a.mie.phase.eval(nu))
                            / (scatter_r + scatter_m);
                        total += weight * phase * sun[c];
                    }
                    let species = if rng.unit_f64() * (scatter_r + scatter_m) < scatter_r {
                        &samplers[0]
                    } else {
                        &samplers[1]
                    };
                    w = species.sample(w, rng);
                    p = q;
                }
                None if ground => {
                    let q = p + length * w;
                    let normal = q.normalize();
                    weight *= a.ground_albedo;
                    if weight == 0.0 {
                        break;
                    }
                    if event >= 2 {
                        let mu_s = normal.dot(self.sun);
                        if mu_s > 0.0 {
                            self.sunlight(q, &mut sun[..a.channels()]);
                            total += weight * mu_s / std::f64::consts::PI * sun[c];
                        }
                    }
                    w = sample_cosine(normal, rng);
                    // Step off the ground so that the next flight starts above it.
                    p = q + normal * 1e-3;
                }
                None => break,
            }
            // Russian roulette once the weight is small.
            if event >= 3 {
                let survive = weight.min(0.95);
                if rng.unit_f64() >= survive {
                    break;
                }
                weight /= survive;
            }
        }
        total
    }

    /// The distance to the next collision from `p` along `w` in channel `c`, or `None`
    /// if the path reaches `length` (the ground or space) first; with `force`, always a
    /// collision, drawn given that there is one. Also returns the transmittance over
    /// the whole `length`. The optical depth is marched in steps (two Gauss nodes
    /// each) and inverted linearly within the step that crosses the drawn depth.
    fn free_flight(
        &self,
        p: DVec3,
        w: DVec3,
        length: f64,
        c: usize,
        force: bool,
        rng: &mut SplitMix64,
    ) -> (Option<f64>, f64) {
        let a = self.atmosphere;
        let h = length / FREE_FLIGHT_STEPS as f64;
        let mut depth = [0.0; FREE_FLIGHT_STEPS + 1];
        for s in 0..FREE_FLIGHT_STEPS {
            let columns = self.columns(p + (s as f64 * h) * w, w, h, 1);
            depth[s + 1] = depth[s] + a.optical_depth(&columns, c);
        }
        let total = depth[FREE_FLIGHT_STEPS];
        let t_end = (-total).exp();
        let u = rng.unit_f64();
        let target = if force {
            -(1.0 - u * (1.0 - t_end)).ln()
        } else {
            -(1.0 - u).ln()
        };
        if target >= total {
            return (None, t_end);
        }
        let s = depth
            .partition_point(|&x| x <= target)
            .clamp(1, FREE_FLIGHT_STEPS)
            - 1;
        let f = (target - depth[s]) / (depth[s + 1] - depth[s]).max(1e-300);
        (Some((s as f64 + f.clamp(0.0, 1.0)) * h), t_end)
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
        let mut a = Atmosphere::earth().with_ozone(false).unwrap();
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
