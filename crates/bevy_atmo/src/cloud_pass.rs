//! The render world's part of the clouds: each cloud on the GPU (atmo-gpu's
//! `GpuClouds`, its light pass recorded when the sun or the particles move), and in
//! each sky view the scene's depth along the view axis and every cloud drawn over the
//! view after the opaque meshes and the aerial perspective, farthest first, each
//! particle's column counted only in front of the meshes (`CloudsPass::scene_depth`).

use std::sync::{Arc, Mutex};

use atmo::atmosphere::PhaseFunction;
use atmo::clouds::render::{AerialHaze, CloudLight};
use atmo::clouds::{Particle, Scattering, Splat};
use atmo::cloudscape::haze_before;
use atmo::sky::lighting::LUMENS_PER_WATT;
use atmo::view::Sun;
use atmo_gpu::clouds::{CloudsPass, GpuClouds};
use atmo_gpu::{wgpu, Gpu, GpuError};
use bevy::prelude::*;
use bevy::render::camera::ExtractedCamera;
use bevy::render::sync_world::RenderEntity;
use bevy::render::view::{ExtractedView, ViewTarget};
use bevy::render::Extract;

use crate::clouds::{AtmoClouds, AtmoCloudsState, CloudSun};
use crate::render::{atmo_camera, begin, AtmoGpu, ExtractedSky, Said, SkyViewParts};
use crate::sky::ReadySky;

/// A lit cloud as the render world takes it.
#[derive(Component)]
pub(crate) struct ExtractedClouds {
    /// The particles in the world frame, and a count that changes when they do.
    particles: Arc<[Particle]>,
    generation: u64,
    /// Their mean position, m.
    centre: Vec3,
    resolution: usize,
    scattering: Scattering,
    phase: PhaseFunction,
    lit: CloudSun,
}

/// Copies each lit cloud into the render world; a cloud not lit yet loses its copy.
pub(crate) fn extract_clouds(
    mut commands: Commands,
    clouds: Extract<Query<(RenderEntity, &AtmoClouds, &AtmoCloudsState)>>,
) {
    for (render_entity, cloud, state) in &clouds {
        let mut entity = commands.entity(render_entity);
        match (&state.particles, state.lit) {
            (Some(particles), Some(lit)) => {
                entity.insert(ExtractedClouds {
                    particles: particles.clone(),
                    generation: state.generation,
                    centre: state.centre,
                    resolution: cloud.resolution,
                    scattering: cloud.scattering,
                    phase: cloud.phase,
                    lit,
                });
            }
            _ => {
                entity.try_remove::<(ExtractedClouds, CloudOnGpu)>();
            }
        }
    }
}

/// A cloud on the GPU: its particles and intensity buffer (in a mutex: the draws,
/// which share it, run in the render graph's systems), and what its buffer was lit for.
#[derive(Component)]
pub(crate) struct CloudOnGpu {
    clouds: Mutex<GpuClouds>,
    generation: u64,
    resolution: usize,
    count: usize,
    lit_by: Option<Sun>,
}

impl CloudOnGpu {
    /// Moves the particles where they changed and records the light pass where they or
    /// the sun did.
    fn relight(
        &mut self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        cloud: &ExtractedClouds,
    ) -> Result<(), GpuError> {
        let clouds = self.clouds.get_mut().unwrap_or_else(|e| e.into_inner());
        if self.generation != cloud.generation {
            clouds.move_particles(gpu, &cloud.particles)?;
            self.generation = cloud.generation;
            self.lit_by = None;
        }
        if self.lit_by != Some(cloud.lit.sun) {
            // Every order: nothing of the scattered light is taken to go on (forward 0).
            clouds.record_light_pass(gpu, encoder, cloud.lit.sun.toward(), 0.0, Splat::Pieces)?;
            self.lit_by = Some(cloud.lit.sun);
        }
        Ok(())
    }
}

/// Uploads new clouds, moves and lights the others, in an encoder submitted before the
/// frame's (whose draws read the buffers).
pub(crate) fn prepare_clouds(
    mut commands: Commands,
    mut said: Local<Said>,
    gpu: Option<Res<AtmoGpu>>,
    mut clouds: Query<(Entity, &ExtractedClouds, Option<&mut CloudOnGpu>)>,
) {
    let Some(gpu) = gpu else { return };
    let gpu = &gpu.0;
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    for (entity, cloud, on_gpu) in &mut clouds {
        let same = |on: &CloudOnGpu| {
            on.resolution == cloud.resolution && on.count == cloud.particles.len()
        };
        let done = match on_gpu.filter(|on| same(on)) {
            Some(mut on) => on.relight(gpu, &mut encoder, cloud),
            None => GpuClouds::new(gpu, &cloud.particles, cloud.resolution).and_then(|made| {
                let mut on = CloudOnGpu {
                    clouds: Mutex::new(made),
                    generation: cloud.generation,
                    resolution: cloud.resolution,
                    count: cloud.particles.len(),
                    lit_by: None,
                };
                on.relight(gpu, &mut encoder, cloud)?;
                commands.entity(entity).insert(on);
                Ok(())
            }),
        };
        if let Err(e) = done {
            said.error("bevy_atmo's clouds", e);
        }
    }
    gpu.queue.submit([encoder.finish()]);
}

