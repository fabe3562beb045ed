//! Geometry shared by every method that traces rays: rays, axis-aligned boxes, the
//! shapes objects are made of (planes, rectangles, spheres, boxes, triangle meshes with
//! their BVH) and their intersections. World frame and metres, see [`crate::view`].

use glam::Vec3;

/// A ray cast from `origin` along the unit vector `dir`.
#[derive(Debug, Clone, Copy)]
pub struct Ray {
    /// Start point, m.
    pub origin: Vec3,
    /// Unit direction.
    pub dir: Vec3,
}

/// An axis-aligned box, m.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Aabb {
    /// Smallest corner.
    pub min: Vec3,
    /// Largest corner.
    pub max: Vec3,
}

impl Aabb {
    /// The empty box (union identity).
    pub const EMPTY: Aabb = Aabb {
        min: Vec3::splat(f32::INFINITY),
        max: Vec3::splat(f32::NEG_INFINITY),
    };

    /// The smallest box holding both.
    pub fn union(self, other: Aabb) -> Aabb {
        Aabb {
            min: self.min.min(other.min),
            max: self.max.max(other.max),
        }
    }

    /// The smallest box holding `self` and `p`.
    pub fn grow(self, p: Vec3) -> Aabb {
        Aabb {
            min: self.min.min(p),
            max: self.max.max(p),
        }
    }

    /// The eight corners.
    pub fn corners(&self) -> [Vec3; 8] {
        std::array::from_fn(|k| {
            Vec3::select(
                glam::BVec3::new(k & 1 != 0, k & 2 != 0, k & 4 != 0),
                self.max,
                self.min,
            )
        })
    }

    /// The parameter interval `[t0, t1]` (clipped to `[t_min, t_max]`) where the line
    /// `origin + t dir` is inside the box, by the slab method; `None` if it misses.
    /// `inv_dir` is `1 / dir` per component (infinite components are fine).
    #[inline]
    pub fn clip(&self, origin: Vec3, inv_dir: Vec3, t_min: f32, t_max: f32) -> Option<(f32, f32)> {
        let a = (self.min - origin) * inv_dir;
        let b = (self.max - origin) * inv_dir;
        // NaN (0 * inf, on a slab face) compares false and is dropped by max/min.
        let t0 = a.min(b).max_element().max(t_min);
        let t1 = a.max(b).min_element().min(t_max);
        (t0 <= t1).then_some((t0, t1))
    }

    /// True when `p` is inside or on the box.
    #[inline]
    pub fn contains(&self, p: Vec3) -> bool {
        p.cmpge(self.min).all() && p.cmple(self.max).all()
    }
}

/// The shape of an object, in world coordinates (m).
#[derive(Debug, Clone)]
pub enum Shape {
    /// The infinite plane through `point` with unit `normal`.
    Plane { point: Vec3, normal: Vec3 },
    /// The parallelogram `corner + a edge_a + b edge_b`, `a, b` in [0, 1].
    Rect {
        corner: Vec3,
        edge_a: Vec3,
        edge_b: Vec3,
    },
    /// A sphere.
    Sphere { center: Vec3, radius: f32 },
    /// An axis-aligned box.
    Box(Aabb),
    /// Triangles with a bounding volume hierarchy.
    Mesh(Mesh),
}

/// Surfaces closer than this to a ray's origin are not hit, m: keeps a shadow ray from
/// finding the surface it starts on.
pub const RAY_EPSILON: f32 = 1e-4;

