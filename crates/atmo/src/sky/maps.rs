//! The scattering maps of a bundle of rays (sky 3.3, Fig. 3).
//!
//! Along a ray the scattered radiance is a sum over its shell crossings of four maps,
//! sky (3): the light reaching the point (light map `I_l`, sky (6)), the phase function
//! (phase map `F`, sky (7)-(8)), the density (density map `D`, sky (4)-(5)) and the
//! attenuation back to the ray's origin (attenuation map `G`, sky (9)). Density and
//! attenuation do not depend on the sun, so they are computed once, here, multiplied
//! together with the quadrature weight of each crossing; moving the sun recomputes only
//! the light and phase maps, as the end of sky 3.3 says.
//!
//! The quadrature weight of a crossing comes from integrating, over each interval
//! between crossings, a source that varies linearly times an attenuation that varies
//! exponentially (optical depth linear in distance). A plain trapezoid rule would be
//! 6 % off on a horizontal ray near the ground, where the blue light is extinguished
//! within one 20 km interval; this rule is exact there.

use glam::DVec3;
use rayon::prelude::*;

use super::light_map::{LightMap, ScatteredLightMap};
use super::shells::SamplingShells;
use crate::atmosphere::optical_depth::column_densities;
use crate::atmosphere::{Atmosphere, CONSTITUENTS};

/// Most wavelengths a spectrum may have (validated in `Atmosphere`); sizes stack buffers.
pub const MAX_CHANNELS: usize = 64;

/// Gauss-Legendre segments per interval between crossings for the attenuation map.
const ATTENUATION_SEGMENTS: usize = 2;

/// The sun-independent maps (density x attenuation x quadrature weight) of a bundle of
/// rays, each starting on a shell.
#[derive(Debug, Clone)]
pub struct ScatteringMaps {
    channels: usize,
    /// Sample range of each ray: `ray_start[i]..ray_start[i + 1]`.
    ray_start: Vec<u32>,
    /// Radius (m) of each ray's origin.
    origin_r: Vec<f64>,
    /// Shell of each sample.
    shell: Vec<u16>,
    /// Distance (m) of each sample from its ray's origin.
    distance: Vec<f64>,
    /// Zenith cosine of the ray's direction at each sample.
    mu: Vec<f64>,
    /// `[sample][channel]`: Rayleigh scattering coefficient x density map x
    /// attenuation map x quadrature weight (m^-1 x m = dimensionless).
    rayleigh: Vec<f32>,
    /// The same for aerosols.
    mie: Vec<f32>,
    /// `[ray][channel]`: ground albedo / pi x attenuation to the ground; zero for rays
    /// that do not end on the ground or over a black one.
    ground: Vec<f32>,
    /// Distance to the ground (m) of each ray, or a negative value.
    ground_distance: Vec<f64>,
}

/// Where the sun is, seen from a ray's origin, and the ray's angle to it.
#[derive(Debug, Clone, Copy)]
pub struct SunGeometry {
    /// Cosine of the sun's zenith angle at the ray's origin.
    pub mu_s: f64,
    /// Cosine of the angle between the ray and the direction to the sun.
    pub nu: f64,
}

/// Which scattering orders to sum, inclusive (1 = single scattering).
#[derive(Debug, Clone, Copy)]
pub struct Orders {
    /// Lowest order included.
    pub first: u32,
    /// Highest order included.
    pub last: u32,
}

/// What lights the points on the shells: the sun through the light map, and the
/// scattered light of the orders below through the scattered light maps.
pub struct Sources<'a> {
    pub atmosphere: &'a Atmosphere,
    pub shells: &'a SamplingShells,
    pub sunlight: &'a LightMap,
    /// `scattered[n - 1]` holds the radiance of order `n` arriving at the shells.
    pub scattered: &'a [ScatteredLightMap],
    /// Whether aerosols scatter the orders above the first (the paper: no).
    pub multiple_mie: bool,
}

/// Weights of the two ends of an interval with a linear source under an attenuation
/// whose optical depth grows by `delta` across it: the integrals over [0, 1] of
/// `(1 - u) exp(-delta u)` and `u exp(-delta u)`.
fn interval_weights(delta: f64) -> (f64, f64) {
    if delta < 1e-3 {
        (
            0.5 - delta / 6.0 + delta * delta / 24.0,
            0.5 - delta / 3.0 + delta * delta / 8.0,
        )
    } else {
        let e = (-delta).exp();
        let d2 = delta * delta;
        ((delta - 1.0 + e) / d2, (1.0 - (1.0 + delta) * e) / d2)
    }
}

struct RayMaps {
    shell: Vec<u16>,
    distance: Vec<f64>,
    mu: Vec<f64>,
    rayleigh: Vec<f32>,
    mie: Vec<f32>,
    ground: Vec<f32>,
    ground_distance: f64,
}

