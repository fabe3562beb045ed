//! The render world's part of the beams: each hazy view's atmo scene (its camera, the
//! haze, the beams and the meshes that shadow them), its shadow maps, planes and
//! surfaces recorded each frame by atmo-gpu (`GpuShafts::haze_over`), and the haze's
//! light drawn over the view as `dst T + S` after the opaque meshes, the sky and the
//! clouds: the meshes end the rays, so a wall hides the beams behind it.

use std::sync::Arc;

use atmo::image::{Display, ToneMap};
use atmo::shafts::haze::Haze;
use atmo::shafts::objects::{Object, Objects};
use atmo::shafts::scene::IntensityUnit;
use atmo::shafts::spotlight::Spotlight;
use atmo::shafts::{PlaneSettings, Scene};
use atmo::view::Camera as AtmoCamera;
use atmo_gpu::shafts::{GpuShafts, ShaftsMethod, ShaftsPass, ShaftsPipelines};
use atmo_gpu::{wgpu, Gpu, GpuError};
use bevy::prelude::*;
use bevy::render::camera::ExtractedCamera;
use bevy::render::renderer::{RenderContext, ViewQuery};
use bevy::render::sync_world::RenderEntity;
use bevy::render::view::{ExtractedView, Msaa, ViewTarget};
use bevy::render::Extract;

use crate::beams::{AtmoHaze, Beams};
use crate::render::{atmo_camera, begin, AtmoGpu, Said};

/// This frame's beams and their shadows' meshes, as the render world takes them.
#[derive(Resource, Default)]
pub(crate) struct ExtractedBeams {
    lights: Vec<Spotlight>,
    occluders: Arc<Vec<Object>>,
    generation: u64,
}

/// A hazy camera's haze and sampling, checked.
#[derive(Component)]
pub(crate) struct ExtractedHaze {
    haze: Haze,
    planes: PlaneSettings,
    /// The beams' resolution against the view's.
    scale: f32,
}

/// A 3-D camera, with its haze where it has one.
type HazyCamera<'a> = (RenderEntity, Option<&'a AtmoHaze>);

/// Copies the beams and each hazy camera's haze into the render world; a camera whose
/// haze is invalid draws none and says why once.
pub(crate) fn extract_beams(
    mut commands: Commands,
    beams: Extract<Res<Beams>>,
    cameras: Extract<Query<HazyCamera, With<Camera3d>>>,
    mut extracted: ResMut<ExtractedBeams>,
) {
    extracted.lights.clone_from(&beams.lights);
    if extracted.generation != beams.generation {
        extracted.occluders = beams.occluders.clone();
        extracted.generation = beams.generation;
    }
    for (render_entity, haze) in &cameras {
        let mut entity = commands.entity(render_entity);
        let checked = haze.map(|h| h.haze().map(|haze| (haze, h)));
        match checked {
            Some(Ok((haze, h))) if !beams.lights.is_empty() => {
                let planes = PlaneSettings {
                    planes: h.planes,
                    shadow_map: h.shadow_map,
                    // The GPU draws every pixel.
                    adaptive: false,
                    ..PlaneSettings::default()
                };
                match planes.validate() {
                    Ok(()) => {
                        entity.insert(ExtractedHaze {
                            haze,
                            planes,
                            scale: h.resolution_scale,
                        });
                    }
                    Err(e) => {
                        warn_once!("bevy_atmo draws no beams: AtmoHaze: {e}");
                        entity.try_remove::<(ExtractedHaze, ViewBeams)>();
                    }
                }
            }
            Some(Err(e)) => {
                warn_once!("bevy_atmo draws no beams: {e}");
                entity.try_remove::<(ExtractedHaze, ViewBeams)>();
            }
            _ => {
                entity.try_remove::<(ExtractedHaze, ViewBeams)>();
            }
        }
    }
}

/// A hazy view's beams: its atmo scene (the meshes replaced when they change), and the
/// pass that draws this frame's picture over the view.
#[derive(Component)]
pub(crate) struct ViewBeams {
    scene: Scene,
    occluders: u64,
    pass: ShaftsPass,
    target: (wgpu::TextureFormat, u32),
}

/// A hazy view, as its beams see it.
type HazyView<'a> = (
    Entity,
    &'a ExtractedHaze,
    &'a ExtractedView,
    &'a ExtractedCamera,
    &'a ViewTarget,
    &'a Msaa,
    Option<&'a mut ViewBeams>,
);

