//! Multiple scattering by a transfer table (atmo's model for every order of the sun's
//! light on the CPU; docs/clouds.md, "Every order: a transfer table"). The light that
//! the orders past the first send toward the eye from a droplet is taken as a function
//! `F` of five things the drawing knows or can know cheaply, one of the particle and
//! four at the blob's emission nodes on the pixel's ray
//! ([`super::particles::emission_nodes`]), their mean by the nodes' weights:
//!
//! - the cloud's thickness through the particle: its greatest optical depth through
//!   the particle's centre along the three axes ([`CloudDepths::thickness`]). The
//!   orders past the first need cloud around a droplet to scatter light back to it,
//!   which the other four cannot tell: without it the fit read the thin clouds of few,
//!   large blobs 11-14 % too bright and the thickest 5-7 % too dark;
//! - `tau_sun`, the optical depth toward the sun: the intensity buffer's `-ln Gamma`
//!   (clouds (7));
//! - `tau_eye`, the optical depth toward the eye: the cloud's in front of the blob on
//!   the ray plus the nodes' own depth into it;
//! - `tau_out`, the least optical depth out of the cloud: the least of the particle's
//!   along the six axes at its centre ([`CloudDepths`], a property of the particles
//!   alone, not of the sun), `tau_eye` and `tau_sun` (the ray back to the eye and the
//!   sun's ray are ways out too; for a large, thick blob, whose light comes from its
//!   face, the centre's depth would say it lies deep);
//! - `cos`, the cosine between the directions toward the sun and of the ray's travel
//!   (the phase function's argument).
//!
//! `F` is multilinear over the nodes [`THICKNESS`], [`SUN`], [`OUT`], [`COSINE`] and
//! [`EYE`] (3 x 6 x 5 x 6 x 4 = 2,160 values, 1/sr per unit sun irradiance), and a blob adds
//! `albedo (1 - e^-tau) F` times what gets through in front of it, as its single
//! scattering is added (clouds (5)). The values are fitted, at least 0, by least squares
//! to the volumetric path tracer
//! ([`crate::reference::clouds::ReferenceCloud::path_traced`]): its light less the
//! billboards' own single scattering, over 108 views of nine cumulus clouds of 200 to
//! 20,000 particles and optical depth about 3 to 55 (`tools/fit-clouds
//! --transfer`, whose `--write` makes `transfer_fitted.rs`).
//!
//! Why a table rather than octaves ([`super::octaves`]): octaves see only the depth
//! toward the sun, and their light at a point cannot know how deep in the cloud the
//! point lies the other ways, which decides the level of the diffuse light of the many
//! orders. Over the 108 views (128 paths a pixel) the octaves' worst view is 1.32 times
//! the path tracer, 50 views are within 10 % in the mean and 52 % of the 8 x 8 blocks
//! within 15 % (42 % by their medians); the table's 1.11, 107 and 80 % (67 % by
//! medians; 76 and 64 % on average over each cloud held out of the fit in turn). On the
//! twelve views of the bench's 60,134-particle cloud, which no fit has seen: the
//! table's worst view 1.10, all twelve within 10 %, 64 % of blocks (57 % by medians),
//! the octaves' 1.29, 6, 47 % (38 %). It costs three coarse light passes once per
//! cloud shape (not per sun) and a 16-node lookup a blob-pixel in one slice of the
//! thickness or two. The GPU's billboards, blended in hardware
//! back to front, do not know the depth in front of a blob on its pixel: they read the
//! depth toward the eye from a second buffer lit from the eye along each pixel's ray
//! (`atmo_gpu::clouds`), which over the 108 views scored 66 % of blocks where the sum
//! along the pixel scored 72 % (with the table of four axes, before the thickness).

use super::particles::Particle;
use super::sky_light::{depths_along, vertical_depths};
use crate::error::Result;
use crate::lanes::{first, Lanes};
use glam::{Vec3, Vec4, Vec4Swizzles};

/// Nodes of the optical depth toward the sun.
pub const SUN: [f32; 6] = [0.0, 0.5, 1.5, 4.0, 10.0, 30.0];
/// Nodes of the least optical depth out of the cloud along the six axes.
pub const OUT: [f32; 5] = [0.0, 0.5, 1.5, 4.0, 10.0];
/// Nodes of the cosine between the sun's direction and the view ray's.
pub const COSINE: [f32; 6] = [-1.0, -0.5, 0.0, 0.5, 0.8, 1.0];
/// Nodes of the optical depth from the eye to the blob's middle.
pub const EYE: [f32; 4] = [0.0, 1.0, 3.0, 8.0];