/// A cloud in a view: its pass into the view's target (of a format and sample count),
/// and the camera and light it is drawn with this frame.
struct ViewCloud {
    entity: Entity,
    pass: CloudsPass,
    target: (wgpu::TextureFormat, u32),
    camera: atmo::view::Camera,
    light: CloudLight,
    distance_m: f32,
}

/// A sky view's clouds: the scene's depth they are hidden behind, and the clouds,
/// farthest first.
#[derive(Component)]
pub(crate) struct ViewClouds {
    depth: SceneDepth,
    clouds: Vec<ViewCloud>,
}

/// A sky view's frame, as its clouds need it.
struct CloudFrame<'a> {
    sky: &'a ExtractedSky,
    view: &'a ExtractedView,
    /// atmo's camera at the view's eye, of the viewport's size.
    camera: atmo::view::Camera,
    target: (wgpu::TextureFormat, u32),
    /// Luminance per radiance times the camera's exposure.
    exposure: f32,
    depth: &'a wgpu::TextureView,
}

/// Sets up each sky view's clouds for this frame: the scene's depth pass, and each
/// cloud's pass, camera and light (the air in front of it from the view's sky model);
/// a view without clouds to draw loses them.
pub(crate) fn prepare_view_clouds(
    mut commands: Commands,
    mut said: Local<Said>,
    gpu: Option<Res<AtmoGpu>>,
    mut views: Query<SkyViewParts<ViewClouds>>,
    clouds: Query<(Entity, &ExtractedClouds), With<CloudOnGpu>>,
) {
    let Some(gpu) = gpu else { return };
    let gpu = &gpu.0;
    for (entity, sky, view, camera, target, msaa, depth, view_clouds) in &mut views {
        let depth = depth.attachment.depth_stencil_views().depth_only_view();
        let (Some(depth), Some((mut atmo_camera, _)), false) =
            (depth, atmo_camera(view), clouds.is_empty())
        else {
            if view_clouds.is_some() {
                commands.entity(entity).remove::<ViewClouds>();
            }
            continue;
        };
        atmo_camera.position = view.world_from_view.translation();
        let frame = CloudFrame {
            sky,
            view,
            camera: atmo_camera,
            target: (target.main_texture_format(), msaa.samples()),
            exposure: LUMENS_PER_WATT as f32 * camera.exposure,
            depth,
        };
        let done = match view_clouds {
            Some(mut kept) => kept.update(gpu, &frame, &clouds),
            None => SceneDepth::new(gpu, &frame).and_then(|depth| {
                let mut made = ViewClouds {
                    depth,
                    clouds: Vec::new(),
                };
                made.update(gpu, &frame, &clouds)?;
                commands.entity(entity).insert(made);
                Ok(())
            }),
        };
        if let Err(e) = done {
            said.error("bevy_atmo's clouds", e);
        }
    }
}

impl ViewClouds {
    /// The scene's depth pass and every cloud's pass, camera and light for `frame`
    /// (the passes kept where the view's target is the same).
    fn update(
        &mut self,
        gpu: &Gpu,
        frame: &CloudFrame,
        clouds: &Query<(Entity, &ExtractedClouds), With<CloudOnGpu>>,
    ) -> Result<(), GpuError> {
        if !self.depth.fits(frame) {
            self.depth = SceneDepth::new(gpu, frame)?;
        }
        self.depth.prepare(gpu, frame);
        let eye = frame.camera.position;
        let mut kept = std::mem::take(&mut self.clouds);
        for (entity, cloud) in clouds {
            let mut pass = match kept.iter().position(|c| c.entity == entity) {
                Some(i) if kept[i].target == frame.target => kept.swap_remove(i).pass,
                _ => CloudsPass::new(gpu, frame.target.0, frame.target.1)?,
            };
            pass.exposure = frame.exposure;
            pass.corner = [frame.view.viewport.x, frame.view.viewport.y];
            pass.scene_depth = Some(self.depth.view.clone());
            let haze = match &frame.sky.ready {
                ReadySky::Model(model, _) => haze_before(model, cloud.lit.sun, cloud.centre - eye)?,
                ReadySky::Table(_) => {
                    warn_once!(
                        "bevy_atmo: clouds under a table's sky are drawn without the air in front"
                    );
                    AerialHaze::CLEAR
                }
            };
            self.clouds.push(ViewCloud {
                entity,
                pass,
                target: frame.target,
                camera: frame.camera.clone(),
                light: CloudLight {
                    to_sun: cloud.lit.sun.toward(),
                    sun: cloud.lit.sunlight,
                    ambient: cloud.lit.skylight,
                    phase: cloud.phase,
                    haze,
                    scattering: cloud.scattering,
                },
                distance_m: (cloud.centre - eye).length(),
            });
        }
        self.clouds
            .sort_by(|a, b| b.distance_m.total_cmp(&a.distance_m));
        Ok(())
    }
}

