//! References for the clouds: the exact transmittance of a particle field; the paper's
//! own way of filling the intensity buffer (clouds 4.1), slice by slice with shadow
//! polygons, which the prefix-sum fill of [`crate::clouds::buffer`] must equal; and the
//! light the particles' Gaussian density scatters toward a camera, single scattering by
//! quadrature and every order by a volumetric path tracer ([`ReferenceCloud`]), which
//! the billboards are held to.

use glam::{DVec3, Vec3};
use rayon::prelude::*;

use crate::atmosphere::PhaseFunction;
use crate::clouds::buffer::{IntensityBuffer, FOOTPRINT};
use crate::clouds::generator::SplitMix64;
use crate::clouds::particles::{Line, Particle};
use crate::reference::sampling::{mean_and_error, sample_cosine, PhaseSampler};
use crate::view::Camera;

/// The fraction of sunlight arriving at `point` through `particles` with nothing
/// scattered into its path: `exp(-tau)`, `tau` the optical depth from the sun (along
/// `-to_sun`) to the point, summed exactly particle by particle.
pub fn transmittance(particles: &[Particle], to_sun: Vec3, point: Vec3) -> f64 {
    let light = -to_sun.normalize();
    let tau: f64 = particles
        .iter()
        .map(|p| {
            let d = point - p.position;
            let along = d.dot(light);
            let b = (d - along * light).length();
            p.column(b as f64, f64::NEG_INFINITY, along as f64)
        })
        .sum();
    (-tau).exp()
}

/// `Gamma` at the centres of `grid`'s voxels as the paper computes it: for each
/// particle, each slice perpendicular to `z` within its footprint gets a rectangle
/// covering the footprint's width and everything from its sun-side edge on, filled with its
/// factor `G = a tau p(l,l)/4pi + T` at each voxel's distance from the particle's axis,
/// and the rectangles are multiplied in. `[x][z][y]` like [`IntensityBuffer::log_gamma`].
pub fn shadow_polygons(grid: &IntensityBuffer, particles: &[Particle], forward: f32) -> Vec<f32> {
    let n = grid.resolution;
    let mut gamma = vec![1.0f64; n * n * n];
    let centre = |axis: usize, i: usize| grid.min[axis] + (i as f32 + 0.5) * grid.voxel[axis];
    for p in particles {
        let c = grid.buffer_from_world * p.position;
        let reach = FOOTPRINT * p.sigma();
        for iz in 0..n {
            let dz = centre(2, iz) - c.z;
            if dz.abs() > reach {
                continue;
            }
            for ix in 0..n {
                let dx = centre(0, ix) - c.x;
                if dx.abs() > reach {
                    continue;
                }
                let b = ((dx * dx + dz * dz) as f64).sqrt();
                let tau = p.column(b, f64::NEG_INFINITY, f64::INFINITY);
                let g = (-tau).exp() + p.albedo as f64 * forward as f64 * tau;
                for iy in 0..n {
                    if centre(1, iy) >= c.y - p.radius {
                        gamma[(ix * n + iz) * n + iy] *= g;
                    }
                }
            }
        }
    }
    gamma.into_iter().map(|g| g as f32).collect()
}

/// Standard deviations from its centre beyond which a particle is left out of a ray:
/// the column there is `exp(-12.5)`, 4e-6 of the axis's. (The fast method's footprints
/// stop sooner; this is the Gaussian the particles describe.)
const REACH: f64 = 5.0;

/// The particles indexed for rays: a uniform grid whose cells list the particles that
/// reach into them, walked cell by cell along a ray (Amanatides and Woo), so that a ray
/// meets only the particles near it. Everything in f64.
pub struct CloudVolume<'a> {
    particles: &'a [Particle],
    /// The grid's smallest corner, m, and its cells' side, m.
    min: DVec3,
    cell: f64,
    dims: [usize; 3],
    /// The particles of cell `c` are `entries[starts[c]..starts[c + 1]]`.
    starts: Vec<u32>,
    entries: Vec<u32>,
}

