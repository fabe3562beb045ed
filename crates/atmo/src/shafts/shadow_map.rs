//! The shadow map of a spotlight (shafts 4.1): for each texel of the light's `(u, v)`
//! square, the light-space depth `z` of the nearest surface. A point is lit when it is
//! nearer than that: `H` of shafts (2) on the sample and sub-sample planes, and the
//! shadows on surfaces. The map holds what one ray through each texel centre meets,
//! which is what a rasteriser's depth buffer holds at that texel (each shape is drawn
//! over its footprint alone: a mesh triangle by triangle, the rest by their boxes). A
//! min-max chain over it answers for a whole box of points at once
//! ([`ShadowMap::region`]), and boxes around where blocks of its rays end bound the lit
//! volume for any camera ([`ShadowMap::end_boxes`]).

use glam::Vec3;
use rayon::prelude::*;

use super::objects::Objects;
use super::spotlight::Spotlight;
use crate::geometry::{Aabb, Ray, Shape, RAY_EPSILON};

/// Depths of the nearest surfaces seen from a light.
#[derive(Debug, Clone)]
pub struct ShadowMap {
    /// Texels along each side.
    pub size: usize,
    /// Row-major light-space depths `z`, m, top row (`v = 1`) first; infinite where the
    /// texel's ray meets nothing.
    pub depth: Vec<f32>,
    /// Half-width of the `(u, v)` square at `z = 1`: `tan(field / 2)`.
    tan_field: f32,
    /// The depths' least and greatest over blocks of `2^(L + 1)` texels on a side, level
    /// `L` first (a min-max mip chain): what [`ShadowMap::region`] reads to tell a lit
    /// stretch of a ray from a dark one without a lookup per point.
    ranges: Vec<Vec<[f32; 2]>>,
    /// Where the rays of each block of [`END_BLOCK`] x [`END_BLOCK`] texels end, blocks
    /// row-major: what [`ShadowMap::end_boxes`] reads.
    ends: Vec<EndBlock>,
}

/// Texels along each side of a block of [`ShadowMap::end_boxes`]: at the default 512
/// texels, 1024 blocks, few enough to bound each frame and small enough that a frame
/// walks a few of them only.
pub const END_BLOCK: usize = 16;

/// Where the rays of a block of texels end, whatever depth rays that meet nothing are
/// cut at.
#[derive(Debug, Clone, Copy)]
struct EndBlock {
    /// Around the ends of the rays that meet a surface (world space, m).
    met: Aabb,
    /// The greatest light-space depth among those, m (0 for none).
    deepest: f32,
    /// Around the directions (world space, light-space `z` = 1) of the rays that meet
    /// nothing.
    open: Aabb,
}

/// What the shadow map says of every point of a region ([`ShadowMap::region`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stretch {
    /// Every point is nearer the lamp than the surfaces it projects onto: `H = 1`.
    Lit,
    /// Every point is behind them: `H = 0`.
    Dark,
    /// Some of each, or too near to tell without looking each point up.
    Mixed,
}

impl ShadowMap {
    /// What a `size` x `size` map holds, bytes: its depths (4 a texel), their min-max
    /// chain (8 a block, a third more again over the levels: 6.7 bytes a texel in all)
    /// and its end blocks. Charging the depths alone undercounted the maps 1.7 times.
    pub fn bytes(size: usize) -> u64 {
        // The levels as `min_max_chain` makes them: halves of the side down to one.
        let mut width = size.div_ceil(2);
        let mut bytes = 4 * size * size + 8 * width * width;
        while width > 1 {
            width = width.div_ceil(2);
            bytes += 8 * width * width;
        }
        bytes += std::mem::size_of::<EndBlock>() * size.div_ceil(END_BLOCK).pow(2);
        bytes as u64
    }

