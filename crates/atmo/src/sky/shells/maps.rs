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
//! The quadrature weight of a crossing comes from integrating, over the intervals on
//! either side of it, the exact density x attenuation times a linear "hat" (the light
//! is interpolated linearly between crossings). A plain trapezoid rule would be 6 %
//! off on a horizontal ray near the ground, where the blue light is extinguished within
//! one 20 km interval, and 1 % off where the densest air lies between two crossings.

use glam::DVec3;
use rayon::prelude::*;

use super::light_map::{LightMap, ScatteredLightMap};
use super::sampling_shells::SamplingShells;
use crate::atmosphere::geometry::radius_at;
use crate::atmosphere::optical_depth::column_densities;
use crate::atmosphere::{Atmosphere, CONSTITUENTS};
use crate::quadrature::gauss_legendre;

/// Most wavelengths a spectrum may have (validated in `Atmosphere`); sizes stack buffers.
pub const MAX_CHANNELS: usize = 64;

/// Lanes of the longest spectrum.
pub const MAX_LANES: usize = MAX_CHANNELS / 4;

pub use crate::lanes::{lanes, pack, unpack_add, Lane};

/// A sample's scattering weight below which its higher orders are not evaluated.
const NEGLIGIBLE_WEIGHT: f32 = 1e-8;

/// Marks closer than this to a crossing are put on it, m.
const MARK_SNAP_M: f64 = 1e-3;

/// One ray to build maps for: from shell `origin` with zenith cosine `mu`, intervals
/// split at `max_interval_m`, marks at the distances `marks` (the ray then ends at the
/// last one).
#[derive(Clone, Copy)]
struct RaySpec<'a> {
    origin: usize,
    mu: f64,
    max_interval_m: f64,
    marks: &'a [f64],
}

/// Gauss-Legendre segments (of 4 nodes) per interval between crossings.
const INTERVAL_SEGMENTS: usize = 2;

/// The sun-independent maps (density x attenuation x quadrature weight) of a bundle of
/// rays, each starting on a shell.
#[derive(Debug, Clone)]
pub struct ScatteringMaps {
    channels: usize,
    /// Sample range of each ray: `ray_start[i]..ray_start[i + 1]`.
    pub(crate) ray_start: Vec<u32>,
    /// Radius (m) of each ray's origin.
    pub(crate) origin_r: Vec<f64>,
    /// Shell of each sample: the one it lies on, or the one just below it.
    pub(crate) shell: Vec<u16>,
    /// 0 for a sample on its shell; otherwise its fractional position in radius
    /// between `shell` and the next shell up (a sub-sample of a long interval).
    pub(crate) between: Vec<f32>,
    /// Radius (m) of each sample.
    pub(crate) radius: Vec<f64>,
    /// Distance (m) of each sample from its ray's origin.
    pub(crate) distance: Vec<f64>,
    /// Zenith cosine of the ray's direction at each sample.
    pub(crate) mu: Vec<f64>,
    /// `[sample][lane]`: Rayleigh scattering coefficient x density map x attenuation
    /// map x quadrature weight (m^-1 x m = dimensionless), packed.
    pub(crate) rayleigh: Vec<Lane>,
    /// The same for aerosols.
    pub(crate) mie: Vec<Lane>,
    /// `[ray][channel]`: ground albedo / pi x attenuation to the ground; zero for rays
    /// that do not end on the ground or over a black one.
    pub(crate) ground: Vec<f32>,
    /// Distance to the ground (m) of each ray, or a negative value.
    pub(crate) ground_distance: Vec<f64>,
    /// Marks of each ray (aerial perspective: points at given distances where the
    /// light gathered so far is read): `mark_start[i]..mark_start[i + 1]`.
    pub(crate) mark_start: Vec<u32>,
    /// Per mark: the sample it is at (a ray's last one for marks beyond its end).
    pub(crate) mark_sample: Vec<u32>,
    /// Per mark, `[2][lane]`: the part of its sample's Rayleigh and aerosol weights
    /// that comes from the interval before it (the rest lies beyond the mark).
    pub(crate) mark_left: Vec<Lane>,
    /// Per mark, `[channel]`: transmittance from the ray's origin to it.
    pub(crate) mark_transmittance: Vec<f32>,
}

