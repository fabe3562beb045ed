//! The light of the orders past the first by solving its transfer through the cloud
//! (docs/clouds.md, "Every order: the transfer solve"), in place of a model of a few
//! optical depths ([`super::transfer`], [`super::octaves`]), which cannot know how
//! light diffuses through a particular cloud's shape.
//!
//! The droplets' phase function is strongly forward, so the diffusion approximation is
//! taken after delta-Eddington scaling (Joseph, Wiscombe and Weinman 1976): a share
//! `f = chi_2` of each scattering (the phase's second Legendre moment, 0.50 for the
//! cloud's) is taken to go on straight ahead, the rest to scatter by a phase of mean
//! cosine `g' = (g - f) / (1 - f)`. In that scaled medium the sun's reduced beam falls
//! off as `T' = exp(-(sigma_t - f sigma_s) l)`, and its first scattering is the source
//! of a diffuse field whose fluence `phi` and flux `F` solve the P1 equations
//!
//! ```text
//! div F + sigma_a phi = Q0,        Q0 = (1 - f) sigma_s T'
//! F = -D grad phi + 3 D Q1,        Q1 = g' (1 - f) sigma_s T' w_sun
//! ```
//!
//! with `D = lambda(R) / sigma_tr`, `sigma_tr = sigma_t - g sigma_s` (the same in the
//! scaled medium and the true one), and Levermore and Pomraning's flux limiter
//! `lambda(R) = (coth R - 1/R) / R`, `R = |grad phi| / (sigma_tr phi)`: 1/3 deep in the
//! cloud, where diffusion holds, and `|F| <= k phi` at its thin fringe, where light
//! streams (`k` 0.6: a beam's is 1, light leaving a surface has 1/2). Cells
//! of clear air are left out of the solve; on the cloud's faces to them and on the
//! grid's outer faces Marshak's condition lets the light out (`F . n = phi / 2`),
//! nothing coming in.
//!
//! In the true medium the light that has scattered at least once is that diffuse field
//! plus the forward-scattered part of the sun's beam, `(T' - T)` along `w_sun`. A
//! droplet scatters both toward the eye: per unit scattering coefficient and sun
//! irradiance,
//!
//! ```text
//! J(w) = (phi + 3 g F . w) / 4 pi + p(w . w_sun) (T' - T)
//! ```
//!
//! the first part read from the grid ([`DiffuseLight::at`]), the second from the
//! intensity buffer at the drawing's own emission nodes, as
//! single scattering is. The first order stays the billboards' exact one.
//!
//! The grid is cubic cells over the particles' reach with two cells of air around;
//! the extinction of each cell is the particles' mean over it (differences of `erf`,
//! the Gaussian being separable), the sun's transmittance the intensity buffer's at the
//! cell's centre. The finite-volume system (seven points, symmetric, positive definite
//! for lagged `D`) is solved by conjugate gradients with a Jacobi preconditioner;
//! `D` is lagged six times from the last solution (once when a previous solution is
//! given, [`DiffuseLight::solve`]'s `previous`, as when only the sun has moved a little).

use glam::{Vec3, Vec4};
use rayon::prelude::*;

use super::buffer::IntensityBuffer;
use super::particles::{erf_table, Particle};
use crate::atmosphere::phase::PhaseFunction;
use crate::error::{check_range, Error, Result};
use crate::lanes::Lanes;
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

/// The least optical depth across a cell that counts it as cloud ([`Medium`]).
const THIN: f32 = 1e-3;

/// The flux limiter's streaming limit, `|F| <= STREAMING phi` where light streams
/// (docs/clouds.md, "Every order: the transfer solve"). Levermore and Pomraning's is 1,
/// a beam's; light leaving a surface into a half-space has `|F| = phi / 2`
/// (Marshak's condition). Between the two, chosen on the three tuning clouds' 36 views
/// (0.5, 0.6, 0.75 and 1 tried): at 1 the fringe lets too much light out and every
/// view is 15-25 % dark; at 0.5 the thin fringes hold too much.
const STREAMING: f32 = 0.6;

/// Lagged updates of the flux limiter's `D`, from scratch and from a previous solution.
const LAGS_COLD: usize = 6;
const LAGS_WARM: usize = 1;

/// The conjugate gradients stop when the residual is this share of the right side's.
const TOLERANCE: f64 = 1e-4;

