//! The light of the orders past the first by solving its transfer through the cloud
//! (docs/clouds.md, "Every order: the transfer solve"), in place of a model of a few
//! optical depths ([`super::transfer`], [`super::octaves`]), which cannot know how
//! light diffuses through a particular cloud's shape. A hybrid, as the orders differ:
//! the first stays the billboards' exact one; the second is drawn explicitly with the
//! whole phase function; the third and higher diffuse.
//!
//! *The second order.* The sun's light scattered once (source `sigma_s p T`, `T` the
//! intensity buffer's transmittance) is carried without scattering again along 192
//! directions, one sweep of a grid over the cloud each, and a
//! droplet scatters it toward the eye by the phase: `integral p(w . w') L1(w') dw'`.
//! The droplets' forward lobe is sharp, so `L1` travels delta-Eddington's scaled medium
//! (Joseph, Wiscombe and Weinman 1976): a share `f = chi_2` of each scattering (the
//! phase's second Legendre moment, 0.50 for the cloud's) goes on straight ahead, and
//! `L1` is attenuated by `sigma_t - f sigma_s` only.
//!
//! *The third and higher.* The rest of `L1`'s scattering, `(1 - f) sigma_s`, by a phase
//! of mean cosine `g' = (g - f) / (1 - f)`, is the source of a diffuse field whose
//! fluence `phi` and flux `F` solve the P1 equations
//!
//! ```text
//! div F + sigma_a phi = Q0,        Q0 = (1 - f) sigma_s phi1
//! F = -D grad phi + 3 D Q1,        Q1 = g' (1 - f) sigma_s F1
//! ```
//!
//! (`phi1`, `F1` the fluence and flux of `L1`), with `D = lambda(R) / sigma_tr`,
//! `sigma_tr = sigma_t - g sigma_s` (the same in the scaled medium and the true one),
//! and Levermore and Pomraning's flux limiter `lambda(R) = (coth R - 1/R) / R`, `R =
//! |grad phi| / (sigma_tr phi)`: 1/3 deep in the cloud, where diffusion holds, and
//! `|F| <= k phi` at its thin fringe, where light streams (`k` 0.6: a beam's is 1,
//! light leaving a surface has 1/2). Cells of clear air are left out of the solve; on
//! the cloud's faces to them and on the grid's outer faces Marshak's condition lets
//! the light out (`F . n = phi / 2`), nothing coming in. A droplet scatters the field
//! toward the eye as its radiance rebuilt from `phi` and `F` by Minerbo's closure and
//! scattered by the phase ([`DiffuseLight::toward`]).
//!
//! *The sky's light*, the same way ([`DiffuseLight::sky_toward`]): its radiance from
//! every direction carried in from the grid's faces along the same directions without
//! scattering (the transmittance, each cell's mean along its path), scattered toward
//! the eye by the whole phase (its first order), and the rest of its scattering the
//! source of a diffusion per channel with the sun's field's `D` (its higher orders).
//!
//! All are made toward the eye once a picture for each cell and read at the blobs'
//! emission nodes. The grid is cubic cells over the particles' reach with two cells
//! of air around; the extinction of each cell is the particles' mean over it
//! (differences of `erf`, the Gaussian being separable), the sun's transmittance the
//! intensity buffer's at the cell's centre. The finite-volume system (seven points,
//! symmetric, positive definite for lagged `D`) is solved by conjugate gradients with
//! a Jacobi preconditioner; `D` is lagged six times from scratch, once from a previous
//! solution ([`DiffuseLight::solve`]'s `previous`, as when only the sun has moved a
//! little).

use std::ops::{Add, Mul, Sub};

use glam::{Vec3, Vec4};
use rayon::prelude::*;

use super::buffer::IntensityBuffer;
use super::particles::{erf_table, Particle};
use super::sky_light::SkyLight;
use crate::atmosphere::phase::PhaseFunction;
use crate::error::{check_range, Error, Result};
use crate::lanes::{Lanes, LANES};
use crate::quadrature::legendre;

/// How the transfer solve is set up.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Diffusion {
    /// Cells along the cloud's longest side (the air around it not counted).
    pub cells: usize,
}

impl Diffusion {
    /// The default grid.
    pub const DEFAULT: Diffusion = Diffusion { cells: 32 };

    /// Refuses a grid outside [4, 256] cells a side, naming the field.
    pub fn validate(&self) -> Result<()> {
        check_range("diffusion.cells", self.cells as f64, 4.0, 256.0)
    }
}

/// Cells of air around the cloud on each side.
const MARGIN: usize = 2;

/// The least optical depth across a cell that counts it as cloud (clear air is left
/// out of the solve).
pub const THIN: f32 = 1e-3;

/// The flux limiter's streaming limit, `|F| <= STREAMING phi` where light streams
/// (docs/clouds.md, "Every order: the transfer solve"). Levermore and Pomraning's is 1,
/// a beam's; light leaving a surface into a half-space has `|F| = phi / 2`
/// (Marshak's condition). Between the two, chosen on the three tuning clouds' 36 views
/// (0.5, 0.6, 0.75 and 1 tried): at 1 the fringe lets too much light out and every
/// view is 15-25 % dark; at 0.5 the thin fringes hold too much.
pub const STREAMING: f32 = 0.6;

/// Lagged updates of the flux limiter's `D`, from scratch and from a previous solution.
pub const LAGS_COLD: usize = 6;
pub const LAGS_WARM: usize = 1;

/// The conjugate gradients stop when the residual is this share of the right side's.
pub const TOLERANCE: f64 = 1e-4;

/// The solved light of the orders past the first.
#[derive(Debug, Clone)]
pub struct DiffuseLight {
    /// The grid and the particles' medium it was solved on.
    grid: SolveGrid,
    /// Per cell, `[x][y][z]` (z fastest): the diffuse field's `phi / 4 pi` and
    /// `F / 4 pi` per unit sun irradiance.
    values: Vec<Vec4>,
    /// The phase's tables: the diffuse radiance's angles from its fluence and flux,
    /// scattered by the phase, and the phase itself.
    tables: PhaseTables,
    /// The sunlight scattered once, whose scattering toward the eye is the second order.
    once: OnceScattered,
    /// The fluence `phi` per cell, kept to start the next solve from.
    fluence: Vec<f32>,
    /// The sky's light through the same diffusion, if there is any sky.
    sky: Option<SkyField>,
    /// Conjugate-gradient iterations the solve took, over all its lags.
    pub iterations: usize,
}

/// The medium on the grid and the solve's sources.
struct Medium {
    dims: [usize; 3],
    /// The cells' side, m.
    h: f32,
    /// Per cell: transport extinction `sigma_tr` and absorption `sigma_a` (1/m), the
    /// diffusion's sources `Q0` and `Q1` (per unit sun irradiance, 1/m).
    sigma_tr: Vec<f32>,
    sigma_a: Vec<f32>,
    q0: Vec<f32>,
    q1: Vec<Vec3>,
    /// Extinction and scattering (1/m) and the sun's transmittance at the centre.
    sigma_t: Vec<f32>,
    sigma_s: Vec<f32>,
    sun: Vec<f32>,
    /// Whether a cell is cloud (its optical depth across at least [`THIN`]) or clear
    /// air, which the solve leaves out: the cloud's faces to it let light out by
    /// Marshak's condition, as the grid's outer faces do.
    inside: Vec<bool>,
}

impl DiffuseLight {
    /// The light of the orders past the first in `particles` lit through `buffer` (the
    /// sun's transmittance; lit from `to_sun`), scattered by `phase`, and the light of
    /// every order from the sky `sky` (through the same solve; none for
    /// [`SkyLight::NONE`]).
    /// `previous`, a solution on the same grid (same particles' bounds), starts the
    /// solve near its end.
    pub fn solve(
        particles: &[Particle],
        buffer: &IntensityBuffer,
        to_sun: Vec3,
        phase: PhaseFunction,
        sky: &SkyLight,
        settings: &Diffusion,
        previous: Option<&DiffuseLight>,
    ) -> Result<DiffuseLight> {
        // The phase's tables, kept from the last solve of the same phase.
        let tables = match previous.filter(|p| p.tables.phase == phase) {
            Some(p) => p.tables.clone(),
            None => PhaseTables::new(phase),
        };
        let (g, f) = (tables.g(), tables.f());
        let grid = SolveGrid::of(particles, settings)?;
        let travel = -to_sun.normalize();
        let mut medium = Medium::of(&grid, buffer, g);
        let once = OnceScattered::of(&medium, &tables, travel);
        medium.scatter(&once, g, f);
        let n = grid.cells();
        let warm = previous.filter(|p| {
            (p.grid.dims, p.grid.first_centre, p.grid.cell)
                == (grid.dims, grid.first_centre, grid.cell)
        });
        let mut phi = warm.map_or_else(|| vec![0.0f32; n], |p| p.fluence.clone());
        let mut iterations = 0;
        let lags = if warm.is_some() { LAGS_WARM } else { LAGS_COLD };
        let mut faces = Faces::plain(&medium);
        for lag in 0..lags {
            if lag > 0 || warm.is_some() {
                faces = Faces::limited(&medium, &phi);
            }
            let rhs = faces.right_side(&medium, &medium.q0, &medium.q1);
            iterations += conjugate_gradients(&medium, &faces, &rhs, &mut phi);
        }
        let values = medium.dilated(faces.values(&medium, &phi, &medium.q1));
        // The sky's transmittance is the particles' alone: kept where they are the same.
        let previous_sky = warm.and_then(|p| p.sky.as_ref());
        let through = warm
            .filter(|p| p.grid == grid)
            .and_then(|p| p.sky.as_ref())
            .map(|s| &s.through[..]);
        let sky = SkyField::solve(
            &medium,
            &faces,
            &tables,
            &once.directions,
            sky,
            previous_sky,
            through,
        );
        if let Some(field) = &sky {
            iterations += field.iterations;
        }
        Ok(DiffuseLight {
            grid,
            values,
            fluence: phi,
            sky,
            once,
            tables,
            iterations,
        })
    }