/// A particle a ray passes: where along the ray it comes closest to the centre (m), its
/// Gaussian along the ray from there, and that line's `erf` at the ray's origin (the
/// depth from the origin to any `t` then costs one `erf`: [`RayThrough::depth_to`]).
#[derive(Debug, Clone, Copy)]
struct Crossing {
    particle: u32,
    closest: f64,
    line: Line,
    at_origin: f64,
}

/// The particles along one ray from its origin, and the exact optical depth and
/// extinction on it.
pub struct RayThrough<'a> {
    particles: &'a [Particle],
    crossings: Vec<Crossing>,
}

impl<'a> CloudVolume<'a> {
    /// Indexes `particles` (not empty).
    pub fn new(particles: &'a [Particle]) -> CloudVolume<'a> {
        let reach = |p: &Particle| REACH * p.sigma() as f64;
        let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
        for p in particles {
            let c = p.position.as_dvec3();
            lo = lo.min(c - reach(p));
            hi = hi.max(c + reach(p));
        }
        // Cells about as wide as a typical particle's reach, at most 128 a side.
        let mut reaches: Vec<f64> = particles.iter().map(reach).collect();
        reaches.sort_by(f64::total_cmp);
        let extent = hi - lo;
        let cell = reaches[reaches.len() / 2].max(extent.max_element() / 128.0);
        let dims = [0, 1, 2].map(|a| ((extent[a] / cell).ceil() as usize).max(1));
        let index = |a: usize, v: f64| (((v - lo[a]) / cell) as usize).min(dims[a] - 1);
        let mut lists: Vec<Vec<u32>> = vec![Vec::new(); dims[0] * dims[1] * dims[2]];
        for (k, p) in particles.iter().enumerate() {
            let c = p.position.as_dvec3();
            let (a, b) = (c - reach(p), c + reach(p));
            for x in index(0, a.x)..=index(0, b.x) {
                for y in index(1, a.y)..=index(1, b.y) {
                    for z in index(2, a.z)..=index(2, b.z) {
                        lists[(x * dims[1] + y) * dims[2] + z].push(k as u32);
                    }
                }
            }
        }
        let mut starts = Vec::with_capacity(lists.len() + 1);
        let mut entries = Vec::new();
        for list in lists {
            starts.push(entries.len() as u32);
            entries.extend(list);
        }
        starts.push(entries.len() as u32);
        CloudVolume {
            particles,
            min: lo,
            cell,
            dims,
            starts,
            entries,
        }
    }

    /// The particles along the ray from `origin` in the unit direction `dir`, each once
    /// however many of the ray's cells it reaches into, in the order the ray first meets
    /// their cells.
    pub fn ray(&self, origin: DVec3, dir: DVec3) -> RayThrough<'a> {
        let mut crossings = Vec::new();
        MAILBOXES.with_borrow_mut(|mailboxes| {
            let ray = mailboxes.next_ray(self.particles.len());
            self.walk(origin, dir, |c| {
                for &k in &self.entries[self.starts[c] as usize..self.starts[c + 1] as usize] {
                    if std::mem::replace(&mut mailboxes.last[k as usize], ray) == ray {
                        continue;
                    }
                    let p = &self.particles[k as usize];
                    let d = p.position.as_dvec3() - origin;
                    let closest = d.dot(dir);
                    let b2 = (d - closest * dir).length_squared();
                    let r = REACH * p.sigma() as f64;
                    if b2 < r * r && closest + r > 0.0 {
                        let line = p.line(b2);
                        crossings.push(Crossing {
                            particle: k,
                            closest,
                            line,
                            at_origin: line.erf_at(-closest),
                        });
                    }
                }
            });
        });
        RayThrough {
            particles: self.particles,
            crossings,
        }
    }

    /// The fraction of light from the unit direction `toward` reaching `point` with
    /// nothing scattered into its path.
    pub fn transmittance(&self, point: DVec3, toward: DVec3) -> f64 {
        (-self.ray(point, toward).depth_to(f64::INFINITY)).exp()
    }

