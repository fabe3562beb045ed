//! Beams in haze (shafts): Bevy's `SpotLight`s marked [`AtmoBeam`] scattering in the
//! [`AtmoHaze`] of a camera, by atmo's sample planes (shafts 4), shadowed by the
//! scene's meshes. The main world's part: the lights as atmo's spotlights each frame,
//! and the meshes that cast shadows as atmo's triangle meshes (with their BVHs), made
//! again only when one of them moved, changed or went.

use std::path::Path;
use std::sync::Arc;

use atmo::atmosphere::PhaseFunction;
use atmo::geometry::{Aabb, Shape};
use atmo::shafts::haze::Haze;
use atmo::shafts::objects::Object;
use atmo::shafts::photometry::Photometry;
use atmo::shafts::scene::{load_gobo, load_photometry, MEASURED_REACH_DEG};
use atmo::shafts::spotlight::{light_frame, Falloff, Gobo, Profile, Sampling, Spotlight};
use bevy::asset::AssetEvent;
use bevy::light::NotShadowCaster;
use bevy::mesh::{Indices, PrimitiveTopology, VertexAttributeValues};
use bevy::prelude::*;

/// Haze in front of a camera that the [`AtmoBeam`] spotlights scatter in: put it on
/// the camera's entity. Outside `bounds` the air is clear; without bounds the haze
/// fills all space, and a ray that meets no mesh sees nothing through it.
///
/// Reflected (an inspector edits it) but for the phase function, atmo's own type.
#[derive(Component, Clone, Debug, Reflect)]
#[reflect(Component, Clone, Debug, Default)]
pub struct AtmoHaze {
    /// Extinction coefficient, 1/m (0.12: a stage haze, about 25 m visibility).
    pub extinction: f32,
    /// Single-scattering albedo, in [0, 1].
    pub albedo: f32,
    /// The haze particles' phase function (the paper's haze: shafts (4)).
    #[reflect(ignore, default = "paper_haze")]
    pub phase: PhaseFunction,
    /// Where the haze is: the box between two corners, m, world frame.
    pub bounds: Option<(Vec3, Vec3)>,
    /// Sample planes through each light's lit volume (shafts (5): 30, the paper's).
    pub planes: u32,
    /// Texels along each side of a light's shadow map.
    pub shadow_map: u32,
    /// The beams' picture's resolution against the view's, in (0, 1]: 0.5 draws a
    /// quarter of the pixels (the cost is about the pixels') and shows them bilinearly
    /// (a beam's edge against a nearer mesh blurs over a pixel of the lower resolution).
    pub resolution_scale: f32,
}

/// The paper's haze phase function (shafts (4), exponent 16).
fn paper_haze() -> PhaseFunction {
    PhaseFunction::PaperHaze { exponent: 16.0 }
}

impl Default for AtmoHaze {
    /// The paper's Fig. 6 haze: 0.12 /m, albedo 0.9, its phase function (exponent 16),
    /// everywhere; 30 planes, 512^2 shadow maps, the view's resolution.
    fn default() -> Self {
        AtmoHaze {
            extinction: 0.12,
            albedo: 0.9,
            phase: paper_haze(),
            bounds: None,
            planes: 30,
            shadow_map: 512,
            resolution_scale: 1.0,
        }
    }
}

impl AtmoHaze {
    /// atmo's haze, checked: errors name the field and its allowed range.
    pub(crate) fn haze(&self) -> atmo::Result<Haze> {
        let invalid = |what: String| Err(atmo::Error::Invalid(what));
        if !(self.extinction.is_finite() && self.extinction > 0.0) {
            return invalid(format!(
                "AtmoHaze.extinction: {} /m, allowed: above 0, finite",
                self.extinction
            ));
        }
        if !(0.0..=1.0).contains(&self.albedo) {
            return invalid(format!("AtmoHaze.albedo: {}, allowed: 0 to 1", self.albedo));
        }
        if !(self.resolution_scale > 0.0 && self.resolution_scale <= 1.0) {
            return invalid(format!(
                "AtmoHaze.resolution_scale: {}, allowed: above 0, at most 1",
                self.resolution_scale
            ));
        }
        if let Some((a, b)) = self.bounds {
            if !(a.cmplt(b).all() && a.is_finite() && b.is_finite()) {
                return invalid(format!(
                    "AtmoHaze.bounds: {a} to {b}, allowed: a finite box, the first corner the least"
                ));
            }
        }
        Ok(Haze {
            extinction: self.extinction,
            albedo: self.albedo,
            phase: self.phase,
            bounds: self.bounds.map(|(min, max)| Aabb { min, max }),
        })
    }
}

/// Marks a `SpotLight` whose light scatters in every [`AtmoHaze`]: a beam of the
/// spotlight's colour and intensity (Bevy's: its lumens over 4 pi sr, in candela),
/// full inside `inner_angle`, falling to nothing at `outer_angle` as a smoothstep in the
/// angle (Bevy's own falloff is a square in the cosine: the beam's edge is a little
/// harder than the lit floor's). A measured profile or a gobo shapes it further.
///
/// Reflected as a component; its profile and gobo, atmo's own types, are not.
#[derive(Component, Clone, Debug, Default, Reflect)]
#[reflect(Component, Clone, Debug, Default)]
#[require(SpotLight)]
pub struct AtmoBeam {
    /// A measured distribution (IES LM-63 or EULUMDAT): the beam's shape and candela
    /// (the file's, times the light's colour) in place of the spotlight's intensity
    /// and angles, out to where the file's light ends (85 deg at most). Bevy still
    /// lights the scene with the `SpotLight`'s own: give it the file's peak candela
    /// times 4 pi in lumens, and its angles, for the floor to match.
    #[reflect(ignore)]
    pub profile: Option<Arc<Photometry>>,
    /// A gobo in the beam, its image's top toward the light's up (its y).
    #[reflect(ignore)]
    pub gobo: Option<Gobo>,
}

