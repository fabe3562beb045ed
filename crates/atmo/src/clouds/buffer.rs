//! The 3-D intensity buffer of clouds 3.3: a voxel grid around the cloud, oriented to
//! the light, holding at each voxel centre `Gamma`, the fraction of sunlight that reaches
//! it after the particles between it and the sun: the product (7) of their factors
//! `G_i = a_i tau_i p(l, l) / 4 pi + T_i` (forward scattering plus transmission).
//!
//! Axes: `y` along the light's travel (from the sun's side of the cloud to the far
//! side), `x` and `z` across it (the paper's xz plane, perpendicular to the light).
//! Storage is `[x][z][y]`, so a column along the light is contiguous.
//!
//! The paper fills the buffer by drawing, for each particle and each slice it crosses,
//! a "shadow polygon" covering the particle's width and everything behind it, multiplied
//! in (added as `log G`) in any order. A CPU does the same sum better in two passes:
//! each particle adds `log G` once per column it covers, at the cell where its shadow
//! starts, and a prefix sum along each column spreads it to everything behind
//! ([`Splat::Whole`], equal to the shadow polygons; the tests show it). And since the
//! CPU is not bound to one value per particle, [`Splat::Pieces`] goes further: each
//! particle's optical depth is split exactly between the cells it crosses, so a voxel
//! inside a particle sees only the part of it on the sun's side. With no forward
//! scattering this makes `Gamma` at voxel centres the exact transmittance.

use glam::{Mat3, Vec3};
use rayon::prelude::*;

use super::particles::{erf_table, Particle};
use crate::error::{check_range, Error, Result};
use crate::lanes::{first, Lanes, LANES};

/// How each particle's factor goes into the buffer.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Splat {
    /// The paper's: one factor per particle and column, shadowing everything from the
    /// particle's sun-side edge on, itself included.
    Whole,
    /// The particle's optical depth split exactly between the cells along the column.
    Pieces,
}

/// `Gamma` on a voxel grid oriented to the light.
#[derive(Debug, Clone)]
pub struct IntensityBuffer {
    /// Voxels along each axis.
    pub resolution: usize,
    /// World to buffer axes: rows are `x`, `y` (the light's travel) and `z`.
    pub buffer_from_world: Mat3,
    /// Buffer coordinates of the grid's smallest corner, m.
    pub min: Vec3,
    /// Voxel size along each buffer axis, m.
    pub voxel: Vec3,
    /// `ln Gamma` at voxel centres, `[x][z][y]`: a sum where the paper multiplies (it
    /// added `log G` in its shaders too), and what [`IntensityBuffer::sample`]
    /// interpolates, so that light falls off exponentially between voxels as it does
    /// through the particles.
    pub log_gamma: Vec<f32>,
}

impl IntensityBuffer {
    /// Bytes a buffer of `resolution`^3 needs (its values and the same again while it is
    /// built).
    pub fn bytes(resolution: usize) -> u64 {
        2 * (resolution as u64).pow(3) * 4
    }

    /// Refuses a resolution outside [2, 2048] or over the run's memory budget ([`crate::budget`]).
    pub fn check_resolution(resolution: usize) -> Result<()> {
        check_range("buffer.resolution", resolution as f64, 2.0, 2048.0)?;
        crate::budget::check(
            &format!("a {resolution}^3 intensity buffer"),
            Self::bytes(resolution),
            "the buffer resolution",
        )
    }

    /// The buffer of `particles` lit from the direction `to_sun` (toward the sun, any
    /// length), `resolution`^3 voxels; `forward` is the paper's `p(l, l) / 4 pi`, the
    /// part of scattered light taken to continue along the light, in [0, 1].
    pub fn new(
        particles: &[Particle],
        to_sun: Vec3,
        resolution: usize,
        forward: f32,
        splat: Splat,
    ) -> Result<IntensityBuffer> {
        Self::check_resolution(resolution)?;
        let mut buffer = IntensityBuffer {
            resolution,
            buffer_from_world: Mat3::IDENTITY,
            min: Vec3::ZERO,
            voxel: Vec3::ONE,
            log_gamma: vec![0.0; resolution.pow(3)],
        };
        buffer.update(particles, to_sun, forward, splat)?;
        Ok(buffer)
    }

