//! The scene's opaque objects: shapes (see [`crate::geometry`]) each with a Lambertian
//! albedo. They are what the camera sees (the first term of shafts (1)), what casts
//! shadows into the beams (H in shafts (2)), and what the shadow maps and the
//! reference's shadow rays are traced against.

use glam::Vec3;

use crate::geometry::{Ray, Shape};

/// Where a ray meets a surface.
#[derive(Debug, Clone, Copy)]
pub struct Hit {
    /// Distance along the ray, m.
    pub t: f32,
    /// Unit surface normal (either side; shading picks the side facing the viewer).
    pub normal: Vec3,
    /// Lambertian albedo of the surface, linear RGB in [0, 1].
    pub albedo: Vec3,
}

/// One object: a shape and its albedo.
#[derive(Debug, Clone)]
pub struct Object {
    /// The geometry.
    pub shape: Shape,
    /// Lambertian albedo, linear RGB in [0, 1].
    pub albedo: Vec3,
    /// Whether it casts shadows: false for a moving head's body, which holds its own
    /// lamp ([`super::show::Fixture::body`]); it is still seen and lit.
    pub casts_shadow: bool,
}

/// All objects of a scene.
#[derive(Debug, Clone, Default)]
pub struct Objects {
    /// The objects, in file order.
    pub list: Vec<Object>,
}

impl Objects {
    /// The nearest hit with `t` in `(RAY_EPSILON, t_max)`.
    pub fn hit(&self, ray: &Ray, t_max: f32) -> Option<Hit> {
        nearest_hit(&self.list, ray, t_max)
    }

    /// The objects that may meet a ray from `light` inside its field cone (by their
    /// bounding spheres; unbounded planes always): what its shadow map is traced against.
    pub fn in_cone(&self, light: &super::spotlight::Spotlight) -> Vec<&Object> {
        self.indices_in_cone(light)
            .into_iter()
            .map(|i| &self.list[i as usize])
            .collect()
    }

    /// The indices in `list` of the objects [`Objects::in_cone`] gives.
    pub fn indices_in_cone(&self, light: &super::spotlight::Spotlight) -> Vec<u32> {
        (0..self.list.len() as u32)
            .filter(|&i| self.list[i as usize].casts_shadow)
            .filter(|&i| {
                self.list[i as usize]
                    .shape
                    .bounds()
                    .is_none_or(|b| may_meet_cone(light, &b))
            })
            .collect()
    }
}

/// Whether the box `b` may meet `light`'s field cone: its bounding sphere does (the
/// centre within the radius of the cone, the angle test widened by the radius).
pub fn may_meet_cone(light: &super::spotlight::Spotlight, b: &crate::geometry::Aabb) -> bool {
    let (sin, cos) = light.field_half.sin_cos();
    let axis = light.light_from_world.row(2);
    let centre = 0.5 * (b.min + b.max);
    let radius = 0.5 * (b.max - b.min).length();
    let w = centre - light.position;
    let along = w.dot(axis);
    let across = (w.length_squared() - along * along).max(0.0).sqrt();
    w.length() <= radius || across * cos - along * sin <= radius
}

impl Objects {
    /// True when any surface lies on the ray with `t` in `(RAY_EPSILON, t_max)`: the
    /// shadow ray of the reference integrator.
    pub fn occluded(&self, ray: &Ray, t_max: f32) -> bool {
        self.list
            .iter()
            .any(|o| o.casts_shadow && o.shape.intersect(ray, t_max).is_some())
    }
}

/// The nearest hit among `objects` with `t` in `(RAY_EPSILON, t_max)`.
pub fn nearest_hit<'a>(
    objects: impl IntoIterator<Item = &'a Object>,
    ray: &Ray,
    t_max: f32,
) -> Option<Hit> {
    let mut best: Option<Hit> = None;
    let mut t_max = t_max;
    for object in objects {
        if let Some((t, normal)) = object.shape.intersect(ray, t_max) {
            t_max = t;
            best = Some(Hit {
                t,
                normal,
                albedo: object.albedo,
            });
        }
    }
    best
}
