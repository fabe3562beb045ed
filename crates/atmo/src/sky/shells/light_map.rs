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

/// Cells of the in-scattering tables of non-Rayleigh phases: local directions at
/// `TABLE_MU` zenith cosines uniform over [-1, 1] times `TABLE_PHI` azimuths from the
/// sun's vertical plane uniform over [0, pi] (the light is mirror-symmetric about it):
/// 20 MB for 40 shells and 64 sun bins. The sky it gives is held to the path tracer
/// (tests/sky.rs, `every_order_agrees_with_the_path_tracer`).
pub(crate) const TABLE_MU: usize = 25;
pub(crate) const TABLE_PHI: usize = 13;
const TABLE_CELLS: usize = TABLE_MU * TABLE_PHI;

/// The local direction of table cell `g`.
fn table_direction(g: usize) -> DVec3 {
    let mu = -1.0 + 2.0 * (g / TABLE_PHI) as f64 / (TABLE_MU - 1) as f64;
    let phi = std::f64::consts::PI * (g % TABLE_PHI) as f64 / (TABLE_PHI - 1) as f64;
    let sin = (1.0 - mu * mu).max(0.0).sqrt();
    DVec3::new(sin * phi.cos(), sin * phi.sin(), mu)
}

/// The species that scatter: 0 the molecules, 1 the aerosols.
pub(crate) const SPECIES: usize = 2;

/// Scattered light arriving at the shells, `I_t(P_k, omega_i)` of sky (10)-(11), for
/// one scattering order or the sum of several: radiance arriving at each shell, for
/// each sun zenith bin, from each of `N_omega` directions of a [`SymmetricSphereRule`]
/// in the local frame, and what the view rays read of it: the in-scattering of each
/// species toward any direction, and the irradiance it puts on the ground.
#[derive(Debug, Clone)]
pub struct ScatteredLightMap {
    channels: usize,
    /// Shells the light is known at.
    shells: usize,
    pub(crate) bins: SunBins,
    /// Which species scatter this light (the paper: the molecules only).
    pub(crate) scatters: [bool; SPECIES],
    /// `[shell][bin][direction][channel]`, radiance; kept while orders are built.
    values: Vec<f32>,
    /// `[shell][bin][moment][lane]`: the quadrature of sky (11) reduced to moments,
    /// radiance x sr, packed; serves Rayleigh's phase.
    pub(crate) moments: Vec<Lane>,
    /// Per species that scatters with another phase: `[bin][shell][cell][lane]`, the
    /// in-scattering `integral of phase(omega . d) I_t(omega) d omega` toward the
    /// table's cells `d`, radiance, packed. The sun bin is outermost: the samples of
    /// one light ray read a few bins, all shells (a third of the time the light
    /// maps took with the bin innermost, from cache misses).
    pub(crate) tables: [Option<Vec<Lane>>; SPECIES],
    /// `[bin][channel]`: irradiance on the ground (shell 0) from the light coming down,
    /// what a Lambertian ground reflects into the next order.
    pub(crate) ground_irradiance: Vec<f32>,
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

