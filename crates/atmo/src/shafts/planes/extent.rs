//! Where each light's lit volume lies for the camera (shafts 4.2: the planes are put
//! through it), bounded from the shadow map's blocks of ray ends.

use super::*;

/// Where a light's lit volume (the lamp and its shadow map's ray ends) lies for the
/// camera: what places the light's planes and sizes the attenuation table.
#[derive(Debug, Clone, Copy)]
pub(super) struct Extent {
    /// Least and greatest camera depth, m.
    pub(super) near: f32,
    pub(super) far: f32,
    /// Greatest distance from the lamp and from the eye, squared (no square root a
    /// point), m^2.
    pub(super) from_lamp: f32,
    pub(super) from_eye: f32,
    /// Around every point, m.
    pub(super) bounds: Aabb,
}

impl Extent {
    /// The lit volume of `light` through `shadow`, its rays that meet nothing cut at
    /// light-space depth `reach` m: the same numbers as a walk over every texel's ray
    /// end, found by walking only the blocks of texels that may hold an extreme.
    ///
    /// Each block's box of ray ends ([`ShadowMap::end_boxes`], kept with the map) bounds
    /// what its points can give (a linear depth and a convex distance are greatest at a
    /// corner); for each measure the blocks are taken from the best bound down, walked
    /// until a bound no longer beats what the walked points gave. On the stage
    /// (`scenes/stage.toml`, 512-texel maps) a frame walks 2 to 18 of a map's 856
    /// blocks in the field cone.
    pub(super) fn of(shadow: &ShadowMap, light: &Spotlight, camera: &Camera, reach: f32) -> Extent {
        let lamp = light.position;
        let point = |e: Extent, p: Vec3| e.grow(p, camera, lamp);
        let mut extent = Extent::lamp(lamp, camera);
        let blocks: Vec<(usize, Option<Aabb>)> = shadow.end_boxes(light, reach).collect();
        let mut walked = vec![false; blocks.len()];
        // Per measure, per block, the greatest value its points may give.
        let mut upper = [(); 4].map(|_| vec![f32::NEG_INFINITY; blocks.len()]);
        for (i, &(block, ends)) in blocks.iter().enumerate() {
            let Some(ends) = ends else {
                extent = shadow.block_ends(light, reach, block).fold(extent, point);
                walked[i] = true;
                continue;
            };
            extent.bounds = extent.bounds.union(ends);
            // Widened past the float error of a point's measures against its corners'
            // (a few units in the last place of the coordinates, and of their squares).
            let size = 1.0
                + (ends.min.abs().max(ends.max.abs()))
                    .max(camera.position.abs())
                    .max_element();
            let slack = [
                1e-5 * size,
                1e-5 * size,
                1e-5 * size * size,
                1e-5 * size * size,
            ];
            let bounds = ends
                .corners()
                .into_iter()
                .fold(Extent::NONE, point)
                .measures();
            for ((upper, bound), slack) in upper.iter_mut().zip(bounds).zip(slack) {
                upper[i] = bound + slack;
            }
        }
        for (measure, upper) in upper.iter().enumerate() {
            let mut order: Vec<usize> = (0..blocks.len()).filter(|&i| !walked[i]).collect();
            order.sort_unstable_by(|&a, &b| upper[b].total_cmp(&upper[a]));
            for i in order {
                if upper[i] <= extent.measures()[measure] {
                    break;
                }
                extent = shadow
                    .block_ends(light, reach, blocks[i].0)
                    .fold(extent, point);
                walked[i] = true;
            }
        }
        extent
    }

    /// No point at all.
    pub(super) const NONE: Extent = Extent {
        near: f32::INFINITY,
        far: f32::NEG_INFINITY,
        from_lamp: 0.0,
        from_eye: 0.0,
        bounds: Aabb::EMPTY,
    };

    /// The lamp at `lamp` alone, where the walk over the ray ends starts (its own
    /// distance from the eye left out, as the plane method always has).
    pub(super) fn lamp(lamp: Vec3, camera: &Camera) -> Extent {
        let z = camera.depth(lamp);
        Extent {
            near: z,
            far: z,
            from_lamp: 0.0,
            from_eye: 0.0,
            bounds: Aabb::EMPTY.grow(lamp),
        }
    }

    /// With the point `p` too.
    #[inline]
    pub(super) fn grow(self, p: Vec3, camera: &Camera, lamp: Vec3) -> Extent {
        let z = camera.depth(p);
        Extent {
            near: self.near.min(z),
            far: self.far.max(z),
            from_lamp: self.from_lamp.max((p - lamp).length_squared()),
            from_eye: self.from_eye.max((p - camera.position).length_squared()),
            bounds: self.bounds.grow(p),
        }
    }

    /// The measures a block may beat, each as a greatest value.
    pub(super) fn measures(&self) -> [f32; 4] {
        [-self.near, self.far, self.from_lamp, self.from_eye]
    }
}