    /// The `size` x `size` map of `light` over `objects`. Texels wholly outside the
    /// field cone, where `I_l = 0` and nothing is ever looked up, are not traced.
    ///
    /// Every shape is drawn over its footprint alone, as a rasteriser would: a mesh
    /// triangle by triangle, any other bounded shape by its box, each tested only
    /// against the texels its projection covers (widened by a texel); an unbounded
    /// plane covers the whole map. Flat shapes (planes, rectangles, triangles) are
    /// drawn in closed form in the texel's `(u, v)` (`Flat`), spheres and boxes by
    /// the ray cast's own test on the texel's ray: the depths are those of a ray cast
    /// within rounding. That replaces a walk down a mesh's hierarchy for every texel
    /// under its box, and a test of every shape at every texel.
    pub fn new(light: &Spotlight, objects: &Objects, size: usize) -> ShadowMap {
        let mut depth = vec![f32::INFINITY; size * size];
        let whole = [0, size - 1, 0, size - 1];
        let mut drawn: Vec<(Drawn, [usize; 4])> = Vec::new();
        for object in objects.in_cone(light) {
            match &object.shape {
                // Only the triangles under BVH nodes the cone may meet: a rig's set of
                // 147,004 triangles took 23 s of shadow maps for 76 lights drawn whole.
                Shape::Mesh(mesh) => drawn.extend(
                    mesh.triangles_within(|b| super::objects::may_meet_cone(light, b))
                        .into_iter()
                        .filter_map(|tri| {
                            let corners = [tri[0], tri[0] + tri[1], tri[0] + tri[2]];
                            let flat = Flat::new(light, tri[0], tri[1], tri[2], Flat::TRIANGLE)?;
                            Some((Drawn::Flat(flat), footprint(light, corners, size)?))
                        }),
                ),
                Shape::Rect {
                    corner,
                    edge_a,
                    edge_b,
                } => {
                    let corners = [
                        *corner,
                        *corner + *edge_a,
                        *corner + *edge_b,
                        *corner + *edge_a + *edge_b,
                    ];
                    let flat = Flat::new(light, *corner, *edge_a, *edge_b, Flat::PARALLELOGRAM);
                    drawn.extend(
                        flat.zip(footprint(light, corners, size))
                            .map(|(f, area)| (Drawn::Flat(f), area)),
                    );
                }
                Shape::Plane { point, normal } => {
                    drawn.push((Drawn::plane(light, *point, *normal), whole))
                }
                shape => {
                    let area = shape
                        .bounds()
                        .map_or(Some(whole), |b| footprint(light, b.corners(), size));
                    drawn.extend(area.map(|area| (Drawn::Shape(shape), area)));
                }
            }
        }
        depth
            .par_chunks_mut(size * BAND)
            .enumerate()
            .for_each(|(band, rows)| {
                let (first, last) = (band * BAND, band * BAND + rows.len() / size);
                for (shape, [i0, i1, j0, j1]) in &drawn {
                    for row in (*j0).max(first)..(*j1 + 1).min(last) {
                        let v = -texel_centre(row, size);
                        for col in *i0..=*i1 {
                            let u = texel_centre(col, size);
                            if !touches_disc(u, v, size) {
                                continue;
                            }
                            let d = &mut rows[(row - first) * size + col];
                            if let Some(nearer) = shape.depth(light, u, v, *d) {
                                *d = nearer;
                            }
                        }
                    }
                }
            });
        let blocks = size.div_ceil(END_BLOCK);
        let ends = (0..blocks * blocks)
            .into_par_iter()
            .map(|block| {
                let mut e = EndBlock {
                    met: Aabb::EMPTY,
                    deepest: 0.0,
                    open: Aabb::EMPTY,
                };
                // Comparisons, not `Aabb::grow`'s `min` and `max` with their NaN rule
                // (nothing here is NaN): the same boxes. (The same comparisons inside
                // `Aabb::grow` made this loop slower, not faster: 15.5 -> 19.8 ms for
                // the stage's five maps.)
                let grow = |b: &mut Aabb, p: Vec3| {
                    b.min = Vec3::select(p.cmplt(b.min), p, b.min);
                    b.max = Vec3::select(p.cmpgt(b.max), p, b.max);
                };
                for (k, dir) in block_rays(light, size, block) {
                    let d = depth[k];
                    if d.is_finite() {
                        grow(&mut e.met, light.position + d * dir);
                        e.deepest = if d > e.deepest { d } else { e.deepest };
                    } else {
                        grow(&mut e.open, dir);
                    }
                }
                e
            })
            .collect();
        ShadowMap {
            ranges: min_max_chain(&depth, size),
            size,
            depth,
            tan_field: light.tan_field(),
            ends,
        }
    }

    /// The texel that [`ShadowMap::lit_at`] reads for `(u, v)`, as column and row.
    #[inline(always)]
    fn texel(&self, u: f32, v: f32) -> (i32, i32) {
        texel_of(u, v, self.size)
    }

    /// `H` at every point whose projection and light-space depth `(u, v, z)` (as
    /// [`ShadowMap::lit_at`] takes them) lie between `lo` and `hi`: the texels under
    /// the box (texel indices are monotonic in `u` and `v`, so its corners' bound
    /// every point's) against at most four blocks of the min-max chain.
    pub fn region(&self, lo: [f32; 3], hi: [f32; 3]) -> Stretch {
        // Rows run down in v: the region's top row is at its greatest v.
        let ((i0, j0), (i1, j1)) = (self.texel(lo[0], hi[1]), self.texel(hi[0], lo[1]));
        // The finest level where the box spans at most two blocks each way.
        let mut shift = 1;
        while (i0 >> shift) + 1 < i1 >> shift || (j0 >> shift) + 1 < j1 >> shift {
            shift += 1;
        }
        let Some(blocks) = self.ranges.get(shift - 1) else {
            return Stretch::Mixed;
        };
        let width = self.size.div_ceil(1 << shift);
        let (mut least, mut greatest) = (f32::INFINITY, 0.0f32);
        for j in j0 >> shift..=j1 >> shift {
            for i in i0 >> shift..=i1 >> shift {
                let [l, h] = blocks[j as usize * width + i as usize];
                (least, greatest) = (least.min(l), greatest.max(h));
            }
        }
        if hi[2] < least {
            Stretch::Lit
        } else if lo[2] >= greatest {
            Stretch::Dark
        } else {
            Stretch::Mixed
        }
    }