impl AtmoBeam {
    /// The beam shaped by the photometric file at `path` (`.ldt`: EULUMDAT, else IES
    /// LM-63); errors name the file and what is wrong with it.
    pub fn with_photometry(mut self, path: &Path) -> atmo::Result<Self> {
        let eulumdat = path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("ldt"));
        self.profile = Some(Arc::new(load_photometry(path, eulumdat)?));
        Ok(self)
    }

    /// The beam through the gobo image at `path` (PNG), sampled bilinearly; errors
    /// name the file.
    pub fn with_gobo(mut self, path: &Path) -> atmo::Result<Self> {
        self.gobo = Some(load_gobo(path, Sampling::Bilinear)?);
        Ok(self)
    }
}

/// The beams of this frame and the meshes that shadow them, as atmo's; shared with
/// the render world.
#[derive(Resource, Default)]
pub(crate) struct Beams {
    pub lights: Vec<Spotlight>,
    /// The meshes that cast shadows, and a count that changes when they do.
    pub occluders: Arc<Vec<Object>>,
    pub generation: u64,
    /// Some mesh was not loaded when they were last made: made again next frame.
    pending: bool,
}

/// A light's beam as atmo's spotlight: at the light, along its forward (-z), its up
/// the light's y.
fn spotlight(transform: &GlobalTransform, light: &SpotLight, beam: &AtmoBeam) -> Option<Spotlight> {
    let forward = transform.forward().as_vec3();
    let up = if forward.y.abs() > 0.999 {
        Vec3::Z
    } else {
        Vec3::Y
    };
    let colour = Vec3::from_slice(&light.color.to_linear().to_f32_array()[..3]);
    let (intensity, field_half, profile) = match &beam.profile {
        Some(measured) => (
            colour * measured.peak(),
            measured.reach().min(MEASURED_REACH_DEG).to_radians(),
            Profile::Measured(measured.clone()),
        ),
        None => {
            let field_half = light.outer_angle.min(89.9f32.to_radians());
            let profile = Profile::Beam {
                beam_half: light.inner_angle.clamp(0.0, field_half),
                falloff: Falloff::Smooth,
            };
            let candela = light.intensity / (4.0 * std::f32::consts::PI);
            (colour * candela, field_half, profile)
        }
    };
    if field_half <= 0.0 {
        return None;
    }
    Some(Spotlight::new(
        transform.translation(),
        light_frame(forward, up)?,
        intensity,
        field_half,
        profile,
        beam.gobo.clone(),
    ))
}

/// The triangles of `mesh` placed by `transform`, world frame; `None` for a mesh that
/// is not a triangle list with positions.
fn triangles(mesh: &Mesh, transform: &GlobalTransform) -> Option<Vec<[Vec3; 3]>> {
    if mesh.primitive_topology() != PrimitiveTopology::TriangleList {
        return None;
    }
    let Some(VertexAttributeValues::Float32x3(positions)) =
        mesh.attribute(Mesh::ATTRIBUTE_POSITION)
    else {
        return None;
    };
    let world: Vec<Vec3> = positions
        .iter()
        .map(|p| transform.transform_point(Vec3::from_array(*p)))
        .collect();
    let corners: Vec<usize> = match mesh.indices() {
        Some(Indices::U16(i)) => i.iter().map(|&k| k as usize).collect(),
        Some(Indices::U32(i)) => i.iter().map(|&k| k as usize).collect(),
        None => (0..world.len()).collect(),
    };
    corners
        .as_chunks::<3>()
        .0
        .iter()
        .map(|t| Some([*world.get(t[0])?, *world.get(t[1])?, *world.get(t[2])?]))
        .collect()
}

/// A mesh moved or given another mesh this frame.
type MovedMesh = (
    With<Mesh3d>,
    Or<(Changed<GlobalTransform>, Changed<Mesh3d>)>,
);

/// A mesh that may cast a shadow into the beams.
type Occluder<'a> = (&'a Mesh3d, &'a GlobalTransform);

/// Takes this frame's beams, and the shadows' meshes again where one of them moved,
/// changed, came or went (nothing of either without a beam).
pub(crate) fn gather_beams(
    mut beams: ResMut<Beams>,
    lights: Query<(&GlobalTransform, &SpotLight, &AtmoBeam)>,
    occluders: Query<Occluder, Without<NotShadowCaster>>,
    changed: Query<(), MovedMesh>,
    mut removed: RemovedComponents<Mesh3d>,
    mut edited: MessageReader<AssetEvent<Mesh>>,
    meshes: Res<Assets<Mesh>>,
) {
    beams.lights = lights
        .iter()
        .filter_map(|(transform, light, beam)| spotlight(transform, light, beam))
        .collect();
    let moved = !changed.is_empty() || removed.read().count() > 0 || edited.read().count() > 0;
    if beams.lights.is_empty() || !(moved || beams.pending || beams.generation == 0) {
        return;
    }
    let mut pending = false;
    let mut objects = Vec::new();
    for (mesh, transform) in &occluders {
        let Some(mesh) = meshes.get(&mesh.0) else {
            pending = true;
            continue;
        };
        if let Some(triangles) = triangles(mesh, transform).filter(|t| !t.is_empty()) {
            objects.push(Object {
                shape: Shape::Mesh(atmo::geometry::Mesh::new(triangles)),
                // Unseen: the surfaces are Bevy's to shade.
                albedo: Vec3::ZERO,
                casts_shadow: true,
            });
        }
    }
    beams.occluders = Arc::new(objects);
    beams.generation += 1;
    beams.pending = pending;
}
