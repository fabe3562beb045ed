//! The light maps: what lights each point on a sampling shell.
//!
//! - [`LightMap`] is sky (6): sunlight reaching a shell, `I_sun exp(-tau)`, zero where
//!   the sun has set behind the planet.
//! - [`ScatteredLightMap`] is the first-order light map `I_t(P_k, omega_i)` of sky
//!   (10)-(11): scattered light arriving at a shell point from `N_omega` directions,
//!   and, built the same way from it, the light of each higher order.
//!
//! Both are tabulated over the cosine `mu_s` of the sun's zenith angle at the point,
//! with the directions `omega_i` fixed in the point's local frame (z up, sun in the xz
//! plane). By the symmetry of a spherical atmosphere about the axis through the sun,
//! the light at a point depends on nothing else, so these tables do not depend on where
//! the sun is: moving the sun is only a new lookup. The paper recomputes them per sun.

use std::sync::Arc;

use glam::DVec3;
use rayon::prelude::*;

use super::maps::{lanes, pack, Lane, Orders, ScatteringMaps, Sources, SunGeometry, MAX_CHANNELS};
use super::sampling_shells::SamplingShells;
use crate::atmosphere::geometry::horizon_mu;
use crate::atmosphere::phase::RAYLEIGH_NORM;
use crate::atmosphere::{Atmosphere, PhaseFunction, TransmittanceTable};
use crate::quadrature::SymmetricSphereRule;

/// Entries per shell of the sunlight light map: uniform in `mu_s` from the last light
/// to the zenith, about 0.001 apart (a tenth of the sun disc's passage through the
/// horizon), so a lookup is one multiply.
pub(crate) const LIGHT_MAP_SIZE: usize = 1024;

/// Sunlight `I_sun exp(-tau)` reaching each shell, over the sun's zenith cosine, sky (6).
#[derive(Debug, Clone)]
pub struct LightMap {
    /// For samples between shells.
    pub(crate) table: Arc<TransmittanceTable>,
    pub(crate) irradiance: Vec<f32>,
    /// Per shell, the lowest `mu_s` with any sunlight (the disc's last edge setting).
    pub(crate) mu_low: Vec<f64>,
    /// Per shell, entries per unit of `mu_s`.
    pub(crate) scale: Vec<f64>,
    /// `[shell][entry][lane]`; entry `k` is at `mu_s = mu_low + k / scale`.
    pub(crate) values: Vec<Lane>,
}

impl LightMap {
    /// The light map of every shell, from the transmittance table.
    pub fn new(
        atmosphere: &Atmosphere,
        table: Arc<TransmittanceTable>,
        shells: &SamplingShells,
    ) -> Self {
        let n = atmosphere.channels();
        let mu_low: Vec<f64> = shells
            .radii()
            .iter()
            .map(|&r| {
                let half_disc = atmosphere.bottom_radius_m / r * atmosphere.sun_angular_radius;
                (horizon_mu(r, atmosphere.bottom_radius_m) - 1.01 * half_disc).max(-1.0)
            })
            .collect();
        let irradiance: Vec<f32> = atmosphere
            .solar_irradiance
            .iter()
            .map(|&e| e as f32)
            .collect();
        let l = lanes(n);
        let mut values = vec![Lane::ZERO; shells.len() * LIGHT_MAP_SIZE * l];
        values
            .par_chunks_mut(LIGHT_MAP_SIZE * l)
            .zip(shells.radii().par_iter().zip(&mu_low))
            .for_each(|(shell, (&r, &low))| {
                for (k, out) in shell.chunks_mut(l).enumerate() {
                    let x = k as f64 / (LIGHT_MAP_SIZE - 1) as f64;
                    sunlight(&table, &irradiance, r, low + (1.0 - low) * x, out);
                }
            });
        let scale = mu_low
            .iter()
            .map(|low| (LIGHT_MAP_SIZE - 1) as f64 / (1.0 - low))
            .collect();
        LightMap {
            table,
            irradiance,
            mu_low,
            scale,
            values,
        }
    }