/// Where the sun is, seen from a ray's origin, and the ray's angle to it.
#[derive(Debug, Clone, Copy)]
pub struct SunGeometry {
    /// Cosine of the sun's zenith angle at the ray's origin.
    pub mu_s: f64,
    /// Cosine of the angle between the ray and the direction to the sun.
    pub nu: f64,
}

/// Which parts of the light to sum: single scattering of sunlight (with the sunlit
/// ground), and the light of the higher orders (scattered light scattered again, and
/// skylight reflected by the ground).
#[derive(Debug, Clone, Copy)]
pub struct Orders {
    /// Order 1.
    pub single: bool,
    /// The orders above 1 that [`Sources::higher`] holds the light for.
    pub multiple: bool,
}

/// What lights the points on the shells: the sun through the light map, and the
/// scattered light of the orders below through a scattered light map.
pub struct Sources<'a> {
    pub atmosphere: &'a Atmosphere,
    pub shells: &'a SamplingShells,
    pub sunlight: &'a LightMap,
    /// The scattered light (of one order or the sum of several) whose scattering gives
    /// the higher orders, with the species that scatter it.
    pub higher: Option<&'a ScatteredLightMap>,
}

impl ScatteringMaps {
    /// Maps for rays given as (origin shell, zenith cosine), computed in parallel; the
    /// result does not depend on the thread count. Intervals between crossings longer
    /// than `max_interval_m` are split evenly by sub-samples.
    pub fn new(
        atmosphere: &Atmosphere,
        shells: &SamplingShells,
        rays: &[(usize, f64)],
        max_interval_m: f64,
    ) -> Self {
        Self::with_marks(atmosphere, shells, rays, max_interval_m, &[])
    }

    /// Maps as [`ScatteringMaps::new`] with, on every ray, a mark at each of the
    /// distances `marks` (m, increasing): [`ScatteringMaps::radiance_at_marks`] reads
    /// the light gathered between the origin and each.
    pub fn with_marks(
        atmosphere: &Atmosphere,
        shells: &SamplingShells,
        rays: &[(usize, f64)],
        max_interval_m: f64,
        marks: &[f64],
    ) -> Self {
        let per_ray: Vec<ScatteringMaps> = rays
            .par_iter()
            .map_init(Vec::new, |crossings, &(origin, mu)| {
                let ray = RaySpec {
                    origin,
                    mu,
                    max_interval_m,
                    marks,
                };
                Self::ray_maps(atmosphere, shells, ray, crossings)
            })
            .collect();
        let mut maps = ScatteringMaps::empty(atmosphere.channels());
        for ray in per_ray {
            maps.append(ray);
        }
        maps
    }

    fn empty(channels: usize) -> Self {
        ScatteringMaps {
            channels,
            ray_start: vec![0],
            origin_r: Vec::new(),
            shell: Vec::new(),
            between: Vec::new(),
            radius: Vec::new(),
            distance: Vec::new(),
            mu: Vec::new(),
            rayleigh: Vec::new(),
            mie: Vec::new(),
            ground: Vec::new(),
            ground_distance: Vec::new(),
            mark_start: vec![0],
            mark_sample: Vec::new(),
            mark_left: Vec::new(),
            mark_transmittance: Vec::new(),
        }
    }

    /// Appends the rays of `other` after these.
    fn append(&mut self, mut other: ScatteringMaps) {
        let offset = self.shell.len() as u32;
        self.ray_start
            .extend(other.ray_start[1..].iter().map(|s| s + offset));
        self.origin_r.append(&mut other.origin_r);
        self.shell.append(&mut other.shell);
        self.between.append(&mut other.between);
        self.radius.append(&mut other.radius);
        self.distance.append(&mut other.distance);
        self.mu.append(&mut other.mu);
        self.rayleigh.append(&mut other.rayleigh);
        self.mie.append(&mut other.mie);
        self.ground.append(&mut other.ground);
        self.ground_distance.append(&mut other.ground_distance);
        let marks = self.mark_sample.len() as u32;
        self.mark_start
            .extend(other.mark_start[1..].iter().map(|m| m + marks));
        self.mark_sample
            .extend(other.mark_sample.iter().map(|s| s + offset));
        self.mark_left.append(&mut other.mark_left);
        self.mark_transmittance
            .append(&mut other.mark_transmittance);
    }