/// The solved light of the orders past the first.
#[derive(Debug, Clone)]
pub struct DiffuseLight {
    /// World position of cell `(0, 0, 0)`'s centre, m.
    min: Vec3,
    /// The cells' side, m.
    cell: f32,
    /// Cells along x, y and z.
    dims: [usize; 3],
    /// Per cell, `[x][y][z]` (z fastest): `phi / 4 pi` and `F / 4 pi` per unit sun
    /// irradiance, the first part of `J` ([`DiffuseLight::at`]).
    values: Vec<Vec4>,
    /// The diffuse radiance's angles from its fluence and flux, scattered by the phase.
    closure: Closure,
    /// The phase the tables are of.
    phase: PhaseFunction,
    /// The fluence `phi` per cell, kept to start the next solve from.
    fluence: Vec<f32>,
    /// The phase's forward share `f` ([`DiffuseLight::forward`]).
    forward_share: f32,
    /// The phase convolved with itself, at [`TWICE_STEPS`] + 1 cosines from -1 to 1
    /// ([`DiffuseLight::twice_scattered`]).
    twice: Vec<f32>,
    /// Conjugate-gradient iterations the solve took, over all its lags.
    pub iterations: usize,
}

/// The medium on the grid and the solve's sources.
struct Medium {
    dims: [usize; 3],
    /// The cells' side, m.
    h: f32,
    /// Per cell: transport extinction `sigma_tr` and absorption `sigma_a` (1/m), `Q0`
    /// and `Q1` along the light's travel (per unit sun irradiance, 1/m).
    sigma_tr: Vec<f32>,
    sigma_a: Vec<f32>,
    q0: Vec<f32>,
    q1: Vec<f32>,
    /// Whether a cell is cloud (its optical depth across at least [`THIN`]) or clear
    /// air, which the solve leaves out: the cloud's faces to it let light out by
    /// Marshak's condition, as the grid's outer faces do.
    inside: Vec<bool>,
}

impl DiffuseLight {
    /// The light of the orders past the first in `particles` lit through `buffer` (the
    /// sun's transmittance; lit from `to_sun`), scattered by `phase`. `previous`, a
    /// solution on the same grid (same particles' bounds), starts the solve near its
    /// end.
    pub fn solve(
        particles: &[Particle],
        buffer: &IntensityBuffer,
        to_sun: Vec3,
        phase: PhaseFunction,
        settings: &Diffusion,
        previous: Option<&DiffuseLight>,
    ) -> Result<DiffuseLight> {
        settings.validate()?;
        if particles.is_empty() {
            return Err(Error::Invalid("the transfer solve needs particles".into()));
        }
        // The phase's tables, kept from the last solve of the same phase.
        let (closure, twice) = match previous.filter(|p| p.phase == phase) {
            Some(p) => (p.closure.clone(), p.twice.clone()),
            None => (Closure::new(phase), twice_scattered(phase)),
        };
        let g = closure.chi[1] as f32;
        let f = (closure.chi[2] as f32).clamp(0.0, 0.99);
        let (min, h, dims) = grid(particles, settings.cells);
        let travel = -to_sun.normalize();
        let medium = Medium::of(particles, buffer, min, h, dims, g, f);
        let n = dims[0] * dims[1] * dims[2];
        let first_centre = min + Vec3::splat(0.5 * h);
        let warm = previous.filter(|p| p.dims == dims && p.min == first_centre && p.cell == h);
        let mut phi = warm.map_or_else(|| vec![0.0f32; n], |p| p.fluence.clone());
        let mut iterations = 0;
        let lags = if warm.is_some() { LAGS_WARM } else { LAGS_COLD };
        let mut faces = Faces::plain(&medium);
        for lag in 0..lags {
            if lag > 0 || warm.is_some() {
                faces = Faces::limited(&medium, &phi);
            }
            let rhs = faces.right_side(&medium, travel);
            iterations += conjugate_gradients(&medium, &faces, &rhs, &mut phi);
        }
        let values = medium.dilated(faces.values(&medium, &phi, travel));
        Ok(DiffuseLight {
            min: first_centre,
            cell: h,
            dims,
            values,
            fluence: phi,
            forward_share: f,
            twice,
            closure,
            phase,
            iterations,
        })
    }

    /// Cells along x, y and z.
    pub fn dims(&self) -> [usize; 3] {
        self.dims
    }