impl Shape {
    /// The nearest `(t, unit normal)` with `t` in `(RAY_EPSILON, t_max)`.
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<(f32, Vec3)> {
        let valid = |t: f32| t > RAY_EPSILON && t < t_max;
        match self {
            Shape::Plane { point, normal } => {
                let denom = normal.dot(ray.dir);
                let t = (*point - ray.origin).dot(*normal) / denom;
                valid(t).then_some((t, *normal))
            }
            Shape::Rect {
                corner,
                edge_a,
                edge_b,
            } => {
                let (t, a, b) = parallelogram(ray, *corner, *edge_a, *edge_b)?;
                (valid(t) && (0.0..=1.0).contains(&a) && (0.0..=1.0).contains(&b))
                    .then(|| (t, edge_a.cross(*edge_b).normalize()))
            }
            Shape::Sphere { center, radius } => {
                // Haines et al., "Precision improvements for ray/sphere intersection"
                // (Ray Tracing Gems, 2019): the discriminant from the ray's closest
                // approach to the centre, r^2 - |f - (f.d) d|^2, and the near root as
                // c / q. The textbook b^2 - c lost the hit by half a millimetre for a
                // ray from 40 m grazing a 0.6 m ball, inside it by more than a shadow
                // ray's lift: the reference's acne on a lit sphere's rim (test
                // grazing_rays_meet_a_sphere_on_its_surface_and_never_shadow_it).
                let f = ray.origin - *center;
                let b = -f.dot(ray.dir);
                let closest = f + b * ray.dir;
                let disc = radius * radius - closest.length_squared();
                if disc < 0.0 {
                    return None;
                }
                let c = f.length_squared() - radius * radius;
                let q = b + b.signum() * disc.sqrt();
                let (t0, t1) = if q == 0.0 { (0.0, 0.0) } else { (c / q, q) };
                let (near, far) = (t0.min(t1), t0.max(t1));
                let t = if valid(near) { near } else { far };
                valid(t).then(|| (t, (ray.origin + t * ray.dir - *center).normalize()))
            }
            Shape::Box(aabb) => {
                let (t0, t1) = aabb.clip(ray.origin, ray.dir.recip(), f32::NEG_INFINITY, t_max)?;
                let t = if valid(t0) { t0 } else { t1 };
                if !valid(t) {
                    return None;
                }
                // The face hit is the one the point lies on (nearest slab).
                let p = ray.origin + t * ray.dir;
                let centre = 0.5 * (aabb.min + aabb.max);
                let d = (p - centre) / (0.5 * (aabb.max - aabb.min));
                let a = d.abs();
                let normal = if a.x >= a.y && a.x >= a.z {
                    Vec3::X * d.x.signum()
                } else if a.y >= a.z {
                    Vec3::Y * d.y.signum()
                } else {
                    Vec3::Z * d.z.signum()
                };
                Some((t, normal))
            }
            Shape::Mesh(mesh) => mesh.intersect(ray, t_max),
        }
    }

    /// A box holding the shape, or `None` for an unbounded plane.
    pub fn bounds(&self) -> Option<Aabb> {
        match self {
            Shape::Plane { .. } => None,
            Shape::Rect {
                corner,
                edge_a,
                edge_b,
            } => Some(
                [
                    *corner,
                    *corner + *edge_a,
                    *corner + *edge_b,
                    *corner + *edge_a + *edge_b,
                ]
                .into_iter()
                .fold(Aabb::EMPTY, Aabb::grow),
            ),
            Shape::Sphere { center, radius } => Some(Aabb {
                min: *center - Vec3::splat(*radius),
                max: *center + Vec3::splat(*radius),
            }),
            Shape::Box(b) => Some(*b),
            Shape::Mesh(mesh) => Some(mesh.nodes[0].bounds),
        }
    }
}

/// Ray against the parallelogram `corner + a edge_a + b edge_b` (Möller-Trumbore):
/// `(t, a, b)`, or `None` when the ray is parallel to it.
#[inline]
fn parallelogram(ray: &Ray, corner: Vec3, edge_a: Vec3, edge_b: Vec3) -> Option<(f32, f32, f32)> {
    let p = ray.dir.cross(edge_b);
    let det = edge_a.dot(p);
    if det.abs() < 1e-12 {
        return None;
    }
    let inv = 1.0 / det;
    let s = ray.origin - corner;
    let a = s.dot(p) * inv;
    let q = s.cross(edge_a);
    let b = ray.dir.dot(q) * inv;
    let t = edge_b.dot(q) * inv;
    Some((t, a, b))
}

/// Where `ray` meets the triangle `[a, b - a, c - a]` (as [`Mesh::triangles`] holds
/// it), with `t` in `(RAY_EPSILON, t_max)`.
#[inline]
pub fn triangle_hit(ray: &Ray, tri: &[Vec3; 3], t_max: f32) -> Option<f32> {
    let (t, a, b) = parallelogram(ray, tri[0], tri[1], tri[2])?;
    (t > RAY_EPSILON && t < t_max && a >= 0.0 && b >= 0.0 && a + b <= 1.0).then_some(t)
}

/// A triangle mesh with a bounding volume hierarchy (binary, split at the median
/// centroid along the longest axis; at most [`Mesh::LEAF_SIZE`] triangles a leaf).
/// Written here rather than taken from a crate: it is 60 lines, and the crates for it
/// pull in far more than the ray-triangle test this needs.
#[derive(Debug, Clone)]
pub struct Mesh {
    /// Triangles as (vertex, edge 1, edge 2), m, in BVH leaf order.
    triangles: Vec<[Vec3; 3]>,
    nodes: Vec<BvhNode>,
}

#[derive(Debug, Clone, Copy)]
struct BvhNode {
    bounds: Aabb,
    /// Leaf: first triangle; inner: index of the second child (the first follows).
    start: u32,
    /// Leaf: triangle count; inner: 0.
    count: u32,
}

impl Mesh {
    /// Most triangles in a leaf.
    pub const LEAF_SIZE: usize = 4;