    /// Calls `visit` with each grid cell the ray crosses (for `t >= 0`), in order.
    fn walk(&self, origin: DVec3, dir: DVec3, mut visit: impl FnMut(usize)) {
        let size = DVec3::new(
            self.dims[0] as f64,
            self.dims[1] as f64,
            self.dims[2] as f64,
        );
        let max = self.min + size * self.cell;
        // Where the ray is inside the grid's box (slabs).
        let (mut enter, mut exit) = (0.0f64, f64::INFINITY);
        for a in 0..3 {
            if dir[a] == 0.0 {
                if origin[a] < self.min[a] || origin[a] > max[a] {
                    return;
                }
                continue;
            }
            let (t0, t1) = (
                (self.min[a] - origin[a]) / dir[a],
                (max[a] - origin[a]) / dir[a],
            );
            enter = enter.max(t0.min(t1));
            exit = exit.min(t0.max(t1));
        }
        if enter > exit {
            return;
        }
        let start = (origin + dir * enter - self.min) / self.cell;
        let mut cell = [0usize; 3];
        let (mut next, mut delta, mut step) = ([f64::INFINITY; 3], [f64::INFINITY; 3], [0i64; 3]);
        for a in 0..3 {
            cell[a] = (start[a].floor().max(0.0) as usize).min(self.dims[a] - 1);
            if dir[a] != 0.0 {
                step[a] = dir[a].signum() as i64;
                delta[a] = self.cell / dir[a].abs();
                let edge = self.min[a] + (cell[a] as f64 + (dir[a] > 0.0) as u8 as f64) * self.cell;
                next[a] = (edge - origin[a]) / dir[a];
            }
        }
        loop {
            visit((cell[0] * self.dims[1] + cell[1]) * self.dims[2] + cell[2]);
            let a = (0..3)
                .min_by(|&i, &j| next[i].total_cmp(&next[j]))
                .unwrap_or(0);
            if next[a] > exit {
                return;
            }
            let moved = cell[a] as i64 + step[a];
            if moved < 0 || moved >= self.dims[a] as i64 {
                return;
            }
            cell[a] = moved as usize;
            next[a] += delta[a];
        }
    }
}

/// Mailboxes (Amanatides and Woo, section 4): for each particle, the last ray of this
/// thread that met it, so that a ray takes a particle listed in several of its cells
/// once without sorting what it met. Sorting and deduplicating took a quarter of the
/// path tracer's time (perf, the fit's 9,382-particle views).
struct Mailboxes {
    /// This thread's last ray, counted from 1 (0: none).
    ray: u32,
    /// Per particle index, the last ray that met it.
    last: Vec<u32>,
}

impl Mailboxes {
    /// A new ray's number, with a box for each of `particles`; every box emptied when
    /// the count wraps.
    fn next_ray(&mut self, particles: usize) -> u32 {
        if self.last.len() < particles {
            self.last.resize(particles, 0);
        }
        self.ray = self.ray.wrapping_add(1);
        if self.ray == 0 {
            self.last.fill(0);
            self.ray = 1;
        }
        self.ray
    }
}

thread_local! {
    static MAILBOXES: std::cell::RefCell<Mailboxes> = const {
        std::cell::RefCell::new(Mailboxes { ray: 0, last: Vec::new() })
    };
}