    /// Sunlight reaching radius `r` (between shells), from the table, packed.
    pub fn sample_at(&self, r: f64, mu_s: f64, out: &mut [Lane]) {
        sunlight(&self.table, &self.irradiance, r, mu_s, out);
    }

    /// Sunlight reaching shell `shell` with the sun at zenith cosine `mu_s`, packed.
    #[inline]
    pub fn sample(&self, shell: usize, mu_s: f64, out: &mut [Lane]) {
        let low = self.mu_low[shell];
        if mu_s <= low {
            out.fill(Lane::ZERO);
            return;
        }
        let x = (mu_s - low) * self.scale[shell];
        let k = (x as usize).min(LIGHT_MAP_SIZE - 2);
        let f = (x - k as f64) as f32;
        let l = out.len();
        let base = (shell * LIGHT_MAP_SIZE + k) * l;
        let (a, b) = self.values[base..base + 2 * l].split_at(l);
        for ((o, a), b) in out.iter_mut().zip(a).zip(b) {
            *o = *a + (*b - *a) * f;
        }
    }
}

/// Sunlight `I_sun exp(-tau)` reaching radius `r` with the sun at zenith cosine `mu_s`,
/// sky (6), packed into lanes: what every entry of the light map holds.
fn sunlight(table: &TransmittanceTable, irradiance: &[f32], r: f64, mu_s: f64, out: &mut [Lane]) {
    let mut t = [0.0f32; MAX_CHANNELS];
    let t = &mut t[..irradiance.len()];
    table.to_sun(r, mu_s, t);
    for (v, e) in t.iter_mut().zip(irradiance) {
        *v *= e;
    }
    pack(t, out);
}

/// Bins over the sun's zenith cosine: uniform in `x` in [-1, 1] with
/// `mu_s = x (a + (1 - a)|x|)`, three times denser near the horizon than at the zenith.
#[derive(Debug, Clone, Copy)]
pub(crate) struct SunBins {
    pub(crate) count: usize,
}

impl SunBins {
    pub(crate) const A: f64 = 0.3;

    fn mu_s(&self, b: usize) -> f64 {
        let x = 2.0 * b as f64 / (self.count - 1) as f64 - 1.0;
        x * (Self::A + (1.0 - Self::A) * x.abs())
    }

    /// Fractional bin of `mu_s`.
    fn coordinate(&self, mu_s: f64) -> f64 {
        let m = mu_s.abs().min(1.0);
        let a = Self::A;
        let x = (-a + (a * a + 4.0 * (1.0 - a) * m).sqrt()) / (2.0 * (1.0 - a));
        (0.5 * (x.copysign(mu_s) + 1.0)) * (self.count - 1) as f64
    }

    fn lerp(&self, mu_s: f64) -> (usize, f32) {
        let x = self.coordinate(mu_s);
        let b = (x as usize).min(self.count - 2);
        (b, (x - b as f64) as f32)
    }
}

/// Number of moments that reduce a Rayleigh-phase integral: the integral of the light
/// itself and of `x^2`, `y^2`, `z^2` and `xz` times it.
pub(crate) const MOMENTS: usize = 5;

/// The light map of scattered light of one order, `I_t(P_k, omega_i)` of sky (10)-(11):
/// radiance arriving at each shell, for each sun zenith bin, from each of `N_omega`
/// directions of a [`SymmetricSphereRule`] in the local frame.
#[derive(Debug, Clone)]
pub struct ScatteredLightMap {
    channels: usize,
    pub(crate) bins: SunBins,
    /// The directions of each shell, split at its horizon.
    rules: Vec<SymmetricSphereRule>,
    /// `[shell][bin][direction][channel]`, radiance.
    values: Vec<f32>,
    /// `[shell][bin][moment][lane]`: the quadrature of sky (11) reduced to moments,
    /// radiance x sr, packed.
    pub(crate) moments: Vec<Lane>,
}