impl ScatteringMaps {
    /// Maps for rays given as (origin shell, zenith cosine), computed in parallel; the
    /// result does not depend on the thread count.
    pub fn new(atmosphere: &Atmosphere, shells: &SamplingShells, rays: &[(usize, f64)]) -> Self {
        let per_ray: Vec<RayMaps> = rays
            .par_iter()
            .map_init(Vec::new, |crossings, &(origin, mu)| {
                Self::ray_maps(atmosphere, shells, origin, mu, crossings)
            })
            .collect();
        let channels = atmosphere.channels();
        let mut maps = ScatteringMaps {
            channels,
            ray_start: Vec::with_capacity(rays.len() + 1),
            origin_r: rays.iter().map(|&(o, _)| shells.radii()[o]).collect(),
            shell: Vec::new(),
            distance: Vec::new(),
            mu: Vec::new(),
            rayleigh: Vec::new(),
            mie: Vec::new(),
            ground: Vec::with_capacity(rays.len() * channels),
            ground_distance: Vec::with_capacity(rays.len()),
        };
        maps.ray_start.push(0);
        for r in per_ray {
            maps.shell.extend_from_slice(&r.shell);
            maps.distance.extend_from_slice(&r.distance);
            maps.mu.extend_from_slice(&r.mu);
            maps.rayleigh.extend_from_slice(&r.rayleigh);
            maps.mie.extend_from_slice(&r.mie);
            maps.ground.extend_from_slice(&r.ground);
            maps.ground_distance.push(r.ground_distance);
            maps.ray_start.push(maps.shell.len() as u32);
        }
        maps
    }

    fn ray_maps(
        atmosphere: &Atmosphere,
        shells: &SamplingShells,
        origin: usize,
        mu0: f64,
        crossings: &mut Vec<(u16, f64)>,
    ) -> RayMaps {
        let n = atmosphere.channels();
        let on_ground = shells.crossings(origin, mu0, crossings);
        let m = crossings.len();
        let r0 = shells.radii()[origin];
        // Optical depth from the origin to each crossing, per channel.
        let mut tau = vec![0.0f64; m * n];
        let mut columns = [0.0f64; CONSTITUENTS];
        for i in 1..m {
            let (t0, t1) = (crossings[i - 1].1, crossings[i].1);
            let mu_a = (r0 * mu0 + t0) / shells.radii()[crossings[i - 1].0 as usize];
            let step = column_densities(
                atmosphere,
                shells.radii()[crossings[i - 1].0 as usize],
                mu_a.clamp(-1.0, 1.0),
                t1 - t0,
                ATTENUATION_SEGMENTS,
            );
            for k in 0..CONSTITUENTS {
                columns[k] += step[k];
            }
            for c in 0..n {
                tau[i * n + c] = atmosphere.optical_depth(&columns, c);
            }
        }
        // Quadrature weights, folded with the attenuation map.
        let mut weight = vec![0.0f64; m * n];
        for i in 1..m {
            let dt = crossings[i].1 - crossings[i - 1].1;
            for c in 0..n {
                let (ta, tb) = (tau[(i - 1) * n + c], tau[i * n + c]);
                let (wa, wb) = interval_weights(tb - ta);
                let e = (-ta).exp() * dt;
                weight[(i - 1) * n + c] += e * wa;
                weight[i * n + c] += e * wb;
            }
        }
        let mut maps = RayMaps {
            shell: crossings.iter().map(|c| c.0).collect(),
            distance: crossings.iter().map(|c| c.1).collect(),
            mu: Vec::with_capacity(m),
            rayleigh: Vec::with_capacity(m * n),
            mie: Vec::with_capacity(m * n),
            ground: vec![0.0; n],
            ground_distance: -1.0,
        };
        for (i, &(j, t)) in crossings.iter().enumerate() {
            let r = shells.radii()[j as usize];
            maps.mu.push(((r0 * mu0 + t) / r).clamp(-1.0, 1.0));
            let h = atmosphere.altitude(r);
            let (rho_r, rho_m) = (atmosphere.rayleigh.density(h), atmosphere.mie.density(h));
            for c in 0..n {
                let w = weight[i * n + c];
                maps.rayleigh
                    .push((w * atmosphere.rayleigh.scattering_per_m[c] * rho_r) as f32);
                maps.mie
                    .push((w * atmosphere.mie.scattering_per_m[c] * rho_m) as f32);
            }
        }
        if on_ground {
            maps.ground_distance = crossings[m - 1].1;
            for c in 0..n {
                maps.ground[c] = (atmosphere.ground_albedo / std::f64::consts::PI
                    * (-tau[(m - 1) * n + c]).exp()) as f32;
            }
        }
        maps
    }

    /// Number of rays.
    pub fn rays(&self) -> usize {
        self.origin_r.len()
    }

    /// Total number of shell crossings over all rays.
    pub fn samples(&self) -> usize {
        self.shell.len()
    }