impl RayThrough<'_> {
    /// Optical depth between `t0 <= t1` m along the ray (infinite allowed).
    pub fn depth(&self, t0: f64, t1: f64) -> f64 {
        self.crossings
            .iter()
            .map(|c| c.line.depth(t0 - c.closest, t1 - c.closest))
            .sum()
    }

    /// Optical depth from the origin to `t >= 0` m along the ray (infinite allowed):
    /// [`RayThrough::depth`]`(0, t)`, one `erf` a crossing.
    pub fn depth_to(&self, t: f64) -> f64 {
        self.crossings
            .iter()
            .map(|c| c.line.half_depth * (c.line.erf_at(t - c.closest) - c.at_origin))
            .sum()
    }

    /// Extinction and scattering coefficients `t` m along the ray, 1/m.
    pub fn extinction(&self, t: f64) -> (f64, f64) {
        self.crossings.iter().fold((0.0, 0.0), |(e, s), c| {
            let v = c.line.extinction(t - c.closest);
            (
                e + v,
                s + v * self.particles[c.particle as usize].albedo as f64,
            )
        })
    }

    /// Where the particles along the ray lie: the first and last `t` (m) within their
    /// reach, or `None` for a ray that meets none.
    pub fn span(&self) -> Option<(f64, f64)> {
        self.crossings.iter().fold(None, |span, c| {
            let r = REACH * self.particles[c.particle as usize].sigma() as f64;
            let (a, b) = ((c.closest - r).max(0.0), c.closest + r);
            Some(span.map_or((a, b), |(lo, hi): (f64, f64)| (lo.min(a), hi.max(b))))
        })
    }

    /// The standard deviation of the smallest particle on the ray, m.
    fn finest(&self) -> f64 {
        self.crossings
            .iter()
            .map(|c| self.particles[c.particle as usize].sigma() as f64)
            .fold(f64::INFINITY, f64::min)
    }

    /// The distance `t` at which the optical depth from the origin reaches `target`, or
    /// `None` if the whole ray holds less: free-flight sampling by inverting the exact
    /// depth (Newton steps kept inside a bisection bracket), with no majorant.
    pub fn free_flight(&self, target: f64) -> Option<f64> {
        let (_, end) = self.span()?;
        if self.depth_to(end) < target {
            return None;
        }
        let (mut lo, mut hi) = (0.0, end);
        let mut t = 0.5 * end;
        for _ in 0..100 {
            let f = self.depth_to(t) - target;
            if f.abs() <= 1e-10 * target.max(1.0) {
                break;
            }
            if f > 0.0 {
                hi = t;
            } else {
                lo = t;
            }
            let (sigma, _) = self.extinction(t);
            let newton = t - f / sigma;
            t = if sigma > 0.0 && newton > lo && newton < hi {
                newton
            } else {
                0.5 * (lo + hi)
            };
            if hi - lo < 1e-9 * end {
                break;
            }
        }
        Some(t)
    }
}

/// How a reference cloud is lit: sunlight of irradiance 1 from `to_sun`, scattered by
/// `phase`, and optionally a sky of uniform radiance over the upper hemisphere (`y` up).
#[derive(Debug, Clone, Copy)]
pub struct ReferenceLight {
    /// Unit vector toward the sun.
    pub to_sun: DVec3,
    pub phase: PhaseFunction,
    /// Radiance of the sky above the horizon (0: none), per unit sun irradiance.
    pub sky: f64,
}

/// The light a cloud scatters toward a camera, integrated without the fast method's
/// buffer or billboards: the single-scattering integral by quadrature, and every order
/// by a volumetric path tracer.
pub struct ReferenceCloud<'a> {
    pub volume: CloudVolume<'a>,
    light: ReferenceLight,
    /// Draws scattering directions from `light.phase` (built once: its rejection bound
    /// takes thousands of evaluations).
    sampler: PhaseSampler,
}

/// What a path tracer is asked for.
#[derive(Debug, Clone, Copy)]
pub struct PathSettings {
    /// Paths per pixel.
    pub paths: usize,
    /// The highest scattering order followed: 1 for single scattering.
    pub orders: usize,
    pub seed: u64,
}

/// Scattering orders a path follows at most with `orders` unbounded (a path in a cloud
/// of optical depth 10 scatters some 20 times on average; this many leave out less than
/// 1e-6 of the light).
pub const MAX_ORDER: usize = 2000;

