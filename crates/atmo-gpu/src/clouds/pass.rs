//! The pass that puts the billboards over a caller's target (clouds (5)-(6)), blended
//! in hardware back to front.

use super::*;

/// The cloud drawn into a caller's colour target of one format: a full-screen
/// triangle that puts the picture [`GpuClouds::prepare`] recorded (with its higher
/// octaves) over what the target holds, pixel for pixel from [`CloudsPass::corner`],
/// times [`CloudsPass::exposure`], hidden where the caller's scene is in front
/// ([`CloudsPass::scene_depth`]). It keeps the two targets the billboards are drawn
/// into between frames of one size.
pub struct CloudsPass {
    pub(super) pipeline: wgpu::RenderPipeline,
    pub(super) layout: wgpu::BindGroupLayout,
    pub(super) params: wgpu::Buffer,
    pub(super) group: Option<wgpu::BindGroup>,
    /// The picture's and the higher octaves' targets, and their size.
    pub(super) targets: Option<((u32, u32), [wgpu::Texture; 2])>,
    /// Multiplies the radiance written.
    pub exposure: f32,
    /// The target's pixel where the picture's (0, 0) goes.
    pub corner: [u32; 2],
    /// The caller's scene: each pixel's depth along the camera's view axis, m, in an
    /// `R32Float` texture of the picture's size (`f32::MAX` where nothing is). Each
    /// particle's column counts only in front of it, so a surface inside a cloud fades
    /// into it as the cloud thins before it. `None`: the cloud is in front of everything.
    pub scene_depth: Option<wgpu::TextureView>,
}

impl CloudsPass {
    /// The pass for colour targets of `format` (blendable) with `samples` samples a
    /// pixel (every sample takes the pixel's cloud): refused by name where the device
    /// cannot render to it.
    pub fn new(gpu: &Gpu, format: wgpu::TextureFormat, samples: u32) -> Result<Self, GpuError> {
        let module = wgsl::module(gpu, "screen.wgsl clouds_composite.wgsl")?;
        // Premultiplied "over": the cloud, then (1 - its coverage) of what is behind.
        let over = wgpu::BlendComponent {
            src_factor: wgpu::BlendFactor::One,
            dst_factor: wgpu::BlendFactor::OneMinusSrcAlpha,
            operation: wgpu::BlendOperation::Add,
        };
        let target = wgpu::ColorTargetState {
            format,
            blend: Some(wgpu::BlendState {
                color: over,
                alpha: over,
            }),
            write_mask: wgpu::ColorWrites::ALL,
        };
        let (layout, pipeline_layout) = crate::display::picture_layout(gpu, "the clouds", 2);
        let pipeline = gpu.screen_pipeline(
            "the clouds' composite",
            &module,
            Some(&pipeline_layout),
            &[Some(target)],
            None,
            samples,
        )?;
        Ok(CloudsPass {
            pipeline,
            layout,
            params: gpu.uniform(
                "the clouds' composite",
                &<CompositeParams as bytemuck::Zeroable>::zeroed(),
            ),
            group: None,
            targets: None,
            exposure: 1.0,
            corner: [0, 0],
            scene_depth: None,
        })
    }

    /// Records the cloud into `pass` (nothing before a [`GpuClouds::prepare`]).
    pub fn draw(&self, pass: &mut wgpu::RenderPass<'_>) {
        crate::display::draw_screen(pass, &self.pipeline, self.group.as_ref());
    }
}