    /// The light of the orders `orders` arriving at the shells, integrating along `rays`
    /// the light that `sources` provide; `scatters` says which species scatter it in
    /// turn (into the next order, or toward the eye).
    pub fn new(
        rules: &[SymmetricSphereRule],
        rays: &ScatteringMaps,
        sources: &Sources,
        orders: Orders,
        sun_bins: usize,
        scatters: [bool; SPECIES],
    ) -> Self {
        let atmosphere = sources.atmosphere;
        let n = atmosphere.channels();
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
                        rays.radiance(j * nd + i, geometry, sources, orders, out);
                    }
                }
            });
        Self::from_values(rules, atmosphere, values, bins, scatters)
    }

    /// The map of the radiance `values` (`[shell][bin][direction][channel]`).
    fn from_values(
        rules: &[SymmetricSphereRule],
        atmosphere: &Atmosphere,
        values: Vec<f32>,
        bins: SunBins,
        scatters: [bool; SPECIES],
    ) -> Self {
        let n = atmosphere.channels();
        let sun_bins = bins.count;
        let nd = rules[0].directions.len();
        let per_shell = sun_bins * nd * n;
        let l = lanes(n);
        let mut moments = vec![Lane::ZERO; rules.len() * sun_bins * MOMENTS * l];
        moments
            .par_chunks_mut(sun_bins * MOMENTS * l)
            .zip(values.par_chunks(per_shell))
            .zip(rules.par_iter())
            .for_each(|((shell, cells), rule)| {
                for (m, cell) in shell.chunks_mut(MOMENTS * l).zip(cells.chunks(nd * n)) {
                    let mut sums = [0.0f32; MOMENTS * MAX_CHANNELS];
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
            });
        let species = [&atmosphere.rayleigh.phase, &atmosphere.mie.phase];
        let tables = std::array::from_fn(|k| {
            (scatters[k] && !species[k].is_rayleigh())
                .then(|| phase_tables(rules, &values, sun_bins, n, species[k]))
        });
        // Light coming down onto the ground, cosine-weighted.
        let mut ground_irradiance = vec![0.0f32; sun_bins * n];
        for (b, e) in ground_irradiance.chunks_mut(n).enumerate() {
            let cell = &values[b * nd * n..(b + 1) * nd * n];
            for ((d, weight), light) in rules[0]
                .directions
                .iter()
                .zip(&rules[0].weights)
                .zip(cell.chunks(n))
            {
                if d.z > 0.0 {
                    for (e, v) in e.iter_mut().zip(light) {
                        *e += (weight * d.z) as f32 * v;
                    }
                }
            }
        }
        ScatteredLightMap {
            channels: n,
            shells: rules.len(),
            bins,
            scatters,
            values,
            moments,
            tables,
            ground_irradiance,
        }
    }

    /// Adds the light of `other` (other orders, same shells and directions) to this.
    pub fn add(&mut self, other: &ScatteredLightMap) {
        fn sum<T: Copy + std::ops::AddAssign>(a: &mut [T], b: &[T]) {
            a.iter_mut().zip(b).for_each(|(a, b)| *a += *b);
        }
        sum(&mut self.values, &other.values);
        sum(&mut self.moments, &other.moments);
        sum(&mut self.ground_irradiance, &other.ground_irradiance);
        for (a, b) in self.tables.iter_mut().zip(&other.tables) {
            if let (Some(a), Some(b)) = (a, b) {
                sum(a, b);
            }
        }
    }

    /// The largest share `other`'s light would add to this sum anywhere (any shell, sun
    /// bin, direction and wavelength), each wavelength's values floored at 1e-3 of
    /// this sum's brightest: light a million times fainter than the sky's brightest
    /// does not decide convergence.
    pub fn largest_share(&self, other: &ScatteredLightMap) -> f64 {
        let n = self.channels;
        let mut floor = vec![0.0f32; n];
        for v in self.values.chunks(n) {
            for (f, v) in floor.iter_mut().zip(v) {
                *f = f.max(*v);
            }
        }
        floor.iter_mut().for_each(|f| *f *= 1e-3);
        self.values
            .par_chunks(n)
            .zip(other.values.par_chunks(n))
            .map(|(a, b)| {
                a.iter()
                    .zip(b)
                    .zip(&floor)
                    .map(|((a, b), f)| (b / (a + b).max(*f).max(f32::MIN_POSITIVE)) as f64)
                    .fold(0.0, f64::max)
            })
            .reduce(|| 0.0, f64::max)
    }

    /// The light of all the orders after `self`, estimated as a geometric series from
    /// `self` and the order before it, `previous`: where each order is a fixed
    /// fraction `q` of the one before (as they become once the light has forgotten the
    /// sun's direction), the rest is `self q / (1 - q)`. `q` is taken per entry, at
    /// most 0.9.
    pub fn geometric_tail(
        &self,
        previous: &ScatteredLightMap,
        rules: &[SymmetricSphereRule],
        atmosphere: &Atmosphere,
    ) -> Self {
        let values = self
            .values
            .par_iter()
            .zip(&previous.values)
            .map(|(&v, &p)| {
                let q = if p > 0.0 {
                    (v / p).clamp(0.0, 0.9)
                } else {
                    0.0
                };
                v * q / (1.0 - q)
            })
            .collect();
        Self::from_values(rules, atmosphere, values, self.bins, self.scatters)
    }

    /// Frees the per-direction radiance once no further order is built from it.
    pub fn drop_values(&mut self) {
        self.values = Vec::new();
    }

    /// `integral of phase(omega . d) I_t(omega) d omega` over the sphere, sky (11), per
    /// channel, for species `k` with phase `phase`, at shell `shell` with the sun at
    /// `mu_s`, toward the local direction `d` (the direction the light leaves in,
    /// reversed). For the Rayleigh phase, which is `a + b (omega . d)^2`, the sum over
    /// the directions is exactly a sum of five moments; other phases read the table.
    pub fn inscatter(
        &self,
        k: usize,
        phase: &PhaseFunction,
        shell: usize,
        mu_s: f64,
        d: DVec3,
        out: &mut [Lane],
    ) {
        let l = out.len();
        let (b, f) = self.bins.lerp(mu_s);
        let Some(table) = &self.tables[k] else {
            debug_assert!(phase.is_rayleigh());
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
        };
        // Trilinear in the sun bin, the zenith cosine and the azimuth of `d`.
        let x = (d.z + 1.0).clamp(0.0, 2.0) * 0.5 * (TABLE_MU - 1) as f64;
        let i = (x as usize).min(TABLE_MU - 2);
        let fx = (x - i as f64) as f32;
        let y = d.y.atan2(d.x).clamp(0.0, std::f64::consts::PI) / std::f64::consts::PI
            * (TABLE_PHI - 1) as f64;
        let j = (y as usize).min(TABLE_PHI - 2);
        let fy = (y - j as f64) as f32;
        let shells = self.shells;
        out.fill(Lane::ZERO);
        for (g, w) in [
            (i * TABLE_PHI + j, (1.0 - fx) * (1.0 - fy)),
            (i * TABLE_PHI + j + 1, (1.0 - fx) * fy),
            ((i + 1) * TABLE_PHI + j, fx * (1.0 - fy)),
            ((i + 1) * TABLE_PHI + j + 1, fx * fy),
        ] {
            let at = ((b * shells + shell) * TABLE_CELLS + g) * l;
            let next = at + shells * TABLE_CELLS * l;
            let (v0, v1) = (&table[at..at + l], &table[next..next + l]);
            for ((o, a), b) in out.iter_mut().zip(v0).zip(v1) {
                *o += (*a + (*b - *a) * f) * w;
            }
        }
    }

    /// Irradiance per channel on the ground from this light with the sun at `mu_s`
    /// there, packed.
    pub fn ground_irradiance(&self, mu_s: f64, out: &mut [Lane]) {
        let n = self.channels;
        let (b, f) = self.bins.lerp(mu_s);
        let (e0, e1) = self.ground_irradiance[b * n..(b + 2) * n].split_at(n);
        let mut e = [0.0f32; MAX_CHANNELS];
        for ((e, a), b) in e.iter_mut().zip(e0).zip(e1) {
            *e = a + (b - a) * f;
        }
        pack(&e[..n], out);
    }
}