/// Records each hazy view's shafts for this frame's camera and beams, in an encoder of
/// its own submitted before the frame's (whose pass draws their picture).
pub(crate) fn prepare_beams(
    mut commands: Commands,
    mut said: Local<Said>,
    gpu: Option<Res<AtmoGpu>>,
    mut pipelines: Local<Option<Arc<ShaftsPipelines>>>,
    beams: Res<ExtractedBeams>,
    mut views: Query<HazyView>,
) {
    let Some(gpu) = gpu else { return };
    let gpu = &gpu.0;
    if views.is_empty() {
        return;
    }
    let shared = match pipelines.as_ref() {
        Some(made) => made.clone(),
        None => match ShaftsPipelines::new(gpu) {
            Ok(made) => pipelines.insert(made).clone(),
            Err(e) => {
                said.error("bevy_atmo's beams", e);
                return;
            }
        },
    };
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    for (entity, haze, view, camera, target, msaa, view_beams) in &mut views {
        let Some((mut atmo_camera, _)) = atmo_camera(view) else {
            warn_once!("bevy_atmo draws beams for perspective cameras only");
            continue;
        };
        atmo_camera.position = view.world_from_view.translation();
        // A lower resolution: fewer pixels over the same frustum (the lens keeps it).
        let shown = [view.viewport.z, view.viewport.w];
        if haze.scale < 1.0 {
            let fewer = shown.map(|s| ((s as f32 * haze.scale).ceil() as u32).max(1));
            (atmo_camera.width, atmo_camera.height) = (fewer[0], fewer[1]);
        }
        let frame = BeamFrame {
            camera: atmo_camera,
            haze,
            beams: &beams,
            target: (target.main_texture_format(), msaa.samples()),
            exposure: camera.exposure,
            corner: [view.viewport.x, view.viewport.y],
            shown: (haze.scale < 1.0).then_some(shown),
        };
        let done = match view_beams {
            Some(mut kept) => kept.record(gpu, &mut encoder, &shared, &frame),
            None => ShaftsPass::over(gpu, frame.target.0, frame.target.1).and_then(|pass| {
                let mut made = ViewBeams {
                    scene: scene(frame.camera.clone(), haze, &beams),
                    occluders: beams.generation,
                    pass,
                    target: frame.target,
                };
                made.record(gpu, &mut encoder, &shared, &frame)?;
                commands.entity(entity).insert(made);
                Ok(())
            }),
        };
        if let Err(e) = done {
            said.error("bevy_atmo's beams", e);
        }
    }
    gpu.queue.submit([encoder.finish()]);
}

/// A hazy view's frame, as its beams need it.
struct BeamFrame<'a> {
    /// atmo's camera at the view's eye, of the viewport's size.
    camera: AtmoCamera,
    haze: &'a ExtractedHaze,
    beams: &'a ExtractedBeams,
    /// The view's colour format and samples.
    target: (wgpu::TextureFormat, u32),
    /// The camera's exposure (the picture is in cd/m^2, Bevy's units already).
    exposure: f32,
    /// The viewport's corner in the target, pixels, and its size where the beams'
    /// picture is of fewer pixels.
    corner: [u32; 2],
    shown: Option<[u32; 2]>,
}

impl ViewBeams {
    /// Brings the scene to `frame` (the camera, the haze and the lights each frame;
    /// the meshes when they changed; the pass when the view's target did) and records
    /// its shafts into `encoder`.
    fn record(
        &mut self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        pipelines: &Arc<ShaftsPipelines>,
        frame: &BeamFrame,
    ) -> Result<(), GpuError> {
        if self.target != frame.target {
            self.pass = ShaftsPass::over(gpu, frame.target.0, frame.target.1)?;
            self.target = frame.target;
        }
        if self.occluders != frame.beams.generation {
            self.scene.objects.list = frame.beams.occluders.as_ref().clone();
            self.occluders = frame.beams.generation;
        }
        self.scene.camera = frame.camera.clone();
        self.scene.haze = frame.haze.haze.clone();
        self.scene.planes = frame.haze.planes;
        self.scene.spotlights.clone_from(&frame.beams.lights);
        self.pass.exposure = frame.exposure;
        self.pass.corner = frame.corner;
        self.pass.shown = frame.shown;
        let shafts = GpuShafts::haze_over(gpu, &self.scene, pipelines.clone())?;
        shafts.prepare(gpu, encoder, &mut self.pass, ShaftsMethod::Planes)
    }
}

/// Draws the view's beams over it (after the sky and the clouds: the haze is nearer).
pub(crate) fn draw_beams(
    view: ViewQuery<(&ExtractedCamera, &ViewTarget, &ViewBeams)>,
    mut ctx: RenderContext,
) {
    let (camera, target, beams) = view.into_inner();
    beams.pass.draw(&mut begin(
        ctx.command_encoder(),
        camera,
        target,
        "atmo beams",
        None,
    ));
}

/// An atmo scene of `beams` in `haze` seen by `camera`.
fn scene(camera: AtmoCamera, haze: &ExtractedHaze, beams: &ExtractedBeams) -> Scene {
    Scene {
        camera,
        haze: haze.haze.clone(),
        spotlights: beams.lights.clone(),
        objects: Objects {
            list: beams.occluders.as_ref().clone(),
        },
        planes: haze.planes,
        // Unused: Bevy's tone mapping shows the picture.
        display: Display {
            exposure: 1.0,
            tone: ToneMap::Clamp,
        },
        unit: IntensityUnit::Candela,
        files: Vec::new(),
        files_bytes: 0,
        show: Default::default(),
    }
}