    /// Cells along x, y and z.
    pub fn dims(&self) -> [usize; 3] {
        self.grid.dims
    }

    /// The light each cell's centre sends toward `eye`, per unit scattering coefficient
    /// and sun irradiance (1/sr), `[x][y][z]`: the second order's, scattered by the
    /// whole phase, and the diffuse field's (its radiance rebuilt by the closure).
    pub fn toward(&self, eye: Vec3) -> Vec<f32> {
        self.both_toward(eye).into_iter().map(|v| v.x).collect()
    }

    /// The sky's light each cell's centre sends toward `eye` by every order, per unit
    /// scattering coefficient (the sky's radiance units, RGB), `[x][y][z]`; `None`
    /// without a sky.
    pub fn sky_toward(&self, eye: Vec3) -> Option<Vec<Vec3>> {
        self.sky.as_ref()?;
        Some(
            self.both_toward(eye)
                .into_iter()
                .map(|v| Vec3::new(v.y, v.z, v.w))
                .collect(),
        )
    }

    /// Per cell [`DiffuseLight::toward`]'s (x) and [`DiffuseLight::sky_toward`]'s (y, z,
    /// w; 0 without a sky): the lights carried along the directions scattered toward
    /// `eye` by the phase, read once for both, and the diffuse fields' by the closure.
    fn both_toward(&self, eye: Vec3) -> Vec<Vec4> {
        (0..self.values.len())
            .into_par_iter()
            .map(|cell| {
                let w = (eye - self.grid.centre(cell)).normalize_or_zero();
                let (mut sun, mut sky, mut norm) = (0.0, Vec3::ZERO, 0.0);
                for (k, d) in self.once.directions.iter().enumerate() {
                    // The phase normalised over the directions: `integral p L dw'`.
                    let p = self.tables.lobe.at(d.dot(w));
                    sun += p * self.once.radiance[k][cell];
                    if let Some(field) = &self.sky {
                        sky += p * field.through[k][cell] * field.radiance[k];
                    }
                    norm += p;
                }
                if norm > 0.0 {
                    (sun, sky) = (sun / norm, sky / norm);
                }
                sun += self.leaving(self.values[cell], w);
                if let Some(field) = &self.sky {
                    sky += Vec3::from_array(field.values[cell].map(|v| self.leaving(v, w)));
                }
                Vec4::new(sun, sky.x, sky.y, sky.z)
            })
            .collect()
    }

    /// [`DiffuseLight::toward`] made once for a picture: its lookups along the pixels'
    /// rays are then one value's trilinear read (the rays pass the centres at angles a
    /// cell's width apart as seen from the eye).
    pub(crate) fn seen_from(&self, eye: Vec3) -> Seen {
        Seen {
            min: self.grid.first_centre,
            cell: self.grid.cell,
            dims: self.grid.dims,
            light: self.both_toward(eye),
            has_sky: self.sky.is_some(),
        }
    }

    /// What a droplet scatters along the unit `w` of the diffuse field of a cell's
    /// `values`: the radiance's angles by Minerbo's closure, scattered by the phase.
    #[inline]
    fn leaving(&self, v: Vec4, w: Vec3) -> f32 {
        let flux = Vec3::new(v.y, v.z, v.w);
        let size = flux.length();
        if v.x <= 0.0 || v.x.is_nan() {
            return 0.0;
        }
        let cos = if size > 0.0 { flux.dot(w) / size } else { 0.0 };
        v.x * self.tables.closure.at(size / v.x, cos)
    }
}

/// The solve's tables of a phase function, made once for a phase: Minerbo's closure
/// scattered by it (the module doc), the phase over the cosine, its mean cosine `g` and
/// delta-Eddington's share `f` (the module doc). Public for a solve on another device
/// (atmo-gpu's), which reads the same tables.
#[derive(Debug, Clone)]
pub struct PhaseTables {
    phase: PhaseFunction,
    closure: Closure,
    lobe: Lobe,
}

impl PhaseTables {
    /// The tables of `phase`.
    pub fn new(phase: PhaseFunction) -> PhaseTables {
        PhaseTables {
            phase,
            closure: Closure::new(phase),
            lobe: Lobe::new(phase),
        }
    }

    /// The phase the tables are of.
    pub fn phase(&self) -> PhaseFunction {
        self.phase
    }

    /// The phase's mean cosine, its first Legendre moment.
    pub fn g(&self) -> f32 {
        self.closure.chi[1] as f32
    }

    /// Delta-Eddington's share of each scattering that goes on straight ahead: the
    /// phase's second Legendre moment (at most 0.99).
    pub fn f(&self) -> f32 {
        (self.closure.chi[2] as f32).clamp(0.0, 0.99)
    }

    /// The closure scattered by the phase, `[r][cos]`, ([`CLOSURE_STEPS`] + 1)^2 values:
    /// `r = |F| / phi` from 0 to [`CLOSURE_MAX`], the cosine from -1 to 1, per unit
    /// `phi / 4 pi`.
    pub fn closure(&self) -> &[f32] {
        &self.closure.values
    }

    /// The phase over the cosine, [`LOBE_STEPS`] + 1 values from -1 to 1 (1/sr).
    pub fn lobe(&self) -> &[f32] {
        &self.lobe.0
    }

    /// Each of `directions`' share of the sunlight scattered once when the sun's light
    /// travels along the unit `travel` (1/sr): the phase, normalised so that the shares
    /// times the directions' solid angle (4 pi over their number) sum to 1.
    pub fn shares(&self, directions: &[Vec3], travel: Vec3) -> Vec<f32> {
        let weight = 4.0 * std::f32::consts::PI / directions.len() as f32;
        let phases: Vec<f32> = directions
            .iter()
            .map(|w| self.lobe.at(w.dot(travel)))
            .collect();
        let total = phases.iter().sum::<f32>() * weight;
        phases.into_iter().map(|p| p / total).collect()
    }
}

/// The [`DIRECTIONS`] directions the light scattered once travels along (a spherical
/// Fibonacci lattice).
pub fn directions() -> Vec<Vec3> {
    crate::quadrature::fibonacci_sphere(DIRECTIONS)
        .iter()
        .map(|d| d.as_vec3())
        .collect()
}

/// The diffuse field's radiance at a point from its fluence `phi` and flux `F` alone,
/// by Minerbo's maximum-entropy closure: `L(w) ~ exp(b w . F/|F|)`, `b` such that its
/// mean cosine is `r = |F| / phi` (Langevin's `coth b - 1/b = r`, the function the flux
/// limiter is made of), and what the phase scatters of it along `w`: by Funk and
/// Hecke, `sum (2l + 1) chi_l A_l(r) P_l(cos)` times `phi / 4 pi`, `A_l` the
/// distribution's Legendre moments. Its first two terms are P1's `phi + 3 g F . w`;
/// the rest give a field streaming out of the cloud its forward lobe, which P1 cannot
/// (with P1 alone the cloud's back-lit fringe came out 15-20 % dark and its side-lit
/// fringe as much bright). Tabulated over [`CLOSURE_STEPS`] + 1 values of `r` in
/// [0, [`CLOSURE_MAX`]] and of `cos` in [-1, 1].
#[derive(Debug, Clone)]
struct Closure {
    values: Vec<f32>,
    /// The phase's Legendre moments, `chi_0` to `chi_TERMS`.
    chi: Vec<f64>,
}

/// Steps of the closure's table along each of its axes.
pub const CLOSURE_STEPS: usize = 64;

/// The largest flux over fluence the closure's table holds (`b` about 20).
pub const CLOSURE_MAX: f32 = 0.95;

/// Legendre terms of the closure.
const CLOSURE_TERMS: usize = 48;