/// Nodes of the cloud's thickness through the particle: its greatest optical depth
/// through the particle's centre along the three axes ([`CloudDepths::thickness`]).
pub const THICKNESS: [f32; 3] = [4.0, 16.0, 64.0];

/// The values of one thickness, `[sun][out][cosine][eye]` row-major.
pub const SLICE: usize = SUN.len() * OUT.len() * COSINE.len() * EYE.len();

/// The table's values, `[thickness][sun][out][cosine][eye]` row-major.
pub const VALUES: usize = THICKNESS.len() * SLICE;

/// The light of the orders past the first, `F(thickness, tau_sun, tau_out, cos,
/// tau_eye)`, 1/sr per unit sun irradiance (the module doc).
#[derive(Debug, Clone, PartialEq)]
pub struct TransferTable {
    /// `[thickness][sun][out][cosine][eye]`, row-major.
    pub values: [f32; VALUES],
}

impl TransferTable {
    /// The table fitted to the path tracer (the module doc).
    pub const FITTED: TransferTable = TransferTable {
        values: super::transfer_fitted::VALUES,
    };

    /// `F` at one point, multilinear between the nodes and held at the end nodes
    /// outside them (the table laid out anew each call: for a few points, where a
    /// picture lays it out once).
    pub fn at(&self, thickness: f32, tau_sun: f32, tau_out: f32, cos: f32, tau_eye: f32) -> f32 {
        let [s, o, c, e] = [tau_sun, tau_out, cos, tau_eye].map(Lanes::splat);
        first(self.cells().at(Slices::of(thickness), s, o, c, e))
    }

    /// [`Cells`] of this table, made once for a picture.
    pub(crate) fn cells(&self) -> Cells {
        let strides = [STRIDE_SUN, STRIDE_OUT, STRIDE_COSINE, STRIDE_EYE];
        let lengths = [SUN.len(), OUT.len(), COSINE.len(), EYE.len()];
        let cells = (0..VALUES)
            .map(|base| {
                let node = |axis: usize| base % SLICE / strides[axis] % lengths[axis];
                if (0..4).any(|axis| node(axis) + 1 >= lengths[axis]) {
                    return Cell::default();
                }
                let corner = |k: usize| {
                    let offset: usize = (0..4)
                        .map(|axis| (k >> (3 - axis) & 1) * strides[axis])
                        .sum();
                    self.values[base + offset]
                };
                Cell(std::array::from_fn(|q| {
                    Vec4::from_array(std::array::from_fn(|k| corner(4 * q + k)))
                }))
            })
            .collect();
        Cells(cells)
    }
}

/// Strides of the table's axes.
const STRIDE_EYE: usize = 1;
const STRIDE_COSINE: usize = EYE.len();
const STRIDE_OUT: usize = COSINE.len() * STRIDE_COSINE;
const STRIDE_SUN: usize = OUT.len() * STRIDE_OUT;

/// The table laid out for drawing ([`TransferTable::cells`]): at each node of each
/// thickness, the 16 corners of the cell above it, `[sun][out][cosine][eye]` in binary
/// (the eye's the lowest bit), in one cache line; 0 where the cell would leave the table (never a
/// lookup's lowest corner).
pub(crate) struct Cells(Vec<Cell>);

/// One node's cell: its corners as four quarters, `[sun][out]`, of `[cosine][eye]`.
#[derive(Clone, Copy, Default)]
#[repr(C, align(64))]
struct Cell([Vec4; 4]);

/// A particle's slices of the table by its thickness ([`THICKNESS`]): the lower's first
/// cell and the upper's weight, 0 outside the nodes (held at the end node, whose slice
/// alone is read).
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct Slices {
    base: usize,
    share: f32,
}

impl Slices {
    /// The slices around `thickness`, by the other axes' hat; at or past the last node
    /// (the upper's weight 1) the last slice alone.
    pub(crate) fn of(thickness: f32) -> Slices {
        let (node, share) = hat_lanes(&THICKNESS, Lanes::splat(thickness));
        let (node, share) = (first(node) as usize, first(share));
        let (node, share) = if share >= 1.0 {
            (node + 1, 0.0)
        } else {
            (node, share)
        };
        Slices {
            base: node * SLICE,
            share,
        }
    }
}

