//! The shadow map of a spotlight (shafts 4.1): for each texel of the light's `(u, v)`
//! square, the light-space depth `z` of the nearest surface. A point is lit when it is
//! nearer than that: `H` of shafts (2) on the sample and sub-sample planes, and the
//! shadows on surfaces. The map is made by casting one ray through each texel centre,
//! which is what a rasteriser's depth buffer holds at that texel.

use glam::Vec3;
use rayon::prelude::*;

use super::objects::{nearest_hit, Objects};
use super::spotlight::Spotlight;
use crate::geometry::Ray;

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
}

impl ShadowMap {
    /// The `size` x `size` map of `light` over `objects`. Texels wholly outside the
    /// field cone, where `I_l = 0` and nothing is ever looked up, are not traced.
    pub fn new(light: &Spotlight, objects: &Objects, size: usize) -> ShadowMap {
        let mut depth = vec![f32::INFINITY; size * size];
        let objects = objects.in_cone(light);
        depth
            .par_chunks_mut(size)
            .enumerate()
            .for_each(|(row, out)| {
                let v = 1.0 - 2.0 * (row as f32 + 0.5) / size as f32;
                for (col, d) in out.iter_mut().enumerate() {
                    let u = 2.0 * (col as f32 + 0.5) / size as f32 - 1.0;
                    if !touches_disc(u, v, size) {
                        continue;
                    }
                    let dir = light.world_direction(u, v);
                    let length = dir.length();
                    let ray = Ray {
                        origin: light.position,
                        dir: dir / length,
                    };
                    if let Some(hit) = nearest_hit(objects.iter().copied(), &ray, f32::INFINITY) {
                        // The direction has light-space z = 1: depth is distance / length.
                        *d = hit.t / length;
                    }
                }
            });
        ShadowMap {
            size,
            depth,
            tan_field: light.tan_field(),
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
        let half = 0.5 * self.size as f32;
        let last = (self.size - 1) as i32;
        // Through i32: a float to usize conversion costs several instructions more, and
        // this is the innermost loop of the plane method.
        let i = ((half + u * half) as i32).clamp(0, last) as usize;
        let j = ((half - v * half) as i32).clamp(0, last) as usize;
        z < self.depth[j * self.size + i]
    }

    /// The lit fraction around a surface point, by percentage-closer filtering: the
    /// depth test at the four nearest texels, weighted bilinearly. `local` should be
    /// pushed off its surface first (see [`ShadowMap::texel_size`]).
    #[inline]
    pub fn visibility(&self, local: Vec3) -> f32 {
        let (x, y) = self.texel_coordinates(local);
        let (fx, fy) = (x - 0.5, y - 0.5);
        let (i, j) = (fx.floor(), fy.floor());
        let (a, b) = (fx - i, fy - j);
        let last = self.size as isize - 1;
        let lit = |di: isize, dj: isize| {
            let ii = (i as isize + di).clamp(0, last) as usize;
            let jj = (j as isize + dj).clamp(0, last) as usize;
            (local.z < self.depth[jj * self.size + ii]) as u8 as f32
        };
        (lit(0, 0) * (1.0 - a) + lit(1, 0) * a) * (1.0 - b)
            + (lit(0, 1) * (1.0 - a) + lit(1, 1) * a) * b
    }

    /// The width of one texel at light-space depth `z`, m.
    #[inline]
    pub fn texel_size(&self, z: f32) -> f32 {
        2.0 * z * self.tan_field / self.size as f32
    }

    /// World positions where the rays of the texels of `row` end: at the surface they
    /// meet, or at light-space depth `reach` m where they meet nothing. Texels outside
    /// the field cone are left out. With the lamp, the ends of all rows bound the lit
    /// volume.
    pub fn ray_ends<'a>(
        &'a self,
        light: &'a Spotlight,
        reach: f32,
        row: usize,
    ) -> impl Iterator<Item = Vec3> + 'a {
        let n = self.size;
        let v = 1.0 - 2.0 * (row as f32 + 0.5) / n as f32;
        // The texel directions along a row are affine in u.
        let (left, right) = (
            light.world_direction(-1.0, v),
            light.world_direction(1.0, v),
        );
        (0..n).filter_map(move |col| {
            let u = 2.0 * (col as f32 + 0.5) / n as f32 - 1.0;
            if !touches_disc(u, v, n) {
                return None;
            }
            let dir = left + (right - left) * (0.5 * (u + 1.0));
            Some(light.position + self.depth[row * n + col].min(reach) * dir)
        })
    }
}

/// Whether the texel centred at `(u, v)` of a `size`-texel map touches the unit disc
/// (the field cone): only those can be lit.
#[inline]
fn touches_disc(u: f32, v: f32, size: usize) -> bool {
    let half = 1.0 / size as f32;
    let (du, dv) = ((u.abs() - half).max(0.0), (v.abs() - half).max(0.0));
    du * du + dv * dv <= 1.0
}