    /// The maps of one ray.
    fn ray_maps(
        atmosphere: &Atmosphere,
        shells: &SamplingShells,
        ray: RaySpec,
        crossings: &mut Vec<(u16, f64)>,
    ) -> ScatteringMaps {
        let (origin, mu0) = (ray.origin, ray.mu);
        let n = atmosphere.channels();
        let mut on_ground = shells.crossings(origin, mu0, crossings);
        // A marked ray ends at its last mark: nothing beyond it is read.
        let end = ray.marks.last().copied().unwrap_or(f64::INFINITY);
        let radii = shells.radii();
        let r0 = radii[origin];
        let mut maps = ScatteringMaps::empty(n);
        maps.origin_r.push(r0);
        maps.ground = vec![0.0; n];
        maps.ground_distance.push(-1.0);
        let mut push = |shell: u16, between: f32, r: f64, t: f64| -> usize {
            maps.shell.push(shell);
            maps.between.push(between);
            maps.radius.push(r);
            maps.distance.push(t);
            maps.mu.push(((r0 * mu0 + t) / r).clamp(-1.0, 1.0));
            maps.shell.len() - 1
        };
        // The sample each mark lands on.
        let mut mark_samples = vec![usize::MAX; ray.marks.len()];
        let mut inside = Vec::new();
        for (k, &(j, t)) in crossings.iter().enumerate() {
            if k > 0 {
                // Sub-samples of a long interval and marks inside it, between the shells
                // that bracket them.
                let t_prev = crossings[k - 1].1;
                let parts = ((t - t_prev) / ray.max_interval_m).ceil() as usize;
                inside.clear();
                inside.extend(
                    (1..parts).map(|q| (t_prev + (t - t_prev) * q as f64 / parts as f64, None)),
                );
                for (m, &d) in ray.marks.iter().enumerate() {
                    if d > t_prev + MARK_SNAP_M && d < t - MARK_SNAP_M {
                        inside.push((d, Some(m)));
                    }
                }
                inside.sort_by(|a, b| a.0.total_cmp(&b.0));
                for &(tq, mark) in &inside {
                    if tq > end {
                        break;
                    }
                    let r = radius_at(r0, mu0, tq).clamp(radii[0], radii[radii.len() - 1]);
                    let below = (radii.partition_point(|&x| x <= r) - 1).min(radii.len() - 2);
                    let f = (r - radii[below]) / (radii[below + 1] - radii[below]);
                    let at = push(below as u16, f.max(1e-6) as f32, r, tq);
                    if let Some(m) = mark {
                        mark_samples[m] = at;
                    }
                }
            }
            if t > end + MARK_SNAP_M {
                on_ground = false;
                break;
            }
            push(j, 0.0, radii[j as usize], t);
        }
        // Marks on a crossing, before the origin or beyond the ray's end: the sample
        // nearest them.
        let last = maps.distance.len() - 1;
        for (m, &d) in ray.marks.iter().enumerate() {
            if mark_samples[m] == usize::MAX {
                mark_samples[m] = if d >= maps.distance[last] {
                    last
                } else {
                    (0..=last)
                        .min_by(|&a, &b| {
                            (maps.distance[a] - d)
                                .abs()
                                .total_cmp(&(maps.distance[b] - d).abs())
                        })
                        .unwrap_or(0)
                };
            }
        }
        let m = maps.shell.len();
        maps.ray_start.push(m as u32);
        let (mut rayleigh, mut mie) = (vec![0.0f32; m * n], vec![0.0f32; m * n]);
        // With marks: the part of each weight from the interval before its sample, and
        // the transmittance from the origin to each sample.
        let marked = !ray.marks.is_empty();
        let (mut left, mut transmittance) = if marked {
            (vec![0.0f32; 2 * m * n], vec![1.0f32; m * n])
        } else {
            (Vec::new(), Vec::new())
        };
        // Quadrature weights folded with the density and attenuation maps: over each
        // interval between crossings the light (light map x phase map) is taken as
        // linear, and density x attenuation is integrated exactly, which also covers
        // the densest point of a ray that dips between two crossings of one shell.
        let mut columns = [0.0f64; CONSTITUENTS];
        for i in 1..m {
            let (ta, tb) = (maps.distance[i - 1], maps.distance[i]);
            let dt = tb - ta;
            gauss_legendre(ta, tb, INTERVAL_SEGMENTS, |t, w| {
                let to_node = column_densities(atmosphere, r0, mu0, ta, t - ta, 1);
                let total: [f64; CONSTITUENTS] = std::array::from_fn(|k| columns[k] + to_node[k]);
                let h = atmosphere.altitude(radius_at(r0, mu0, t));
                let u = (t - ta) / dt;
                let (rho_r, rho_m) = (atmosphere.rayleigh.density(h), atmosphere.mie.density(h));
                for c in 0..n {
                    let e = w * (-atmosphere.optical_depth(&total, c)).exp();
                    let (r, m) = (
                        e * rho_r * atmosphere.rayleigh.scattering_per_m[c],
                        e * rho_m * atmosphere.mie.scattering_per_m[c],
                    );
                    rayleigh[(i - 1) * n + c] += ((1.0 - u) * r) as f32;
                    rayleigh[i * n + c] += (u * r) as f32;
                    mie[(i - 1) * n + c] += ((1.0 - u) * m) as f32;
                    mie[i * n + c] += (u * m) as f32;
                    if marked {
                        left[(2 * i) * n + c] += (u * r) as f32;
                        left[(2 * i + 1) * n + c] += (u * m) as f32;
                    }
                }
            });
            let step = column_densities(atmosphere, r0, mu0, ta, dt, INTERVAL_SEGMENTS);
            for k in 0..CONSTITUENTS {
                columns[k] += step[k];
            }
            if marked {
                for c in 0..n {
                    transmittance[i * n + c] =
                        (-atmosphere.optical_depth(&columns, c)).exp() as f32;
                }
            }
        }
        let l = lanes(n);
        for (flat, packed) in [(&rayleigh, &mut maps.rayleigh), (&mie, &mut maps.mie)] {
            *packed = vec![Lane::ZERO; m * l];
            for (values, out) in flat.chunks(n).zip(packed.chunks_mut(l)) {
                pack(values, out);
            }
        }
        maps.mark_start.push(mark_samples.len() as u32);
        for &at in &mark_samples {
            maps.mark_sample.push(at as u32);
            let mut lanes_of = [Lane::ZERO; 2 * MAX_LANES];
            for (k, out) in lanes_of.chunks_mut(l).take(2).enumerate() {
                pack(&left[(2 * at + k) * n..(2 * at + k + 1) * n], out);
            }
            maps.mark_left.extend_from_slice(&lanes_of[..2 * l]);
            maps.mark_transmittance
                .extend_from_slice(&transmittance[at * n..(at + 1) * n]);
        }
        if on_ground {
            maps.ground_distance[0] = maps.distance[m - 1];
            for (c, g) in maps.ground.iter_mut().enumerate() {
                let tau = atmosphere.optical_depth(&columns, c);
                *g = (atmosphere.ground_albedo / std::f64::consts::PI * (-tau).exp()) as f32;
            }
        }
        maps
    }