    /// Radiance per channel arriving at ray `ray`'s origin from along the ray, of the
    /// scattering orders `orders`, sky (3) summed over the crossings; added to `out`.
    pub fn radiance(
        &self,
        ray: usize,
        sun: SunGeometry,
        sources: &Sources,
        orders: Orders,
        out: &mut [f32],
    ) {
        let n = self.channels;
        let atmosphere = sources.atmosphere;
        let radii = sources.shells.radii();
        let r0_mu_s = self.origin_r[ray] * sun.mu_s;
        let nu = sun.nu;
        // The phase maps, sky (7)-(8): one value per ray, the sun being at infinity.
        let phase_r = atmosphere.rayleigh.phase.eval(nu) as f32;
        let phase_m = atmosphere.mie.phase.eval(nu) as f32;
        let mut light = [0.0f32; MAX_CHANNELS];
        let light = &mut light[..n];
        let range = self.ray_start[ray] as usize..self.ray_start[ray + 1] as usize;
        for s in range {
            let j = self.shell[s] as usize;
            let r = radii[j];
            let mu_s = ((r0_mu_s + self.distance[s] * nu) / r).clamp(-1.0, 1.0);
            let (ray_r, ray_m) = (
                &self.rayleigh[s * n..(s + 1) * n],
                &self.mie[s * n..(s + 1) * n],
            );
            if orders.first <= 1 {
                // The light map, sky (6): sunlight reaching the crossing.
                sources.sunlight.sample(j, mu_s, light);
                for c in 0..n {
                    out[c] += light[c] * (ray_r[c] * phase_r + ray_m[c] * phase_m);
                }
            }
            if orders.last < 2 {
                continue;
            }
            let d = local_direction(self.mu[s], mu_s, nu);
            for order in orders.first.max(2)..=orders.last {
                // Light of the order below arriving from every direction, sky (10)-(11).
                let map = &sources.scattered[order as usize - 2];
                map.inscatter(j, mu_s, d, &atmosphere.rayleigh.phase, light);
                for c in 0..n {
                    out[c] += ray_r[c] * light[c];
                }
                if sources.multiple_mie {
                    map.inscatter(j, mu_s, d, &atmosphere.mie.phase, light);
                    for c in 0..n {
                        out[c] += ray_m[c] * light[c];
                    }
                }
            }
        }
        // Sunlight reflected by a Lambertian ground at the end of the ray (order 1).
        let t_ground = self.ground_distance[ray];
        if orders.first <= 1 && t_ground >= 0.0 && atmosphere.ground_albedo > 0.0 {
            let mu_s = ((r0_mu_s + t_ground * nu) / radii[0]).clamp(-1.0, 1.0);
            if mu_s > 0.0 {
                sources.sunlight.sample(0, mu_s, light);
                let g = &self.ground[ray * n..(ray + 1) * n];
                for c in 0..n {
                    out[c] += light[c] * mu_s as f32 * g[c];
                }
            }
        }
    }
}

/// The ray's direction in the local frame of a point (z up, sun in the xz plane with
/// x >= 0), from the ray's zenith cosine `mu`, the sun's zenith cosine `mu_s` and the
/// cosine `nu` of the angle between them. The light field is symmetric about the sun's
/// vertical plane, so the y component is taken non-negative.
#[inline]
pub fn local_direction(mu: f64, mu_s: f64, nu: f64) -> DVec3 {
    let sin_d = (1.0 - mu * mu).max(0.0).sqrt();
    let sin_s = (1.0 - mu_s * mu_s).max(0.0).sqrt();
    let cos_phi = if sin_d * sin_s > 1e-9 {
        ((nu - mu * mu_s) / (sin_d * sin_s)).clamp(-1.0, 1.0)
    } else {
        1.0
    };
    let sin_phi = (1.0 - cos_phi * cos_phi).max(0.0).sqrt();
    DVec3::new(sin_d * cos_phi, sin_d * sin_phi, mu)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn interval_weights_integrate_exactly() {
        for delta in [0.0, 1e-4, 0.3, 2.0, 10.0] {
            let (a, b) = interval_weights(delta);
            let (mut ea, mut eb) = (0.0, 0.0);
            crate::quadrature::gauss_legendre(0.0, 1.0, 64, |u, w| {
                ea += w * (1.0 - u) * (-delta * u).exp();
                eb += w * u * (-delta * u).exp();
            });
            assert!(
                (a - ea).abs() < 1e-9 && (b - eb).abs() < 1e-9,
                "{delta}: {a} {ea} {b} {eb}"
            );
        }
    }

    #[test]
    fn local_direction_keeps_the_angles() {
        let d = local_direction(0.3, 0.5, 0.2);
        let s = DVec3::new((1.0f64 - 0.25).sqrt(), 0.0, 0.5);
        assert!((d.length() - 1.0).abs() < 1e-12);
        assert!((d.z - 0.3).abs() < 1e-12 && (d.dot(s) - 0.2).abs() < 1e-12);
    }
}