impl Closure {
    fn new(phase: PhaseFunction) -> Closure {
        let chi = phase.legendre_moments(CLOSURE_TERMS as u32);
        let mut nodes = Vec::new();
        crate::quadrature::gauss_legendre(-1.0, 1.0, 64, |mu, w| nodes.push((mu, w)));
        // The polynomials at the quadrature's nodes and at the table's cosines, the same
        // for every row.
        let at_nodes: Vec<Vec<f64>> = nodes
            .iter()
            .map(|&(mu, _)| legendre(mu, CLOSURE_TERMS))
            .collect();
        let at_cosines: Vec<Vec<f64>> = (0..=CLOSURE_STEPS)
            .map(|j| legendre(-1.0 + 2.0 * j as f64 / CLOSURE_STEPS as f64, CLOSURE_TERMS))
            .collect();
        let mut values = Vec::with_capacity((CLOSURE_STEPS + 1).pow(2));
        for i in 0..=CLOSURE_STEPS {
            let r = CLOSURE_MAX as f64 * i as f64 / CLOSURE_STEPS as f64;
            let b = langevin_inverse(r);
            // The distribution's Legendre moments, its exponent shifted by -b.
            let weights: Vec<f64> = nodes
                .iter()
                .map(|&(mu, w)| w * (b * (mu - 1.0)).exp())
                .collect();
            let total: f64 = weights.iter().sum();
            let mut moments = vec![0.0; CLOSURE_TERMS + 1];
            for (polynomials, weight) in at_nodes.iter().zip(&weights) {
                for (m, p) in moments.iter_mut().zip(polynomials) {
                    *m += weight * p / total;
                }
            }
            // Funk and Hecke: the phase scales each moment by its own; then
            // `sum (2l + 1) c_l P_l(cos)` at each cosine.
            let scattered: Vec<f64> = moments.iter().zip(&chi).map(|(m, c)| m * c).collect();
            for polynomials in &at_cosines {
                let series: f64 = polynomials
                    .iter()
                    .zip(&scattered)
                    .enumerate()
                    .map(|(l, (p, c))| (2 * l + 1) as f64 * c * p)
                    .sum();
                values.push(series.max(0.0) as f32);
            }
        }
        Closure { values, chi }
    }

    /// The table at `r` (clamped to its range) and `cos`, bilinear.
    #[inline]
    fn at(&self, r: f32, cos: f32) -> f32 {
        let n = CLOSURE_STEPS as f32;
        let x = (r / CLOSURE_MAX).clamp(0.0, 1.0) * n;
        let y = (cos.clamp(-1.0, 1.0) + 1.0) * 0.5 * n;
        let (i, j) = (
            (x as usize).min(CLOSURE_STEPS - 1),
            (y as usize).min(CLOSURE_STEPS - 1),
        );
        let (fx, fy) = (x - i as f32, y - j as f32);
        let row = CLOSURE_STEPS + 1;
        let v = |i: usize, j: usize| self.values[i * row + j];
        let low = v(i, j) + fy * (v(i, j + 1) - v(i, j));
        let high = v(i + 1, j) + fy * (v(i + 1, j + 1) - v(i + 1, j));
        low + fx * (high - low)
    }
}

/// `b` with `coth b - 1/b = r`, by bisection (0 for `r = 0`).
fn langevin_inverse(r: f64) -> f64 {
    let langevin = |b: f64| {
        if b < 1e-4 {
            b / 3.0
        } else {
            1.0 / b.tanh() - 1.0 / b
        }
    };
    let (mut lo, mut hi) = (0.0, 200.0);
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if langevin(mid) < r {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// The sun's light scattered once and carried on without scattering again, along
/// [`DIRECTIONS`] directions (a spherical Fibonacci lattice): the second order's
/// light, drawn explicitly with the whole phase function, where the diffusion would
/// make it too isotropic (the droplets' forward lobe carries it far). It travels the
/// scaled medium (`sigma_t - f sigma_s`): what scatters into the lobe goes on with it.
/// Each direction is one sweep of the grid from its upwind side, each cell's light its
/// upwind neighbours' (weighted by the direction's components) attenuated across the
/// cell and its own source added, both exact for a homogeneous cell.
#[derive(Debug, Clone)]
struct OnceScattered {
    directions: Vec<Vec3>,
    /// `[direction][cell]`, per unit sun irradiance (1/sr).
    radiance: Vec<Vec<f32>>,
    /// Per cell its fluence and flux (per unit sun irradiance).
    moments: Vec<Vec4>,
}

/// Directions of the light scattered once: enough to resolve the cloud's forward lobe,
/// about 15 degrees apart (with 48, 30 degrees apart, the tuning views scored 32 of 36
/// within 10 % and 79 % of blocks, against 35 and 84 %).
pub const DIRECTIONS: usize = 192;

impl OnceScattered {
    fn of(medium: &Medium, tables: &PhaseTables, travel: Vec3) -> OnceScattered {
        let directions = directions();
        let weight = 4.0 * std::f32::consts::PI / DIRECTIONS as f32;
        let shares = tables.shares(&directions, travel);
        let f = tables.f();
        let [nx, ny, nz] = medium.dims;
        let radiance: Vec<Vec<f32>> = directions
            .par_iter()
            .zip(&shares)
            .map(|(&w, &share)| sweep(medium, w, Sweep::Scattered(share), f))
            .collect();
        let moments = (0..nx * ny * nz)
            .into_par_iter()
            .map(|cell| {
                directions
                    .iter()
                    .zip(&radiance)
                    .fold(Vec4::ZERO, |m, (w, l)| {
                        m + Vec4::new(1.0, w.x, w.y, w.z) * (l[cell] * weight)
                    })
            })
            .collect();
        OnceScattered {
            directions,
            radiance,
            moments,
        }
    }
}

/// What a [`sweep`] carries.
#[derive(Clone, Copy)]
enum Sweep {
    /// The sun's light scattered once, its source this share (1/sr) times the cell's
    /// scattering and sun; none from outside the grid.
    Scattered(f32),
    /// Radiance 1 from outside the grid and no source: the transmittance from the
    /// grid's faces, each cell's its mean along its path across the cell (the droplets
    /// that scatter it are spread over the cell, and a thick cell passes on a fraction
    /// of its mean: the sky's light on the 2,000-particle cloud read at the cells'
    /// exits came out 19 % dark from above).
    FromOutside,
}

/// A cell's exit over its mean along the path across it, of optical depth `tau`,
/// radiance from upwind and no source: `tau e^-tau / (1 - e^-tau)`.
#[inline]
fn exit_over_mean(tau: f32) -> f32 {
    if tau > 1e-4 {
        tau / tau.exp_m1()
    } else {
        1.0 - 0.5 * tau
    }
}

/// The light along `w` in every cell of `medium` (`what`), through the scaled medium
/// (`f` of each scattering going on ahead): one sweep from the upwind side.
fn sweep(medium: &Medium, w: Vec3, what: Sweep, f: f32) -> Vec<f32> {
    let rate = w.abs() / medium.h;
    let across = rate.x + rate.y + rate.z;
    let (source, outside, means) = match what {
        Sweep::Scattered(share) => (share, 0.0, false),
        Sweep::FromOutside => (0.0, 1.0, true),
    };
    let [nx, ny, nz] = medium.dims;
    let mut l = vec![0.0f32; nx * ny * nz];
    // What each cell passes on downwind: its light where it leaves the cell (with
    // `means`, not its mean), kept apart so that the next cells need not undo the mean.
    let mut passed = vec![0.0f32; nx * ny * nz];
    let order = |n: usize, ahead: bool| -> Vec<usize> {
        if ahead {
            (0..n).collect()
        } else {
            (0..n).rev().collect()
        }
    };
    let (xs, ys, zs) = (
        order(nx, w.x >= 0.0),
        order(ny, w.y >= 0.0),
        order(nz, w.z >= 0.0),
    );
    let dims = [nx, ny, nz];
    let strides = [(ny * nz) as isize, nz as isize, 1isize];
    let step: [isize; 3] =
        std::array::from_fn(|a| if w[a] >= 0.0 { -strides[a] } else { strides[a] });
    for &ix in &xs {
        for &iy in &ys {
            for &iz in &zs {
                let cell = (ix * ny + iy) * nz + iz;
                let index = [ix, iy, iz];
                let mut inflow = 0.0;
                for a in 0..3 {
                    let upwind = if step[a] < 0 {
                        index[a] > 0
                    } else {
                        index[a] + 1 < dims[a]
                    };
                    inflow += rate[a]
                        * if upwind {
                            passed[(cell as isize + step[a]) as usize]
                        } else {
                            outside
                        };
                }
                // Across the cell along `w`: the upwind light attenuated and the cell's
                // own added, exact for a homogeneous cell (a linear upwind step let a
                // thick cell pass a third where it passes e^-2, and the thick cloud's
                // shadowed side came out 1.2-2.3 times too bright).
                let emitted = medium.sigma_s[cell] * medium.sun[cell] * source;
                let extinction = medium.sigma_t[cell] - f * medium.sigma_s[cell];
                let tau = extinction / across;
                let kept = (-tau).exp();
                let own = if tau > 1e-4 {
                    emitted / extinction * (1.0 - kept)
                } else {
                    emitted / across
                };
                let exit = inflow / across * kept;
                (l[cell], passed[cell]) = if means {
                    (exit / exit_over_mean(tau), exit)
                } else {
                    (exit + own, exit + own)
                };
            }
        }
    }
    l
}

/// The phase function tabulated over the cosine ([`LOBE_STEPS`] + 1 values from -1
/// to 1, linear between them): the light scattered once reads it for every direction
/// of every cell.
#[derive(Debug, Clone)]
struct Lobe(Vec<f32>);

/// Steps of the phase's table.
pub const LOBE_STEPS: usize = 2048;

impl Lobe {
    fn new(phase: PhaseFunction) -> Lobe {
        Lobe(
            (0..=LOBE_STEPS)
                .map(|i| phase.eval_f32(-1.0 + 2.0 * i as f32 / LOBE_STEPS as f32))
                .collect(),
        )
    }

    #[inline]
    fn at(&self, cos: f32) -> f32 {
        let x = (cos.clamp(-1.0, 1.0) + 1.0) * 0.5 * LOBE_STEPS as f32;
        let i = (x as usize).min(LOBE_STEPS - 1);
        self.0[i] + (x - i as f32) * (self.0[i + 1] - self.0[i])
    }
}

/// The diffuse light each cell sends toward one eye ([`DiffuseLight::seen_from`]): per
/// cell the sun's (x) and, with a sky, the sky's RGB (y, z, w).
pub(crate) struct Seen {
    min: Vec3,
    cell: f32,
    dims: [usize; 3],
    light: Vec<Vec4>,
    has_sky: bool,
}

impl Seen {
    /// Whether the sky's light comes through the solve.
    pub(crate) fn has_sky(&self) -> bool {
        self.has_sky
    }

    /// The light toward the eye at the world point `p`, trilinear (0 outside the grid).
    #[inline]
    pub(crate) fn at(&self, p: Vec3) -> Vec4 {
        trilinear(&self.light, self.min, self.cell, self.dims, p)
    }

    /// The light toward the eye about a blob's centre `centre` of standard deviation
    /// `spread` m, for the blob's pixels ([`Near`]).
    pub(crate) fn near(&self, centre: Vec3, spread: f32) -> Near<'_> {
        let first_order = (spread < FIRST_ORDER_SPREAD * self.cell).then(|| {
            let slope = std::array::from_fn(|axis| {
                let h = Vec3::AXES[axis] * spread;
                (self.at(centre + h) - self.at(centre - h)) / (2.0 * spread)
            });
            FirstOrder {
                centre,
                value: self.at(centre),
                slope,
            }
        });
        Near {
            seen: self,
            first_order,
        }
    }
}

/// Blobs narrower than this share of a cell (their standard deviation) read the solve
/// to first order about their centre ([`Near`]).
const FIRST_ORDER_SPREAD: f32 = 0.35;

/// [`Seen`] about a blob. A blob narrow beside the cells reads it to first order about
/// its centre, its slopes the differences across twice its standard deviation (its
/// column weights its pixels by a Gaussian of that width): one multiply-add an axis
/// at each pixel where the trilinear read took a third of the frame. What the first
/// order leaves out (the trilinear's products of fractions, its kinks at the cells'
/// faces) grows with the blob's width beside the cell's; wider blobs, which it left
/// visibly wrong at a cloud's thin fringe, read the trilinear at each pixel.
pub(crate) struct Near<'a> {
    seen: &'a Seen,
    first_order: Option<FirstOrder>,
}