    /// Texel coordinates (continuous, texel centres at +0.5) of the light-space point.
    #[inline]
    fn texel_coordinates(&self, local: Vec3) -> (f32, f32) {
        let scale = 0.5 * self.size as f32 / (local.z * self.tan_field);
        (
            0.5 * self.size as f32 + local.x * scale,
            0.5 * self.size as f32 - local.y * scale,
        )
    }

    /// `H`: whether the point at light-space depth `z` projecting to `(u, v)` (inside
    /// the `[-1, 1]^2` square) is nearer the light than the surface in its texel.
    #[inline]
    pub fn lit_at(&self, u: f32, v: f32, z: f32) -> bool {
        let (i, j) = self.texel(u, v);
        z < self.depth[j as usize * self.size + i as usize]
    }

    /// The lit fraction at a surface point, by percentage-closer filtering against the
    /// receiver's plane: each of the four nearest texels is lit when its depth lies
    /// beyond where the point's tangent plane (light-space `normal`, on the side facing
    /// the lamp) crosses that texel's ray, and the four are weighted bilinearly.
    ///
    /// Comparing each texel with the plane, not with the point's own depth, is what
    /// keeps the receiver from shadowing itself (acne) without moving the lookup: the
    /// usual cure, lifting the point along its normal, shifts its projection away from
    /// the lamp and with it the shadow's edge toward the lamp by the lift's projection
    /// (on the paper's Fig. 6 floor, a pixel-wide rim up to 150 levels wrong). Exact for
    /// flat receivers; a convex one lies behind its tangent plane, so it stays lit; a
    /// concave one is held by [`RECEIVER_BIAS`].
    #[inline]
    pub fn visibility(&self, local: Vec3, normal: Vec3) -> f32 {
        let (x, y) = self.texel_coordinates(local);
        let (fx, fy) = (x - 0.5, y - 0.5);
        let (i, j) = (fx.floor(), fy.floor());
        let (a, b) = (fx - i, fy - j);
        let last = self.size as isize - 1;
        let plane = normal.dot(local);
        let lit = |di: isize, dj: isize| {
            let ii = (i as isize + di).clamp(0, last);
            let jj = (j as isize + dj).clamp(0, last);
            // The texel centre's ray (light-space z = 1) and where it meets the plane;
            // where it does not (it grazes or passes the plane), the point's own depth.
            let ray = Vec3::new(
                texel_centre(ii as usize, self.size) * self.tan_field,
                -texel_centre(jj as usize, self.size) * self.tan_field,
                1.0,
            );
            let facing = normal.dot(ray);
            let z = if facing < 0.0 && plane < 0.0 {
                plane / facing
            } else {
                local.z
            };
            (z * (1.0 - RECEIVER_BIAS) < self.depth[jj as usize * self.size + ii as usize]) as u8
                as f32
        };
        (lit(0, 0) * (1.0 - a) + lit(1, 0) * a) * (1.0 - b)
            + (lit(0, 1) * (1.0 - a) + lit(1, 1) * a) * b
    }

    /// For each block of [`END_BLOCK`] x [`END_BLOCK`] texels with a texel in the field
    /// cone, the block's index and the box around where its rays end (world space, m)
    /// when those that meet nothing are cut at light-space depth `reach`: the smallest
    /// box, to the bit, that holds the points [`ShadowMap::block_ends`] gives; `None`
    /// where a surface lies beyond `reach` (walk those blocks). Made from boxes kept
    /// since the map was built: the cut ends `lamp + reach dir` have the box `lamp +
    /// reach` times the directions' box, coordinate by coordinate (rounding is monotonic).
    pub fn end_boxes<'a>(
        &'a self,
        light: &'a Spotlight,
        reach: f32,
    ) -> impl Iterator<Item = (usize, Option<Aabb>)> + 'a {
        self.ends.iter().enumerate().filter_map(move |(block, e)| {
            if e.met == Aabb::EMPTY && e.open == Aabb::EMPTY {
                return None;
            }
            let open = Aabb {
                min: light.position + reach * e.open.min,
                max: light.position + reach * e.open.max,
            };
            Some((block, (e.deepest <= reach).then(|| e.met.union(open))))
        })
    }

    /// World positions where the rays of the texels of block `block` (as
    /// [`ShadowMap::end_boxes`] numbers them) end: at the surface they meet, or at
    /// light-space depth `reach` m where they meet nothing. Texels outside the field
    /// cone are left out. With the lamp, the ends of all blocks bound the lit volume.
    pub fn block_ends<'a>(
        &'a self,
        light: &'a Spotlight,
        reach: f32,
        block: usize,
    ) -> impl Iterator<Item = Vec3> + 'a {
        block_rays(light, self.size, block)
            .map(move |(k, dir)| light.position + self.depth[k].min(reach) * dir)
    }
}

