//! Showing a linear HDR picture on a display: exposure, tone map and sRGB encoding on
//! the GPU, as `atmo::image::Display` does for PNG files, drawn into any colour target
//! (a window's surface texture, the caller's own). The viewer shows every frame through
//! it; an engine that draws the sky into an HDR target can finish with it too.

use atmo::image::{Display, ToneMap};

use crate::wgsl::{self, TONE_ACES, TONE_CLAMP, TONE_EXPONENTIAL};
use crate::{gpu_struct, Gpu, GpuError};

gpu_struct! {
    /// The display pass's parameters (see display.wgsl).
    pub struct DisplayParams in "screen.wgsl display.wgsl" {
        corner: [f32; 2],
        exposure: f32,
        tone: u32,
        encode: u32,
        pad0: u32,
        pad1: u32,
        pad2: u32,
    }
}

/// The WGSL code of a tone map (a `TONE_*` of the prelude).
pub fn tone_code(tone: ToneMap) -> u32 {
    match tone {
        ToneMap::Clamp => TONE_CLAMP,
        ToneMap::Exponential => TONE_EXPONENTIAL,
        ToneMap::Aces => TONE_ACES,
    }
}

/// Draws an RGBA f32 picture (linear radiance) into a target of one format: a
/// full-screen triangle that reads the picture texel by texel (no filtering: the
/// picture's pixels land on the target's one to one, from [`DisplayPass::corner`]).
pub struct DisplayPass {
    pipeline: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
    params: wgpu::Buffer,
    group: Option<wgpu::BindGroup>,
    /// Whether the target stores linear values (the pass encodes sRGB itself).
    encode: bool,
    /// Exposure and tone map.
    pub display: Display,
    /// The target's pixel where the picture's (0, 0) goes.
    pub corner: [u32; 2],
}

impl DisplayPass {
    /// The pass for targets of `format` (an `*Srgb` format encodes on store; any other
    /// gets sRGB-encoded values).
    pub fn new(gpu: &Gpu, format: wgpu::TextureFormat) -> Result<Self, GpuError> {
        let module = wgsl::module(gpu, "screen.wgsl display.wgsl")?;
        let (layout, pipeline_layout) = picture_layout(gpu, "display", 1);
        let pipeline = gpu.screen_pipeline(
            "the display pass",
            &module,
            Some(&pipeline_layout),
            &[Some(format.into())],
            None,
            1,
        )?;
        Ok(DisplayPass {
            pipeline,
            layout,
            params: gpu.uniform("display", &<DisplayParams as bytemuck::Zeroable>::zeroed()),
            group: None,
            encode: !format.is_srgb(),
            display: Display {
                exposure: 1.0,
                tone: ToneMap::default(),
            },
            corner: [0, 0],
        })
    }

    /// Sets the picture the next draw shows (an RGBA f32 texture's view) and writes
    /// this pass's exposure, tone map and corner.
    pub fn prepare(&mut self, gpu: &Gpu, picture: &wgpu::TextureView) {
        let params = DisplayParams {
            corner: self.corner.map(|c| c as f32),
            exposure: self.display.exposure,
            tone: tone_code(self.display.tone),
            encode: self.encode as u32,
            pad0: 0,
            pad1: 0,
            pad2: 0,
        };
        gpu.queue
            .write_buffer(&self.params, 0, bytemuck::bytes_of(&params));
        self.group = Some(gpu.bind_group(
            &self.layout,
            &[
                self.params.as_entire_binding(),
                wgpu::BindingResource::TextureView(picture),
            ],
        ));
    }

    /// Records the picture into `pass`, whose colour attachment has this pass's format;
    /// nothing before [`DisplayPass::prepare`].
    pub fn draw(&self, pass: &mut wgpu::RenderPass<'_>) {
        crate::display::draw_screen(pass, &self.pipeline, self.group.as_ref());
    }
}

