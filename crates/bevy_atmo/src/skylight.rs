//! The sky's light on the scene, as [`AtmoSky::sky_light`] says: an environment map of
//! the whole sky (without the sun's disc, which is the `DirectionalLight`) that Bevy
//! filters into its diffuse and specular light, or an `AmbientLight` of the light the
//! sky puts on a horizontal surface. Recomputed on a background thread when the sun has
//! moved by more than [`AtmoSky::sky_light_every_deg`] or the sky changed.

use atmo::atmosphere::spectrum::srgb_luminance;
use atmo::sky::envmap::cube_direction;
use atmo::sky::lighting::{irradiance_up, LUMENS_PER_WATT, PROJECTION_ROWS};
use atmo::sky::SkyPicture;
use atmo::view::Sun;
use bevy::asset::RenderAssetUsages;
use bevy::light::GeneratedEnvironmentMapLight;
use bevy::prelude::*;
use bevy::render::render_resource::{
    Extent3d, TextureDimension, TextureFormat, TextureViewDescriptor, TextureViewDimension,
};
use bevy::tasks::{futures::check_ready, AsyncComputeTaskPool, Task};

use crate::sky::{AtmoSky, AtmoSkyState, ReadySky};
use crate::sun::SunNow;

/// How the sky lights a camera's scene.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Reflect)]
pub enum SkyLight {
    /// Not at all (the scene's own lights only).
    Off,
    /// A `GeneratedEnvironmentMapLight` from a cubemap of the sky, `size` pixels a face
    /// (a power of two): Bevy filters it into diffuse light that depends on a surface's
    /// orientation and into reflections.
    EnvironmentMap { size: u32 },
    /// An `AmbientLight`: the light of the whole sky on a horizontal surface, the same
    /// on every orientation (cheaper: nothing filtered on the GPU).
    Ambient,
}

/// The sky's light as a build gives it.
enum Built {
    /// Six faces in Bevy's cube order, RGBA f16 bytes.
    Cube {
        size: u32,
        bytes: Vec<u8>,
    },
    Ambient(AmbientLight),
}

/// A camera's sky light: the sun and sky it was computed for, the one under way, and
/// the cubemap it keeps.
#[derive(Component, Default)]
pub(crate) struct SkyLightState {
    lit: Option<(Sun, u64, SkyLight)>,
    building: Option<Task<atmo::Result<Built>>>,
    cube: Option<Handle<Image>>,
}

/// The ambient light of a sky: a surface of albedo `a` under a sky whose irradiance on a
/// horizontal surface is `E` reflects `a E / pi`, which Bevy's ambient term gives for a
/// brightness (cd/m^2) of `683 Y(E) / pi` and the colour of `E`.
fn ambient_of(picture: &SkyPicture) -> AmbientLight {
    let e = irradiance_up(&picture.equirect(PROJECTION_ROWS, false));
    let y = srgb_luminance(e).max(0.0);
    let [r, g, b] = e.map(|c| if y > 0.0 { (c / y) as f32 } else { 0.0 });
    AmbientLight {
        color: Color::linear_rgb(r, g, b),
        brightness: (LUMENS_PER_WATT * y / std::f64::consts::PI) as f32,
        ..default()
    }
}

/// The sky's cubemap as Bevy samples it: its cubemaps are left-handed (it looks a world
/// direction `d` up at `(d.x, d.y, -d.z)`), so face texel `c` holds the radiance from
/// `(c.x, c.y, -c.z)`; linear sRGB radiance as RGBA f16.
fn cube_of(picture: &SkyPicture, size: u32) -> Vec<u8> {
    let pixel = std::f32::consts::FRAC_PI_2 / size as f32;
    let mut bytes = Vec::with_capacity((6 * size * size * 8) as usize);
    for face in 0..6 {
        let frame = picture.render_directions(size, size, pixel, false, |x, y| {
            let c = cube_direction(face, x, y, size);
            Vec3::new(c.x, c.y, -c.z)
        });
        for p in &frame.pixels {
            for v in [p.x, p.y, p.z, 1.0] {
                bytes.extend_from_slice(&half::f16::from_f32(v).to_le_bytes());
            }
        }
    }
    bytes
}