impl<'a> ReferenceCloud<'a> {
    pub fn new(particles: &'a [Particle], light: ReferenceLight) -> ReferenceCloud<'a> {
        ReferenceCloud {
            volume: CloudVolume::new(particles),
            light,
            sampler: PhaseSampler::new(light.phase),
        }
    }

    /// Single-scattered sunlight reaching `origin` from the unit direction `-dir` (the
    /// ray travels along `dir`), and the ray's transmittance through the cloud:
    /// `integral sigma_s(t) p T_sun(t) T(0, t) dt`, in steps of a quarter of the finest
    /// particle's standard deviation, each step's
    /// `integral sigma T dt = T(t_i) - T(t_i+1)` exact and its albedo, phase and sun
    /// transmittance taken at its middle.
    pub fn single_scattering(&self, origin: DVec3, dir: DVec3) -> (f64, f64) {
        self.single_scattering_with(origin, dir, 4.0)
    }

    /// [`ReferenceCloud::single_scattering`] in steps of `1 / steps_per_sigma` of the
    /// finest particle's standard deviation (to show it converged).
    pub fn single_scattering_with(
        &self,
        origin: DVec3,
        dir: DVec3,
        steps_per_sigma: f64,
    ) -> (f64, f64) {
        let ray = self.volume.ray(origin, dir);
        let Some((a, b)) = ray.span() else {
            return (0.0, 1.0);
        };
        let phase = self.light.phase.eval(self.light.to_sun.dot(dir));
        let steps = ((b - a) / ray.finest() * steps_per_sigma).ceil().max(1.0) as usize;
        let h = (b - a) / steps as f64;
        let mut before = (-ray.depth_to(a)).exp();
        let mut radiance = 0.0;
        for i in 0..steps {
            let t = a + (i as f64 + 0.5) * h;
            let after = before * (-ray.depth(t - 0.5 * h, t + 0.5 * h)).exp();
            let (sigma, scattering) = ray.extinction(t);
            if sigma > 0.0 && before > after {
                let sun = self
                    .volume
                    .transmittance(origin + dir * t, self.light.to_sun);
                radiance += scattering / sigma * phase * sun * (before - after);
            }
            before = after;
        }
        (radiance, before)
    }

    /// Every order of sunlight (and sky light, if any) scattered toward `origin` from
    /// the unit direction `-dir`, up to `settings.orders`: the mean over
    /// `settings.paths` paths and its standard error. Each path flies by inverting the
    /// exact optical depth ([`RayThrough::free_flight`]), keeps the albedo as a weight,
    /// adds the sunlight scattered toward the eye at every event (next-event estimation
    /// with the exact transmittance to the sun), takes its next direction from the
    /// phase function and, leaving the cloud upward, adds the sky's radiance.
    pub fn path_traced(
        &self,
        origin: DVec3,
        dir: DVec3,
        settings: &PathSettings,
        seed: u64,
    ) -> (f64, f64) {
        let mut rng = SplitMix64::new(seed);
        let orders = settings.orders.min(MAX_ORDER);
        mean_and_error((0..settings.paths).map(|_| self.path(origin, dir, orders, &mut rng)))
    }

    /// The irradiance on a horizontal surface at `point` (beneath the cloud, `y` up) per
    /// unit sun irradiance, in two parts: the sun's own, `mu_s T` with the exact
    /// transmittance, and the light the cloud scatters down onto it,
    /// `integral L cos dw` over the upper hemisphere, as `pi` times the mean of `paths`
    /// cosine-weighted directions each followed through every order
    /// ([`ReferenceCloud::path_traced`]'s paths), with its standard error.
    pub fn ground_irradiance(&self, point: DVec3, paths: usize, seed: u64) -> GroundIrradiance {
        let mu_s = self.light.to_sun.y.max(0.0);
        let direct = mu_s * self.volume.transmittance(point, self.light.to_sun);
        let mut rng = SplitMix64::new(seed);
        let (mean, error) = mean_and_error((0..paths).map(|_| {
            let dir = sample_cosine(DVec3::Y, &mut rng);
            self.path(point, dir, MAX_ORDER, &mut rng)
        }));
        GroundIrradiance {
            direct,
            scattered: std::f64::consts::PI * mean,
            error: std::f64::consts::PI * error,
        }
    }

    fn path(&self, mut origin: DVec3, mut dir: DVec3, orders: usize, rng: &mut SplitMix64) -> f64 {
        let mut weight = 1.0;
        let mut total = 0.0;
        for order in 1..=orders {
            let ray = self.volume.ray(origin, dir);
            let Some(t) = ray.free_flight(-(1.0 - rng.unit_f64()).ln()) else {
                // Out of the cloud: the sky, seen after one scattering or more.
                if order > 1 && dir.y > 0.0 {
                    total += weight * self.light.sky;
                }
                break;
            };
            let (sigma, scattering) = ray.extinction(t);
            weight *= scattering / sigma;
            origin += dir * t;
            let sun = self.volume.transmittance(origin, self.light.to_sun);
            total += weight * self.light.phase.eval(self.light.to_sun.dot(dir)) * sun;
            dir = self.sampler.sample(dir, rng);
        }
        total
    }

    /// [`ReferenceCloud::single_scattering`] at every pixel centre of `camera`: radiance
    /// and transmittance, row by row.
    pub fn single_scattering_picture(&self, camera: &Camera) -> Vec<(f64, f64)> {
        pixels(camera)
            .into_par_iter()
            .map(|(origin, dir)| self.single_scattering(origin, dir))
            .collect()
    }

    /// The pixels of `camera` that the cloud covers, row by row: those whose ray
    /// crosses an optical depth over 0.1 (where pictures are compared).
    pub fn covered(&self, camera: &Camera) -> Vec<bool> {
        pixels(camera)
            .into_par_iter()
            .map(|(origin, dir)| self.volume.ray(origin, dir).depth_to(f64::INFINITY) > 0.1)
            .collect()
    }

    /// The cloud's optical depth along every pixel's ray of `camera`, row by row.
    pub fn depths(&self, camera: &Camera) -> Vec<f64> {
        pixels(camera)
            .into_par_iter()
            .map(|(origin, dir)| self.volume.ray(origin, dir).depth_to(f64::INFINITY))
            .collect()
    }

    /// [`ReferenceCloud::path_traced`] at every pixel centre of `camera`: mean and
    /// standard error, row by row (each pixel its own random sequence).
    pub fn path_traced_picture(&self, camera: &Camera, settings: &PathSettings) -> Vec<(f64, f64)> {
        pixels(camera)
            .into_par_iter()
            .enumerate()
            .map(|(k, (origin, dir))| {
                let seed = settings.seed ^ (k as u64 + 1).wrapping_mul(0x9e37_79b9_7f4a_7c15);
                self.path_traced(origin, dir, settings, seed)
            })
            .collect()
    }
}

/// How a picture of a cloud agrees with a reference picture of it (both row by row,
/// `width` wide), over the pixels the cloud covers ([`ReferenceCloud::covered`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Agreement {
    /// The picture's mean over the covered pixels, over the reference's.
    pub mean_ratio: f64,
    /// The root mean square of the picture less the reference over the covered
    /// pixels, over the reference's mean there.
    pub rms_of_mean: f64,
    /// 8 x 8 blocks with at least half their pixels covered whose means are within 15 %
    /// of each other, and all such blocks (a measure of the picture's shape).
    pub blocks_within_15: usize,
    pub blocks: usize,
    /// Of the same blocks, those whose medians (over their covered pixels, the picture's
    /// and the reference's each) are within 15 % of each other: the issue's own wording
    /// of the measure. A path-traced reference needs more paths for it than for the
    /// means: with few paths a pixel its pixels' noise is skewed (most paths bring little
    /// light, a few much), and their median lies below their mean.
    pub medians_within_15: usize,
}