/// The bindings of a pass that reads pictures texel by texel: a uniform at binding 0,
/// then `pictures` RGBA f32 textures (unfilterable: an automatic layout would want
/// them filterable) at 1, 2, ...; and the pipeline layout of that one group.
pub(crate) fn picture_layout(
    gpu: &Gpu,
    label: &str,
    pictures: u32,
) -> (wgpu::BindGroupLayout, wgpu::PipelineLayout) {
    let entry = |binding, ty| wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::FRAGMENT,
        ty,
        count: None,
    };
    let uniform = wgpu::BindingType::Buffer {
        ty: wgpu::BufferBindingType::Uniform,
        has_dynamic_offset: false,
        min_binding_size: None,
    };
    let texture = wgpu::BindingType::Texture {
        sample_type: wgpu::TextureSampleType::Float { filterable: false },
        view_dimension: wgpu::TextureViewDimension::D2,
        multisampled: false,
    };
    let entries: Vec<_> = std::iter::once(entry(0, uniform))
        .chain((1..=pictures).map(|b| entry(b, texture)))
        .collect();
    let layout = gpu
        .device
        .create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some(label),
            entries: &entries,
        });
    let pipeline_layout = gpu
        .device
        .create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some(label),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
    (layout, pipeline_layout)
}

/// Records the full-screen triangle of `pipeline` reading `group` into `pass`: how
/// every picture pass draws; nothing before its group is set (before its `prepare`).
pub(crate) fn draw_screen(
    pass: &mut wgpu::RenderPass<'_>,
    pipeline: &wgpu::RenderPipeline,
    group: Option<&wgpu::BindGroup>,
) {
    if let Some(group) = group {
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, group, &[]);
        pass.draw(0..3, 0..1);
    }
}

/// A render pass into `target` alone, cleared to `colour`: what a picture or a window's
/// frame starts from.
pub fn cleared_pass<'e>(
    encoder: &'e mut wgpu::CommandEncoder,
    target: &wgpu::TextureView,
    label: &str,
    colour: wgpu::Color,
) -> wgpu::RenderPass<'e> {
    target_pass(encoder, target, label, wgpu::LoadOp::Clear(colour))
}

/// A render pass into `target` alone over what it holds: for a pass that puts a
/// picture over another (the clouds over a sky).
pub fn loaded_pass<'e>(
    encoder: &'e mut wgpu::CommandEncoder,
    target: &wgpu::TextureView,
    label: &str,
) -> wgpu::RenderPass<'e> {
    target_pass(encoder, target, label, wgpu::LoadOp::Load)
}

fn target_pass<'e>(
    encoder: &'e mut wgpu::CommandEncoder,
    target: &wgpu::TextureView,
    label: &str,
    load: wgpu::LoadOp<wgpu::Color>,
) -> wgpu::RenderPass<'e> {
    encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some(label),
        color_attachments: &[Some(wgpu::RenderPassColorAttachment {
            view: target,
            depth_slice: None,
            resolve_target: None,
            ops: wgpu::Operations {
                load,
                store: wgpu::StoreOp::Store,
            },
        })],
        ..Default::default()
    })
}

/// An RGBA f32 picture texture of `width` x `height` (checked against the device's
/// limit) that a [`crate::sky::SkyPass`] can draw into, a [`DisplayPass`] can show,
/// [`write_frame`] can fill from the CPU and [`Gpu::read_texture`] can read back.
pub fn picture_texture(gpu: &Gpu, width: u32, height: u32) -> Result<wgpu::Texture, GpuError> {
    for side in [width, height] {
        gpu.check_texture_side("the picture", side, "the picture's size")?;
    }
    Ok(gpu.texture_2d(
        "the picture",
        (width, height),
        wgpu::TextureFormat::Rgba32Float,
        wgpu::TextureUsages::RENDER_ATTACHMENT
            | wgpu::TextureUsages::TEXTURE_BINDING
            | wgpu::TextureUsages::COPY_SRC
            | wgpu::TextureUsages::COPY_DST,
    ))
}

/// Writes a CPU `frame` into a [`picture_texture`] of its size (alpha 1): how a
/// picture drawn on the CPU reaches a window.
pub fn write_frame(gpu: &Gpu, texture: &wgpu::Texture, frame: &atmo::image::Frame) {
    let texels: Vec<[f32; 4]> = frame.pixels.iter().map(|p| [p.x, p.y, p.z, 1.0]).collect();
    gpu.queue.write_texture(
        texture.as_image_copy(),
        bytemuck::cast_slice(&texels),
        wgpu::TexelCopyBufferLayout {
            offset: 0,
            bytes_per_row: Some(frame.width * 16),
            rows_per_image: None,
        },
        texture.size(),
    );
}