/// Records the view's clouds into its colour target: the scene's depth, then each
/// cloud's billboards (into their own targets) and its composite over the view,
/// farthest first.
pub(crate) fn draw_clouds(
    gpu: &Gpu,
    encoder: &mut wgpu::CommandEncoder,
    camera: &ExtractedCamera,
    target: &ViewTarget,
    view_clouds: &mut ViewClouds,
    clouds: &Query<&CloudOnGpu>,
    said: &mut Said,
) {
    view_clouds.depth.draw(encoder);
    for cloud in &mut view_clouds.clouds {
        let Ok(on) = clouds.get(cloud.entity) else {
            continue;
        };
        let on_gpu = on.clouds.lock().unwrap_or_else(|e| e.into_inner());
        if let Err(e) = on_gpu.prepare(gpu, encoder, &mut cloud.pass, &cloud.camera, &cloud.light) {
            said.error("bevy_atmo's clouds", e);
            continue;
        }
        cloud
            .pass
            .draw(&mut begin(encoder, camera, target, "atmo clouds", None));
    }
}

/// The scene's depth along the view axis for the clouds (depth.wgsl): Bevy's depth
/// buffer of one sample count turned into an `R32Float` texture of the viewport's size.
struct SceneDepth {
    pipeline: wgpu::RenderPipeline,
    samples: u32,
    size: (u32, u32),
    params: wgpu::Buffer,
    view: wgpu::TextureView,
    group: Option<wgpu::BindGroup>,
}

/// depth.wgsl for a depth buffer of `samples` samples a pixel (the nearest of them).
fn depth_source(samples: u32) -> String {
    let (texture, nearest) = if samples > 1 {
        (
            "texture_depth_multisampled_2d",
            "var z = 0.0;\n    for (var i = 0; i < i32(textureNumSamples(depth)); i++) {\n        \
             z = max(z, textureLoad(depth, texel, i));\n    }",
        )
    } else {
        ("texture_depth_2d", "let z = textureLoad(depth, texel, 0);")
    };
    include_str!("depth.wgsl")
        .replace("DEPTH_TEXTURE", texture)
        .replace("NEAREST", nearest)
}

/// The pass's parameters (depth.wgsl's `DepthParams`).
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct DepthParams {
    view_from_clip: [f32; 16],
    viewport: [f32; 4],
}

impl SceneDepth {
    /// The pass for `frame`'s depth buffer and viewport.
    fn new(gpu: &Gpu, frame: &CloudFrame) -> Result<Self, GpuError> {
        let samples = frame.target.1;
        let module = gpu.shader("depth.wgsl", &depth_source(samples))?;
        let pipeline = gpu.screen_pipeline(
            "the scene's depth for the clouds",
            &module,
            None,
            &[Some(wgpu::TextureFormat::R32Float.into())],
            None,
            1,
        )?;
        let size = (frame.view.viewport.z, frame.view.viewport.w);
        let texture = gpu.texture_2d(
            "the scene's depth for the clouds",
            size,
            wgpu::TextureFormat::R32Float,
            wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
        );
        Ok(SceneDepth {
            pipeline,
            samples,
            size,
            params: gpu.uniform(
                "the scene's depth",
                &<DepthParams as bytemuck::Zeroable>::zeroed(),
            ),
            view: texture.create_view(&Default::default()),
            group: None,
        })
    }

    /// Whether the pass serves `frame`'s depth buffer and viewport.
    fn fits(&self, frame: &CloudFrame) -> bool {
        self.samples == frame.target.1
            && self.size == (frame.view.viewport.z, frame.view.viewport.w)
    }

    /// Sets the pass to read `frame`'s depth buffer this frame.
    fn prepare(&mut self, gpu: &Gpu, frame: &CloudFrame) {
        let params = DepthParams {
            view_from_clip: frame.view.clip_from_view.inverse().to_cols_array(),
            viewport: frame.view.viewport.to_array().map(|v| v as f32),
        };
        gpu.queue
            .write_buffer(&self.params, 0, bytemuck::bytes_of(&params));
        self.group = Some(gpu.bind_group(
            &self.pipeline.get_bind_group_layout(0),
            &[
                self.params.as_entire_binding(),
                wgpu::BindingResource::TextureView(frame.depth),
            ],
        ));
    }

    /// Records the pass.
    fn draw(&self, encoder: &mut wgpu::CommandEncoder) {
        let Some(group) = &self.group else { return };
        let mut pass = atmo_gpu::display::cleared_pass(
            encoder,
            &self.view,
            "the scene's depth for the clouds",
            wgpu::Color::TRANSPARENT,
        );
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, group, &[]);
        pass.draw(0..3, 0..1);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn both_variants_of_the_depth_shader_are_valid_wgsl() {
        for samples in [1, 4] {
            let text = depth_source(samples);
            let module = naga::front::wgsl::parse_str(&text)
                .unwrap_or_else(|e| panic!("{samples} samples: {}", e.emit_to_string(&text)));
            naga::valid::Validator::new(
                naga::valid::ValidationFlags::all(),
                naga::valid::Capabilities::all(),
            )
            .validate(&module)
            .unwrap_or_else(|e| panic!("{samples} samples: {e:?}"));
        }
    }
}
