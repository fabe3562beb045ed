//! The first term of shafts (1): the surface a camera ray meets, lit by the spotlights
//! (Lambertian) and dimmed by the haze on both legs, from the lamp and to the eye.

use std::f32::consts::FRAC_1_PI;

use glam::Vec3;

use super::objects::{nearest_hit, Object};
use super::spotlight::Spotlight;
use super::Scene;
use crate::geometry::Ray;

/// The nearest surface along a camera ray.
#[derive(Debug, Clone, Copy)]
pub struct SurfacePoint {
    /// Where, m.
    pub position: Vec3,
    /// Unit normal on the side facing the eye.
    pub normal: Vec3,
    /// Lambertian albedo.
    pub albedo: Vec3,
    /// Distance from the eye, m.
    pub distance: f32,
}

/// The nearest surface along the unit direction `dir` from the camera, within
/// `max_distance` m.
pub fn first_hit(scene: &Scene, dir: Vec3, max_distance: f32) -> Option<SurfacePoint> {
    first_hit_among(scene, &scene.objects.list, dir, max_distance)
}

/// [`first_hit`] among `objects` alone (the others known not to lie on the ray).
pub fn first_hit_among<'a>(
    scene: &Scene,
    objects: impl IntoIterator<Item = &'a Object>,
    dir: Vec3,
    max_distance: f32,
) -> Option<SurfacePoint> {
    let origin = scene.camera.position;
    let hit = nearest_hit(objects, &Ray { origin, dir }, max_distance)?;
    let normal = if hit.normal.dot(dir) > 0.0 {
        -hit.normal
    } else {
        hit.normal
    };
    Some(SurfacePoint {
        position: origin + hit.t * dir,
        normal,
        albedo: hit.albedo,
        distance: hit.t,
    })
}

/// `I_o exp(-sigma_t T)`: the radiance the eye receives from `point`. `visibility`
/// gives, for a light index and the light, the fraction of the lamp the point sees
/// (a shadow map lookup or a shadow ray).
pub fn surface_radiance(
    scene: &Scene,
    point: &SurfacePoint,
    visibility: impl Fn(usize, &Spotlight) -> f32,
) -> Vec3 {
    let haze = &scene.haze;
    let mut sum = Vec3::ZERO;
    for (k, light) in scene.lights().enumerate() {
        let to_lamp = light.position - point.position;
        let s = to_lamp.length();
        let cos = point.normal.dot(to_lamp) / s;
        if cos <= 0.0 {
            continue;
        }
        let intensity = light.intensity_toward(light.to_light(point.position));
        if intensity == Vec3::ZERO {
            continue;
        }
        let v = visibility(k, light);
        if v <= 0.0 {
            continue;
        }
        let attenuation =
            (-haze.extinction * haze.length_inside(light.position, point.position)).exp();
        sum += intensity * (v * cos * attenuation / (s * s));
    }
    if sum == Vec3::ZERO {
        return sum;
    }
    let to_eye =
        (-haze.extinction * haze.length_inside(scene.camera.position, point.position)).exp();
    point.albedo * FRAC_1_PI * sum * to_eye
}

/// 1 when nothing lies between the surface point (lifted off its surface by 0.1 mm)
/// and the lamp, else 0: the exact visibility, which the reference takes everywhere and
/// the plane method where a shadow map's filter straddles an edge.
pub fn shadow_ray(scene: &Scene, light: &Spotlight, point: &SurfacePoint) -> f32 {
    let origin = point.position + point.normal * 1e-4;
    let to_lamp = light.position - origin;
    let s = to_lamp.length();
    let ray = Ray {
        origin,
        dir: to_lamp / s,
    };
    (!scene.objects.occluded(&ray, s)) as u8 as f32
}

/// The pixels (row-major indices) of `scene`'s camera whose centre ray meets a surface,
/// and the others, where only haze is seen: errors are told apart by kind (a shadow's
/// edge is among the first, the lamp's own pixel among the second).
pub fn pixel_kinds(scene: &Scene) -> (Vec<usize>, Vec<usize>) {
    let camera = &scene.camera;
    let (width, far) = (camera.width as usize, scene.far_m());
    (0..width * camera.height as usize).partition(|&k| {
        let ray = camera.ray((k % width) as f32 + 0.5, (k / width) as f32 + 0.5);
        let length = ray.length();
        first_hit(scene, ray / length, far * length).is_some()
    })
}
