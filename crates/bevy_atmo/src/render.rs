//! The render world's part: atmo on Bevy's own device, each sky camera's sky uploaded
//! and its maps recorded per frame (atmo-gpu's passes, unchanged), and the picture pass
//! drawn into Bevy's colour target after the opaque meshes, where its depth buffer is
//! still at the far plane.

use std::sync::Arc;

use atmo::sky::lighting::LUMENS_PER_WATT;
use atmo::sky::{SkyModel, SkylightTable, View};
use atmo::view::{Camera as AtmoCamera, Fov, Sun};
use atmo_gpu::sky::{DepthTarget, GpuSkyModel, GpuSkyTable, SkyPass, SkyTarget};
use atmo_gpu::{wgpu, Gpu, GpuError};
use bevy::prelude::*;
use bevy::render::camera::ExtractedCamera;
use bevy::render::render_resource::{RenderPassDescriptor, StoreOp};
use bevy::render::renderer::{
    RenderAdapterInfo, RenderContext, RenderDevice, RenderQueue, ViewQuery,
};
use bevy::render::sync_world::RenderEntity;
use bevy::render::view::{ExtractedView, Msaa, ViewDepthStencilTexture, ViewTarget};
use bevy::render::Extract;

use crate::aerial::{AerialFrame, AerialTarget, ViewAerial};
use crate::cloud_pass::{draw_clouds, CloudOnGpu, ViewClouds};
use crate::sky::{AtmoSky, AtmoSkyState, ReadySky};
use crate::sun::SunNow;

/// atmo on Bevy's device and queue (absent where the device lacks what atmo needs).
#[derive(Resource)]
pub(crate) struct AtmoGpu(pub(crate) Gpu);

/// Wraps Bevy's device for atmo; where it lacks float32 blending, atmo draws nothing
/// and says why once.
pub(crate) fn init_gpu(
    mut commands: Commands,
    device: Res<RenderDevice>,
    queue: Res<RenderQueue>,
    info: Res<RenderAdapterInfo>,
) {
    match Gpu::from_device(
        device.wgpu_device().clone(),
        (**queue).clone(),
        (**info).clone(),
    ) {
        Ok(gpu) => commands.insert_resource(AtmoGpu(gpu)),
        Err(e) => error!("bevy_atmo draws nothing: {e}"),
    }
}

/// What a render system has said went wrong: each error is logged the first time it
/// happens, not again every frame it stays (at most the last few distinct ones kept).
#[derive(Default)]
pub(crate) struct Said(Vec<String>);

impl Said {
    /// Logs `what: error` unless it was said already.
    pub(crate) fn error(&mut self, what: &str, error: impl std::fmt::Display) {
        let line = format!("{what}: {error}");
        if !self.0.contains(&line) {
            error!("{line}");
            if self.0.len() == 16 {
                self.0.remove(0);
            }
            self.0.push(line);
        }
    }
}

/// A sky camera's frame as the render world takes it: what to draw, seen from where,
/// under which sun.
#[derive(Component)]
pub(crate) struct ExtractedSky {
    pub(crate) ready: ReadySky,
    generation: u64,
    altitude_m: f64,
    sun: Sun,
    sun_disc: bool,
}

/// A 3-D camera, with its sky where it has one.
type SkyCamera<'a> = (
    RenderEntity,
    &'a GlobalTransform,
    Option<(&'a AtmoSky, &'a AtmoSkyState)>,
);

/// Copies each sky camera's sky into the render world; a camera whose sky is not ready
/// (no model yet, no sun) or gone loses its copy.
pub(crate) fn extract_skies(
    mut commands: Commands,
    sun: Extract<Res<SunNow>>,
    cameras: Extract<Query<SkyCamera, With<Camera3d>>>,
) {
    for (render_entity, transform, sky) in &cameras {
        let drawable = sky.and_then(|(sky, state)| Some((sky, state, state.ready.clone()?)));
        match (drawable, sun.0) {
            (Some((sky, state, ready)), Some(sun)) => {
                let altitude_m = ready.drawn_altitude(sky.altitude_m(transform.translation().y));
                commands.entity(render_entity).insert(ExtractedSky {
                    ready,
                    generation: state.generation,
                    altitude_m,
                    sun,
                    sun_disc: sky.sun_disc,
                });
            }
            _ => {
                commands
                    .entity(render_entity)
                    .try_remove::<(ExtractedSky, ViewSky)>();
            }
        }
    }
}

/// A sky on the GPU, shared with the main world's copy.
type GpuSky = atmo_gpu::sky::GpuSky<Arc<SkyModel>, Arc<SkylightTable>>;

/// The sky of `ready` uploaded.
fn upload(gpu: &Gpu, ready: &ReadySky) -> Result<GpuSky, GpuError> {
    Ok(match ready {
        ReadySky::Model(model, _) => GpuSky::Model(GpuSkyModel::new(gpu, model.clone())?),
        ReadySky::Table(table) => GpuSky::Table(GpuSkyTable::new(gpu, table.clone())?),
    })
}