    /// A mesh of the triangles `[a, b, c]` (at least one, none degenerate).
    pub fn new(triangles: Vec<[Vec3; 3]>) -> Mesh {
        let mut tris: Vec<[Vec3; 3]> = triangles
            .into_iter()
            .map(|[a, b, c]| [a, b - a, c - a])
            .collect();
        let mut nodes = Vec::with_capacity(2 * tris.len() / Self::LEAF_SIZE + 1);
        Self::build(&mut tris, 0, &mut nodes);
        Mesh {
            triangles: tris,
            nodes,
        }
    }

    /// Number of triangles.
    pub fn len(&self) -> usize {
        self.triangles.len()
    }

    /// What the triangles and their hierarchy hold, bytes.
    pub fn bytes(&self) -> u64 {
        (std::mem::size_of_val(&self.triangles[..]) + std::mem::size_of_val(&self.nodes[..])) as u64
    }

    /// The triangles as the BVH orders them, each as `[a, b - a, c - a]`.
    pub fn triangles(&self) -> &[[Vec3; 3]] {
        &self.triangles
    }

    /// The BVH, depth first from the root: `(bounds, start, count)`; a leaf holds
    /// triangles `start..start + count`, an inner node (`count` 0) has its first child
    /// next to it and its second at `start`.
    pub fn nodes(&self) -> impl Iterator<Item = (Aabb, u32, u32)> + '_ {
        self.nodes.iter().map(|n| (n.bounds, n.start, n.count))
    }

    /// The triangles (as [`Mesh::triangles`] gives them) under the BVH's leaves whose
    /// every ancestor's bounds `keep` accepts: a rejected node skips its subtree, so a
    /// light's shadow map draws only the part of a large mesh its cone may meet.
    pub fn triangles_within(&self, keep: impl Fn(&Aabb) -> bool) -> Vec<&[Vec3; 3]> {
        let mut out = Vec::new();
        let mut stack = vec![0u32];
        while let Some(index) = stack.pop() {
            let node = self.nodes[index as usize];
            if !keep(&node.bounds) {
                continue;
            }
            if node.count == 0 {
                stack.extend([index + 1, node.start]);
            } else {
                out.extend(
                    &self.triangles[node.start as usize..(node.start + node.count) as usize],
                );
            }
        }
        out
    }

    /// True when the mesh has no triangles.
    pub fn is_empty(&self) -> bool {
        self.triangles.is_empty()
    }

    fn build(tris: &mut [[Vec3; 3]], offset: usize, nodes: &mut Vec<BvhNode>) {
        let bounds = tris.iter().fold(Aabb::EMPTY, |b, [a, e1, e2]| {
            b.grow(*a).grow(*a + *e1).grow(*a + *e2)
        });
        let index = nodes.len();
        nodes.push(BvhNode {
            bounds,
            start: offset as u32,
            count: tris.len() as u32,
        });
        if tris.len() <= Self::LEAF_SIZE {
            return;
        }
        let centroid = |t: &[Vec3; 3]| t[0] + (t[1] + t[2]) / 3.0;
        let extent = bounds.max - bounds.min;
        let axis = if extent.x >= extent.y && extent.x >= extent.z {
            0
        } else if extent.y >= extent.z {
            1
        } else {
            2
        };
        let mid = tris.len() / 2;
        tris.select_nth_unstable_by(mid, |a, b| centroid(a)[axis].total_cmp(&centroid(b)[axis]));
        let (left, right) = tris.split_at_mut(mid);
        Self::build(left, offset, nodes);
        nodes[index].start = nodes.len() as u32;
        nodes[index].count = 0;
        Self::build(right, offset + mid, nodes);
    }

    fn intersect(&self, ray: &Ray, t_max: f32) -> Option<(f32, Vec3)> {
        let inv = ray.dir.recip();
        let mut best: Option<(f32, Vec3)> = None;
        let mut t_best = t_max;
        let mut stack = [0u32; 64];
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let index = stack[top];
            let node = self.nodes[index as usize];
            if node.bounds.clip(ray.origin, inv, 0.0, t_best).is_none() {
                continue;
            }
            if node.count == 0 {
                // Children: the first follows its parent, the second is at `start`.
                stack[top] = index + 1;
                stack[top + 1] = node.start;
                top += 2;
                continue;
            }
            for tri in &self.triangles[node.start as usize..(node.start + node.count) as usize] {
                if let Some(t) = triangle_hit(ray, tri, t_best) {
                    t_best = t;
                    best = Some((t, tri[1].cross(tri[2]).normalize()));
                }
            }
        }
        best
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// SplitMix64 numbers in [0, 1): the same soup of triangles on every machine.
    struct Numbers(u64);

    impl Numbers {
        fn next(&mut self) -> f32 {
            self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
            let mut z = self.0;
            z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
            ((z ^ (z >> 31)) >> 40) as f32 / (1u64 << 24) as f32
        }

        fn point(&mut self, half: f32) -> Vec3 {
            Vec3::new(self.next(), self.next(), self.next()) * (2.0 * half) - Vec3::splat(half)
        }
    }

    /// The BVH finds exactly the nearest hit that testing every triangle finds: 2,000
    /// small triangles strewn through a box (deep trees, overlapping leaves), 4,000
    /// rays from outside and inside it, some cut short by `t_max`.
    #[test]
    fn the_bvh_finds_what_every_triangle_tested_finds() {
        let mut n = Numbers(7);
        let soup: Vec<[Vec3; 3]> = (0..2000)
            .map(|_| {
                let a = n.point(10.0);
                [a, a + n.point(0.8), a + n.point(0.8)]
            })
            .collect();
        let mesh = Mesh::new(soup);
        assert!(mesh.nodes().count() > 500, "a deep tree");
        let (mut hits, mut misses) = (0, 0);
        for k in 0..4000 {
            let origin = n.point(if k % 2 == 0 { 14.0 } else { 8.0 });
            let dir = (n.point(1.0) + Vec3::splat(1e-3)).normalize();
            let ray = Ray { origin, dir };
            let t_max = if k % 3 == 0 { 6.0 } else { f32::INFINITY };
            let brute = mesh
                .triangles()
                .iter()
                .filter_map(|tri| triangle_hit(&ray, tri, t_max).map(|t| (t, tri)))
                .min_by(|a, b| a.0.total_cmp(&b.0));
            let bvh = mesh.intersect(&ray, t_max);
            match (brute, bvh) {
                (None, None) => misses += 1,
                (Some((t, tri)), Some((t_bvh, normal))) => {
                    assert_eq!(t, t_bvh, "ray {k}");
                    // The normal is that of a triangle the ray meets at that distance.
                    let same = tri[1].cross(tri[2]).normalize();
                    assert!(
                        normal == same
                            || mesh.triangles().iter().any(|o| {
                                triangle_hit(&ray, o, t_max) == Some(t)
                                    && o[1].cross(o[2]).normalize() == normal
                            }),
                        "ray {k}"
                    );
                    hits += 1;
                }
                (brute, bvh) => panic!("ray {k}: every triangle {brute:?}, BVH {bvh:?}"),
            }
        }
        // Both outcomes are well represented.
        assert!(hits > 500 && misses > 500, "{hits} hits, {misses} misses");
    }

    /// Rays from 5 to 40 m that graze a 0.6 m sphere (the camera rays of a silhouette's
    /// pixels) hit it on its surface, and a shadow ray from each lit hit (lifted 0.1 mm
    /// along its normal, as the reference lifts it) toward a light beside the sphere,
    /// its light grazing the terminator, is never stopped by the sphere itself.
    #[test]
    fn grazing_rays_meet_a_sphere_on_its_surface_and_never_shadow_it() {
        let (center, radius) = (Vec3::new(-0.8, 0.6, -1.2), 0.6f32);
        let sphere = Shape::Sphere { center, radius };
        let mut n = Numbers(11);
        let (mut grazing, mut worst, mut shadowed) = (0, 0f32, 0);
        for _ in 0..20_000 {
            // From 5 to 40 m: a stage's camera, up to the back of a hall.
            let eye = center + (Vec3::new(0.3, 1.1, 9.9) + n.point(0.5)) * (0.5 + 3.5 * n.next());
            let to = center - eye;
            // The ray passes the centre at radius (1 - delta), delta 1e-7 to 1e-3: its
            // angle off the centre's direction has sine r (1 - delta) / |to|.
            let side = to.cross(n.point(1.0)).normalize();
            let delta = 1e-7 * 1e4f32.powf(n.next());
            let sine = radius * (1.0 - delta) / to.length();
            let dir = (to.normalize() * (1.0 - sine * sine).sqrt() + side * sine).normalize();
            let ray = Ray { origin: eye, dir };
            let Some((t, normal)) = sphere.intersect(&ray, f32::INFINITY) else {
                continue;
            };
            grazing += 1;
            let p = eye + t * dir;
            worst = worst.max(((p - center).length() - radius).abs());
            // Lights around the sphere, grazing the point's tangent plane.
            let tangent = normal.cross(dir).normalize();
            for light in [1e-4, 1e-3, 0.02].map(|e| (tangent + e * normal).normalize()) {
                if normal.dot(light) <= 0.0 {
                    continue;
                }
                let origin = p + normal * 1e-4;
                let shadow = Ray { origin, dir: light };
                shadowed += sphere.intersect(&shadow, 50.0).is_some() as usize;
            }
        }
        assert!(grazing > 10_000, "{grazing} of 20,000 rays met the sphere");
        assert!(
            worst < 2e-5 && shadowed == 0,
            "a hit {worst} m off the surface; {shadowed} lit points shadowed by their own sphere"
        );
    }
}
