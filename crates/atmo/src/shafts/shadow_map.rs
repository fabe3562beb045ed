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
                let v = -texel_centre(row, size);
                for (col, d) in out.iter_mut().enumerate() {
                    let u = texel_centre(col, size);
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
        let v = -texel_centre(row, n);
        // The texel directions along a row are affine in u.
        let (left, right) = (
            light.world_direction(-1.0, v),
            light.world_direction(1.0, v),
        );
        (0..n).filter_map(move |col| {
            let u = texel_centre(col, n);
            if !touches_disc(u, v, n) {
                return None;
            }
            let dir = left + (right - left) * (0.5 * (u + 1.0));
            Some(light.position + self.depth[row * n + col].min(reach) * dir)
        })
    }
}

/// How much nearer than the receiver's plane, as a fraction of its depth, a surface in
/// a shadow map must be to shadow it: above the float error of the two depths (1e-6 of
/// the distances) and the sag of a concave receiver across a texel (a 0.1 m radius
/// seen through 6 mm texels sags 1e-4 of 5 m), below any gap a scene shows (2.5 mm at
/// 5 m).
pub const RECEIVER_BIAS: f32 = 5e-4;

/// The `u` of the centre of column `index` of a `size`-texel map, in [-1, 1]; the `v`
/// of row `index` is its negative (the top row first).
#[inline]
fn texel_centre(index: usize, size: usize) -> f32 {
    2.0 * (index as f32 + 0.5) / size as f32 - 1.0
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
    use crate::geometry::Shape;
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

    /// Whether the lamp sees the floor point under the light-space projection (u, v).
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
}