impl Agreement {
    /// Compares `picture` with `reference` over the `covered` pixels.
    pub fn of(picture: &[f64], reference: &[f64], covered: &[bool], width: usize) -> Agreement {
        // Sums of the picture and the reference over the covered pixels among `pixels`,
        // and how many those are.
        let sums = |pixels: &mut dyn Iterator<Item = usize>| {
            pixels
                .filter(|&k| covered[k])
                .fold((0.0, 0.0, 0), |(p, r, n), k| {
                    (p + picture[k], r + reference[k], n + 1)
                })
        };
        let (p, r, n) = sums(&mut (0..picture.len()));
        let squares: f64 = (0..picture.len())
            .filter(|&k| covered[k])
            .map(|k| (picture[k] - reference[k]).powi(2))
            .sum();
        let mut agreement = Agreement {
            mean_ratio: p / r,
            rms_of_mean: (squares / n as f64).sqrt() / (r / n as f64),
            blocks_within_15: 0,
            blocks: 0,
            medians_within_15: 0,
        };
        for by in 0..picture.len() / width / 8 {
            for bx in 0..width / 8 {
                let block = || {
                    (by * 8..by * 8 + 8)
                        .flat_map(move |y| (bx * 8..bx * 8 + 8).map(move |x| y * width + x))
                };
                let (bp, br, n) = sums(&mut block());
                if n >= 32 {
                    agreement.blocks += 1;
                    agreement.blocks_within_15 += usize::from((bp / br - 1.0).abs() < 0.15);
                    let median_of = |values: &[f64]| {
                        median(block().filter(|&k| covered[k]).map(|k| values[k]).collect())
                    };
                    let ratio = median_of(picture) / median_of(reference);
                    agreement.medians_within_15 += usize::from((ratio - 1.0).abs() < 0.15);
                }
            }
        }
        agreement
    }
}