    /// Recomputes the buffer for moved particles or a moved sun, in its own memory: the
    /// light pass of a dynamic cloud, run whenever either changes. (A fresh allocation of
    /// a 256^3 buffer each time costs more than filling it, in page faults.)
    pub fn update(
        &mut self,
        particles: &[Particle],
        to_sun: Vec3,
        forward: f32,
        splat: Splat,
    ) -> Result<()> {
        let frame = LightFrame::new(particles, to_sun, forward)?;
        self.buffer_from_world = frame.from_world;
        self.min = frame.min;
        self.voxel = (frame.max - frame.min) / self.resolution as f32;
        self.fill(particles, forward, splat);
        Ok(())
    }

    /// Voxel index range `[first, last)` along `axis` whose centres lie within
    /// `[a, b]` (buffer coordinates, m).
    fn centres_within(&self, axis: usize, a: f32, b: f32) -> (usize, usize) {
        let n = self.resolution as f32;
        let to_index = |v: f32| (v - self.min[axis]) / self.voxel[axis] - 0.5;
        let first = to_index(a).ceil().clamp(0.0, n) as usize;
        let last = (to_index(b).floor() + 1.0).clamp(0.0, n) as usize;
        (first, last)
    }

    /// Buffer coordinate of the centre of voxel `i` along `axis`.
    #[inline]
    fn centre(&self, axis: usize, i: usize) -> f32 {
        self.min[axis] + (i as f32 + 0.5) * self.voxel[axis]
    }

    /// Adds every particle's `log G` at the cells where it starts to shadow, then sums
    /// along each column. Parallel over `x` planes, each particle in the same order into
    /// each voxel, so the result does not depend on the thread count.
    fn fill(&mut self, particles: &[Particle], forward: f32, splat: Splat) {
        let n = self.resolution;
        let this = &*self;
        let stamps: Vec<Stamp> = particles
            .par_iter()
            .map(|p| Stamp::new(this, p, forward, splat))
            .collect();
        // The particles touching each x plane, in particle order.
        let mut planes: Vec<Vec<u32>> = vec![Vec::new(); n];
        for (k, stamp) in stamps.iter().enumerate() {
            for plane in &mut planes[stamp.x.0..stamp.x.1] {
                plane.push(k as u32);
            }
        }
        let mut gamma = std::mem::take(&mut self.log_gamma);
        gamma.resize(n * n * n, 0.0);
        gamma
            .par_chunks_mut(n * n)
            .zip(&planes)
            .enumerate()
            .for_each(|(ix, (plane, touching))| {
                plane.fill(0.0);
                // Per column, the first cell anything was added to (n: none).
                let mut start = vec![n; n];
                for &k in touching {
                    stamps[k as usize].add_to(plane, ix, n, &mut start);
                }
                // Prefix sums along y: ln Gamma at each centre (0 before the start).
                for (column, &first) in plane.chunks_mut(n).zip(&start) {
                    let mut sum = 0.0f64;
                    for v in &mut column[first..] {
                        sum += *v as f64;
                        *v = sum as f32;
                    }
                }
            });
        self.log_gamma = gamma;
    }

    /// `Gamma` at voxel `(ix, iy, iz)`.
    #[inline]
    pub fn at(&self, ix: usize, iy: usize, iz: usize) -> f32 {
        self.log_at(ix, iy, iz).exp()
    }

    /// `ln Gamma` at voxel `(ix, iy, iz)`.
    #[inline]
    fn log_at(&self, ix: usize, iy: usize, iz: usize) -> f32 {
        let n = self.resolution;
        self.log_gamma[(ix * n + iz) * n + iy]
    }

    /// World position of the centre of voxel `(ix, iy, iz)`.
    pub fn voxel_centre(&self, ix: usize, iy: usize, iz: usize) -> Vec3 {
        let local = Vec3::new(self.centre(0, ix), self.centre(1, iy), self.centre(2, iz));
        self.buffer_from_world.transpose() * local
    }

    /// `Gamma` at the world point `p`: `ln Gamma` trilinear between voxel centres
    /// (clamped to the grid: 1 on the sun's side of it), exponentiated.
    pub fn sample(&self, p: Vec3) -> f32 {
        self.sample_grid(self.grid_coordinates(p))
    }