/// The in-scattering tables of `phase` for every shell from the radiance `values`
/// (`[shell][bin][direction][channel]`): per shell a product of the phase matrix
/// (cell x direction, each direction paired with its mirror image) and the radiance,
/// laid out `[bin][shell][cell][lane]`.
fn phase_tables(
    rules: &[SymmetricSphereRule],
    values: &[f32],
    bins: usize,
    n: usize,
    phase: &PhaseFunction,
) -> Vec<Lane> {
    let nd = rules[0].directions.len();
    let row = bins * n;
    let mut out = vec![0.0f32; rules.len() * TABLE_CELLS * row];
    out.par_chunks_mut(TABLE_CELLS * row)
        .zip(values.par_chunks(nd * row))
        .zip(rules.par_iter())
        .for_each(|((out, values), rule)| {
            // The radiance by direction, all bins and channels of one in a row.
            let mut by_direction = vec![0.0f32; nd * row];
            for b in 0..bins {
                for i in 0..nd {
                    by_direction[i * row + b * n..i * row + (b + 1) * n]
                        .copy_from_slice(&values[(b * nd + i) * n..(b * nd + i + 1) * n]);
                }
            }
            for (g, cell) in out.chunks_mut(row).enumerate() {
                let d = table_direction(g);
                for ((w, weight), light) in rule
                    .directions
                    .iter()
                    .zip(&rule.weights)
                    .zip(by_direction.chunks(row))
                {
                    let mirrored = DVec3::new(w.x, -w.y, w.z);
                    let p = (0.5 * weight * (phase.eval(w.dot(d)) + phase.eval(mirrored.dot(d))))
                        as f32;
                    for (o, v) in cell.iter_mut().zip(light) {
                        *o += p * v;
                    }
                }
            }
        });
    let l = lanes(n);
    let shells = rules.len();
    let mut packed = vec![Lane::ZERO; out.len() / n * l];
    for (k, values) in out.chunks(n).enumerate() {
        let (shell, g, b) = (k / (TABLE_CELLS * bins), k / bins % TABLE_CELLS, k % bins);
        let at = ((b * shells + shell) * TABLE_CELLS + g) * l;
        pack(values, &mut packed[at..at + l]);
    }
    packed
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
        let shells = SamplingShells::new(&a, 40, &[1000.0]);
        let map = LightMap::new(&a, table.clone(), &shells);
        let n = a.channels();
        let (mut lanes_out, mut want) = (vec![Lane::ZERO; lanes(n)], vec![0.0; n]);
        for j in [0, 5, shells.index_of(&a, 1000.0).unwrap(), 39] {
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
