//! Sixteen neighbouring rays at a time through the sub-samples (shafts (7)-(9)), and
//! what a slice's lookups can skip (the min-max shadow map's classes).

use super::*;

/// The rays `ray(p)` of up to [`LANES`] pixels `p` of a picture `width` wide, and their
/// sub-sample offsets ([`interleaved_offset`]).
pub(super) fn lanes_of(
    pixels: impl Iterator<Item = u32>,
    ray: impl Fn(u32) -> Vec3,
    width: u32,
) -> ([Vec3; LANES], [f32; LANES]) {
    let (mut rays, mut offsets) = ([Vec3::ZERO; LANES], [0.0f32; LANES]);
    for (l, p) in pixels.enumerate() {
        rays[l] = ray(p);
        offsets[l] = interleaved_offset(p % width, p / width);
    }
    (rays, offsets)
}

/// Pixels that go through the sub-samples together: the width of the vector loops.
pub const LANES: usize = crate::lanes::LANES_OF_RAYS;

/// What [`SamplePlanes::scattered`] needs of up to [`LANES`] camera rays for one light.
pub(super) struct Lanes {
    /// Rays in use (the rest are inactive padding).
    pub(super) count: usize,
    /// Plane spacing of the light, m of camera depth.
    pub(super) dz: f32,
    /// Sub-plane spacing, m of camera depth, and the first plane interval's start.
    pub(super) sub: f32,
    pub(super) z_near: f32,
    /// The eye in the light's space, and `1 / tan(field / 2)`.
    pub(super) origin: Vec3,
    pub(super) inv_tan: f32,
    /// Camera rays (unit length along the view axis).
    pub(super) ray: [Vec3; LANES],
    /// The rays in light space, per axis.
    pub(super) step: [[f32; LANES]; 3],
    /// `|ray|` and its inverse.
    pub(super) length: [f32; LANES],
    pub(super) inv_length: [f32; LANES],
    /// Each ray's sub-plane shift in [0, 1).
    pub(super) offset: [f32; LANES],
    /// Where each ray enters the haze, m (0 without a haze box).
    pub(super) entry: [f32; LANES],
    /// Each ray's lit sub-samples are `k_first..k_last` (empty: 0..0).
    pub(super) k_first: [u32; LANES],
    pub(super) k_last: [u32; LANES],
    /// Each ray's lit stretch in camera depth, m (empty: `z_lit[0] >= z_lit[1]`).
    pub(super) z_lit: [[f32; 2]; LANES],
    /// Whether some ray's lit stretch may hold a slab that passes near the lamp.
    pub(super) near_lamp: bool,
}

impl Lanes {
    /// The rays' lit stretches for `light`: inside its field cone, its lit volume's box
    /// and the haze, in front of `ends` (m from the eye) and between its first and last
    /// plane.
    pub(super) fn new(
        method: &SamplePlanes,
        light: &Spotlight,
        planes: &LightPlanes,
        rays: &[Vec3],
        offsets: &[f32],
        ends: &[f32; LANES],
    ) -> Lanes {
        let scene = method.scene;
        let haze = &scene.haze;
        let eye = scene.camera.position;
        let n = scene.planes.planes as usize;
        let m = scene.planes.sub_planes as usize;
        let dz = (planes.z_far - planes.z_near) / n as f32;
        let inv_sub = 1.0 / (dz / m as f32);
        let mut lanes = Lanes {
            count: rays.len(),
            dz,
            sub: dz / m as f32,
            z_near: planes.z_near,
            origin: planes.eye,
            inv_tan: 1.0 / light.tan_field(),
            ray: [Vec3::ZERO; LANES],
            step: [[0.0; LANES]; 3],
            length: [1.0; LANES],
            inv_length: [1.0; LANES],
            offset: [0.0; LANES],
            entry: [0.0; LANES],
            k_first: [0; LANES],
            k_last: [0; LANES],
            z_lit: [[0.0; 2]; LANES],
            near_lamp: false,
        };
        for (l, (ray, offset)) in rays.iter().zip(offsets).enumerate() {
            let length = ray.length();
            let dir = *ray / length;
            let step = light.light_from_world * *ray;
            (
                lanes.ray[l],
                lanes.length[l],
                lanes.inv_length[l],
                lanes.offset[l],
            ) = (*ray, length, 1.0 / length, *offset);
            (lanes.step[0][l], lanes.step[1][l], lanes.step[2][l]) = (step.x, step.y, step.z);
            let Some((ta, tb)) = planes
                .bounds
                .clip(eye, dir.recip(), 0.0, ends[l])
                .and_then(|(a, b)| light.cone_interval(eye, dir, a, b))
                .and_then(|(a, b)| haze.clip(eye, dir, a, b))
            else {
                continue;
            };
            // A point in the (convex) haze at distance t has t - entry of its path to
            // the eye in it.
            lanes.entry[l] = haze
                .clip(eye, dir, 0.0, f32::INFINITY)
                .map_or(0.0, |(a, _)| a);
            // The lit stretch in camera depth, as sub-sample indices.
            let (za, zb) = (
                (ta / length).max(planes.z_near),
                (tb / length).min(planes.z_far),
            );
            lanes.z_lit[l] = [za, zb];
            if za < zb {
                // A slab near the lamp has its centre within `slab / NEAR_LAMP` of it and
                // overlaps the lit stretch, so the stretch comes within
                // `slab (1 / NEAR_LAMP + 1/2)` of the lamp (1 % more for rounding).
                let reach = 1.01 * dz * length * (1.0 / NEAR_LAMP + 0.5);
                let nearest = (-planes.eye.dot(step) / (length * length)).clamp(za, zb);
                lanes.near_lamp |= (planes.eye + nearest * step).length_squared() < reach * reach;
                lanes.k_first[l] = ceil_nonnegative((za - planes.z_near) * inv_sub - offset) as u32;
                lanes.k_last[l] =
                    ceil_nonnegative((zb - planes.z_near) * inv_sub - offset).min(n * m) as u32;
            }
        }
        lanes
    }