impl ScatteredLightMap {
    /// The directions `omega_i` of the second-order quadrature for each shell (split at
    /// its horizon), with the rays from every shell along each of them
    /// (`rays[shell * N_omega + i]`): sun-independent geometry.
    pub fn rays(
        atmosphere: &Atmosphere,
        shells: &SamplingShells,
        directions: usize,
        max_interval_m: f64,
    ) -> (Vec<SymmetricSphereRule>, ScatteringMaps) {
        let rules: Vec<SymmetricSphereRule> = shells
            .radii()
            .iter()
            .map(|&r| {
                SymmetricSphereRule::with_about(
                    directions,
                    horizon_mu(r, atmosphere.bottom_radius_m),
                )
            })
            .collect();
        let rays: Vec<(usize, f64)> = rules
            .iter()
            .enumerate()
            .flat_map(|(j, rule)| rule.directions.iter().map(move |d| (j, d.z)))
            .collect();
        let maps = ScatteringMaps::new(atmosphere, shells, &rays, max_interval_m);
        (rules, maps)
    }

    /// The light map of scattering order `order`, integrating along `rays` the light
    /// that `sources` provide for that order.
    pub fn new(
        order: u32,
        rules: &[SymmetricSphereRule],
        rays: &ScatteringMaps,
        sources: &Sources,
        sun_bins: usize,
    ) -> Self {
        let n = sources.atmosphere.channels();
        let bins = SunBins { count: sun_bins };
        let nd = rules[0].directions.len();
        let per_shell = sun_bins * nd * n;
        let mut values = vec![0.0f32; sources.shells.len() * per_shell];
        values
            .par_chunks_mut(per_shell)
            .enumerate()
            .for_each(|(j, shell)| {
                for b in 0..sun_bins {
                    let mu_s = bins.mu_s(b);
                    let sun = DVec3::new((1.0 - mu_s * mu_s).max(0.0).sqrt(), 0.0, mu_s);
                    for (i, d) in rules[j].directions.iter().enumerate() {
                        let out = &mut shell[(b * nd + i) * n..(b * nd + i + 1) * n];
                        let geometry = SunGeometry {
                            mu_s,
                            nu: d.dot(sun),
                        };
                        let orders = Orders {
                            first: order,
                            last: order,
                        };
                        rays.radiance(j * nd + i, geometry, sources, orders, out);
                    }
                }
            });
        let l = lanes(n);
        let mut moments = vec![Lane::ZERO; sources.shells.len() * sun_bins * MOMENTS * l];
        for (k, (cell, m)) in values
            .chunks(nd * n)
            .zip(moments.chunks_mut(MOMENTS * l))
            .enumerate()
        {
            let rule = &rules[k / sun_bins];
            let mut sums = vec![0.0f32; MOMENTS * n];
            for ((d, weight), light) in rule
                .directions
                .iter()
                .zip(&rule.weights)
                .zip(cell.chunks(n))
            {
                let f = [1.0, d.x * d.x, d.y * d.y, d.z * d.z, d.x * d.z];
                for (fk, sum) in f.iter().zip(sums.chunks_mut(n)) {
                    for (s, v) in sum.iter_mut().zip(light) {
                        *s += (weight * fk) as f32 * v;
                    }
                }
            }
            for (sum, out) in sums.chunks(n).zip(m.chunks_mut(l)) {
                pack(sum, out);
            }
        }
        ScatteredLightMap {
            channels: n,
            bins,
            rules: rules.to_vec(),
            values,
            moments,
        }
    }