/// [`Seen::at`] to first order about `centre`.
struct FirstOrder {
    centre: Vec3,
    value: Vec4,
    /// d/dx, d/dy, d/dz, per metre.
    slope: [Vec4; 3],
}

impl Near<'_> {
    /// The first `CHANNELS` channels of the light (the sun's, then the sky's RGB) at
    /// eight world points, none below 0.
    #[inline(always)]
    pub(crate) fn lanes<const CHANNELS: usize>(&self, p: &[Lanes; 3]) -> [Lanes; CHANNELS] {
        match &self.first_order {
            Some(f) => {
                let d: [Lanes; 3] =
                    std::array::from_fn(|axis| p[axis] - Lanes::splat(f.centre[axis]));
                std::array::from_fn(|c| {
                    let v = (0..3).fold(Lanes::splat(f.value[c]), |v, axis| {
                        v + d[axis] * f.slope[axis][c]
                    });
                    v.fast_max(Lanes::ZERO)
                })
            }
            None => {
                let [px, py, pz] = p.map(|c| c.to_array());
                let at: [Vec4; LANES] =
                    std::array::from_fn(|k| self.seen.at(Vec3::new(px[k], py[k], pz[k])));
                std::array::from_fn(|c| Lanes::new(at.map(|v| v[c])))
            }
        }
    }
}

/// `values` on the grid of cells `cell` m wide whose first centre is `min`, trilinear
/// at `p` (0 beyond the centres).
#[inline(always)]
fn trilinear<T>(values: &[T], min: Vec3, cell: f32, dims: [usize; 3], p: Vec3) -> T
where
    T: Copy + Default + Add<Output = T> + Sub<Output = T> + Mul<f32, Output = T>,
{
    let g = (p - min) / cell;
    let [nx, ny, nz] = dims;
    if !(g.x >= 0.0
        && g.y >= 0.0
        && g.z >= 0.0
        && g.x < (nx - 1) as f32
        && g.y < (ny - 1) as f32
        && g.z < (nz - 1) as f32)
    {
        return T::default();
    }
    let (ix, iy, iz) = (g.x as usize, g.y as usize, g.z as usize);
    let (fx, fy, fz) = (g.x - ix as f32, g.y - iy as f32, g.z - iz as f32);
    let base = (ix * ny + iy) * nz + iz;
    let (sx, sy) = (ny * nz, nz);
    let lerp = |a: T, b: T, t: f32| a + (b - a) * t;
    let lerp_z = |b: usize| lerp(values[b], values[b + 1], fz);
    let lerp_y = |b: usize| lerp(lerp_z(b), lerp_z(b + sy), fy);
    lerp(lerp_y(base), lerp_y(base + sx), fx)
}

/// The solve's grid over a cloud and the particles' medium on it: what stays while only
/// the sun moves. Public for a solve on another device (atmo-gpu's), which starts from
/// it.
#[derive(Debug, Clone, PartialEq)]
pub struct SolveGrid {
    /// World position of cell `(0, 0, 0)`'s centre, m.
    pub first_centre: Vec3,
    /// The cells' side, m.
    pub cell: f32,
    /// Cells along x, y and z; the per-cell values are `[x][y][z]`, z fastest.
    pub dims: [usize; 3],
    /// Per cell the particles' mean extinction and scattering coefficients, 1/m.
    pub sigma_t: Vec<f32>,
    pub sigma_s: Vec<f32>,
}