/// A view's sky on the GPU: the sky and its aerial perspective (remade when what is
/// drawn changes) and the passes (remade when the view's targets do).
#[derive(Component)]
pub(crate) struct ViewSky {
    sky: GpuSky,
    generation: u64,
    pass: SkyPass,
    target: SkyTarget,
    aerial: Option<ViewAerial>,
}

/// The aerial perspective of `ready` for `target`, where it has view rays and the
/// device filters f32 textures (the froxels are f32; said once where it does not).
fn aerial_of(
    gpu: &Gpu,
    sky: &GpuSky,
    ready: &ReadySky,
    target: AerialTarget,
) -> Result<Option<ViewAerial>, GpuError> {
    let (GpuSky::Model(model), ReadySky::Model(_, Some(rays))) = (sky, ready) else {
        return Ok(None);
    };
    if !gpu
        .device
        .features()
        .contains(wgpu::Features::FLOAT32_FILTERABLE)
    {
        warn_once!("bevy_atmo: no aerial perspective (the device does not filter f32 textures)");
        return Ok(None);
    }
    ViewAerial::new(gpu, model, rays.clone(), target).map(Some)
}

/// The aerial pass's target for a view's colour target.
fn aerial_target(gpu: &Gpu, sky: SkyTarget) -> AerialTarget {
    AerialTarget {
        format: sky.format,
        samples: sky.samples,
        dual_source: gpu
            .device
            .features()
            .contains(wgpu::Features::DUAL_SOURCE_BLENDING),
    }
}

/// The camera of a view as atmo's (at the origin: the sky is at infinity), for its
/// viewport, and its vertical field of view, degrees; `None` for a projection that is
/// not a perspective.
pub(crate) fn atmo_camera(view: &ExtractedView) -> Option<(AtmoCamera, f32)> {
    let projection = view.clip_from_view;
    // Bevy's perspectives are infinite reversed z: y_axis.y = 1 / tan(fov_y / 2).
    if projection.w_axis.w != 0.0 || projection.y_axis.y <= 0.0 {
        return None;
    }
    let fov_deg = (2.0 * (1.0 / projection.y_axis.y).atan()).to_degrees();
    let (forward, up) = (view.world_from_view.forward(), view.world_from_view.up());
    let size = (view.viewport.z, view.viewport.w);
    let camera = AtmoCamera::look_at(Vec3::ZERO, *forward, *up, Fov::Vertical(fov_deg), size);
    Some((camera.ok()?, fov_deg))
}

/// A view with a sky to draw: what its sky (`T`: `ViewSky`) or its clouds
/// (`ViewClouds`) need to be set up, and what they kept from the last frame.
pub(crate) type SkyViewParts<'a, T> = (
    Entity,
    &'a ExtractedSky,
    &'a ExtractedView,
    &'a ExtractedCamera,
    &'a ViewTarget,
    &'a Msaa,
    &'a ViewDepthStencilTexture,
    Option<&'a mut T>,
);

/// Uploads what changed and records each sky view's maps for this frame's sun in an
/// encoder of its own, submitted before Bevy's frame (which draws them).
pub(crate) fn prepare_skies(
    mut commands: Commands,
    mut said: Local<Said>,
    gpu: Option<Res<AtmoGpu>>,
    mut views: Query<SkyViewParts<ViewSky>>,
) {
    let Some(gpu) = gpu else {
        return;
    };
    let gpu = &gpu.0;
    for (entity, sky, view, camera, target, msaa, depth, view_sky) in &mut views {
        let Some((atmo_camera, fov_deg)) = atmo_camera(view) else {
            warn_once!("bevy_atmo draws the sky for perspective cameras only");
            continue;
        };
        let wanted = SkyTarget {
            format: target.main_texture_format(),
            depth: Some(DepthTarget {
                format: depth.texture().format(),
                reversed_z: true,
            }),
            samples: msaa.samples(),
        };
        // A view's first sky is drawn from the next frame on, once inserted.
        let Some(mut view_sky) = view_sky else {
            match made_new(gpu, sky, wanted) {
                Ok(new) => {
                    commands.entity(entity).insert(new);
                }
                Err(e) => said.error("bevy_atmo's sky", e),
            }
            continue;
        };
        if let Err(e) = remake(gpu, &mut view_sky, sky, wanted) {
            said.error("bevy_atmo's sky", e);
            continue;
        }
        let view_sky = &mut *view_sky;
        view_sky.pass.exposure = LUMENS_PER_WATT as f32 * camera.exposure;
        view_sky.pass.corner = [view.viewport.x, view.viewport.y];
        let atmo_view = View {
            camera: atmo_camera,
            sun_disc: sky.sun_disc,
        };
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        let mut prepared = view_sky.sky.prepare(
            gpu,
            &mut encoder,
            &mut view_sky.pass,
            sky.sun,
            sky.altitude_m,
            &atmo_view,
        );
        if let (Some(aerial), GpuSky::Model(model), Some(depth_view)) = (
            &mut view_sky.aerial,
            &view_sky.sky,
            depth.attachment.depth_stencil_views().depth_only_view(),
        ) {
            let frame = AerialFrame {
                sun: sky.sun,
                forward: atmo_view.camera.forward,
                up: atmo_view.camera.up,
                fov_deg,
                view_from_clip: view.clip_from_view.inverse(),
                viewport: view.viewport.to_array(),
                scale: view_sky.pass.exposure,
                depth: depth_view,
            };
            prepared = prepared.and_then(|()| aerial.prepare(gpu, &mut encoder, model, &frame));
        }
        match prepared {
            Ok(()) => {
                gpu.queue.submit([encoder.finish()]);
            }
            Err(e) => said.error("bevy_atmo's sky", e),
        }
    }
}