    /// The light of the diffuse field a droplet at the world point `p` scatters along
    /// the unit `w`, per unit scattering coefficient and sun irradiance (1/sr): the
    /// fluence and flux trilinear between cell centres (0 outside the grid), the
    /// radiance's angles by Minerbo's closure, scattered by the phase.
    pub fn at(&self, p: Vec3, w: Vec3) -> f32 {
        self.leaving(self.sample(p), w)
    }

    /// The light each cell's centre sends toward `eye` ([`DiffuseLight::at`]), made once
    /// for a picture: its lookups along the pixels' rays are then one value's trilinear
    /// read (the rays pass the centres at angles a cell's width apart as seen from the
    /// eye).
    pub(crate) fn seen_from(&self, eye: Vec3) -> Seen {
        let [_, ny, nz] = self.dims;
        let values = (0..self.values.len())
            .into_par_iter()
            .map(|cell| {
                let index = Vec3::new(
                    (cell / (ny * nz)) as f32,
                    (cell / nz % ny) as f32,
                    (cell % nz) as f32,
                );
                let centre = self.min + index * self.cell;
                self.leaving(self.values[cell], (eye - centre).normalize_or_zero())
            })
            .collect();
        Seen {
            min: self.min,
            cell: self.cell,
            dims: self.dims,
            values,
        }
    }

    /// The light scattered along `w` from a cell's `values` ([`DiffuseLight::at`]).
    #[inline]
    fn leaving(&self, v: Vec4, w: Vec3) -> f32 {
        let flux = Vec3::new(v.y, v.z, v.w);
        let size = flux.length();
        if v.x <= 0.0 || v.x.is_nan() {
            return 0.0;
        }
        let cos = if size > 0.0 { flux.dot(w) / size } else { 0.0 };
        v.x * self.closure.at(size / v.x, cos)
    }

    /// The grid's four values at `p`, trilinear (0 outside).
    #[inline]
    fn sample(&self, p: Vec3) -> Vec4 {
        trilinear(
            &self.values,
            self.min,
            self.cell,
            self.dims,
            p,
            Vec4::ZERO,
            Vec4::lerp,
        )
    }

    /// The forward-scattered part of the sun's beam scattered toward the eye, per unit
    /// scattering coefficient: `p2 (T' - T)` for a point whose `ln T` is `log_gamma`, of
    /// albedo `albedo`, `p2` the phase scattered twice for the ray's angle
    /// ([`DiffuseLight::twice_scattered`]; the module doc).
    #[inline(always)]
    pub(crate) fn forward(&self, twice: Lanes, log_gamma: Lanes, albedo: Lanes) -> Lanes {
        let scaled = Lanes::ONE - Lanes::splat(self.forward_share) * albedo;
        twice * ((log_gamma * scaled).exp() - log_gamma.exp())
    }

