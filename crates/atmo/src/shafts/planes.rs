//! The paper's method (shafts 4.2-4.3): sample planes parallel to the screen through
//! the lit volume of each light; on each, `g = F h` from the tables (5)-(6); between
//! them, sub-sample planes that average `H I_l` over the plane's interval (7)-(9).
//!
//! The GPU draws every plane over the whole screen and lets blending add them up. The
//! CPU version keeps that arithmetic exactly, pixel by pixel, and skips only what
//! cannot contribute: sub-samples where `I_l = 0` (outside the light's field cone, found
//! per ray by [`Spotlight::cone_interval`]), beyond the surface the ray meets (the
//! GPU's depth test), outside the haze, and planes whose whole interval is such. The
//! result is the same sum; the work follows the lit part of each ray.
//!
//! For light `l`, with planes at camera depths `z_i = z_near + (i + 1/2) dz`
//! (`i < n`) and sub-planes at `z_ij = z_near + (i + (j + 1/2)/m) dz` (`j < m`), a
//! camera ray `r` (unit length along the view axis, `|r| = 1 / cos` of its angle off
//! the axis) receives
//!
//! ```text
//! I_s = sum_i J_i F(alpha_i) h(s_i, t_i) dz |r|,   J_i = 1/m sum_j H(z_ij) I_l(z_ij)
//! ```
//!
//! `dz |r|` is shafts' `Delta t`, the length of ray between two planes.

use std::borrow::Cow;

use glam::Vec3;
use rayon::prelude::*;

use super::objects::Aabb;
use super::render_rays;
use super::shadow_map::ShadowMap;
use super::spotlight::Spotlight;
use super::surface::{first_hit, surface_radiance, SurfacePoint};
use super::tables::{AttenuationTable, LightMap, PhaseTable};
use super::Scene;
use crate::image::Frame;

/// Nearest camera depth a plane is put at, m.
const NEAR_PLANE: f32 = 1e-3;

/// One light's shadow map and the depths its planes span.
#[derive(Debug, Clone)]
pub struct LightPlanes<'a> {
    /// `H` for this light: built here, or borrowed when the light and the objects have
    /// not moved since it was built.
    pub shadow: Cow<'a, ShadowMap>,
    /// Camera depth where the first plane interval starts, m.
    pub z_near: f32,
    /// Camera depth where the last plane interval ends, m.
    pub z_far: f32,
    /// A box around the lit volume (the lamp and its shadow map's ray ends): rays that
    /// miss it skip the light.
    pub bounds: Aabb,
    /// Whether the lamp is in the haze: then its in-haze distance to any point in the
    /// (convex) haze is the whole distance.
    lamp_in_haze: bool,
    /// The beam profile, tabulated.
    light_map: LightMap,
}

/// Everything the plane method prepares once a frame: shadow maps, the lit volumes'
/// depth ranges, and the `F` and `h` tables.
#[derive(Debug, Clone)]
pub struct SamplePlanes<'a> {
    scene: &'a Scene,
    /// Per light, in scene order.
    pub lights: Vec<LightPlanes<'a>>,
    phase: PhaseTable,
    attenuation: AttenuationTable,
}

impl<'a> SamplePlanes<'a> {
    /// Builds the shadow maps, finds where each light's lit volume lies in camera depth
    /// (the lamp and the ends of its shadow map's rays), and tabulates `F` and `h`.
    pub fn new(scene: &'a Scene) -> SamplePlanes<'a> {
        SamplePlanes::prepare(
            scene,
            shadow_maps(scene).into_iter().map(Cow::Owned).collect(),
        )
    }

    /// As [`SamplePlanes::new`] with the shadow maps of an earlier frame (from
    /// [`shadow_maps`]), for when only the camera moved: an interactive viewer rebuilds
    /// a light's map only when that light or an object changes.
    pub fn with_shadow_maps(scene: &'a Scene, maps: &'a [ShadowMap]) -> SamplePlanes<'a> {
        assert_eq!(maps.len(), scene.lights.len(), "one shadow map a light");
        SamplePlanes::prepare(scene, maps.iter().map(Cow::Borrowed).collect())
    }