/// How `picture` agrees with `reference` on the thinnest and the thickest fifth of the
/// `covered` pixels by the cloud's optical depth along them (`depths`,
/// [`ReferenceCloud::depths`]): the picture's mean over the reference's on each, the
/// thin fringe first, then the thick core.
pub fn fifths(picture: &[f64], reference: &[f64], covered: &[bool], depths: &[f64]) -> [f64; 2] {
    let mut order: Vec<usize> = (0..picture.len()).filter(|&k| covered[k]).collect();
    order.sort_by(|&a, &b| depths[a].total_cmp(&depths[b]));
    let fifth = (order.len() / 5).max(1);
    let ratio = |pixels: &[usize]| {
        let p: f64 = pixels.iter().map(|&k| picture[k]).sum();
        let r: f64 = pixels.iter().map(|&k| reference[k]).sum();
        p / r
    };
    [ratio(&order[..fifth]), ratio(&order[order.len() - fifth..])]
}

/// The median of `values` (not empty): the middle one, or the mean of the two middle
/// ones.
fn median(mut values: Vec<f64>) -> f64 {
    values.sort_by(f64::total_cmp);
    let m = values.len() / 2;
    if values.len() % 2 == 1 {
        values[m]
    } else {
        0.5 * (values[m - 1] + values[m])
    }
}

/// [`ReferenceCloud::ground_irradiance`]: per unit sun irradiance, W m^-2 per W m^-2.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GroundIrradiance {
    /// The sun's, unscattered: `mu_s T`.
    pub direct: f64,
    /// Scattered down by the cloud, every order, and its standard error.
    pub scattered: f64,
    pub error: f64,
}

impl GroundIrradiance {
    /// Both parts.
    pub fn total(&self) -> f64 {
        self.direct + self.scattered
    }
}