    /// Sub-sample `k` of lane `l` in the light's space: its projection `(u, v)` onto the
    /// `[-1, 1]^2` square and its depth `z`.
    #[inline(always)]
    pub(super) fn project(&self, l: usize, k: usize) -> [f32; 3] {
        let depth = self.z_near + (k as f32 + self.offset[l]) * self.sub;
        let [sx, sy, sz] = &self.step;
        // Inside the cone z > 0; the guard keeps rounding at the apex harmless.
        let z = (self.origin.z + depth * sz[l]).max(1e-6);
        let scale = self.inv_tan / z;
        [
            (self.origin.x + depth * sx[l]) * scale,
            (self.origin.y + depth * sy[l]) * scale,
            z,
        ]
    }

    /// The planes whose slices hold sub-samples some lane needs, each with those of its
    /// sub-samples (`m` a plane) from the smallest first to the largest last.
    pub(super) fn slices(&self, m: usize) -> impl Iterator<Item = (usize, std::ops::Range<usize>)> {
        let (first, last) = self.k_range();
        let planes = if first < last {
            first / m..last.div_ceil(m)
        } else {
            0..0
        };
        planes.map(move |plane| (plane, (plane * m).max(first)..((plane + 1) * m).min(last)))
    }

    /// The sub-samples any lane needs: from the smallest first to the largest last.
    pub(super) fn k_range(&self) -> (usize, usize) {
        let mut range = (usize::MAX, 0);
        for l in 0..self.count {
            if self.k_first[l] < self.k_last[l] {
                range = (
                    range.0.min(self.k_first[l] as usize),
                    range.1.max(self.k_last[l] as usize),
                );
            }
        }
        range
    }
}

/// Which lookups the lanes' sub-samples in one plane's slice need.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Lookups {
    /// None: no lit sub-sample in the slice, or all wholly in shadow (`H = 0`).
    None,
    /// Wholly lit inside the beam's core: `H I_l = 1` at each sub-sample.
    Core,
    /// Wholly lit: the light map's profile alone.
    Profile,
    /// The shadow map's `H` and the light map's profile.
    Both,
}

impl Lookups {
    /// `H I_l` without the gobo at a sub-sample projecting to `(u, v)` at light-space
    /// depth `z`, as the slice's lookups need it.
    #[inline(always)]
    pub(super) fn weight(self, light: &Spotlight, shadow: &ShadowMap, [u, v, z]: [f32; 3]) -> f32 {
        match self {
            Lookups::None | Lookups::Core => 1.0,
            Lookups::Profile => light.intensity_map.get(u, v),
            Lookups::Both => shadow.lit_at(u, v, z) as u8 as f32 * light.intensity_map.get(u, v),
        }
    }

    /// What the lanes' lit sub-samples among `slice` (one plane's) need: the first and
    /// last of each lane's bound its stretch (a straight piece of its ray, which
    /// projects onto the segment between their projections, with its depth between
    /// theirs), and the box around all stretches is what the shadow map is asked about
    /// ([`ShadowMap::region`], the box widened by [`STRETCH_MARGIN`] for the rounding of
    /// the points between). The profile is 1 along all of them when every end's `q`
    /// lies in the core, since `q = u^2 + v^2` along a projected stretch is greatest at
    /// an end. One answer for the sixteen neighbouring rays costs one query a slice and
    /// keeps the loops over the lanes free of branches.
    pub(super) fn of_slice(
        light: &Spotlight,
        shadow: &ShadowMap,
        lanes: &Lanes,
        slice: std::ops::Range<usize>,
    ) -> Lookups {
        let (mut lo, mut hi) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
        let mut q_max = 0.0f32;
        for l in 0..lanes.count {
            let from = slice.start.max(lanes.k_first[l] as usize);
            let to = slice.end.min(lanes.k_last[l] as usize);
            if from >= to {
                continue;
            }
            for p in [lanes.project(l, from), lanes.project(l, to - 1)] {
                for c in 0..3 {
                    (lo[c], hi[c]) = (lo[c].min(p[c]), hi[c].max(p[c]));
                }
                q_max = q_max.max(p[0] * p[0] + p[1] * p[1]);
            }
        }
        if lo[2] > hi[2] {
            return Lookups::None;
        }
        let margin = |x: f32, sign: f32| x + sign * STRETCH_MARGIN * x.abs().max(1.0);
        let (lo, hi) = (lo.map(|x| margin(x, -1.0)), hi.map(|x| margin(x, 1.0)));
        match shadow.region(lo, hi) {
            Stretch::Dark => Lookups::None,
            Stretch::Lit if margin(q_max, 1.0) < light.intensity_map.q_beam => Lookups::Core,
            Stretch::Lit => Lookups::Profile,
            Stretch::Mixed => Lookups::Both,
        }
    }
}

/// How far [`Lookups::of_slice`] widens the box around a stretch's ends (relative to
/// each coordinate, at least 1e-5 absolute): well above the float error of the
/// sub-samples computed between them (a few 1e-7 of the coordinate), and enough with
/// [`ShadowMap::region`]'s exact texel bounds to keep those inside.
pub(super) const STRETCH_MARGIN: f32 = 1e-5;