/// The texels of block `block` (row-major blocks of [`END_BLOCK`] texels on a side) of
/// a `size`-texel map of `light` that touch the field cone: each one's index in the map
/// and its ray's world direction (light-space `z` = 1).
fn block_rays(
    light: &Spotlight,
    size: usize,
    block: usize,
) -> impl Iterator<Item = (usize, Vec3)> + '_ {
    let blocks = size.div_ceil(END_BLOCK);
    let (row0, col0) = ((block / blocks) * END_BLOCK, (block % blocks) * END_BLOCK);
    let cols = col0..(col0 + END_BLOCK).min(size);
    (row0..(row0 + END_BLOCK).min(size)).flat_map(move |row| {
        let v = -texel_centre(row, size);
        // The texel directions along a row are affine in u.
        let (left, right) = (
            light.world_direction(-1.0, v),
            light.world_direction(1.0, v),
        );
        cols.clone().filter_map(move |col| {
            let u = texel_centre(col, size);
            touches_disc(u, v, size)
                .then(|| (row * size + col, left + (right - left) * (0.5 * (u + 1.0))))
        })
    })
}

/// How much nearer than the receiver's plane, as a fraction of its depth, a surface in
/// a shadow map must be to shadow it: above the float error of the two depths (1e-6 of
/// the distances) and the sag of a concave receiver across a texel (a 0.1 m radius
/// seen through 6 mm texels sags 1e-4 of 5 m), below any gap a scene shows (2.5 mm at
/// 5 m).
pub const RECEIVER_BIAS: f32 = 5e-4;

/// Rows of texels a thread makes of a shadow map at a time.
const BAND: usize = 8;

/// What a shadow map draws: one triangle of a mesh, or a whole shape.
#[derive(Clone, Copy)]
enum Drawn<'a> {
    /// A triangle of a mesh or a rectangle.
    Flat(Flat),
    /// A sphere or a box, ray cast.
    Shape(&'a Shape),
    /// An unbounded plane.
    Plane(PlaneDepth),
}

/// A plane seen from a light: the light-space point `z (u tan, v tan, 1)` of the texel
/// ray through `(u, v)` lies on it at `z = depth / (slope . (u, v, 1))`, where
/// `slope` is the light-space normal `n` with its `x` and `y` times `tan` and `depth`
/// is `n` dotted with any point of the plane, the lamp at the origin.
#[derive(Clone, Copy)]
struct PlaneDepth {
    depth: f32,
    slope: Vec3,
}

impl PlaneDepth {
    /// From the light-space normal `n` (any length) and `depth`, `n` dotted with a
    /// point of the plane relative to the lamp.
    fn new(light: &Spotlight, n: Vec3, depth: f32) -> PlaneDepth {
        PlaneDepth {
            depth,
            slope: texel_slope(light, n),
        }
    }

    /// The plane's depth on the texel ray through `(u, v)`.
    #[inline]
    fn depth(&self, u: f32, v: f32) -> f32 {
        self.depth / (self.slope.x * u + self.slope.y * v + self.slope.z)
    }
}

impl Drawn<'_> {
    /// The plane through `point` with unit `normal` (world space) seen from `light`.
    fn plane(light: &Spotlight, point: Vec3, normal: Vec3) -> Drawn<'static> {
        let n = light.light_from_world * normal;
        Drawn::Plane(PlaneDepth::new(
            light,
            n,
            normal.dot(point - light.position),
        ))
    }

    /// The light-space depth at which the ray of `light` through `(u, v)` first meets
    /// this nearer than `nearer_than`, at a distance from the lamp above
    /// [`RAY_EPSILON`], as a ray cast finds it.
    #[inline]
    fn depth(&self, light: &Spotlight, u: f32, v: f32, nearer_than: f32) -> Option<f32> {
        match self {
            Drawn::Flat(flat) => flat.depth(u, v, nearer_than),
            Drawn::Shape(shape) => {
                let (ray, length) = texel_ray(light, u, v);
                let hit = shape.intersect(&ray, nearer_than * length);
                hit.map(|(t, _)| t / length)
            }
            Drawn::Plane(plane) => {
                let z = plane.depth(u, v);
                valid_depth(z, u, v, light.tan_field(), nearer_than).then_some(z)
            }
        }
    }
}

/// The light-space vector `w` as a function of the texel's `(u, v)`: `w` dotted with
/// the texel ray's point `(u tan, v tan, 1)` is `texel_slope . (u, v, 1)`.
fn texel_slope(light: &Spotlight, w: Vec3) -> Vec3 {
    let tan = light.tan_field();
    Vec3::new(w.x * tan, w.y * tan, w.z)
}

/// A parallelogram `corner + a edge_a + b edge_b` (`a, b` in [0, 1]) or a triangle
/// (`a, b >= 0`, `a + b <= 1`) seen from a light, as functions of the texel's `(u, v)`:
/// its plane's depth `z` ([`PlaneDepth`]), and the point's `a` and `b`,
/// `z (a_slope . (u, v, 1)) - a_at_lamp` (the same for `b`): the light-space point
/// `z (u tan, v tan, 1)` dotted with the edges' dual vectors. No ray and no root a
/// texel, where Moller-Trumbore on the texel's unit ray took both.
#[derive(Clone, Copy)]
struct Flat {
    plane: PlaneDepth,
    a_slope: Vec3,
    b_slope: Vec3,
    a_at_lamp: f32,
    b_at_lamp: f32,
    /// `a + b` at most this: 1 for a triangle, 2 (always so) for a parallelogram.
    sum_max: f32,
    /// `tan(field / 2)` of the light, for the distance's guard.
    tan: f32,
}

