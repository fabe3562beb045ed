//! Aerial perspective on Bevy's meshes: atmo's froxels (`GpuAerial`, the sky model's
//! view rays cut at 32 slice distances) applied to every pixel Bevy's depth buffer puts
//! in front of the far plane, blended into the colour target as `dst * T + S`.

use std::sync::Arc;

use atmo::sky::aerial::AerialRays;
use atmo::sky::SkyModel;
use atmo::view::{Camera as AtmoCamera, Fov, Sun};
use atmo_gpu::sky::{AerialTextures, GpuAerial, GpuSkyModel, AERIAL_LIGHT_WGSL};
use atmo_gpu::{wgpu, Gpu, GpuError};
use bevy::math::Mat4;

/// Froxel columns across the picture (rows: as many as keep them square) and slices:
/// atmo's aerial defaults, 32 x 32 x 32 for a square picture.
pub const FROXEL_COLUMNS: u32 = 32;
pub const SLICES: usize = 32;
/// Elevation rows of the marked rays (512: each froxel within 1.4 % of its own ray).
pub const ROWS: usize = 512;

/// The blend of the aerial pass: `dst * T + S`, colour only.
fn blend(dual_source: bool) -> wgpu::BlendState {
    let transmittance = if dual_source {
        wgpu::BlendFactor::Src1
    } else {
        wgpu::BlendFactor::SrcAlpha
    };
    wgpu::BlendState {
        color: wgpu::BlendComponent {
            src_factor: wgpu::BlendFactor::One,
            dst_factor: transmittance,
            operation: wgpu::BlendOperation::Add,
        },
        alpha: wgpu::BlendComponent {
            src_factor: wgpu::BlendFactor::Zero,
            dst_factor: wgpu::BlendFactor::One,
            operation: wgpu::BlendOperation::Add,
        },
    }
}

/// The shader's source for a depth buffer of `samples` samples a pixel, with two blend
/// sources (per-channel transmittance) or one (their mean in alpha).
fn source(samples: u32, dual_source: bool) -> String {
    let (depth, input, index) = if samples > 1 {
        (
            "texture_depth_multisampled_2d",
            ", @builtin(sample_index) sample: u32",
            "i32(sample)",
        )
    } else {
        ("texture_depth_2d", "", "0")
    };
    let (header, output, value) = if dual_source {
        (
            "enable dual_source_blending;",
            "struct Output {\n    @location(0) @blend_src(0) inscatter: vec4<f32>,\n    \
             @location(0) @blend_src(1) transmittance: vec4<f32>,\n}",
            "Output(vec4<f32>(s, 0.0), vec4<f32>(t, 1.0))",
        )
    } else {
        (
            "",
            "struct Output {\n    @location(0) colour: vec4<f32>,\n}",
            "Output(vec4<f32>(s, (t.r + t.g + t.b) / 3.0))",
        )
    };
    include_str!("aerial.wgsl")
        .replace("DUAL_SOURCE", header)
        .replace("AERIAL_LIGHT", AERIAL_LIGHT_WGSL)
        .replace("DEPTH_TEXTURE", depth)
        .replace("SAMPLE_INPUT", input)
        .replace("SAMPLE_INDEX", index)
        .replace("OUTPUT_STRUCT", output)
        .replace("OUTPUT", value)
}

/// The pass's parameters (aerial.wgsl's `AerialParams`).
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct AerialParams {
    view_from_clip: [f32; 16],
    viewport: [f32; 4],
    froxels: [f32; 4],
}

/// What the pass is made for: the colour target's format and samples, and whether the
/// device blends two sources.
#[derive(Clone, Copy, PartialEq, Eq)]
pub(crate) struct AerialTarget {
    pub format: wgpu::TextureFormat,
    pub samples: u32,
    pub dual_source: bool,
}

/// A view's aerial perspective: the froxels' pass and textures, and the pass over the
/// depth buffer that applies them.
pub(crate) struct ViewAerial {
    froxels: GpuAerial,
    textures: AerialTextures,
    target: AerialTarget,
    pipeline: wgpu::RenderPipeline,
    params: wgpu::Buffer,
    sampler: wgpu::Sampler,
    group: Option<wgpu::BindGroup>,
}

/// A view's frame, as the aerial pass needs it.
pub(crate) struct AerialFrame<'a> {
    pub sun: Sun,
    /// The view's axes (unit forward and up, world frame) and vertical field of view.
    pub forward: bevy::math::Vec3,
    pub up: bevy::math::Vec3,
    pub fov_deg: f32,
    pub view_from_clip: Mat4,
    /// Corner and size of the viewport, pixels.
    pub viewport: [u32; 4],
    /// Luminance per radiance times the camera's exposure.
    pub scale: f32,
    pub depth: &'a wgpu::TextureView,
}