impl SolveGrid {
    /// The grid over `particles`' reach, `settings.cells` along the longest side and
    /// two cells of air around, and each cell's mean of the particles' extinction
    /// (differences of `erf`, the Gaussian being separable). Refuses a grid out of range
    /// and no particles.
    pub fn of(particles: &[Particle], settings: &Diffusion) -> Result<SolveGrid> {
        settings.validate()?;
        if particles.is_empty() {
            return Err(Error::Invalid("the transfer solve needs particles".into()));
        }
        let (lo, hi) = particles.iter().fold(
            (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
            |(lo, hi), p| {
                let r = Vec3::splat(p.reach());
                (lo.min(p.position - r), hi.max(p.position + r))
            },
        );
        let extent = hi - lo;
        let h = extent.max_element() / settings.cells as f32;
        let dims = extent
            .to_array()
            .map(|e| ((e / h).ceil() as usize).max(1) + 2 * MARGIN);
        let centre = 0.5 * (lo + hi);
        let size = Vec3::new(dims[0] as f32, dims[1] as f32, dims[2] as f32) * h;
        let min = centre - 0.5 * size;
        let [nx, ny, nz] = dims;
        let n = nx * ny * nz;
        // Each particle's mean over the cells it reaches, separable: per axis the
        // Gaussian's share of each cell, `(erf(b) - erf(a)) / 2` over the cell's side
        // in units of the Gaussian's integral.
        let sums = particles
            .par_chunks(1024)
            .fold(
                || vec![[0.0f32; 2]; n],
                |mut sums, chunk| {
                    for p in chunk {
                        let s = p.sigma();
                        let scale = 1.0 / (std::f32::consts::SQRT_2 * s);
                        let axis = |a: usize| -> (usize, Vec<f32>) {
                            let c = (p.position[a] - min[a]) / h;
                            let r = p.reach() / h;
                            let i0 = (c - r).floor().max(0.0) as usize;
                            let i1 = ((c + r).ceil() as usize).min(dims[a]);
                            let weights = (i0..i1)
                                .map(|i| {
                                    let e = |x: f32| erf_table((x - c) * h * scale);
                                    0.5 * (e(i as f32 + 1.0) - e(i as f32))
                                })
                                .collect();
                            (i0, weights)
                        };
                        let ((x0, wx), (y0, wy), (z0, wz)) = (axis(0), axis(1), axis(2));
                        // The Gaussian's integral over the cell's volume, times its
                        // peak: its mean over the cell.
                        let peak = p.density * (2.0 * std::f32::consts::PI).powf(1.5) * s.powi(3)
                            / h.powi(3);
                        for (i, wx) in wx.iter().enumerate() {
                            for (j, wy) in wy.iter().enumerate() {
                                let row = ((x0 + i) * ny + y0 + j) * nz + z0;
                                let w = peak * wx * wy;
                                for (k, wz) in wz.iter().enumerate() {
                                    let e = w * wz;
                                    let cell = &mut sums[row + k];
                                    cell[0] += e;
                                    cell[1] += e * p.albedo;
                                }
                            }
                        }
                    }
                    sums
                },
            )
            .reduce(
                || vec![[0.0f32; 2]; n],
                |mut a, b| {
                    a.iter_mut().zip(&b).for_each(|(a, b)| {
                        a[0] += b[0];
                        a[1] += b[1];
                    });
                    a
                },
            );
        Ok(SolveGrid {
            first_centre: min + Vec3::splat(0.5 * h),
            cell: h,
            dims,
            sigma_t: sums.iter().map(|v| v[0]).collect(),
            sigma_s: sums.iter().map(|v| v[1]).collect(),
        })
    }

    /// How many cells.
    pub fn cells(&self) -> usize {
        self.dims.iter().product()
    }

    /// The world position of `cell`'s centre, m.
    pub fn centre(&self, cell: usize) -> Vec3 {
        let [_, ny, nz] = self.dims;
        let index = Vec3::new(
            (cell / (ny * nz)) as f32,
            (cell / nz % ny) as f32,
            (cell % nz) as f32,
        );
        self.first_centre + index * self.cell
    }
}

impl Medium {
    /// The medium of `grid` and the sources of the sun lit through `buffer` (the module
    /// doc).
    fn of(grid: &SolveGrid, buffer: &IntensityBuffer, g: f32) -> Medium {
        let n = grid.cells();
        let h = grid.cell;
        let mut medium = Medium {
            dims: grid.dims,
            h,
            sigma_tr: vec![0.0; n],
            sigma_a: vec![0.0; n],
            q0: vec![0.0; n],
            q1: vec![Vec3::ZERO; n],
            sigma_t: grid.sigma_t.clone(),
            sigma_s: grid.sigma_s.clone(),
            sun: vec![0.0; n],
            inside: grid.sigma_t.iter().map(|t| t * h >= THIN).collect(),
        };
        medium
            .sigma_tr
            .par_iter_mut()
            .zip(&mut medium.sigma_a)
            .zip(&mut medium.sun)
            .enumerate()
            .for_each(|(cell, ((tr, a), sun))| {
                let (t, s) = (grid.sigma_t[cell], grid.sigma_s[cell]);
                *tr = (t - g * s).max(0.0);
                *a = (t - s).max(0.0);
                *sun = buffer.sample(grid.centre(cell));
            });
        medium
    }

    /// The diffusion's sources: the second scattering of the light scattered `once`,
    /// less the share `f` that goes on ahead with it (the module doc).
    fn scatter(&mut self, once: &OnceScattered, g: f32, f: f32) {
        let g_scaled = (g - f) / (1.0 - f);
        for (cell, m) in once.moments.iter().enumerate() {
            let second = (1.0 - f) * self.sigma_s[cell];
            self.q0[cell] = second * m.x;
            self.q1[cell] = g_scaled * second * Vec3::new(m.y, m.z, m.w);
        }
    }

    /// The cell to the + side of `cell` along `axis`, if any.
    #[inline]
    fn next(&self, cell: usize, axis: usize) -> Option<usize> {
        let [_, ny, nz] = self.dims;
        let (i, stride) = match axis {
            0 => (cell / (ny * nz), ny * nz),
            1 => (cell / nz % ny, nz),
            _ => (cell % nz, 1),
        };
        (i + 1 < self.dims[axis]).then_some(cell + stride)
    }

    /// `values` with each cell of clear air beside the cloud given the mean of its
    /// cloud neighbours': the cloud's light up to its faces, so that lookups between a
    /// fringe cell and the air beside it do not fade toward 0 across the fringe.
    fn dilated(&self, values: Vec<Vec4>) -> Vec<Vec4> {
        (0..values.len())
            .into_par_iter()
            .map(|cell| {
                if self.inside[cell] {
                    return values[cell];
                }
                let (sum, count) = (0..3)
                    .flat_map(|a| [self.next(cell, a), self.previous(cell, a)])
                    .flatten()
                    .filter(|&n| self.inside[n])
                    .fold((Vec4::ZERO, 0), |(s, k), n| (s + values[n], k + 1));
                if count > 0 {
                    sum / count as f32
                } else {
                    Vec4::ZERO
                }
            })
            .collect()
    }

    /// The cell to the - side of `cell` along `axis`, if any.
    #[inline]
    fn previous(&self, cell: usize, axis: usize) -> Option<usize> {
        let [_, ny, nz] = self.dims;
        let stride = [ny * nz, nz, 1][axis];
        (medium_index(self, cell, axis) > 0).then(|| cell - stride)
    }

    /// Whether the face between `cell` and its neighbour (if any) is inside the cloud.
    #[inline]
    fn joined(&self, cell: usize, neighbour: Option<usize>) -> bool {
        neighbour.is_some_and(|n| self.inside[cell] && self.inside[n])
    }

    /// How many of a cloud cell's faces let light out: on the grid's boundary or to
    /// clear air (0 for a cell of air).
    #[inline]
    fn outer_faces(&self, cell: usize) -> usize {
        if !self.inside[cell] {
            return 0;
        }
        (0..3)
            .map(|a| {
                usize::from(!self.joined(cell, self.next(cell, a)))
                    + usize::from(!self.joined(cell, self.previous(cell, a)))
            })
            .sum()
    }

    /// The light leaving `cell` through its outer faces per unit fluence and volume
    /// (1/m).
    #[inline]
    fn outflow(&self, cell: usize) -> f32 {
        self.outer_faces(cell) as f32 * self.marshak(cell) / self.h
    }

    /// The flux out of `cell` through one of its outer faces per unit fluence:
    /// Marshak's `F . n = phi / 2` at the face, behind half a cell of diffusion.
    #[inline]
    fn marshak(&self, cell: usize) -> f32 {
        1.0 / (0.5 * self.h / self.plain_d(cell) + 2.0)
    }

    /// `D` of a cell from its own `sigma_tr` alone (no limiter), capped as faces' are.
    #[inline]
    fn plain_d(&self, cell: usize) -> f32 {
        (1.0 / (3.0 * self.sigma_tr[cell])).min(self.d_max())
    }

    /// The most `D` may be (m): the grid's longest side, as far as light streaming
    /// through clear air diffuses in a solve over it.
    fn d_max(&self) -> f32 {
        *self.dims.iter().max().expect("three axes") as f32 * self.h
    }
}

/// `D` on every inner face (`[axis][cell]`: the face to the + side of the cell, 0
/// where either side is clear air) and the system's diagonal.
struct Faces {
    d: [Vec<f32>; 3],
    /// The system's diagonal per cell.
    diagonal: Vec<f32>,
}

impl Faces {
    /// `D = 1 / 3 sigma_tr` of the faces' mean `sigma_tr` (capped): the first lag.
    fn plain(medium: &Medium) -> Faces {
        Faces::with(medium, |cell, next, _| {
            let tr = 0.5 * (medium.sigma_tr[cell] + medium.sigma_tr[next]);
            (1.0 / (3.0 * tr)).min(medium.d_max())
        })
    }

    /// `D` by the flux limiter from the fluence `phi` (the module doc).
    fn limited(medium: &Medium, phi: &[f32]) -> Faces {
        let h = medium.h;
        // The fluence's gradient at each cell by central differences.
        let gradient: Vec<Vec3> = (0..phi.len())
            .into_par_iter()
            .map(|cell| {
                Vec3::from_array(std::array::from_fn(|a| {
                    let up = medium.next(cell, a).map_or(0.0, |c| phi[c]);
                    let down = medium.previous(cell, a).map_or(0.0, |c| phi[c]);
                    (up - down) / (2.0 * h)
                }))
            })
            .collect();
        Faces::with(medium, |cell, next, axis| {
            let mut grad = 0.5 * (gradient[cell] + gradient[next]);
            grad[axis] = (phi[next] - phi[cell]) / h;
            let phi_f = 0.5 * (phi[cell] + phi[next]);
            let tr = 0.5 * (medium.sigma_tr[cell] + medium.sigma_tr[next]);
            limited_d(grad.length(), phi_f, tr).min(medium.d_max())
        })
    }