impl Flat {
    const TRIANGLE: f32 = 1.0;
    const PARALLELOGRAM: f32 = 2.0;

    /// The flat shape with world-space `corner` and edges seen from `light`; `None`
    /// when it is degenerate (no area).
    fn new(
        light: &Spotlight,
        corner: Vec3,
        edge_a: Vec3,
        edge_b: Vec3,
        sum_max: f32,
    ) -> Option<Flat> {
        let m = light.light_from_world;
        let (c, ea, eb) = (m * (corner - light.position), m * edge_a, m * edge_b);
        let n = ea.cross(eb);
        let n2 = n.length_squared();
        if n2 <= 0.0 || !n2.is_finite() {
            return None;
        }
        // (p - c) . dual_a = a and (p - c) . dual_b = b for p = c + a ea + b eb.
        let (dual_a, dual_b) = (eb.cross(n) / n2, n.cross(ea) / n2);
        Some(Flat {
            plane: PlaneDepth::new(light, n, n.dot(c)),
            a_slope: texel_slope(light, dual_a),
            b_slope: texel_slope(light, dual_b),
            a_at_lamp: c.dot(dual_a),
            b_at_lamp: c.dot(dual_b),
            sum_max,
            tan: light.tan_field(),
        })
    }

    /// The depth of the texel ray through `(u, v)` where it meets the shape, nearer than
    /// `nearer_than` and farther from the lamp than [`RAY_EPSILON`].
    #[inline]
    fn depth(&self, u: f32, v: f32, nearer_than: f32) -> Option<f32> {
        let at = |w: Vec3| w.x * u + w.y * v + w.z;
        let z = self.plane.depth(u, v);
        let (a, b) = (
            z * at(self.a_slope) - self.a_at_lamp,
            z * at(self.b_slope) - self.b_at_lamp,
        );
        let inside = (0.0..=1.0).contains(&a) && (0.0..=1.0).contains(&b) && a + b <= self.sum_max;
        (inside && valid_depth(z, u, v, self.tan, nearer_than)).then_some(z)
    }
}

/// Whether a surface at light-space depth `z` on the texel ray through `(u, v)` counts:
/// nearer than `nearer_than`, and farther from the lamp than [`RAY_EPSILON`] (the
/// distance is `z` times the direction's length, compared squared, without a root).
#[inline]
fn valid_depth(z: f32, u: f32, v: f32, tan: f32, nearer_than: f32) -> bool {
    let length2 = 1.0 + (u * tan).powi(2) + (v * tan).powi(2);
    z > 0.0 && z * z * length2 > RAY_EPSILON * RAY_EPSILON && z < nearer_than
}

/// The columns and rows `[i0, i1, j0, j1]` (inclusive) of a `size`-texel map of `light`
/// that a convex body with these `corners` (world space) may cover: their projections
/// widened by a texel; the whole map when a corner is not in front of the lamp, and
/// `None` when none is (rays from the lamp into its field cannot meet it).
fn footprint<const N: usize>(
    light: &Spotlight,
    corners: [Vec3; N],
    size: usize,
) -> Option<[usize; 4]> {
    let last = size as i32 - 1;
    let corners = corners.map(|p| light.to_light(p));
    if corners.iter().all(|c| c.z <= 0.0) {
        return None;
    }
    if corners.iter().any(|c| c.z <= 1e-6) {
        return Some([0, last as usize, 0, last as usize]);
    }
    let scale = 1.0 / light.tan_field();
    let (mut lo, mut hi) = ([i32::MAX; 2], [i32::MIN; 2]);
    for c in corners {
        let (i, j) = texel_of(c.x / c.z * scale, c.y / c.z * scale, size);
        (lo, hi) = ([lo[0].min(i), lo[1].min(j)], [hi[0].max(i), hi[1].max(j)]);
    }
    let clamp = |k: i32| k.clamp(0, last) as usize;
    Some([
        clamp(lo[0] - 1),
        clamp(hi[0] + 1),
        clamp(lo[1] - 1),
        clamp(hi[1] + 1),
    ])
}

/// The texel of a `size`-texel map under `(u, v)` (column, row), clamped to the map.
#[inline(always)]
fn texel_of(u: f32, v: f32, size: usize) -> (i32, i32) {
    let half = 0.5 * size as f32;
    let last = size as i32 - 1;
    // Through i32: a float to usize conversion costs several instructions more, and
    // this is the innermost loop of the plane method.
    (
        ((half + u * half) as i32).clamp(0, last),
        ((half - v * half) as i32).clamp(0, last),
    )
}