    /// The grid coordinates of the world point `p`: voxel `(i, j, k)`'s centre is at
    /// `(i, j, k)`. Affine in `p`, so a caller walking a line of points can step them.
    #[inline]
    pub fn grid_coordinates(&self, p: Vec3) -> Vec3 {
        (self.buffer_from_world * p - self.min) / self.voxel - Vec3::splat(0.5)
    }

    /// The step in grid coordinates of the world displacement `v` (m).
    #[inline]
    pub fn grid_step(&self, v: Vec3) -> Vec3 {
        (self.buffer_from_world * v) / self.voxel
    }

    /// [`IntensityBuffer::sample`] at grid coordinates `g`.
    #[inline]
    pub fn sample_grid(&self, g: Vec3) -> f32 {
        self.sample_log_grid(g).exp()
    }

    /// The optical depth of the whole cloud along the sun's ray through grid
    /// coordinates `g`: `-ln Gamma` at the grid's far end (its last layer along the
    /// light), bilinear across the light.
    #[inline]
    pub fn column_depth_grid(&self, g: Vec3) -> f32 {
        first(self.sample_lanes::<true>([g.x, g.y, g.z].map(Lanes::splat))[2])
    }

    /// The cloud's extinction coefficient at the world point `p` (1/m) as the buffer
    /// holds it: how fast `ln Gamma` falls along the light's travel there (between the
    /// voxel centres on either side of `p` along the light, bilinear across it). With
    /// [`Splat::Pieces`] and no forward scattering, the particles' extinction averaged
    /// over a voxel along the light; with forward scattering, less the share scattered
    /// forward.
    pub fn extinction(&self, p: Vec3) -> f32 {
        let g = self.grid_coordinates(p);
        -first(self.sample_lanes::<false>([g.x, g.y, g.z].map(Lanes::splat))[1]) / self.voxel.y
    }

    /// `ln Gamma` at grid coordinates `g`, trilinear between voxel centres (clamped to
    /// the grid: 0 on the sun's side of it).
    #[inline]
    pub fn sample_log_grid(&self, g: Vec3) -> f32 {
        first(self.sample_log_lanes([g.x, g.y, g.z].map(Lanes::splat)))
    }

    /// [`IntensityBuffer::sample_log_grid`] at eight points (grid coordinates).
    #[inline(always)]
    pub(crate) fn sample_log_lanes(&self, g: [Lanes; 3]) -> Lanes {
        self.sample_lanes::<false>(g)[0]
    }