    /// The phase convolved with itself (1/sr) at the scattering-angle cosine `cos`: the
    /// angles of light scattered once along the sun's beam and then toward the eye,
    /// which the forward-scattered sunlight `T' - T` is taken to be (its lobe is no
    /// delta: scattered once more by the phase at 90 degrees, the side views' higher
    /// orders would lack much of their second).
    pub fn twice_scattered(&self, cos: f32) -> f32 {
        let x = (cos.clamp(-1.0, 1.0) + 1.0) * 0.5 * TWICE_STEPS as f32;
        let i = (x as usize).min(TWICE_STEPS - 1);
        let t = &self.twice;
        t[i] + (x - i as f32) * (t[i + 1] - t[i])
    }
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
const CLOSURE_STEPS: usize = 64;

/// The largest flux over fluence the closure's table holds (`b` about 20).
const CLOSURE_MAX: f32 = 0.95;

/// Legendre terms of the closure.
const CLOSURE_TERMS: usize = 48;

impl Closure {
    fn new(phase: PhaseFunction) -> Closure {
        let chi = phase.legendre_moments(CLOSURE_TERMS as u32);
        let mut nodes = Vec::new();
        crate::quadrature::gauss_legendre(-1.0, 1.0, 64, |mu, w| nodes.push((mu, w)));
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
            for (&(mu, _), weight) in nodes.iter().zip(&weights) {
                for (m, p) in moments.iter_mut().zip(legendre(mu, CLOSURE_TERMS)) {
                    *m += weight * p / total;
                }
            }
            // Funk and Hecke: the phase scales each moment by its own.
            let scattered: Vec<f64> = moments.iter().zip(&chi).map(|(m, c)| m * c).collect();
            for j in 0..=CLOSURE_STEPS {
                let c = -1.0 + 2.0 * j as f64 / CLOSURE_STEPS as f64;
                values.push(legendre_series(&scattered, c).max(0.0) as f32);
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

/// `sum (2l + 1) c_l P_l(x)` over the `coefficients` `c_l`.
fn legendre_series(coefficients: &[f64], x: f64) -> f64 {
    legendre(x, coefficients.len() - 1)
        .iter()
        .zip(coefficients)
        .enumerate()
        .map(|(l, (p, c))| (2 * l + 1) as f64 * c * p)
        .sum()
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

/// Steps of the table of the phase convolved with itself.
const TWICE_STEPS: usize = 512;

/// Legendre terms of that convolution: `chi_l^2` of the cloud's phase (its forward lobe
/// `g = 0.8`) is below 1e-9 past 48.
const TWICE_TERMS: u32 = 64;

/// `p * p` at [`TWICE_STEPS`] + 1 cosines: by Funk and Hecke, its Legendre moments are
/// the phase's squared, `sum (2l + 1) / 4 pi chi_l^2 P_l(c)`.
fn twice_scattered(phase: PhaseFunction) -> Vec<f32> {
    let moments: Vec<f64> = phase
        .legendre_moments(TWICE_TERMS)
        .iter()
        .map(|chi| chi * chi)
        .collect();
    (0..=TWICE_STEPS)
        .map(|i| {
            let c = -1.0 + 2.0 * i as f64 / TWICE_STEPS as f64;
            (legendre_series(&moments, c) / (4.0 * std::f64::consts::PI)).max(0.0) as f32
        })
        .collect()
}

/// The diffuse light each cell sends toward one eye ([`DiffuseLight::seen_from`]).
pub(crate) struct Seen {
    min: Vec3,
    cell: f32,
    dims: [usize; 3],
    values: Vec<f32>,
}

impl Seen {
    /// The light toward the eye at eight world points, trilinear (0 outside the grid).
    #[inline]
    pub(crate) fn at_lanes(&self, p: [Lanes; 3]) -> Lanes {
        let [px, py, pz] = p.map(|c| c.to_array());
        Lanes::new(std::array::from_fn(|k| {
            let p = Vec3::new(px[k], py[k], pz[k]);
            trilinear(
                &self.values,
                self.min,
                self.cell,
                self.dims,
                p,
                0.0,
                |a, b, t| a + t * (b - a),
            )
        }))
    }
}

/// `values` on the grid of cells `cell` m wide whose first centre is `min`, trilinear
/// at `p` by `lerp` (`outside` beyond the centres).
#[inline(always)]
fn trilinear<T: Copy>(
    values: &[T],
    min: Vec3,
    cell: f32,
    dims: [usize; 3],
    p: Vec3,
    outside: T,
    lerp: impl Fn(T, T, f32) -> T,
) -> T {
    let g = (p - min) / cell;
    let [nx, ny, nz] = dims;
    if !(g.x >= 0.0
        && g.y >= 0.0
        && g.z >= 0.0
        && g.x < (nx - 1) as f32
        && g.y < (ny - 1) as f32
        && g.z < (nz - 1) as f32)
    {
        return outside;
    }
    let (ix, iy, iz) = (g.x as usize, g.y as usize, g.z as usize);
    let (fx, fy, fz) = (g.x - ix as f32, g.y - iy as f32, g.z - iz as f32);
    let base = (ix * ny + iy) * nz + iz;
    let (sx, sy) = (ny * nz, nz);
    let lerp_z = |b: usize| lerp(values[b], values[b + 1], fz);
    let lerp_y = |b: usize| lerp(lerp_z(b), lerp_z(b + sy), fy);
    lerp(lerp_y(base), lerp_y(base + sx), fx)
}

/// The grid over `particles`' reach, `cells` along the longest side and [`MARGIN`]
/// around: its smallest corner, the cells' side and the cells along each axis.
fn grid(particles: &[Particle], cells: usize) -> (Vec3, f32, [usize; 3]) {
    let (lo, hi) = particles.iter().fold(
        (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
        |(lo, hi), p| {
            let r = Vec3::splat(p.reach());
            (lo.min(p.position - r), hi.max(p.position + r))
        },
    );
    let extent = hi - lo;
    let h = extent.max_element() / cells as f32;
    let dims = extent
        .to_array()
        .map(|e| ((e / h).ceil() as usize).max(1) + 2 * MARGIN);
    let centre = 0.5 * (lo + hi);
    let size = Vec3::new(dims[0] as f32, dims[1] as f32, dims[2] as f32) * h;
    (centre - 0.5 * size, h, dims)
}

impl Medium {
    /// The particles' extinction and scattering averaged over each cell, and the
    /// sources of the sun lit through `buffer` (the module doc).
    fn of(
        particles: &[Particle],
        buffer: &IntensityBuffer,
        min: Vec3,
        h: f32,
        dims: [usize; 3],
        g: f32,
        f: f32,
    ) -> Medium {
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
        let g_scaled = (g - f) / (1.0 - f);
        let mut medium = Medium {
            dims,
            h,
            sigma_tr: vec![0.0; n],
            sigma_a: vec![0.0; n],
            q0: vec![0.0; n],
            q1: vec![0.0; n],
            inside: sums.iter().map(|[t, _]| t * h >= THIN).collect(),
        };
        medium
            .sigma_tr
            .par_iter_mut()
            .zip(&mut medium.sigma_a)
            .zip(&mut medium.q0)
            .zip(&mut medium.q1)
            .enumerate()
            .for_each(|(cell, (((tr, a), q0), q1))| {
                let [t, s] = sums[cell];
                *tr = (t - g * s).max(0.0);
                *a = (t - s).max(0.0);
                if s > 0.0 {
                    let (ix, iy, iz) = (cell / (ny * nz), cell / nz % ny, cell % nz);
                    let centre = min + (Vec3::new(ix as f32, iy as f32, iz as f32) + 0.5) * h;
                    let log_t = buffer.sample(centre).max(f32::MIN_POSITIVE).ln();
                    let reduced = (log_t * (1.0 - f * s / t)).exp();
                    *q0 = (1.0 - f) * s * reduced;
                    *q1 = g_scaled * *q0;
                }
            });
        medium
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

    /// The drift of the source across the face to the + side of `cell` along `axis`
    /// (m/m^3 per unit sun irradiance): `3 D Q1 . n`, `Q1` the two cells' mean.
    #[inline]
    fn drift(&self, medium: &Medium, cell: usize, next: usize, axis: usize, travel: Vec3) -> f32 {
        3.0 * self.d[axis][cell] * 0.5 * (medium.q1[cell] + medium.q1[next]) * travel[axis]
    }

    /// The system's right side: `Q0` less the divergence of the drift.
    fn right_side(&self, medium: &Medium, travel: Vec3) -> Vec<f32> {
        let h = medium.h;
        (0..medium.q0.len())
            .into_par_iter()
            .map(|cell| {
                if !medium.inside[cell] {
                    return 0.0;
                }
                let mut b = medium.q0[cell];
                for a in 0..3 {
                    if let Some(next) = medium.next(cell, a) {
                        b -= self.drift(medium, cell, next, a, travel) / h;
                    }
                    if let Some(prev) = medium.previous(cell, a) {
                        b += self.drift(medium, prev, cell, a, travel) / h;
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

    /// Per cell `phi / 4 pi` and `F / 4 pi`, `F` the mean of the flux through its
    /// two faces along each axis (the outer faces' by Marshak's condition).
    fn values(&self, medium: &Medium, phi: &[f32], travel: Vec3) -> Vec<Vec4> {
        let h = medium.h;
        let flux = |cell: usize, next: usize, a: usize| {
            -self.d[a][cell] * (phi[next] - phi[cell]) / h
                + self.drift(medium, cell, next, a, travel)
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
        let light =
            DiffuseLight::solve(&particles, &buffer, to_sun, phase, &settings, None).unwrap();
        let (g, f) = (
            phase.legendre_moment(1) as f32,
            phase.legendre_moment(2) as f32,
        );
        let (min, h, dims) = grid(&particles, settings.cells);
        let medium = Medium::of(&particles, &buffer, min, h, dims, g, f);
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
            let rhs = faces.right_side(&medium, -to_sun);
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
        let first = DiffuseLight::solve(&particles, &lit(a), a, phase, &settings, None).unwrap();
        let warm =
            DiffuseLight::solve(&particles, &lit(b), b, phase, &settings, Some(&first)).unwrap();
        let cold = DiffuseLight::solve(&particles, &lit(b), b, phase, &settings, None).unwrap();
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
}