/// A view's sky and pass made for the first time.
fn made_new(gpu: &Gpu, sky: &ExtractedSky, target: SkyTarget) -> Result<ViewSky, GpuError> {
    let on_gpu = upload(gpu, &sky.ready)?;
    Ok(ViewSky {
        aerial: aerial_of(gpu, &on_gpu, &sky.ready, aerial_target(gpu, target))?,
        sky: on_gpu,
        generation: sky.generation,
        pass: SkyPass::new(gpu, target)?,
        target,
    })
}

/// Remakes what is out of date in `view_sky`: the sky when what is drawn changed, the
/// pass when the view's targets did (a new format, MSAA switched).
fn remake(
    gpu: &Gpu,
    view_sky: &mut ViewSky,
    sky: &ExtractedSky,
    target: SkyTarget,
) -> Result<(), GpuError> {
    if view_sky.generation != sky.generation {
        view_sky.sky = upload(gpu, &sky.ready)?;
        view_sky.aerial = aerial_of(gpu, &view_sky.sky, &sky.ready, aerial_target(gpu, target))?;
        view_sky.generation = sky.generation;
    }
    if view_sky.target != target {
        view_sky.pass = SkyPass::new(gpu, target)?;
        if let Some(aerial) = &mut view_sky.aerial {
            aerial.retarget(gpu, aerial_target(gpu, target))?;
        }
        view_sky.target = target;
    }
    Ok(())
}

/// Draws the sky into the view's colour target (its multisampled one with MSAA on),
/// depth-tested against the opaque meshes so that it fills only the far plane, the
/// aerial perspective over the meshes, and the clouds over both.
pub(crate) fn draw_sky(
    view: ViewQuery<(
        &ExtractedCamera,
        &ViewTarget,
        &ViewDepthStencilTexture,
        &ViewSky,
        Option<&mut ViewClouds>,
    )>,
    gpu: Option<Res<AtmoGpu>>,
    clouds: Query<&CloudOnGpu>,
    mut said: Local<Said>,
    mut ctx: RenderContext,
) {
    let (camera, target, depth, sky, view_clouds) = view.into_inner();
    let encoder = ctx.command_encoder();
    let attachment = depth.get_attachment(StoreOp::Store);
    sky.pass.draw(&mut begin(
        encoder,
        camera,
        target,
        "atmo sky",
        Some(attachment),
    ));
    if let Some(aerial) = &sky.aerial {
        // The depth buffer is read as a texture, so not attached.
        aerial.draw(&mut begin(
            encoder,
            camera,
            target,
            "atmo aerial perspective",
            None,
        ));
    }
    if let (Some(mut view_clouds), Some(gpu)) = (view_clouds, gpu) {
        draw_clouds(
            &gpu.0,
            encoder,
            camera,
            target,
            &mut view_clouds,
            &clouds,
            &mut said,
        );
    }
}

/// A render pass into the view's colour target (its multisampled one with MSAA on),
/// over the camera's viewport.
pub(crate) fn begin<'e>(
    encoder: &'e mut wgpu::CommandEncoder,
    camera: &ExtractedCamera,
    target: &'e ViewTarget,
    label: &str,
    depth: Option<wgpu::RenderPassDepthStencilAttachment<'e>>,
) -> wgpu::RenderPass<'e> {
    let mut pass = encoder.begin_render_pass(&RenderPassDescriptor {
        label: Some(label),
        color_attachments: &[Some(target.get_color_attachment())],
        depth_stencil_attachment: depth,
        timestamp_writes: None,
        occlusion_query_set: None,
        multiview_mask: None,
    });
    if let Some(viewport) = &camera.viewport {
        let (at, size) = (viewport.physical_position, viewport.physical_size);
        pass.set_viewport(
            at.x as f32,
            at.y as f32,
            size.x as f32,
            size.y as f32,
            viewport.depth.start,
            viewport.depth.end,
        );
    }
    pass
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_error_is_said_once_while_it_stays_and_the_oldest_are_forgotten() {
        let mut said = Said::default();
        for _ in 0..3 {
            said.error("sky", "lost");
        }
        assert_eq!(said.0, ["sky: lost"]);
        for k in 0..20 {
            said.error("sky", k);
        }
        assert_eq!(said.0.len(), 16);
        assert_eq!(said.0[15], "sky: 19");
        assert!(!said.0.iter().any(|line| line == "sky: lost"));
    }
}