    /// At eight points (grid coordinates): `ln Gamma` trilinear, its slope along the
    /// light per voxel (`-voxel.y` times [`IntensityBuffer::extinction`]) and, with
    /// `DEPTH`, the whole cloud's optical depth along the light through them
    /// ([`IntensityBuffer::column_depth_grid`], else 0), which all share the voxel
    /// across the light. The voxel and the fractions in lanes, the values each point
    /// needs read one by one (no gather on the baseline instruction set), the lerps in
    /// lanes.
    #[inline(always)]
    pub(crate) fn sample_lanes<const DEPTH: bool>(&self, g: [Lanes; 3]) -> [Lanes; 3] {
        let n = self.resolution;
        let sun_side = g[1].simd_lt(Lanes::splat(-0.5));
        let last = Lanes::splat((n - 1) as f32);
        // Clamped to the grid; then the lower voxel, at most the last but one, and the
        // fraction past it. Through i32 (truncation: g >= 0 here).
        let top = wide::i32x8::splat(n as i32 - 2);
        let c = g.map(|v| v.fast_max(Lanes::ZERO).fast_min(last));
        let i = c.map(|v| v.trunc_int().min(top));
        let f: [Lanes; 3] = std::array::from_fn(|k| c[k] - Lanes::from_i32x8(i[k]));
        let [ix, iy, iz] = i.map(|v| v.to_array());
        // [x][z][y]: the two y neighbours are adjacent. Corner (dx, dz)'s pair at
        // `pairs[2 (2 dx + dz) + dy]`, its value in the last layer at `layer[2 dx + dz]`.
        let mut pairs = [[0.0f32; LANES]; 8];
        let mut layer = [[0.0f32; LANES]; 4];
        // Each lane's cell as one slice, its corners at fixed offsets in it: one bounds
        // check a lane rather than one a value took a tenth of the bench frame's
        // instructions away (callgrind, 8.84 to 7.99 billion).
        // The cell's span: its last corner's pair, or value.
        let corners = [0, n, n * n, n * n + n];
        let (pair_span, value_span) = (corners[3] + 2, corners[3] + 1);
        for lane in 0..LANES {
            let column = (ix[lane] as usize * n + iz[lane] as usize) * n;
            let cell = &self.log_gamma[column + iy[lane] as usize..][..pair_span];
            for (corner, offset) in corners.into_iter().enumerate() {
                pairs[2 * corner][lane] = cell[offset];
                pairs[2 * corner + 1][lane] = cell[offset + 1];
            }
            if DEPTH {
                let top = &self.log_gamma[column + n - 1..][..value_span];
                for (corner, offset) in corners.into_iter().enumerate() {
                    layer[corner][lane] = top[offset];
                }
            }
        }
        let lerp = |a: Lanes, b: Lanes, t: Lanes| a + t * (b - a);
        let across = |corners: [Lanes; 4]| {
            lerp(
                lerp(corners[0], corners[2], f[0]),
                lerp(corners[1], corners[3], f[0]),
                f[2],
            )
        };
        let pairs = pairs.map(Lanes::new);
        let log_gamma = across(std::array::from_fn(|corner| {
            lerp(pairs[2 * corner], pairs[2 * corner + 1], f[1])
        }));
        let slope = across(std::array::from_fn(|corner| {
            pairs[2 * corner + 1] - pairs[2 * corner]
        }));
        let depth = if DEPTH {
            -across(layer.map(Lanes::new))
        } else {
            Lanes::ZERO
        };
        [
            sun_side.select(Lanes::ZERO, log_gamma),
            sun_side.select(Lanes::ZERO, slope),
            depth,
        ]
    }
}

/// The frame of a light pass, shared by the buffer, the Harris baseline and the GPU's
/// light pass: world to `(x, y, z)` with `y` along the light's travel, and the box in
/// that frame that holds every particle whole. Making it validates what a light pass
/// is given.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LightFrame {
    /// World to light-pass axes: rows `x`, `y`, `z`.
    pub from_world: Mat3,
    /// The box's corners, in light-pass axes, m.
    pub min: Vec3,
    pub max: Vec3,
}

impl LightFrame {
    /// The frame for `particles` lit from `to_sun` (any length), with `forward` the
    /// forward-scattering share `p(l, l) / 4 pi` in [0, 1].
    pub fn new(particles: &[Particle], to_sun: Vec3, forward: f32) -> Result<LightFrame> {
        check_range("buffer.forward", forward as f64, 0.0, 1.0)?;
        if particles.is_empty() {
            return Err(Error::Invalid("the cloud has no particles".into()));
        }
        let light = (-to_sun)
            .try_normalize()
            .ok_or_else(|| Error::Invalid("the sun direction is zero".into()))?;
        let helper = if light.y.abs() < 0.9 {
            Vec3::Y
        } else {
            Vec3::X
        };
        let x = helper.cross(light).normalize();
        let z = x.cross(light);
        let from_world = Mat3::from_cols(x, light, z).transpose();
        let (mut min, mut max) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
        for p in particles {
            let c = from_world * p.position;
            min = min.min(c - Vec3::splat(p.radius));
            max = max.max(c + Vec3::splat(p.radius));
        }
        Ok(LightFrame {
            from_world,
            min,
            max,
        })
    }
}

/// How far across the light a particle's footprint reaches, in its standard deviations
/// `s`: a column 3.5 `s` from the axis carries 0.2 % of the axis's optical depth.
pub const FOOTPRINT: f32 = 3.5;