/// Each pixel centre's ray of a pinhole `camera`: origin and unit direction.
fn pixels(camera: &Camera) -> Vec<(DVec3, DVec3)> {
    let (w, h) = (camera.width, camera.height);
    (0..w * h)
        .map(|k| {
            let (x, y) = ((k % w) as f32 + 0.5, (k / w) as f32 + 0.5);
            (
                camera.position.as_dvec3(),
                camera.ray(x, y).as_dvec3().normalize(),
            )
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::clouds::generator::Cumulus;

    /// A ray through the grid meets each particle near it once, however many of its
    /// cells the particle reaches into: its optical depth toward the sun is the sum over
    /// every particle ([`transmittance`]), for rays of two clouds taken in turn on one
    /// thread (whose mailboxes they share).
    #[test]
    fn a_ray_through_the_grid_meets_each_particle_once() {
        let clouds = [2_000, 300].map(|count| {
            Cumulus {
                particles: count,
                seed: count as u64,
                ..Cumulus::default()
            }
            .generate()
        });
        let volumes = [CloudVolume::new(&clouds[0]), CloudVolume::new(&clouds[1])];
        let to_sun = Vec3::new(0.3, 0.8, -0.2).normalize();
        let mut rng = SplitMix64::new(7);
        for k in 0..400 {
            let particles = &clouds[k % 2];
            let pick = (rng.unit_f64() * particles.len() as f64) as usize;
            let jitter = Vec3::new(rng.unit_f64() as f32, rng.unit_f64() as f32, 0.5) * 20.0;
            let point = particles[pick.min(particles.len() - 1)].position + jitter;
            let exact = -transmittance(particles, to_sun, point).ln();
            let grid = volumes[k % 2]
                .ray(point.as_dvec3(), to_sun.as_dvec3())
                .depth_to(f64::INFINITY);
            assert!(
                exact > 0.0 && (grid - exact).abs() <= 1e-4 * exact,
                "ray {k}: {grid} through the grid, {exact} over every particle"
            );
        }
    }

    /// The same picture agrees block by block; a block a fifth brighter drops out of
    /// those within 15 % and moves the mean by its share; a block under half covered is
    /// not counted, and pixels the cloud does not cover count for nothing.
    #[test]
    fn agreement_counts_blocks_and_the_mean() {
        let (w, h) = (24, 16);
        let reference: Vec<f64> = (0..w * h).map(|k| 1.0 + (k % 7) as f64).collect();
        let mut covered = vec![true; w * h];
        // Block (2, 1) covered on 16 of its 64 pixels.
        for y in 8..16 {
            for x in 16..24 {
                covered[y * w + x] = x < 18;
            }
        }
        let mut picture = reference.clone();
        let first_block = |k: usize| k % w < 8 && k / w < 8;
        for k in 0..w * h {
            if first_block(k) {
                picture[k] *= 1.2;
            } else if !covered[k] {
                picture[k] = 1e9;
            }
        }
        let same = Agreement::of(&reference, &reference, &covered, w);
        assert_eq!(
            (
                same.mean_ratio,
                same.blocks_within_15,
                same.blocks,
                same.medians_within_15
            ),
            (1.0, 5, 5, 5)
        );
        let brighter = Agreement::of(&picture, &reference, &covered, w);
        let total: f64 = (0..w * h)
            .filter(|&k| covered[k])
            .map(|k| reference[k])
            .sum();
        let block: f64 = (0..w * h)
            .filter(|&k| first_block(k))
            .map(|k| reference[k])
            .sum();
        assert!((brighter.mean_ratio - (1.0 + 0.2 * block / total)).abs() < 1e-12);
        assert_eq!(
            (
                brighter.blocks_within_15,
                brighter.blocks,
                brighter.medians_within_15
            ),
            (4, 5, 4)
        );
    }

    /// Block medians against block means, one 8 x 8 block at a time: three pixels ten
    /// times as bright move the block's mean out of 15 % (1 + 27/64) but not its median;
    /// its left half a third darker moves both (the median the mean of the middle two,
    /// 2/3 and 1); 40 of its 64 pixels a fifth darker move the median (0.8) but not the
    /// mean (0.875).
    #[test]
    fn block_medians_and_means_differ_where_they_should() {
        let reference = vec![1.0; 64];
        let covered = vec![true; 64];
        let within = |changed: &dyn Fn(usize, usize) -> f64| {
            let picture: Vec<f64> = (0..64).map(|k| changed(k % 8, k / 8)).collect();
            let a = Agreement::of(&picture, &reference, &covered, 8);
            assert_eq!(a.blocks, 1);
            (a.blocks_within_15, a.medians_within_15)
        };
        let bright = |x: usize, y: usize| if y == 0 && x < 3 { 10.0 } else { 1.0 };
        let half = |x: usize, _: usize| if x < 4 { 2.0 / 3.0 } else { 1.0 };
        let most = |x: usize, y: usize| if y * 8 + x < 40 { 0.8 } else { 1.0 };
        assert_eq!(within(&bright), (0, 1));
        assert_eq!(within(&half), (0, 0));
        assert_eq!(within(&most), (1, 0));
        assert_eq!(median(vec![3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(vec![4.0, 1.0, 2.0, 3.0]), 2.5);
    }
}