    /// Total number of samples (shell crossings and sub-samples) over all rays.
    pub fn samples(&self) -> usize {
        self.shell.len()
    }

    /// Radiance per channel arriving at ray `ray`'s origin from along the ray, of the
    /// scattering orders `orders`, sky (3) summed over the crossings, and the ground's
    /// reflected light at its end; added to `out`.
    pub fn radiance(
        &self,
        ray: usize,
        sun: SunGeometry,
        sources: &Sources,
        orders: Orders,
        out: &mut [f32],
    ) {
        let l = lanes(self.channels);
        let mut total = [Lane::ZERO; MAX_LANES];
        let total = &mut total[..l];
        self.sources_along(ray, sun, sources, orders, |s, source_r, source_m| {
            self.add_weighted(s, source_r, source_m, total);
        });
        self.ground_light(ray, sun, sources, orders, total);
        unpack_add(total, out);
    }

    /// The aerial perspective of ray `ray` at each of its marks: the radiance scattered
    /// toward the origin from between it and the mark (`inscatter`, `[mark][channel]`),
    /// and the transmittance from the origin to the mark (`transmittance`, the same
    /// layout); both overwritten. A mark beyond the ray's end (the ground or space)
    /// reads the whole ray without the ground's light.
    pub fn radiance_at_marks(
        &self,
        ray: usize,
        sun: SunGeometry,
        sources: &Sources,
        orders: Orders,
        inscatter: &mut [f32],
        transmittance: &mut [f32],
    ) {
        let (n, l) = (self.channels, lanes(self.channels));
        let marks = self.mark_start[ray] as usize..self.mark_start[ray + 1] as usize;
        inscatter.fill(0.0);
        let mut total = [Lane::ZERO; MAX_LANES];
        let total = &mut total[..l];
        let mut next = marks.start;
        self.sources_along(ray, sun, sources, orders, |s, source_r, source_m| {
            // Marks at this sample read the light so far plus its interval before it.
            while next < marks.end && self.mark_sample[next] as usize == s {
                let left = &self.mark_left[2 * next * l..2 * (next + 1) * l];
                let mut at = [Lane::ZERO; MAX_LANES];
                for (k, a) in at[..l].iter_mut().enumerate() {
                    *a = total[k] + left[k] * source_r[k] + left[l + k] * source_m[k];
                }
                let k = next - marks.start;
                unpack_add(&at[..l], &mut inscatter[k * n..(k + 1) * n]);
                next += 1;
            }
            self.add_weighted(s, source_r, source_m, total);
        });
        transmittance.copy_from_slice(&self.mark_transmittance[marks.start * n..marks.end * n]);
    }