    fn prepare(scene: &'a Scene, maps: Vec<Cow<'a, ShadowMap>>) -> SamplePlanes<'a> {
        let camera = &scene.camera;
        let mut s_max = 0.0f32;
        let mut t_max = 0.0f32;
        let lights = scene
            .lights
            .iter()
            .zip(maps)
            .map(|(light, shadow)| {
                // Farther than this from the lamp is beyond the far plane anyway.
                let reach = camera.far * 2.0 + (light.position - camera.position).length();
                let lamp = camera.depth(light.position);
                // Per row: camera depth range, farthest from the lamp, farthest from the eye.
                let start = (lamp, lamp, 0.0f32, 0.0f32, Aabb::EMPTY.grow(light.position));
                let extent = (0..shadow.size)
                    .into_par_iter()
                    .map(|row| {
                        shadow
                            .ray_ends(light, reach, row)
                            .fold(start, |(lo, hi, s, t, b), end| {
                                let z = camera.depth(end);
                                (
                                    lo.min(z),
                                    hi.max(z),
                                    s.max((end - light.position).length()),
                                    t.max((end - camera.position).length()),
                                    b.grow(end),
                                )
                            })
                    })
                    .reduce(
                        || start,
                        |a, b| {
                            (
                                a.0.min(b.0),
                                a.1.max(b.1),
                                a.2.max(b.2),
                                a.3.max(b.3),
                                a.4.union(b.4),
                            )
                        },
                    );
                let (mut lo, mut hi) = (extent.0, extent.1);
                s_max = s_max.max(extent.2);
                t_max = t_max.max(extent.3);
                if let Some(b) = &scene.haze.bounds {
                    let corners = (0..8).map(|k| {
                        Vec3::select(
                            glam::BVec3::new(k & 1 != 0, k & 2 != 0, k & 4 != 0),
                            b.max,
                            b.min,
                        )
                    });
                    let (bl, bh) = corners
                        .map(|c| camera.depth(c))
                        .fold((f32::INFINITY, f32::NEG_INFINITY), |(l, h), z| {
                            (l.min(z), h.max(z))
                        });
                    lo = lo.max(bl);
                    hi = hi.min(bh);
                }
                LightPlanes {
                    shadow,
                    z_near: lo.max(NEAR_PLANE),
                    z_far: hi.min(camera.far),
                    bounds: extent.4,
                    lamp_in_haze: scene
                        .haze
                        .bounds
                        .map_or(true, |b| b.contains(light.position)),
                    light_map: LightMap::new(light),
                }
            })
            .collect();
        // The longest camera ray per unit depth: to the image's corners.
        let corner = (1.0 + camera.tan_half_width.powi(2) + camera.tan_half_height.powi(2)).sqrt();
        let t_max = t_max.min(camera.far * corner);
        SamplePlanes {
            scene,
            lights,
            phase: PhaseTable::new(&scene.haze),
            attenuation: AttenuationTable::new(&scene.haze, s_max, t_max),
        }
    }

    /// The picture: surfaces lit through shadow maps plus the scattered light.
    pub fn render(&self) -> Frame {
        render_rays(&self.scene.camera, |ray, offset| self.radiance(ray, offset))
    }

    /// The radiance along one camera ray (unit length along the view axis), its
    /// sub-sample planes shifted by `offset` in [0, 1) of their spacing (1/2: the
    /// paper's, centred in their slices).
    pub fn radiance(&self, ray: Vec3, offset: f32) -> Vec3 {
        let scene = self.scene;
        let length = ray.length();
        let dir = ray / length;
        let hit = first_hit(scene, dir, scene.camera.far * length);
        let mut radiance = match &hit {
            Some(point) => {
                surface_radiance(scene, point, |k, light| self.visibility(k, light, point))
            }
            None => Vec3::ZERO,
        };
        let end = hit.map_or(scene.camera.far * length, |p| p.distance);
        for (light, planes) in scene.lights.iter().zip(&self.lights) {
            radiance += self.scattered(light, planes, ray, length, end, offset);
        }
        radiance
    }

    /// How much of `light` the surface point sees: its shadow map, filtered, looked up a
    /// little off the surface (one and a half texels along the normal, against acne).
    fn visibility(&self, k: usize, light: &Spotlight, point: &SurfacePoint) -> f32 {
        let shadow = &self.lights[k].shadow;
        let z = light.to_light(point.position).z;
        let lifted = point.position + point.normal * (1.5 * shadow.texel_size(z) + 1e-4);
        shadow.visibility(light.to_light(lifted))
    }

    /// `I_s` of shafts (7) for one light along the ray `ray` (unit length along the view
    /// axis, `length = |ray|`) up to `end` m from the eye.
    fn scattered(
        &self,
        light: &Spotlight,
        planes: &LightPlanes,
        ray: Vec3,
        length: f32,
        end: f32,
        offset: f32,
    ) -> Vec3 {
        let scene = self.scene;
        let haze = &scene.haze;
        let eye = scene.camera.position;
        let dir = ray / length;
        let Some((ta, tb)) = planes
            .bounds
            .clip(eye, dir.recip(), 0.0, end)
            .and_then(|(a, b)| light.cone_interval(eye, dir, a, b))
            .and_then(|(a, b)| haze.clip(eye, dir, a, b))
        else {
            return Vec3::ZERO;
        };
        // Where the ray enters the haze: a point inside it at distance t has t - entry
        // of its path to the eye in the haze (the haze is convex).
        let entry = haze
            .clip(eye, dir, 0.0, f32::INFINITY)
            .map_or(0.0, |(a, _)| a);
        // The lit stretch of the ray in camera depth, and the planes whose intervals meet it.
        let (za, zb) = (
            (ta / length).max(planes.z_near),
            (tb / length).min(planes.z_far),
        );
        if za >= zb {
            return Vec3::ZERO;
        }
        let n = scene.planes.planes as usize;
        let m = scene.planes.sub_planes as usize;
        let dz = (planes.z_far - planes.z_near) / n as f32;
        let sub = dz / m as f32;
        let inv_sub = 1.0 / sub;
        // All sub-samples of the ray form one progression in depth,
        // z_k = z_near + (k + offset) sub, sub-plane j = k mod m of plane i = k / m;
        // those in the lit stretch are k_first..k_last.
        let k_first = ceil_nonnegative((za - planes.z_near) * inv_sub - offset);
        let k_last = ceil_nonnegative((zb - planes.z_near) * inv_sub - offset).min(n * m);
        // Light-space position along the ray is affine in camera depth.
        let origin = light.to_light(eye);
        let step = light.light_from_world * ray;
        let inv_tan = 1.0 / light.tan_field();
        let shadow = &planes.shadow;
        let inv_length = 1.0 / length;
        // Sub-samples a chunk at a time: first their light-space projections (straight
        // arithmetic, which the compiler vectorises), then the lookups and J_i of
        // shafts (9) (times m, without the light's colour) plane by plane, then g of
        // shafts (6) for the planes the chunk finished, the same way.
        const CHUNK: usize = 64;
        let (mut u, mut v, mut z) = ([0.0f32; CHUNK], [0.0f32; CHUNK], [0.0f32; CHUNK]);
        // Planes finished in a chunk, at most CHUNK + 1 (the last one at the end).
        let mut finished = [0u32; CHUNK + 1];
        let mut j_sums = [Vec3::ZERO; CHUNK + 1];
        let (mut cos_alpha, mut s_haze, mut t_haze, mut inv_s2) = (
            [0.0f32; CHUNK + 1],
            [0.0f32; CHUNK + 1],
            [0.0f32; CHUNK + 1],
            [0.0f32; CHUNK + 1],
        );
        let gobo = light.gobo.is_some();
        let mut sum = Vec3::ZERO;
        let (mut plane, mut j) = (k_first / m, k_first % m);
        let mut j_sum = Vec3::ZERO;
        let mut k0 = k_first;
        while k0 < k_last {
            let count = (k_last - k0).min(CHUNK);
            for c in 0..count {
                let depth = planes.z_near + ((k0 + c) as f32 + offset) * sub;
                // Inside the cone z > 0; the guard keeps rounding at the apex harmless.
                let lz = (origin.z + depth * step.z).max(1e-6);
                let scale = inv_tan / lz;
                u[c] = (origin.x + depth * step.x) * scale;
                v[c] = (origin.y + depth * step.y) * scale;
                z[c] = lz;
            }
            let mut done = 0;
            for c in 0..count {
                let lit = shadow.lit_at(u[c], v[c], z[c]) as u8 as f32;
                let weight = lit * planes.light_map.get(u[c] * u[c] + v[c] * v[c]);
                match &light.gobo {
                    None => j_sum.x += weight,
                    Some(gobo) if weight > 0.0 => j_sum += weight * gobo.sample(u[c], v[c]),
                    Some(_) => {}
                }
                j += 1;
                let last = k0 + c + 1 == k_last;
                if j == m || last {
                    // A plane is finished (or the lit stretch ends inside it).
                    let js = std::mem::take(&mut j_sum);
                    if js != Vec3::ZERO {
                        (finished[done], j_sums[done]) = (plane as u32, js);
                        done += 1;
                    }
                    (plane, j) = (plane + 1, 0);
                }
            }
            // g at the finished planes: positions first, then the table lookups.
            for d in 0..done {
                let depth = planes.z_near + (finished[d] as f32 + 0.5) * dz;
                let local = origin + depth * step;
                let s2 = local.length_squared();
                let inv_s = s2.sqrt().recip();
                cos_alpha[d] = -local.dot(step) * inv_s * inv_length;
                s_haze[d] = s2 * inv_s;
                t_haze[d] = (depth * length - entry).max(0.0);
                inv_s2[d] = inv_s * inv_s;
            }
            if !planes.lamp_in_haze {
                for d in 0..done {
                    let depth = planes.z_near + (finished[d] as f32 + 0.5) * dz;
                    s_haze[d] = haze.length_inside(light.position, eye + depth * ray);
                }
            }
            for d in 0..done {
                let g = self.phase.get(cos_alpha[d])
                    * self.attenuation.get(s_haze[d], t_haze[d])
                    * inv_s2[d];
                let js = if gobo {
                    j_sums[d]
                } else {
                    Vec3::splat(j_sums[d].x)
                };
                sum += js * g;
            }
            k0 += count;
        }
        light.intensity * sum * (dz * length / m as f32)
    }
}

/// The shadow map of each light of `scene`, in scene order.
pub fn shadow_maps(scene: &Scene) -> Vec<ShadowMap> {
    let size = scene.planes.shadow_map as usize;
    scene
        .lights
        .iter()
        .map(|light| ShadowMap::new(light, &scene.objects, size))
        .collect()
}

/// The scene by the plane method.
pub fn render(scene: &Scene) -> Frame {
    SamplePlanes::new(scene).render()
}

/// `ceil(x)` for `x >= 0`, else 0, as an index: without the library call `f32::ceil`
/// is on x86-64's baseline instruction set.
#[inline(always)]
fn ceil_nonnegative(x: f32) -> usize {
    if x > 0.0 {
        let t = x as i32;
        (t + (x > t as f32) as i32) as usize
    } else {
        0
    }
}
