//! Shadow maps kept from frame to frame of an animation.

use super::*;

/// Shadow maps kept from frame to frame of an animation: a light's map is rebuilt only
/// when the light moved, turned or changed its field (a gobo, a colour or a dimmer
/// leaves it as it is). A map is found by what it was built for, not by the light's
/// place in the list: a prism put in or taken out changes how many lights come before
/// the others. The objects are taken not to move.
#[derive(Debug, Default)]
pub struct ShadowMaps {
    pub(super) maps: Vec<ShadowMap>,
    /// What each map was built for: position, frame, field, texels.
    pub(super) keys: Vec<MapKey>,
    /// How many maps the last [`ShadowMaps::update`] rebuilt.
    pub rebuilt: usize,
}

/// What a shadow map depends on: the light's position, frame and field, its size.
type MapKey = (Vec3, glam::Mat3, f32, usize);

impl ShadowMaps {
    /// The maps for `scene`'s lights, in their order, rebuilding those of lights that
    /// changed since the last call.
    pub fn update(&mut self, scene: &Scene) -> &[ShadowMap] {
        let size = scene.planes.shadow_map as usize;
        let mut kept: Vec<Option<(MapKey, ShadowMap)>> = self
            .keys
            .drain(..)
            .zip(self.maps.drain(..))
            .map(Some)
            .collect();
        self.rebuilt = 0;
        for light in scene.lights() {
            let key = (
                light.position,
                light.light_from_world,
                light.field_half,
                size,
            );
            let found = kept
                .iter_mut()
                .find(|slot| slot.as_ref().is_some_and(|(k, _)| *k == key))
                .and_then(Option::take);
            let map = found.map_or_else(
                || {
                    self.rebuilt += 1;
                    ShadowMap::new(light, &scene.objects, size)
                },
                |(_, map)| map,
            );
            self.maps.push(map);
            self.keys.push(key);
        }
        &self.maps
    }

    /// `scene`'s picture by the plane method with the maps kept from the frames
    /// before ([`ShadowMaps::update`]): one frame of an animation.
    pub fn render(&mut self, scene: &Scene) -> Frame {
        SamplePlanes::with_shadow_maps(scene, self.update(scene)).render()
    }
}