    /// Faces whose inner `D` is `d(cell, next, axis)`; outer faces by the cell's own.
    fn with(medium: &Medium, d: impl Fn(usize, usize, usize) -> f32 + Sync) -> Faces {
        let n = medium.sigma_tr.len();
        let d: [Vec<f32>; 3] = std::array::from_fn(|axis| {
            (0..n)
                .into_par_iter()
                .map(|cell| match medium.next(cell, axis) {
                    Some(next) if medium.joined(cell, Some(next)) => d(cell, next, axis),
                    _ => 0.0,
                })
                .collect()
        });
        let h = medium.h;
        let diagonal = (0..n)
            .into_par_iter()
            .map(|cell| {
                if !medium.inside[cell] {
                    // Clear air: phi = 0, apart from the system.
                    return 1.0;
                }
                let mut sum = medium.outflow(cell) + medium.sigma_a[cell];
                for (a, d) in d.iter().enumerate() {
                    sum += d[cell] / (h * h);
                    if let Some(prev) = medium.previous(cell, a) {
                        sum += d[prev] / (h * h);
                    }
                }
                sum
            })
            .collect();
        Faces { d, diagonal }
    }

    /// The drift of the source `q1` across the face to the + side of `cell` along
    /// `axis` (m/m^3 per unit light): `3 D Q1 . n`, `Q1` the two cells' mean.
    #[inline]
    fn drift(&self, q1: &[Vec3], cell: usize, next: usize, axis: usize) -> f32 {
        3.0 * self.d[axis][cell] * 0.5 * (q1[cell] + q1[next])[axis]
    }

    /// The system's right side for the sources `q0` and `q1`: `Q0` less the divergence
    /// of the drift.
    fn right_side(&self, medium: &Medium, q0: &[f32], q1: &[Vec3]) -> Vec<f32> {
        let h = medium.h;
        (0..q0.len())
            .into_par_iter()
            .map(|cell| {
                if !medium.inside[cell] {
                    return 0.0;
                }
                let mut b = q0[cell];
                for a in 0..3 {
                    if let Some(next) = medium.next(cell, a) {
                        b -= self.drift(q1, cell, next, a) / h;
                    }
                    if let Some(prev) = medium.previous(cell, a) {
                        b += self.drift(q1, prev, cell, a) / h;
                    }
                }
                b
            })
            .collect()
    }

    /// `y = A x`, `A` the system's matrix.
    fn apply(&self, medium: &Medium, x: &[f32], y: &mut [f32]) {
        let [nx, ny, nz] = medium.dims;
        let inv_h2 = 1.0 / (medium.h * medium.h);
        let [dx, dy, dz] = &self.d;
        // The loops spelled out: neighbours by index, no divisions (the solve's time is
        // this product's).
        y.par_chunks_mut(ny * nz)
            .enumerate()
            .for_each(|(ix, slab)| {
                let base = ix * ny * nz;
                for iy in 0..ny {
                    for iz in 0..nz {
                        let cell = base + iy * nz + iz;
                        let mut v = self.diagonal[cell] * x[cell];
                        let mut off = 0.0;
                        if iz + 1 < nz {
                            off += dz[cell] * x[cell + 1];
                        }
                        if iz > 0 {
                            off += dz[cell - 1] * x[cell - 1];
                        }
                        if iy + 1 < ny {
                            off += dy[cell] * x[cell + nz];
                        }
                        if iy > 0 {
                            off += dy[cell - nz] * x[cell - nz];
                        }
                        if ix + 1 < nx {
                            off += dx[cell] * x[cell + ny * nz];
                        }
                        if ix > 0 {
                            off += dx[cell - ny * nz] * x[cell - ny * nz];
                        }
                        v -= off * inv_h2;
                        slab[iy * nz + iz] = v;
                    }
                }
            });
    }