impl Cells {
    /// `F` in eight lanes ([`TransferTable::at`]), for a particle in `slices`.
    #[inline(always)]
    pub(crate) fn at(
        &self,
        slices: Slices,
        tau_sun: Lanes,
        tau_out: Lanes,
        cos: Lanes,
        tau_eye: Lanes,
    ) -> Lanes {
        let (sun, sun_share) = hat_lanes(&SUN, tau_sun);
        let (out, out_share) = hat_lanes(&OUT, tau_out);
        let (cosine, cosine_share) = hat_lanes(&COSINE, cos);
        let (eye, eye_share) = hat_lanes(&EYE, tau_eye);
        let (o, c, e) = (OUT.len() as f32, COSINE.len() as f32, EYE.len() as f32);
        // The index of each lane's lowest corner in the lower slice.
        let base =
            ((sun * Lanes::splat(o) + out) * Lanes::splat(c) + cosine) * Lanes::splat(e) + eye;
        let [base, fs, fo, fc, fe] =
            [base, sun_share, out_share, cosine_share, eye_share].map(|v| v.to_array());
        // A lane at a time: its cell's four quarters (sun and out) lerped in SSE, then the
        // cosine's pair and the eye's. One cache line a lane and slice: with the 16
        // corners read one by one from the table, the lookup took about 110 ms of the
        // bench's 410 ms frame; this, about 70.
        let value = |lane: usize, cell: usize| {
            let Cell([s0o0, s0o1, s1o0, s1o1]) = self.0[cell];
            let s0 = s0o0.lerp(s0o1, fo[lane]);
            let corners = s0.lerp(s1o0.lerp(s1o1, fo[lane]), fs[lane]);
            let eyes = corners.xy().lerp(corners.zw(), fc[lane]);
            eyes.x + fe[lane] * (eyes.y - eyes.x)
        };
        Lanes::new(std::array::from_fn(|lane| {
            let cell = slices.base + base[lane] as usize;
            let lower = value(lane, cell);
            if slices.share > 0.0 {
                lower + slices.share * (value(lane, cell + SLICE) - lower)
            } else {
                lower
            }
        }))
    }
}

/// The lower of the two nodes of `edges` around each lane's value (a whole number in
/// `f32`) and the upper's weight, held at the end nodes outside them (the upper's weight
/// 0 below the first, 1 above the last).
#[inline(always)]
fn hat_lanes(edges: &[f32], v: Lanes) -> (Lanes, Lanes) {
    let splat = Lanes::splat;
    let (mut node, mut low, mut width) = (Lanes::ZERO, splat(edges[0]), splat(edges[1] - edges[0]));
    for i in 1..edges.len() - 1 {
        let past = v.simd_ge(splat(edges[i]));
        node = past.select(splat(i as f32), node);
        low = past.select(splat(edges[i]), low);
        width = past.select(splat(edges[i + 1] - edges[i]), width);
    }
    let share = ((v - low) / width)
        .fast_max(Lanes::ZERO)
        .fast_min(Lanes::ONE);
    (node, share)
}

/// What the drawing reads of each particle's place in the cloud, which depends on the
/// particles alone (not on the sun or the camera), so a caller that draws the same
/// particles again keeps it ([`super::render_with_depths`]).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct CloudDepths {
    /// Down the vertical through the particle's centre: its optical depth below the
    /// cloud's top and the whole cloud's there, `[tau, T]`
    /// ([`super::SkyDimming::top_share`]).
    pub vertical: Vec<[f32; 2]>,
    /// The least optical depth from its centre out of the cloud along the six axes
    /// (the transfer table's `tau_out`).
    pub out: Vec<f32>,
    /// The cloud's greatest optical depth through its centre along the three axes, the
    /// whole column there (the transfer table's thickness, [`THICKNESS`]).
    pub thickness: Vec<f32>,
}