    /// Adds sample `s`'s weights times the light its species scatter there to `total`.
    #[inline]
    fn add_weighted(&self, s: usize, source_r: &[Lane], source_m: &[Lane], total: &mut [Lane]) {
        let l = total.len();
        let (w_r, w_m) = (
            &self.rayleigh[s * l..(s + 1) * l],
            &self.mie[s * l..(s + 1) * l],
        );
        for ((t, (w_r, w_m)), (r, m)) in total
            .iter_mut()
            .zip(w_r.iter().zip(w_m))
            .zip(source_r.iter().zip(source_m))
        {
            *t += *w_r * *r + *w_m * *m;
        }
    }

    /// Calls `visit(sample, rayleigh, aerosols)` for each sample of ray `ray` in order
    /// with the light each species scatters toward the origin there per unit weight
    /// (packed): sunlight x phase (the light and phase maps, sky (6)-(8)) for order 1,
    /// and the scattered light of the orders below scattered again, sky (10)-(11).
    fn sources_along(
        &self,
        ray: usize,
        sun: SunGeometry,
        sources: &Sources,
        orders: Orders,
        mut visit: impl FnMut(usize, &[Lane], &[Lane]),
    ) {
        let l = lanes(self.channels);
        let atmosphere = sources.atmosphere;
        let r0_mu_s = self.origin_r[ray] * sun.mu_s;
        let nu = sun.nu;
        // The phase maps, sky (7)-(8): one value per ray, the sun being at infinity.
        let phase_r = atmosphere.rayleigh.phase.eval(nu) as f32;
        let phase_m = atmosphere.mie.phase.eval(nu) as f32;
        let mut scratch = [[Lane::ZERO; MAX_LANES]; 4];
        let [light, upper, source_r, source_m] = &mut scratch;
        let (light, upper) = (&mut light[..l], &mut upper[..l]);
        let (source_r, source_m) = (&mut source_r[..l], &mut source_m[..l]);
        let higher = sources.higher.filter(|_| orders.multiple);
        let range = self.ray_start[ray] as usize..self.ray_start[ray + 1] as usize;
        for s in range {
            let (j, between, r) = (self.shell[s] as usize, self.between[s], self.radius[s]);
            let mu_s = ((r0_mu_s + self.distance[s] * nu) / r).clamp(-1.0, 1.0);
            source_r.fill(Lane::ZERO);
            source_m.fill(Lane::ZERO);
            if orders.single {
                // The light map, sky (6): sunlight reaching the sample.
                if between == 0.0 {
                    sources.sunlight.sample(j, mu_s, light);
                } else {
                    sources.sunlight.sample_at(r, mu_s, light);
                }
                for ((r, m), li) in source_r.iter_mut().zip(source_m.iter_mut()).zip(&*light) {
                    *r = *li * phase_r;
                    *m = *li * phase_m;
                }
            }
            if let Some(map) = higher {
                // Scattered light arriving from every direction, scattered again toward
                // the ray, interpolated in radius between two shells.
                let d = local_direction(self.mu[s], mu_s, nu);
                let species = [
                    (
                        &atmosphere.rayleigh.phase,
                        &self.rayleigh[s * l..(s + 1) * l],
                        &mut *source_r,
                    ),
                    (
                        &atmosphere.mie.phase,
                        &self.mie[s * l..(s + 1) * l],
                        &mut *source_m,
                    ),
                ];
                for (k, (phase, weights, source)) in species.into_iter().enumerate() {
                    // Above about 16 km the aerosols' weight is below 1e-8 (a hundred
                    // thousandth of the molecules'): skipping it changes nothing visible
                    // and halves the cost of the aerosols' higher orders.
                    if !map.scatters[k]
                        || weights.iter().all(|w| w.max_element() < NEGLIGIBLE_WEIGHT)
                    {
                        continue;
                    }
                    map.inscatter(k, phase, j, mu_s, d, light);
                    if between > 0.0 {
                        map.inscatter(k, phase, j + 1, mu_s, d, upper);
                        for (li, u) in light.iter_mut().zip(&*upper) {
                            *li += (*u - *li) * between;
                        }
                    }
                    for (o, li) in source.iter_mut().zip(&*light) {
                        *o += *li;
                    }
                }
            }
            visit(s, source_r, source_m);
        }
    }