/// The min-max chain of a `size`-texel depth map: level 0 holds `[least, greatest]`
/// over 2 x 2 texels, each level after it over 2 x 2 blocks of the one before, down to
/// a single block. (Rows of blocks in parallel: a few tenths of a millisecond for 512^2.)
fn min_max_chain(depth: &[f32], size: usize) -> Vec<Vec<[f32; 2]>> {
    let mut levels = vec![halve(depth, size, |d| [d, d])];
    let mut width = size.div_ceil(2);
    while width > 1 {
        let next = halve(levels.last().expect("level 0 is there"), width, |r| r);
        levels.push(next);
        width = width.div_ceil(2);
    }
    levels
}

/// The least and greatest of each 2 x 2 block of a `width`-wide square of `texels`,
/// each of which is the range `range` gives. (An odd width's last row and column pair
/// with themselves: a range joined with itself is itself.)
fn halve<T: Copy + Send + Sync>(
    texels: &[T],
    width: usize,
    range: impl Fn(T) -> [f32; 2] + Sync,
) -> Vec<[f32; 2]> {
    let half = width.div_ceil(2);
    let mut out = vec![[0.0f32; 2]; half * half];
    out.par_chunks_mut(half).enumerate().for_each(|(j, out)| {
        let (a, b) = (
            &texels[2 * j * width..][..width],
            &texels[(2 * j + 1).min(width - 1) * width..][..width],
        );
        for (i, out) in out.iter_mut().enumerate() {
            let (i0, i1) = (2 * i, (2 * i + 1).min(width - 1));
            let [p, q, r, s] = [a[i0], a[i1], b[i0], b[i1]].map(&range);
            *out = [
                p[0].min(q[0]).min(r[0].min(s[0])),
                p[1].max(q[1]).max(r[1].max(s[1])),
            ];
        }
    });
    out
}

/// The `u` of the centre of column `index` of a `size`-texel map, in [-1, 1]; the `v`
/// of row `index` is its negative (the top row first).
#[inline]
fn texel_centre(index: usize, size: usize) -> f32 {
    2.0 * (index as f32 + 0.5) / size as f32 - 1.0
}

/// The unit ray from `light`'s lamp through its light-space projection `(u, v)`, and
/// the length of that direction with light-space `z` 1: a distance along the ray
/// divided by it is the light-space depth a map holds.
#[inline]
fn texel_ray(light: &Spotlight, u: f32, v: f32) -> (Ray, f32) {
    let dir = light.world_direction(u, v);
    let length = dir.length();
    let ray = Ray {
        origin: light.position,
        dir: dir / length,
    };
    (ray, length)
}

/// Whether the texel centred at `(u, v)` of a `size`-texel map touches the unit disc
/// (the field cone): only those can be lit.
#[inline]
fn touches_disc(u: f32, v: f32, size: usize) -> bool {
    let half = 1.0 / size as f32;
    let (du, dv) = ((u.abs() - half).max(0.0), (v.abs() - half).max(0.0));
    du * du + dv * dv <= 1.0
}

#[cfg(test)]
mod tests {

    use super::*;
    use crate::shafts::objects::Object;
    use crate::shafts::spotlight::{light_frame, Falloff, Profile};

    /// The paper's Fig. 6: a lamp up and to the side, a sphere on the floor.
    fn fig6() -> (Spotlight, Objects) {
        let position = Vec3::new(-4.2, 3.0, -1.2);
        let light = Spotlight::new(
            position,
            light_frame(Vec3::new(0.6, 0.0, 0.2) - position, Vec3::Y).unwrap(),
            Vec3::ONE,
            17f32.to_radians(),
            Profile::Beam {
                beam_half: 12f32.to_radians(),
                falloff: Falloff::Smooth,
            },
            None,
        );
        let object = |shape| Object {
            shape,
            albedo: Vec3::splat(0.5),
            casts_shadow: true,
        };
        let objects = Objects {
            list: vec![
                object(Shape::Plane {
                    point: Vec3::ZERO,
                    normal: Vec3::Y,
                }),
                object(Shape::Sphere {
                    center: Vec3::new(-0.7, 0.5, 0.0),
                    radius: 0.5,
                }),
            ],
        };
        (light, objects)
    }

    /// A mesh of small triangles strewn in the cone and far outside it: the map draws
    /// only the triangles under BVH nodes the cone may meet, and comes out the same as
    /// the map of the mesh without the ones outside.
    #[test]
    fn a_map_draws_only_the_part_of_a_mesh_its_cone_meets() {
        let (light, _) = fig6();
        let tiny = |c: Vec3| {
            [
                c,
                c + Vec3::new(0.05, 0.0, 0.0),
                c + Vec3::new(0.0, 0.05, 0.02),
            ]
        };
        let inside: Vec<[Vec3; 3]> = (0..50)
            .map(|k| tiny(Vec3::new(-0.6 + 0.02 * k as f32, 0.3, 0.1)))
            .collect();
        let outside: Vec<[Vec3; 3]> = (0..400)
            .map(|k| {
                tiny(Vec3::new(
                    20.0 + 0.1 * (k % 20) as f32,
                    5.0,
                    10.0 + 0.1 * (k / 20) as f32,
                ))
            })
            .collect();
        let mesh = |tris: Vec<[Vec3; 3]>| Objects {
            list: vec![Object {
                shape: Shape::Mesh(crate::geometry::Mesh::new(tris)),
                albedo: Vec3::splat(0.5),
                casts_shadow: true,
            }],
        };
        let both = mesh([inside.clone(), outside].concat());
        let Shape::Mesh(m) = &both.list[0].shape else {
            unreachable!()
        };
        let drawn = m.triangles_within(|b| crate::shafts::objects::may_meet_cone(&light, b));
        assert!(
            drawn.len() >= 50 && drawn.len() < 100,
            "{} triangles drawn",
            drawn.len()
        );
        assert_eq!(
            ShadowMap::new(&light, &both, 64).depth,
            ShadowMap::new(&light, &mesh(inside), 64).depth
        );
    }