impl CloudDepths {
    /// Both depths of every particle, from [`super::IntensityBuffer`]s lit along the three
    /// axes with no forward scattering as the vertical's ([`vertical_depths`]): the
    /// depth from the side each is lit from, and from the other side the column less
    /// that.
    pub fn of(particles: &[Particle]) -> Result<CloudDepths> {
        let vertical = vertical_depths(particles)?;
        let mut out = vec![f32::INFINITY; particles.len()];
        let mut thickness = vec![0.0f32; particles.len()];
        for along in [
            &vertical,
            &depths_along(particles, Vec3::X)?,
            &depths_along(particles, Vec3::Z)?,
        ] {
            for ((out, thick), &[tau, column]) in out.iter_mut().zip(&mut thickness).zip(along) {
                *out = out.min(tau).min((column - tau).max(0.0));
                *thick = thick.max(column);
            }
        }
        Ok(CloudDepths {
            vertical,
            out,
            thickness,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A table whose value is a given function of the nodes.
    fn table_of(f: impl Fn(f32, f32, f32, f32, f32) -> f32) -> TransferTable {
        let mut values = [0.0; VALUES];
        let mut k = 0;
        for t in THICKNESS {
            for s in SUN {
                for o in OUT {
                    for c in COSINE {
                        for e in EYE {
                            values[k] = f(t, s, o, c, e);
                            k += 1;
                        }
                    }
                }
            }
        }
        TransferTable { values }
    }

    /// Multilinear interpolation is exact for a function linear in each feature (within
    /// the nodes), and holds the end nodes' values outside them.
    #[test]
    fn the_lookup_is_exact_for_multilinear_functions() {
        let f = |t: f32, s: f32, o: f32, c: f32, e: f32| {
            1.0 + 0.3 * s - 0.2 * o * c + 0.05 * s * e + c + 0.02 * t * (1.0 + c)
        };
        let table = table_of(f);
        for k in 0..500u32 {
            let g = |a: f32| (k as f32 * a).fract();
            let (t, s, o, c, e) = (
                4.0 + 60.0 * g(0.37),
                30.0 * g(0.618),
                10.0 * g(0.755),
                2.0 * g(0.57) - 1.0,
                8.0 * g(0.41),
            );
            let got = table.at(t, s, o, c, e);
            let want = f(t, s, o, c, e);
            assert!(
                (got - want).abs() < 1e-4 * want.abs().max(1.0),
                "{t} {s} {o} {c} {e}: {got}"
            );
        }
        assert_eq!(
            table.at(100.0, 100.0, 50.0, 1.0, 20.0),
            f(64.0, 30.0, 10.0, 1.0, 8.0)
        );
        assert_eq!(
            table.at(0.0, -1.0, -1.0, -2.0, -1.0),
            f(4.0, 0.0, 0.0, -1.0, 0.0)
        );
    }

    /// The fitted table's light is never negative, and deep in the cloud (4 out of it
    /// every way) it falls from a droplet 4 deep toward the sun to one 30 deep, at every
    /// thickness and angle; it is not all 0.
    #[test]
    fn the_fitted_light_is_positive_and_dims_into_the_shade() {
        let t = TransferTable::FITTED;
        assert!(t.values.iter().all(|v| *v >= 0.0 && v.is_finite()));
        assert!(t.values.iter().any(|v| *v > 0.1));
        for thickness in THICKNESS {
            for cos in COSINE {
                assert!(
                    t.at(thickness, 4.0, 4.0, cos, 0.0) > t.at(thickness, 30.0, 4.0, cos, 0.0),
                    "{thickness} {cos}"
                );
            }
        }
    }

    /// A lone blob lies at its own depth: its depth out is its half-column along the
    /// axes, and the vertical's is its whole column, about the analytic one, as is its
    /// thickness.
    #[test]
    fn a_lone_blob_is_half_its_column_deep() {
        let p = Particle {
            position: Vec3::new(10.0, 1500.0, -20.0),
            radius: 100.0,
            density: 0.04,
            albedo: 0.99,
        };
        let depths = CloudDepths::of(&[p]).unwrap();
        let column = p.column(0.0, f64::NEG_INFINITY, f64::INFINITY) as f32;
        let [tau, whole] = depths.vertical[0];
        assert!(
            (whole - column).abs() < 0.05 * column,
            "{whole} vs {column}"
        );
        assert!((tau - 0.5 * column).abs() < 0.05 * column, "{tau}");
        assert!(
            (depths.out[0] - 0.5 * column).abs() < 0.05 * column,
            "{}",
            depths.out[0]
        );
        assert!(
            (depths.thickness[0] - column).abs() < 0.05 * column,
            "{}",
            depths.thickness[0]
        );
    }
}