    /// Adds to `total` the light a Lambertian ground at the end of ray `ray` reflects
    /// toward its origin: the sunlight (order 1) and the scattered light coming down on
    /// it (the higher orders), times the attenuation to it.
    fn ground_light(
        &self,
        ray: usize,
        sun: SunGeometry,
        sources: &Sources,
        orders: Orders,
        total: &mut [Lane],
    ) {
        let (n, l) = (self.channels, lanes(self.channels));
        let t_ground = self.ground_distance[ray];
        if t_ground < 0.0 || sources.atmosphere.ground_albedo <= 0.0 {
            return;
        }
        let r0_mu_s = self.origin_r[ray] * sun.mu_s;
        let mu_s = ((r0_mu_s + t_ground * sun.nu) / sources.shells.radii()[0]).clamp(-1.0, 1.0);
        let mut light = [Lane::ZERO; MAX_LANES];
        let light = &mut light[..l];
        let mut irradiance = [Lane::ZERO; MAX_LANES];
        let irradiance = &mut irradiance[..l];
        if orders.single && mu_s > 0.0 {
            sources.sunlight.sample(0, mu_s, light);
            for (e, li) in irradiance.iter_mut().zip(&*light) {
                *e += *li * mu_s as f32;
            }
        }
        if let Some(map) = sources.higher.filter(|_| orders.multiple) {
            map.ground_irradiance(mu_s, light);
            for (e, li) in irradiance.iter_mut().zip(&*light) {
                *e += *li;
            }
        }
        let mut g = [Lane::ZERO; MAX_LANES];
        pack(&self.ground[ray * n..(ray + 1) * n], &mut g[..l]);
        for ((t, e), g) in total.iter_mut().zip(&*irradiance).zip(&g) {
            *t += *e * *g;
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
    fn local_direction_keeps_the_angles() {
        let d = local_direction(0.3, 0.5, 0.2);
        let s = DVec3::new((1.0f64 - 0.25).sqrt(), 0.0, 0.5);
        assert!((d.length() - 1.0).abs() < 1e-12);
        assert!((d.z - 0.3).abs() < 1e-12 && (d.dot(s) - 0.2).abs() < 1e-12);
    }
}