    /// Whether the lamp sees the floor point under the light-space projection (u, v).
    /// The charge a map is checked against before it is built is what it holds.
    #[test]
    fn a_map_is_charged_what_it_holds() {
        let (light, objects) = fig6();
        for size in [1, 2, 17, 64, 100] {
            let map = ShadowMap::new(&light, &objects, size);
            let held = std::mem::size_of_val(&map.depth[..])
                + map
                    .ranges
                    .iter()
                    .map(|l| std::mem::size_of_val(&l[..]))
                    .sum::<usize>()
                + std::mem::size_of_val(&map.ends[..]);
            assert_eq!(ShadowMap::bytes(size), held as u64, "{size}");
        }
    }

    fn floor_lit(light: &Spotlight, objects: &Objects, u: f32, v: f32) -> bool {
        let dir = light.world_direction(u, v).normalize();
        let t = -light.position.y / dir.y;
        let ray = Ray {
            origin: light.position,
            dir,
        };
        objects
            .hit(&ray, f32::INFINITY)
            .is_none_or(|h| h.t >= t * 0.9999)
    }

    #[test]
    fn the_floor_shadow_lies_where_shadow_rays_put_it() {
        let (light, objects) = fig6();
        let size = 512;
        let map = ShadowMap::new(&light, &objects, size);
        let texel = 2.0 / size as f32;
        let normal = light.light_from_world * Vec3::Y;
        let (mut checked, mut shadowed) = (0, 0);
        // Floor points over the shadow and around it, 4 mm apart.
        for i in 0..900 {
            for k in 0..500 {
                let p = Vec3::new(-1.2 + 0.004 * i as f32, 0.0, -1.0 + 0.004 * k as f32);
                let local = light.to_light(p);
                let (u, v) = (
                    local.x / (local.z * light.tan_field()),
                    local.y / (local.z * light.tan_field()),
                );
                if u * u + v * v > 0.8 {
                    continue;
                }
                // Away from the edge: the floor under every texel the filter reads (within
                // one texel of the point's projection) is lit alike.
                let lit = floor_lit(&light, &objects, u, v);
                let clear = (-1..=1).all(|a| {
                    (-1..=1).all(|b| {
                        floor_lit(&light, &objects, u + a as f32 * texel, v + b as f32 * texel)
                            == lit
                    })
                });
                if !clear {
                    continue;
                }
                let visibility = map.visibility(local, normal);
                assert_eq!(
                    visibility, lit as u8 as f32,
                    "{p:?}: {visibility}, lit {lit}"
                );
                checked += 1;
                shadowed += !lit as usize;
            }
        }
        assert!(
            checked > 100_000 && shadowed > 5_000,
            "{checked} {shadowed}"
        );
    }

    /// The blocks hold every texel in the field cone once, each with its centre's ray,
    /// and a block's box of ray ends is the smallest around them, to the bit, whether
    /// the reach cuts the rays that meet nothing or the surfaces: Fig. 6's lamp, and the
    /// same lamp aimed level, half its rays into the open. The map's side is not a
    /// multiple of the block's, so the last blocks are partial.
    #[test]
    fn end_boxes_hold_each_texels_ray_end_exactly() {
        let (fig6, objects) = fig6();
        let mut level = fig6.clone();
        level.light_from_world = light_frame(Vec3::X, Vec3::Y).unwrap();
        let size = 100;
        let in_cone: Vec<usize> = (0..size * size)
            .filter(|k| {
                touches_disc(
                    texel_centre(k % size, size),
                    -texel_centre(k / size, size),
                    size,
                )
            })
            .collect();
        let (mut open, mut exact, mut cut) = (0, 0, 0);
        for light in [fig6, level] {
            let map = ShadowMap::new(&light, &objects, size);
            open += map.depth.iter().filter(|d| d.is_infinite()).count();
            for reach in [1e3, 3.0] {
                let mut seen = Vec::new();
                for (block, ends) in map.end_boxes(&light, reach) {
                    for (k, dir) in block_rays(&light, size, block) {
                        let (u, v) = (texel_centre(k % size, size), -texel_centre(k / size, size));
                        let want = light.world_direction(u, v);
                        assert!((dir - want).length() <= 1e-6 * want.length(), "{k}: {dir}");
                        seen.push(k);
                    }
                    let walked = map
                        .block_ends(&light, reach, block)
                        .fold(Aabb::EMPTY, Aabb::grow);
                    match ends {
                        Some(ends) => {
                            assert_eq!(ends, walked, "block {block}, reach {reach}");
                            exact += 1;
                        }
                        None => cut += 1,
                    }
                }
                seen.sort_unstable();
                assert_eq!(seen, in_cone, "reach {reach}");
            }
        }
        assert!(
            open > 1000 && exact > 50 && cut > 10,
            "{open} {exact} {cut}"
        );
    }