    /// Per cell `phi / 4 pi` and `F / 4 pi` of the field of sources drifting by `q1`,
    /// `F` the mean of the flux through its two faces along each axis (the outer faces'
    /// by Marshak's condition).
    fn values(&self, medium: &Medium, phi: &[f32], q1: &[Vec3]) -> Vec<Vec4> {
        let h = medium.h;
        let flux = |cell: usize, next: usize, a: usize| {
            -self.d[a][cell] * (phi[next] - phi[cell]) / h + self.drift(q1, cell, next, a)
        };
        let four_pi = 4.0 * std::f32::consts::PI;
        (0..phi.len())
            .into_par_iter()
            .map(|cell| {
                if !medium.inside[cell] {
                    return Vec4::ZERO;
                }
                let out = phi[cell] * medium.marshak(cell);
                let f = Vec3::from_array(std::array::from_fn(|a| {
                    let up = match medium.next(cell, a) {
                        Some(next) if medium.joined(cell, Some(next)) => flux(cell, next, a),
                        _ => out,
                    };
                    let down = match medium.previous(cell, a) {
                        Some(prev) if medium.joined(cell, Some(prev)) => flux(prev, cell, a),
                        _ => -out,
                    };
                    0.5 * (up + down)
                }));
                Vec4::new(phi[cell].max(0.0), f.x, f.y, f.z) / four_pi
            })
            .collect()
    }
}

/// The sky's light through the same solve (docs/clouds.md, "Every order: the transfer
/// solve"), as the sun's: its radiance from every direction carried in from the grid's
/// faces without scattering (the sweeps, through the scaled medium, of radiance 1 from
/// outside: the transmittance along each direction, the same for every channel), a
/// droplet scattering it toward the eye by the whole phase (the sky's first order), and
/// the rest of its scattering the source of the diffusion, with the sun's field's `D`
/// (its second order and higher). Per linear-sRGB channel.
#[derive(Debug, Clone)]
struct SkyField {
    /// `[direction][cell]`: the transmittance from the grid's faces along the
    /// direction ([`directions`]); the particles' alone, so kept while they stay.
    through: Vec<Vec<f32>>,
    /// Per direction the sky's radiance arriving along it (from the opposite way), RGB.
    radiance: Vec<Vec3>,
    /// Per cell and channel `phi / 4 pi` and `F / 4 pi` of the diffuse field.
    values: Vec<[Vec4; 3]>,
    /// Per channel the diffuse field's fluence, kept to start the next solve from.
    fluence: [Vec<f32>; 3],
    iterations: usize,
}

impl SkyField {
    /// The field of `sky` in `medium` with the sun's last `faces`, started from
    /// `previous`'s fluence and reading `through` where the medium is the one it was
    /// swept through; `None` for no sky.
    fn solve(
        medium: &Medium,
        faces: &Faces,
        tables: &PhaseTables,
        directions: &[Vec3],
        sky: &SkyLight,
        previous: Option<&SkyField>,
        through: Option<&[Vec<f32>]>,
    ) -> Option<SkyField> {
        if sky.mean().max_element() <= 0.0 {
            return None;
        }
        let (g, f) = (tables.g(), tables.f());
        let through: Vec<Vec<f32>> = match through {
            Some(kept) => kept.to_vec(),
            None => directions
                .par_iter()
                .map(|&w| sweep(medium, w, Sweep::FromOutside, f))
                .collect(),
        };
        debug_assert_eq!(directions.len(), DIRECTIONS, "the sky's directions");
        let radiance = sky.around().to_vec();
        let weight = 4.0 * std::f32::consts::PI / directions.len() as f32;
        let n = medium.sigma_t.len();
        // Per cell the uncollided light's fluence and flux, per channel.
        let moments: Vec<[Vec4; 3]> = (0..n)
            .into_par_iter()
            .map(|cell| {
                let mut m = [Vec4::ZERO; 3];
                for ((w, t), l) in directions.iter().zip(&through).zip(&radiance) {
                    let basis = Vec4::new(1.0, w.x, w.y, w.z) * (t[cell] * weight);
                    for (m, l) in m.iter_mut().zip(l.to_array()) {
                        *m += basis * l;
                    }
                }
                m
            })
            .collect();
        let g_scaled = (g - f) / (1.0 - f);
        let mut iterations = 0;
        let fields: [(Vec<f32>, Vec<Vec4>); 3] = std::array::from_fn(|c| {
            let second = |cell: usize| (1.0 - f) * medium.sigma_s[cell];
            let q0: Vec<f32> = (0..n)
                .map(|cell| second(cell) * moments[cell][c].x)
                .collect();
            let q1: Vec<Vec3> = (0..n)
                .map(|cell| {
                    let m = moments[cell][c];
                    g_scaled * second(cell) * Vec3::new(m.y, m.z, m.w)
                })
                .collect();
            let rhs = faces.right_side(medium, &q0, &q1);
            let mut phi = previous.map_or_else(|| vec![0.0; n], |p| p.fluence[c].clone());
            iterations += conjugate_gradients(medium, faces, &rhs, &mut phi);
            let values = medium.dilated(faces.values(medium, &phi, &q1));
            (phi, values)
        });
        let [(f0, v0), (f1, v1), (f2, v2)] = fields;
        let values = v0
            .iter()
            .zip(&v1)
            .zip(&v2)
            .map(|((a, b), c)| [*a, *b, *c])
            .collect();
        Some(SkyField {
            through,
            radiance,
            values,
            fluence: [f0, f1, f2],
            iterations,
        })
    }
}

/// `cell`'s index along `axis`.
#[inline]
fn medium_index(medium: &Medium, cell: usize, axis: usize) -> usize {
    let [_, ny, nz] = medium.dims;
    match axis {
        0 => cell / (ny * nz),
        1 => cell / nz % ny,
        _ => cell % nz,
    }
}

/// Levermore and Pomraning's `D = lambda(R) / sigma_tr`, `lambda = (coth R - 1/R) /
/// R`, with `R = |grad phi| / (k sigma_tr phi)` and `D` times `k` ([`STREAMING`]): 1 /
/// (3 sigma_tr) deep in the cloud, `k phi / |grad phi|` where light streams, written
/// so that clear air (`sigma_tr = 0`) gives the latter.
fn limited_d(grad: f32, phi: f32, sigma_tr: f32) -> f32 {
    let k = STREAMING;
    if !(phi > 0.0 && grad > 0.0) {
        return 1.0 / (3.0 * sigma_tr);
    }
    if sigma_tr <= 0.0 || sigma_tr.is_nan() {
        return k * phi / grad;
    }
    let r = grad / (k * sigma_tr * phi);
    if r < 1e-3 {
        return 1.0 / (3.0 * sigma_tr);
    }
    let coth = if r > 20.0 { 1.0 } else { 1.0 / r.tanh() };
    (coth - 1.0 / r) * k * phi / grad
}

/// Solves `A phi = b` from the `phi` given by conjugate gradients preconditioned by
/// the diagonal, to [`TOLERANCE`]; the iterations taken.
fn conjugate_gradients(medium: &Medium, faces: &Faces, b: &[f32], phi: &mut [f32]) -> usize {
    let n = b.len();
    let dot = |x: &[f32], y: &[f32]| -> f64 {
        x.par_iter()
            .zip(y)
            .map(|(a, b)| *a as f64 * *b as f64)
            .sum()
    };
    let mut q = vec![0.0f32; n];
    faces.apply(medium, phi, &mut q);
    let mut r: Vec<f32> = b.par_iter().zip(&q).map(|(b, q)| b - q).collect();
    let precondition = |r: &[f32], z: &mut Vec<f32>| {
        z.par_iter_mut()
            .zip(r)
            .zip(&faces.diagonal)
            .for_each(|((z, r), d)| *z = r / d);
    };
    let mut z = vec![0.0f32; n];
    precondition(&r, &mut z);
    let mut p = z.clone();
    let mut rz = dot(&r, &z);
    let goal = TOLERANCE * dot(b, b).sqrt();
    let limit = 4 * n.min(5000);
    for iteration in 0..limit {
        if dot(&r, &r).sqrt() <= goal {
            return iteration;
        }
        faces.apply(medium, &p, &mut q);
        let alpha = (rz / dot(&p, &q)) as f32;
        phi.par_iter_mut()
            .zip(&p)
            .for_each(|(x, p)| *x += alpha * p);
        r.par_iter_mut().zip(&q).for_each(|(r, q)| *r -= alpha * q);
        precondition(&r, &mut z);
        let rz_next = dot(&r, &z);
        let beta = (rz_next / rz) as f32;
        rz = rz_next;
        p.par_iter_mut()
            .zip(&z)
            .for_each(|(p, z)| *p = z + beta * *p);
    }
    limit
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::clouds::buffer::Splat;
    use crate::clouds::generator::Cumulus;

    /// A cumulus of `count` particles of `albedo`, the sun from `to_sun`, its buffer and
    /// its solve's medium and fluence.
    fn solved(count: usize, albedo: f32, to_sun: Vec3) -> (Medium, Faces, Vec<f32>, DiffuseLight) {
        let particles: Vec<Particle> = Cumulus {
            particles: count,
            density: 0.02,
            albedo,
            ..Cumulus::default()
        }
        .generate();
        let buffer = IntensityBuffer::new(&particles, to_sun, 128, 0.0, Splat::Pieces).unwrap();
        let phase = PhaseFunction::CloudMie;
        let settings = Diffusion { cells: 32 };
        let light = DiffuseLight::solve(
            &particles,
            &buffer,
            to_sun,
            phase,
            &SkyLight::NONE,
            &settings,
            None,
        )
        .unwrap();
        let tables = PhaseTables::new(phase);
        let (g, f) = (tables.g(), tables.f());
        let grid = SolveGrid::of(&particles, &settings).unwrap();
        let mut medium = Medium::of(&grid, &buffer, g);
        let once = OnceScattered::of(&medium, &tables, -to_sun);
        medium.scatter(&once, g, f);
        let faces = Faces::limited(&medium, &light.fluence);
        let phi = light.fluence.clone();
        (medium, faces, phi, light)
    }

    /// Energy: in a cloud that absorbs nothing, all the light its first scattering
    /// puts into the diffuse field leaves through the grid's faces (the flux out by
    /// Marshak's condition), within 2 %; with absorption, less.
    #[test]
    fn a_cloud_that_absorbs_nothing_lets_out_all_the_light_scattered_into_it() {
        let to_sun = Vec3::new(0.3, 0.8, -0.2).normalize();
        let balance = |albedo: f32| {
            let (medium, faces, phi, light) = solved(800, albedo, to_sun);
            let source: f64 = medium.q0.iter().map(|q| *q as f64).sum();
            // Solved again with the last lag's faces: the outflow of the system solved.
            let mut phi2 = phi.clone();
            let rhs = faces.right_side(&medium, &medium.q0, &medium.q1);
            conjugate_gradients(&medium, &faces, &rhs, &mut phi2);
            let out: f64 = (0..phi2.len())
                .map(|c| (medium.outflow(c) * phi2[c]) as f64)
                .sum();
            assert!(light.iterations > 0);
            out / source
        };
        let kept = balance(1.0);
        assert!((kept - 1.0).abs() < 0.02, "{kept}");
        let absorbing = balance(0.9);
        assert!(absorbing < 0.9 * kept, "{absorbing}");
    }

    /// A solve started from another sun's (as a moving sun's frames are) ends where a
    /// solve from scratch does: the lags and the conjugate gradients converged.
    #[test]
    fn a_solve_from_the_last_one_ends_where_one_from_scratch_does() {
        let particles: Vec<Particle> = Cumulus {
            particles: 600,
            density: 0.02,
            ..Cumulus::default()
        }
        .generate();
        let settings = Diffusion { cells: 24 };
        let phase = PhaseFunction::CloudMie;
        let lit = |to_sun: Vec3| {
            IntensityBuffer::new(&particles, to_sun, 64, 0.0, Splat::Pieces).unwrap()
        };
        let (a, b) = (
            Vec3::new(0.2, 0.9, 0.1).normalize(),
            Vec3::new(0.3, 0.85, 0.1).normalize(),
        );
        let first = DiffuseLight::solve(
            &particles,
            &lit(a),
            a,
            phase,
            &SkyLight::NONE,
            &settings,
            None,
        )
        .unwrap();
        let warm = DiffuseLight::solve(
            &particles,
            &lit(b),
            b,
            phase,
            &SkyLight::NONE,
            &settings,
            Some(&first),
        )
        .unwrap();
        let cold = DiffuseLight::solve(
            &particles,
            &lit(b),
            b,
            phase,
            &SkyLight::NONE,
            &settings,
            None,
        )
        .unwrap();
        assert!(
            warm.iterations < cold.iterations,
            "{} {}",
            warm.iterations,
            cold.iterations
        );
        let total = |l: &DiffuseLight| l.fluence.iter().map(|v| *v as f64).sum::<f64>();
        let (w, c) = (total(&warm), total(&cold));
        assert!((w / c - 1.0).abs() < 0.01, "{w} {c}");
        // And the sun moved: the light moved with it.
        assert!((total(&first) / c - 1.0).abs() > 1e-4);
    }

    /// `n`^3 cells `h` m wide of a medium that scatters `sigma` (1/m) and absorbs
    /// nothing, lit by the sun unshadowed.
    fn homogeneous(n: usize, h: f32, sigma: f32) -> Medium {
        let cells = n * n * n;
        Medium {
            dims: [n, n, n],
            h,
            sigma_tr: vec![0.0; cells],
            sigma_a: vec![0.0; cells],
            q0: vec![0.0; cells],
            q1: vec![Vec3::ZERO; cells],
            sigma_t: vec![sigma; cells],
            sigma_s: vec![sigma; cells],
            sun: vec![1.0; cells],
            inside: vec![true; cells],
        }
    }

    /// The sweep of the light scattered once is exact along an axis through a
    /// homogeneous medium, `S / sigma' (1 - e^(-sigma' x))` at the far side of the
    /// `x` crossed, `sigma'` the scaled extinction; and no light runs against it.
    #[test]
    fn the_sweep_along_an_axis_is_exponential() {
        let (n, h, sigma, f) = (12, 50.0f32, 0.01f32, 0.5f32);
        let medium = homogeneous(n, h, sigma);
        let source = 0.3;
        let l = sweep(&medium, Vec3::X, Sweep::Scattered(source), f);
        let scaled = sigma * (1.0 - f);
        for ix in 0..n {
            let cell = (ix * n + 5) * n + 7;
            let exact = sigma * source / scaled * (1.0 - (-scaled * h * (ix + 1) as f32).exp());
            assert!(
                (l[cell] / exact - 1.0).abs() < 1e-4,
                "{ix}: {} {exact}",
                l[cell]
            );
        }
        let back = sweep(&medium, -Vec3::X, Sweep::Scattered(source), f);
        assert!((back[(n - 1) * n * n] - l[0]).abs() < 1e-6 * l[0]);
    }

    /// The transmittance swept from outside the grid is each cell's mean along its path:
    /// along an axis through a homogeneous medium, `(e^(-s x0) - e^(-s x1)) / (s h)`
    /// over the cell from `x0` to `x1`, `s` the scaled extinction.
    #[test]
    fn the_sweep_from_outside_holds_each_cells_mean() {
        let (n, h, sigma, f) = (10, 40.0f32, 0.02f32, 0.5f32);
        let medium = homogeneous(n, h, sigma);
        let t = sweep(&medium, -Vec3::Y, Sweep::FromOutside, f);
        let s = sigma * (1.0 - f);
        for iy in 0..n {
            // Travelling down from the top face: the cell's depth from it.
            let (x0, x1) = ((n - 1 - iy) as f32 * h, (n - iy) as f32 * h);
            let exact = ((-s * x0).exp() - (-s * x1).exp()) / (s * h);
            let got = t[(3 * n + iy) * n + 4];
            assert!((got / exact - 1.0).abs() < 1e-4, "{iy}: {got} {exact}");
        }
    }

    /// The closure's first two Legendre terms are P1's: with no flux, the light
    /// scattered is `phi / 4 pi` every way; a field streaming along `w` sends more
    /// forward than back, and more than P1 says forward where the flux is large.
    #[test]
    fn the_closure_is_isotropic_without_flux_and_forward_with_it() {
        let closure = Closure::new(PhaseFunction::CloudMie);
        for c in [-1.0, 0.0, 1.0] {
            assert!(
                (closure.at(0.0, c) - 1.0).abs() < 1e-3,
                "{}",
                closure.at(0.0, c)
            );
        }
        let g = 0.525;
        // Small flux: P1's 1 + 3 g r cos.
        let r = 0.05;
        assert!((closure.at(r, 1.0) - (1.0 + 3.0 * g * r)).abs() < 0.01);
        let r = 0.6;
        assert!(closure.at(r, 1.0) > 1.0 + 3.0 * g * r);
        assert!(closure.at(r, 1.0) > 3.0 * closure.at(r, -1.0));
    }

    /// The solve's light is at least 0 everywhere, greatest deep in the cloud, more on
    /// the sun's side of it than on the far side, and the flux out of the top of a
    /// cloud lit from above goes up (a thick cloud sends back more than it lets
    /// through).
    #[test]
    fn the_diffuse_light_is_positive_and_drifts_with_the_sun() {
        let to_sun = Vec3::new(0.0, 1.0, 0.0);
        let (medium, _, phi, light) = solved(400, 0.99, to_sun);
        assert!(phi.iter().all(|p| *p >= -1e-4), "negative fluence");
        // The most within the cloud's cells that have no face to the air, the most on
        // its surface, and none in the air.
        let most = |keep: &dyn Fn(usize) -> bool| {
            (0..phi.len())
                .filter(|&c| keep(c))
                .map(|c| phi[c])
                .fold(0.0f32, f32::max)
        };
        let deep = most(&|c| medium.inside[c] && medium.outer_faces(c) == 0);
        let surface = most(&|c| medium.outer_faces(c) > 0);
        assert!(deep > 1.5 * surface, "{deep} {surface}");
        assert_eq!(most(&|c| !medium.inside[c]), 0.0);
        let [_, ny, nz] = medium.dims;
        // The mean over the cloud's cells in the upper and the lower half of the grid.
        let half = |upper: bool| -> f32 {
            let cells: Vec<f32> = (0..phi.len())
                .filter(|&c| medium.sigma_tr[c] > 1e-3 && (c / nz % ny >= ny / 2) == upper)
                .map(|c| phi[c])
                .collect();
            cells.iter().sum::<f32>() / cells.len() as f32
        };
        assert!(half(true) > half(false), "{} {}", half(true), half(false));
        // Per cell (phi, 3 g F) / 4 pi: F_y in the top layer of cells inside the grid.
        let top = (0..phi.len()).filter(|&c| c / nz % ny == ny - MARGIN - 1);
        let up: f32 = top.map(|c| light.values[c].z).sum();
        assert!(up > 0.0, "{up}");
    }

    /// A blob narrow beside the cells reads the solve to first order about its centre:
    /// over the points its pixels read (a Gaussian of its width about it), on a solved
    /// cumulus, within 2.5 % of the trilinear read on average (the light at the centre
    /// alone: 8 %) and, for nine blobs in ten, within 15 % of the blob's brightest
    /// light at worst (at the cloud's edge, where the trilinear falls to 0 past the
    /// outer cells); a wide blob reads the trilinear itself.
    #[test]
    fn a_narrow_blob_reads_the_solve_to_first_order_about_its_centre() {
        let to_sun = Vec3::new(0.3, 0.8, 0.2).normalize();
        let (.., light) = solved(2000, 0.9, to_sun);
        let seen = light.seen_from(Vec3::new(-3000.0, 800.0, 2500.0));
        let cell = seen.cell;
        let mut rng = crate::clouds::generator::SplitMix64::new(5);
        // Sums of |error| of the first order and of the centre's light alone, of the
        // trilinear light, and per blob its worst error over its brightest light.
        let (mut first_error, mut centre_error, mut total) = (0.0f64, 0.0f64, 0.0f64);
        let mut worst = Vec::new();
        while worst.len() < 300 {
            let centre = seen.min
                + Vec3::from_array(std::array::from_fn(|axis| {
                    rng.range(1.0, seen.dims[axis] as f32 - 2.0) * cell
                }));
            let here = seen.at(centre).x;
            if here <= 0.0 {
                continue;
            }
            let spread = rng.range(0.1, FIRST_ORDER_SPREAD) * cell;
            let near = seen.near(centre, spread);
            assert!(near.first_order.is_some());
            let (mut blob_error, mut brightest) = (0.0f32, here);
            for _ in 0..8 {
                // A point a Gaussian of the blob's width from its centre (Box-Muller).
                let offset = Vec3::from_array(std::array::from_fn(|_| {
                    let (u, v) = (rng.range(1e-6, 1.0), rng.range(0.0, 1.0));
                    (-2.0 * u.ln()).sqrt() * (std::f32::consts::TAU * v).cos()
                }));
                let p = centre + spread * offset;
                let lanes: [Lanes; 3] = std::array::from_fn(|axis| Lanes::splat(p[axis]));
                let first = near.lanes::<1>(&lanes)[0].to_array()[0];
                let exact = seen.at(p).x;
                first_error += (first - exact).abs() as f64;
                centre_error += (here - exact).abs() as f64;
                total += exact as f64;
                blob_error = blob_error.max((first - exact).abs());
                brightest = brightest.max(exact);
            }
            worst.push(blob_error / brightest);
        }
        let (first, centre) = (first_error / total, centre_error / total);
        worst.sort_by(f32::total_cmp);
        let ninth = worst[worst.len() * 9 / 10];
        assert!(
            first < 0.025 && centre > 0.06 && ninth < 0.15,
            "first order {first}, centre alone {centre}, nine in ten blobs within {ninth}"
        );
        // Wider blobs read the trilinear itself.
        let centre = seen.min + 0.5 * cell * Vec3::from_array(seen.dims.map(|d| d as f32));
        let wide = seen.near(centre, FIRST_ORDER_SPREAD * cell * 1.01);
        assert!(wide.first_order.is_none());
        let p = centre + Vec3::new(0.3, -0.2, 0.1) * cell;
        let lanes: [Lanes; 3] = std::array::from_fn(|axis| Lanes::splat(p[axis]));
        assert_eq!(
            wide.lanes::<4>(&lanes).map(|l| l.to_array()[0]),
            seen.at(p).to_array()
        );
    }
}