/// One particle's contribution to the buffer, prepared once per light pass. The blob is
/// separable: across the light, the column through voxel centres `(x, z)` carries
/// `across_x[x] * across_z[z]` of the depth of the particle's axis, and along it cell
/// `j` (from the centre of voxel `j - 1` to that of voxel `j`; the first reaching back
/// to the sun, the one after the particle on to infinity) takes the same share
/// `along[j]` in every column. So adding it is a multiply-add down contiguous columns,
/// with every `exp` and `erf` done here, once.
struct Stamp {
    /// Voxel index ranges `[first, last)` across (x, z) and, for `Pieces`, along y.
    x: (usize, usize),
    z: (usize, usize),
    y: (usize, usize),
    /// `across_x`, then `across_z`, then `along` (`Pieces`), concatenated.
    factors: Vec<f32>,
    /// `Pieces`: `-(1 - a p/4pi)` times the axis depth. `Whole`: the axis depth.
    scale: f32,
    /// `Whole`: `a p(l,l)/4pi`, for `log G` per column.
    scatter: f32,
    splat: Splat,
}

impl Stamp {
    fn new(buffer: &IntensityBuffer, p: &Particle, forward: f32, splat: Splat) -> Stamp {
        let s = p.sigma();
        let c = buffer.buffer_from_world * p.position;
        let reach = p.reach();
        let inv_2s2 = 1.0 / (2.0 * s * s);
        let x = buffer.centres_within(0, c.x - reach, c.x + reach);
        let z = buffer.centres_within(2, c.z - reach, c.z + reach);
        let across = |axis: usize, (a, b): (usize, usize), centre: f32| {
            (a..b).map(move |i| {
                let d = buffer.centre(axis, i) - centre;
                (-d * d * inv_2s2).exp()
            })
        };
        let mut factors: Vec<f32> = across(0, x, c.x).chain(across(2, z, c.z)).collect();
        let axis = p.density * s * (2.0 * std::f32::consts::PI).sqrt();
        let scatter = p.albedo * forward;
        let (y, scale) = match splat {
            Splat::Whole => {
                // From the sun-side edge of the particle on: the first centre at or past it.
                let (first, _) = buffer.centres_within(1, c.y - p.radius, f32::INFINITY);
                ((first, first + 1), axis)
            }
            Splat::Pieces => {
                // Split thin, the factors multiply into exp(-(1 - a p/4pi) tau): the
                // forward-scattering transport the paper's G approximates per particle,
                // solved exactly.
                let (first, last) = buffer.centres_within(1, c.y - p.radius, c.y + p.radius);
                let end = (last + 1).min(buffer.resolution);
                let k = 1.0 / (s * std::f32::consts::SQRT_2);
                let mut below = -1.0;
                for j in first..end {
                    // The cell after the particle's last centre takes the rest of it.
                    let above = if j == last {
                        1.0
                    } else {
                        erf_table((buffer.centre(1, j) - c.y) * k)
                    };
                    factors.push(0.5 * (above - below));
                    below = above;
                }
                ((first, end), -(1.0 - scatter) * axis)
            }
        };
        Stamp {
            x,
            z,
            y,
            factors,
            scale,
            scatter,
            splat,
        }
    }

    /// Adds the stamp to the x plane `ix` (`plane`, `[z][y]`, `n` voxels a side),
    /// lowering `start[z]` to the first cell it touches in column `z`.
    #[inline]
    fn add_to(&self, plane: &mut [f32], ix: usize, n: usize, start: &mut [usize]) {
        let (nx, nz) = (self.x.1 - self.x.0, self.z.1 - self.z.0);
        let (across_x, rest) = self.factors.split_at(nx);
        let (across_z, along) = rest.split_at(nz);
        let w_x = self.scale * across_x[ix - self.x.0];
        let (first, end) = self.y;
        if first >= end || first >= n {
            return;
        }
        for (iz, a_z) in (self.z.0..self.z.1).zip(across_z) {
            start[iz] = start[iz].min(first);
            let column = &mut plane[iz * n..(iz + 1) * n];
            match self.splat {
                Splat::Whole => {
                    let tau = w_x * a_z;
                    column[first] += ((-tau).exp() + self.scatter * tau).ln();
                }
                Splat::Pieces => {
                    let w = w_x * a_z;
                    for (cell, share) in column[first..end].iter_mut().zip(along) {
                        *cell += w * share;
                    }
                }
            }
        }
    }
}