/// A cube image of six `size` x `size` RGBA f16 faces.
fn cube_image(size: u32, bytes: Vec<u8>) -> Image {
    let mut image = Image::new(
        Extent3d {
            width: size,
            height: size,
            depth_or_array_layers: 6,
        },
        TextureDimension::D2,
        bytes,
        TextureFormat::Rgba16Float,
        // Kept in the main world too (196 KB at 64 a face): a program can read it back.
        RenderAssetUsages::default(),
    );
    image.texture_view_descriptor = Some(TextureViewDescriptor {
        dimension: Some(TextureViewDimension::Cube),
        ..default()
    });
    image
}

/// The angle between two suns, degrees.
fn degrees_between(a: Sun, b: Sun) -> f64 {
    let cos = a.toward().as_dvec3().dot(b.toward().as_dvec3());
    cos.clamp(-1.0, 1.0).acos().to_degrees()
}

/// Starts the sky light of each camera whose sky changed or whose sun moved far enough;
/// puts the finished ones on the cameras.
pub(crate) fn light_the_scene(
    mut commands: Commands,
    sun: Res<SunNow>,
    mut images: ResMut<Assets<Image>>,
    mut cameras: Query<(
        Entity,
        &AtmoSky,
        &AtmoSkyState,
        &GlobalTransform,
        Option<&mut SkyLightState>,
    )>,
) {
    for (entity, sky, state, transform, light) in &mut cameras {
        let Some(mut light) = light else {
            commands.entity(entity).insert(SkyLightState::default());
            continue;
        };
        if let Some(done) = light.building.as_mut().and_then(check_ready) {
            light.building = None;
            match done {
                Ok(Built::Ambient(ambient)) => {
                    commands
                        .entity(entity)
                        .remove::<GeneratedEnvironmentMapLight>()
                        .insert(ambient);
                }
                Ok(Built::Cube { size, bytes }) => {
                    let image = cube_image(size, bytes);
                    let handle = match &light.cube {
                        Some(handle) => {
                            let _ = images.insert(handle.id(), image);
                            handle.clone()
                        }
                        None => images.add(image),
                    };
                    light.cube = Some(handle.clone());
                    // The sky is all the ambient light there is: Bevy's global one off.
                    let none = AmbientLight {
                        brightness: 0.0,
                        ..default()
                    };
                    let map = GeneratedEnvironmentMapLight {
                        environment_map: handle,
                        intensity: LUMENS_PER_WATT as f32,
                        ..default()
                    };
                    commands.entity(entity).insert((map, none));
                }
                Err(e) => error!("atmo's sky light: {e}"),
            }
        }
        let (Some(sun), Some(ready)) = (sun.0, state.ready.clone()) else {
            continue;
        };
        let stale = light.lit.is_none_or(|(lit, generation, mode)| {
            generation != state.generation
                || mode != sky.sky_light
                || degrees_between(lit, sun) > f64::from(sky.sky_light_every_deg)
        });
        if !stale || light.building.is_some() {
            continue;
        }
        light.lit = Some((sun, state.generation, sky.sky_light));
        let mode = sky.sky_light;
        let bad_size = match mode {
            SkyLight::EnvironmentMap { size } => {
                !(8..=1024).contains(&size) || !size.is_power_of_two()
            }
            _ => false,
        };
        if bad_size {
            error!(
                "AtmoSky.sky_light = {mode:?}: a cube face's side must be a power of two \
                 from 8 to 1024"
            );
            continue;
        }
        if mode == SkyLight::Off {
            commands
                .entity(entity)
                .try_remove::<(AmbientLight, GeneratedEnvironmentMapLight)>();
            continue;
        }
        let altitude = ready.drawn_altitude(sky.altitude_m(transform.translation().y));
        light.building = Some(AsyncComputeTaskPool::get().spawn(async move {
            let picture = match ready {
                ReadySky::Model(model, _) => SkyPicture::new(&model, sun),
                ReadySky::Table(table) => SkyPicture::from_table(&table, sun, altitude)?,
            };
            Ok(match mode {
                SkyLight::EnvironmentMap { size } => Built::Cube {
                    size,
                    bytes: cube_of(&picture, size),
                },
                SkyLight::Ambient | SkyLight::Off => Built::Ambient(ambient_of(&picture)),
            })
        }));
    }
}
