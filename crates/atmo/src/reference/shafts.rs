//! The reference for shafts of light: ray marching, the paper's "conventional method"
//! (shafts 5.1, after Nishita et al. 1987). Along each camera ray and for each light,
//! `samples` midpoint samples; at each inside the light's field, a shadow ray traced
//! against the real geometry for `H`, and the exact phase, attenuation and `1/s^2` of
//! shafts (3). Surfaces are lit through shadow rays too.
//!
//! Two uses, differing in samples and span:
//! - the baseline the plane method's speed is measured against, as in the paper:
//!   `planes x sub_planes` samples (180 at the defaults) spread over the ray's whole
//!   stretch in the haze, eye to surface ([`Span::Ray`]);
//! - the converged reference errors are measured against: samples only over the ray's
//!   stretch inside the field cone, where the integrand can be non-zero (an exact
//!   restriction, [`Span::Cone`]), so many that doubling them changes the picture by
//!   less than 0.1 % RMS.

use glam::Vec3;

use crate::geometry::Ray;
use crate::image::Frame;
use crate::shafts::render_rays;
use crate::shafts::spotlight::Spotlight;
use crate::shafts::surface::{first_hit, shadow_ray, surface_radiance};
use crate::shafts::Scene;

/// Which stretch of a camera ray the samples spread over.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Span {
    /// All of the ray in the haze, from the eye to the surface (or the far plane).
    Ray,
    /// The part of that inside the light's field cone.
    Cone,
}

/// Ray marching with shadow rays.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RayMarcher {
    /// Samples per camera ray and light.
    pub samples: u32,
    /// Where they go.
    pub span: Span,
}

impl RayMarcher {
    /// The converged reference: doubling its samples changes the paper's Fig. 6 scene
    /// by less than 0.1 % RMS (`atmo bench shafts` checks it).
    pub const CONVERGED: RayMarcher = RayMarcher {
        samples: 2048,
        span: Span::Cone,
    };

    /// The baseline for `scene`: as many samples as planes x sub-planes along the ray.
    pub fn baseline(scene: &Scene) -> RayMarcher {
        RayMarcher {
            samples: scene.planes.planes * scene.planes.sub_planes,
            span: Span::Ray,
        }
    }

    /// The picture.
    pub fn render(&self, scene: &Scene) -> Frame {
        render_rays(&scene.camera, |ray, _| self.radiance(scene, ray))
    }

    /// The radiance along one camera ray (unit length along the view axis).
    pub fn radiance(&self, scene: &Scene, ray: Vec3) -> Vec3 {
        let length = ray.length();
        let dir = ray / length;
        let far = scene.far_m() * length;
        let hit = first_hit(scene, dir, far);
        let mut radiance = match &hit {
            Some(point) => {
                surface_radiance(scene, point, |_, light| shadow_ray(scene, light, point))
            }
            None => Vec3::ZERO,
        };
        let end = hit.map_or(far, |p| p.distance);
        for light in scene.lights() {
            radiance += self.scattered(scene, light, dir, end);
        }
        radiance
    }

    /// `I_s` of shafts (2) for one light along the unit direction `dir` up to `end` m.
    fn scattered(&self, scene: &Scene, light: &Spotlight, dir: Vec3, end: f32) -> Vec3 {
        let eye = scene.camera.position;
        let haze = &scene.haze;
        let stretch = match self.span {
            Span::Ray => Some((0.0, end)),
            Span::Cone => light.cone_interval(eye, dir, 0.0, end),
        };
        let Some((ta, tb)) = stretch.and_then(|(a, b)| haze.clip(eye, dir, a, b)) else {
            return Vec3::ZERO;
        };
        let dt = (tb - ta) / self.samples as f32;
        let mut sum = Vec3::ZERO;
        for k in 0..self.samples {
            let t = ta + (k as f32 + 0.5) * dt;
            let point = eye + t * dir;
            let intensity = light.intensity_toward(light.to_light(point));
            if intensity == Vec3::ZERO {
                continue;
            }
            let from_lamp = point - light.position;
            let s = from_lamp.length();
            let to_lamp = Ray {
                origin: point,
                dir: -from_lamp / s,
            };
            if scene.objects.occluded(&to_lamp, s) {
                continue;
            }
            let phase = haze.phase.eval_f32(-from_lamp.dot(dir) / s);
            let path = haze.length_inside(light.position, point) + haze.length_inside(eye, point);
            let g = haze.scattering() * phase * (-haze.extinction * path).exp() / (s * s);
            sum += intensity * g;
        }
        sum * dt
    }
}