impl ViewAerial {
    /// The froxels of `rays` (made by `sky`'s model) and the pass for `target`.
    pub fn new(
        gpu: &Gpu,
        sky: &GpuSkyModel<Arc<SkyModel>>,
        rays: Arc<AerialRays>,
        target: AerialTarget,
    ) -> Result<Self, GpuError> {
        let slices = rays.slices_m().len() as u32;
        Ok(ViewAerial {
            froxels: GpuAerial::new(gpu, sky, rays)?,
            textures: AerialTextures::new(gpu, (FROXEL_COLUMNS, FROXEL_COLUMNS, slices))?,
            target,
            pipeline: pipeline(gpu, target)?,
            params: gpu.uniform(
                "the aerial pass",
                &<AerialParams as bytemuck::Zeroable>::zeroed(),
            ),
            sampler: gpu.device.create_sampler(&wgpu::SamplerDescriptor {
                label: Some("the froxels"),
                mag_filter: wgpu::FilterMode::Linear,
                min_filter: wgpu::FilterMode::Linear,
                ..Default::default()
            }),
            group: None,
        })
    }

    /// Remakes the pass for a new `target` (a format, MSAA switched).
    pub fn retarget(&mut self, gpu: &Gpu, target: AerialTarget) -> Result<(), GpuError> {
        if self.target != target {
            self.pipeline = pipeline(gpu, target)?;
            self.target = target;
        }
        Ok(())
    }

    /// Records this frame's froxels into `encoder` and sets the pass to apply them.
    pub fn prepare(
        &mut self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        sky: &GpuSkyModel<Arc<SkyModel>>,
        frame: &AerialFrame,
    ) -> Result<(), GpuError> {
        let [x, y, width, height] = frame.viewport;
        let rows = (FROXEL_COLUMNS as f32 * height as f32 / width.max(1) as f32)
            .round()
            .clamp(1.0, 256.0) as u32;
        let slices_m = self.froxels.rays().slices_m();
        let (slices, far_m) = (slices_m.len() as u32, slices_m[slices_m.len() - 1] as f32);
        if self.textures.size != (FROXEL_COLUMNS, rows, slices) {
            self.textures = AerialTextures::new(gpu, (FROXEL_COLUMNS, rows, slices))?;
        }
        let camera = AtmoCamera::look_at(
            bevy::math::Vec3::ZERO,
            frame.forward,
            frame.up,
            Fov::Vertical(frame.fov_deg),
            (FROXEL_COLUMNS, rows),
        )?;
        self.froxels
            .prepare(gpu, encoder, sky, frame.sun, &camera, &self.textures)?;
        let params = AerialParams {
            view_from_clip: frame.view_from_clip.to_cols_array(),
            viewport: [x, y, width, height].map(|v| v as f32),
            froxels: [far_m, slices as f32, frame.scale, 0.0],
        };
        gpu.queue
            .write_buffer(&self.params, 0, bytemuck::bytes_of(&params));
        let views = [&self.textures.transmittance, &self.textures.inscatter]
            .map(|t| t.create_view(&Default::default()));
        self.group = Some(gpu.bind_group(
            &self.pipeline.get_bind_group_layout(0),
            &[
                self.params.as_entire_binding(),
                wgpu::BindingResource::TextureView(&views[0]),
                wgpu::BindingResource::TextureView(&views[1]),
                wgpu::BindingResource::Sampler(&self.sampler),
                wgpu::BindingResource::TextureView(frame.depth),
            ],
        ));
        Ok(())
    }

    /// Records the pass into `pass` (the view's colour target, no depth attachment).
    pub fn draw(&self, pass: &mut wgpu::RenderPass<'_>) {
        if let Some(group) = &self.group {
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(0, group, &[]);
            pass.draw(0..3, 0..1);
        }
    }
}

/// The pass's pipeline for `target`.
fn pipeline(gpu: &Gpu, target: AerialTarget) -> Result<wgpu::RenderPipeline, GpuError> {
    let module = gpu.shader("aerial.wgsl", &source(target.samples, target.dual_source))?;
    gpu.screen_pipeline(
        "the aerial perspective over the scene",
        &module,
        None,
        &[Some(wgpu::ColorTargetState {
            format: target.format,
            blend: Some(blend(target.dual_source)),
            write_mask: wgpu::ColorWrites::ALL,
        })],
        None,
        target.samples,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_variant_of_the_shader_is_valid_wgsl() {
        for samples in [1, 4] {
            for dual in [false, true] {
                let text = source(samples, dual);
                let module = naga::front::wgsl::parse_str(&text).unwrap_or_else(|e| {
                    panic!(
                        "{samples} samples, dual {dual}: {}",
                        e.emit_to_string(&text)
                    )
                });
                naga::valid::Validator::new(
                    naga::valid::ValidationFlags::all(),
                    naga::valid::Capabilities::all(),
                )
                .validate(&module)
                .unwrap_or_else(|e| panic!("{samples} samples, dual {dual}: {e:?}"));
            }
        }
    }
}