    /// `integral of phase(omega . d) I_t(omega) d omega` over the sphere, sky (11), per
    /// channel, at shell `shell` with the sun at `mu_s`, toward the local direction `d`
    /// (the direction the light leaves in, reversed). For the Rayleigh phase, which is
    /// `a + b (omega . d)^2`, the sum over the directions is exactly a sum of five moments.
    pub fn inscatter(
        &self,
        shell: usize,
        mu_s: f64,
        d: DVec3,
        phase: &PhaseFunction,
        out: &mut [Lane],
    ) {
        let n = self.channels;
        let l = out.len();
        let (b, f) = self.bins.lerp(mu_s);
        if phase.is_rayleigh() {
            let k = RAYLEIGH_NORM;
            let g = [
                k,
                k * d.x * d.x,
                k * d.y * d.y,
                k * d.z * d.z,
                2.0 * k * d.x * d.z,
            ]
            .map(|v| v as f32);
            let at = (shell * self.bins.count + b) * MOMENTS * l;
            let (m0, m1) = self.moments[at..at + 2 * MOMENTS * l].split_at(MOMENTS * l);
            out.fill(Lane::ZERO);
            for ((gi, a), b) in g.iter().zip(m0.chunks_exact(l)).zip(m1.chunks_exact(l)) {
                for ((o, a), b) in out.iter_mut().zip(a).zip(b) {
                    *o += *gi * (*a + (*b - *a) * f);
                }
            }
            return;
        }
        // Any other phase: the direct sum, each direction paired with its mirror image
        // across the sun's vertical plane (the light there is the same).
        let rule = &self.rules[shell];
        let nd = rule.directions.len();
        let at = |b: usize| (shell * self.bins.count + b) * nd * n;
        let (v0, v1) = (
            &self.values[at(b)..at(b) + nd * n],
            &self.values[at(b + 1)..at(b + 1) + nd * n],
        );
        let mut sum = [0.0f32; MAX_CHANNELS];
        for ((w, weight), (a, b)) in rule
            .directions
            .iter()
            .zip(&rule.weights)
            .zip(v0.chunks_exact(n).zip(v1.chunks_exact(n)))
        {
            let mirrored = DVec3::new(w.x, -w.y, w.z);
            let p = (0.5 * weight * (phase.eval(w.dot(d)) + phase.eval(mirrored.dot(d)))) as f32;
            for ((s, a), b) in sum.iter_mut().zip(a).zip(b) {
                *s += p * (a + (b - a) * f);
            }
        }
        pack(&sum[..n], out);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sun_bins_invert() {
        let bins = SunBins { count: 64 };
        for b in 0..64 {
            let x = bins.coordinate(bins.mu_s(b));
            assert!((x - b as f64).abs() < 1e-9, "{b}: {x}");
        }
        assert_eq!(bins.mu_s(0), -1.0);
        assert_eq!(bins.mu_s(63), 1.0);
    }

    #[test]
    fn light_map_matches_the_transmittance_table() {
        let a = Atmosphere::earth();
        let table = Arc::new(TransmittanceTable::new(&a));
        let shells = SamplingShells::new(&a, 40, 1000.0);
        let map = LightMap::new(&a, table.clone(), &shells);
        let n = a.channels();
        let (mut lanes_out, mut want) = (vec![Lane::ZERO; lanes(n)], vec![0.0; n]);
        for j in [0, 5, shells.viewpoint(), 39] {
            let r = shells.radii()[j];
            for k in 0..200 {
                let mu_s = -0.2 + 1.2 * k as f64 / 199.0;
                map.sample(j, mu_s, &mut lanes_out);
                let mut got = vec![0.0f32; n];
                crate::sky::shells::maps::unpack_add(&lanes_out, &mut got);
                table.to_sun(r, mu_s, &mut want);
                for c in 0..n {
                    let w = want[c] * a.solar_irradiance[c] as f32;
                    assert!(
                        (got[c] - w).abs() < 0.01 * a.solar_irradiance[c] as f32,
                        "{j} {mu_s}: {} {w}",
                        got[c]
                    );
                }
            }
        }
    }
}