    #[test]
    fn a_region_is_lit_or_dark_only_when_every_texel_under_it_is() {
        let (light, objects) = fig6();
        let map = ShadowMap::new(&light, &objects, 256);
        let (mut lit, mut dark) = (0, 0);
        for k in 0..4000 {
            // Boxes of all sizes over the map, at depths across the sphere and the floor.
            let f = k as f32;
            let (u, v) = (
                (f * 0.618).fract() * 2.0 - 1.0,
                (f * 0.377).fract() * 2.0 - 1.0,
            );
            let (du, dv) = (
                0.3 * (f * 0.233).fract().powi(3),
                0.3 * (f * 0.571).fract().powi(3),
            );
            let z = 4.0 + 3.0 * (f * 0.731).fract();
            let dz = (f * 0.117).fract().powi(2);
            let (lo, hi) = ([u - du, v - dv, z], [u + du, v + dv, z + dz]);
            let answer = map.region(lo, hi);
            let (i0, j0) = map.texel(lo[0], hi[1]);
            let (i1, j1) = map.texel(hi[0], lo[1]);
            let depths = (j0..=j1).flat_map(|j| (i0..=i1).map(move |i| (i, j)));
            let depths: Vec<f32> = depths
                .map(|(i, j)| map.depth[j as usize * map.size + i as usize])
                .collect();
            match answer {
                Stretch::Lit => {
                    lit += 1;
                    assert!(depths.iter().all(|&d| hi[2] < d), "{lo:?} {hi:?}");
                }
                Stretch::Dark => {
                    dark += 1;
                    assert!(depths.iter().all(|&d| lo[2] >= d), "{lo:?} {hi:?}");
                }
                Stretch::Mixed => {}
            }
        }
        assert!(lit > 500 && dark > 50, "{lit} lit, {dark} dark");
    }

    #[test]
    fn every_shape_drawn_over_its_footprint_gives_the_depths_ray_casting_gives() {
        let folder = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes");
        let stage = crate::shafts::Scene::from_file(&folder.join("stage.toml")).unwrap();
        // Fig. 6 with a box and a card in the beam (no beam of the stage reaches its
        // back wall, a rectangle).
        let (light, mut fig6) = fig6();
        let object = |shape| Object {
            shape,
            albedo: Vec3::splat(0.5),
            casts_shadow: true,
        };
        fig6.list.push(object(Shape::Box(Aabb {
            min: Vec3::new(-2.8, 1.7, -0.9),
            max: Vec3::new(-2.5, 2.0, -0.6),
        })));
        fig6.list.push(object(Shape::Rect {
            corner: Vec3::new(-1.6, 0.9, -0.9),
            edge_a: Vec3::new(0.0, 0.4, 0.0),
            edge_b: Vec3::new(0.1, 0.0, 0.4),
        }));
        let size = 128;
        // Texels whose nearest surface is of each kind of shape.
        let mut seen = std::collections::HashMap::new();
        for (lights, objects) in [
            (stage.spotlights.as_slice(), &stage.objects),
            (&[light], &fig6),
        ] {
            for light in lights {
                let map = ShadowMap::new(light, objects, size);
                for (k, &d) in map.depth.iter().enumerate() {
                    let (u, v) = (texel_centre(k % size, size), -texel_centre(k / size, size));
                    if !touches_disc(u, v, size) {
                        continue;
                    }
                    let (ray, length) = texel_ray(light, u, v);
                    let cast = objects.hit(&ray, f32::INFINITY);
                    let want = cast.map_or(f32::INFINITY, |h| h.t / length);
                    assert!(
                        d == want || (d - want).abs() <= 1e-5 * want,
                        "texel {k}: {d} drawn, {want} cast"
                    );
                    if let Some(hit) = cast {
                        let nearest = objects.list.iter().find(|o| {
                            o.shape
                                .intersect(&ray, f32::INFINITY)
                                .is_some_and(|(t, _)| t == hit.t)
                        });
                        let kind = std::mem::discriminant(&nearest.expect("an object's").shape);
                        *seen.entry(kind).or_insert(0usize) += 1;
                    }
                }
            }
        }
        // A plane, a rectangle, a box, a mesh and a sphere, each the nearest surface
        // somewhere: every footprint is tested.
        assert!(
            seen.len() == 5 && seen.values().all(|&n| n > 20),
            "texels per kind: {seen:?}"
        );
    }
}
