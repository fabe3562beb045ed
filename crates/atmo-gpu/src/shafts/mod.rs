//! Light shafts on the GPU by the paper's method (shafts 4): per frame, the shadow maps
//! of every light by one ray a texel (with the extents of the lit volumes), the planes'
//! depth ranges and the attenuation table, the surfaces, then the sample planes drawn
//! as screen-parallel quads blended additively ([`ShaftsMethod::Planes`], the default)
//! or the same sums in one compute pass ([`ShaftsMethod::Compute`]). Everything stays
//! on the GPU from the scene's upload to the finished picture. Translates
//! `atmo::shafts::SamplePlanes::render`, which the tests hold it to.
//!
//! Two ways out: [`GpuShafts::render`] submits the passes and reads the picture back
//! (the stills); [`GpuShafts::prepare`] records them into the caller's encoder and a
//! [`ShaftsPass`] draws the picture into the caller's own colour target, with no
//! read-back (the viewer, an engine).

use atmo::geometry::Shape;
use atmo::shafts::spotlight::{Falloff, Profile, Sampling};
use atmo::shafts::tables::{AttenuationTable, IntensityMap, PhaseTable};
use atmo::shafts::Scene;
use glam::Vec3;

use crate::wgsl::{
    self, FALLOFF_LINEAR, FALLOFF_MEASURED, FALLOFF_SMOOTH, GOBO_BILINEAR, GOBO_NEAREST, GOBO_NONE,
    OBJECT_BOX, OBJECT_MESH, OBJECT_NO_SHADOW, OBJECT_PLANE, OBJECT_RECT, OBJECT_SPHERE,
};
use crate::{gpu_struct, Gpu, GpuError, Rendered};

/// The WGSL every shafts pass shares, after its bindings' file (writable or readable)
/// and before its own.
pub const COMMON: &str =
    "shafts_common.wgsl shafts_objects.wgsl shafts_spotlight.wgsl shafts_tables.wgsl shafts_sampling.wgsl";

mod renderer;

pub use renderer::{Drawn, ShaftsRenderer};

gpu_struct! {
    /// The scene's camera, haze and sizes (see shafts_common.wgsl).
    pub struct ShaftsParams in "shafts_writable.wgsl shafts_common.wgsl" {
        position: [f32; 4],
        forward: [f32; 4],
        right: [f32; 4],
        up: [f32; 4],
        haze_min: [f32; 4],
        haze_max: [f32; 4],
        width: u32,
        height: u32,
        supersampling: u32,
        lights: u32,
        planes: u32,
        sub_planes: u32,
        shadow_size: u32,
        haze_box: u32,
        objects: u32,
        nodes_at: u32,
        triangles_at: u32,
        phase_size: u32,
        light_map_size: u32,
        attenuation_size: u32,
        /// 1: the surfaces' own light is drawn; 0: the haze alone, its transmittance
        /// in alpha ([`GpuShafts::haze_over`]).
        surfaces: u32,
        pad1: u32,
    }
}

gpu_struct! {
    /// One spotlight (see shafts_common.wgsl).
    pub struct GpuLight in "shafts_writable.wgsl shafts_common.wgsl" {
        position: [f32; 4],
        x_axis: [f32; 4],
        y_axis: [f32; 4],
        z_axis: [f32; 4],
        intensity: [f32; 4],
        field_half: f32,
        falloff: u32,
        gobo: u32,
        gobo_at: u32,
        gobo_width: u32,
        gobo_height: u32,
        cone_at: u32,
        cone_count: u32,
        map_row: u32,
        map_rows: u32,
        gobo_cos: f32,
        gobo_sin: f32,
    }
}

gpu_struct! {
    /// The frame pass's parameters (see shafts_frame.wgsl).
    pub struct ShaftsFrameParams in "screen.wgsl shafts_frame.wgsl" {
        corner: [f32; 2],
        exposure: f32,
        width: u32,
        height: u32,
        pad0: u32,
        /// The frame's size on the target, pixels.
        shown: [f32; 2],
    }
}

/// How the planes' sums are taken on the GPU.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ShaftsMethod {
    /// The paper's: a quad per plane (and sub-pixel ray), blended additively.
    #[default]
    Planes,
    /// The same sums per pixel in one compute pass.
    Compute,
}

/// Floats per light in the `derived` buffer (planes), then 4 table scales.
const PLANE_FLOATS: u64 = 12;

/// The shafts' compiled passes, which depend on no scene: made once a device and
/// shared by every [`GpuShafts`] made from them (an animation's frames, a viewer's
/// edits), since compiling them is most of what setting up a scene costs.
pub struct ShaftsPipelines {
    /// The bindings of the compute passes (writable) and of the planes' render pass
    /// (read-only).
    compute_layout: wgpu::BindGroupLayout,
    render_layout: wgpu::BindGroupLayout,
    shadow: wgpu::ComputePipeline,
    prepare: wgpu::ComputePipeline,
    attenuation: wgpu::ComputePipeline,
    surface: wgpu::ComputePipeline,
    compute: wgpu::ComputePipeline,
    planes: wgpu::RenderPipeline,
    composite: wgpu::ComputePipeline,
}

impl ShaftsPipelines {
    /// Compiles the passes for `gpu`'s device.
    pub fn new(gpu: &Gpu) -> Result<std::sync::Arc<Self>, GpuError> {
        // The compute passes write the frame's buffers; the render pass only reads them,
        // through the same bindings declared read-only (so its vertex stage may too).
        let [(compute_layout, compute_pipeline_layout), (render_layout, render_pipeline_layout)] =
            [false, true].map(|read_only| {
                let layout = bind_group_layout(gpu, read_only);
                let pipeline_layout =
                    gpu.device
                        .create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                            label: Some("shafts"),
                            bind_group_layouts: &[Some(&layout)],
                            immediate_size: 0,
                        });
                (layout, pipeline_layout)
            });
        // Compute passes see the working buffers writable, the planes' render pass
        // read-only: the same declarations in two files (see shafts_common.wgsl).
        let module =
            |pass: &str| wgsl::module(gpu, &format!("shafts_writable.wgsl {COMMON} {pass}"));
        let shadow = module("shafts_shadow.wgsl")?;
        let prepare = module("shafts_prepare.wgsl")?;
        let surface = module("shafts_surface.wgsl")?;
        let compute = module("shafts_compute.wgsl")?;
        let planes = wgsl::module(
            gpu,
            &format!("shafts_readable.wgsl {COMMON} shafts_planes.wgsl"),
        )?;
        let composite = wgsl::module(gpu, "shafts_composite.wgsl")?;
        let with = Some(&compute_pipeline_layout);
        // The table's own pass, with its own bindings: the texture is written there and
        // read (as a texture) by every pass after it.
        let table = module("shafts_attenuation.wgsl")?;
        Ok(std::sync::Arc::new(ShaftsPipelines {
            shadow: gpu.compute_pipeline(&shadow, "main", with)?,
            prepare: gpu.compute_pipeline(&prepare, "planes", with)?,
            attenuation: gpu.compute_pipeline(&table, "main", None)?,
            surface: gpu.compute_pipeline(&surface, "main", with)?,
            compute: gpu.compute_pipeline(&compute, "main", with)?,
            // Additive: the planes' terms sum up (shafts (7)).
            planes: gpu.blended_pipeline(
                &planes,
                Some(&render_pipeline_layout),
                wgpu::BlendComponent {
                    src_factor: wgpu::BlendFactor::One,
                    dst_factor: wgpu::BlendFactor::One,
                    operation: wgpu::BlendOperation::Add,
                },
                1,
            )?,
            composite: gpu.compute_pipeline(&composite, "main", None)?,
            compute_layout,
            render_layout,
        }))
    }
}

/// A scene uploaded, with its passes.
pub struct GpuShafts {
    params: ShaftsParams,
    /// Per light, 10 initial extents (order-preserving encodings).
    extents_init: Vec<u32>,
    extents: wgpu::Buffer,
    out: wgpu::Buffer,
    group: wgpu::BindGroup,
    /// The same resources, read-only, for the planes' render pass.
    render_group: wgpu::BindGroup,
    /// The attenuation pass's own bindings (it writes the table the others read).
    attenuation_group: wgpu::BindGroup,
    pipelines: std::sync::Arc<ShaftsPipelines>,
    /// The planes' render target.
    target: wgpu::Texture,
}

impl GpuShafts {
    /// Uploads `scene` (objects, lights, gobos, the phase table and light maps) and
    /// allocates the frame's buffers, each checked against the device's limits first,
    /// and compiles the passes ([`ShaftsPipelines`]).
    pub fn new(gpu: &Gpu, scene: &Scene) -> Result<Self, GpuError> {
        GpuShafts::with_pipelines(gpu, scene, ShaftsPipelines::new(gpu)?)
    }

    /// The passes this scene draws with, to make the next scene's [`GpuShafts`] from
    /// ([`GpuShafts::with_pipelines`]).
    pub fn pipelines(&self) -> std::sync::Arc<ShaftsPipelines> {
        self.pipelines.clone()
    }

    /// As [`GpuShafts::new`] with passes compiled before: what changes from frame to
    /// frame of an animation (the lights, their gobos) is uploaded, nothing compiled.
    pub fn with_pipelines(
        gpu: &Gpu,
        scene: &Scene,
        pipelines: std::sync::Arc<ShaftsPipelines>,
    ) -> Result<Self, GpuError> {
        GpuShafts::upload(gpu, scene, pipelines, true)
    }

    /// The haze of `scene` alone, for drawing over a scene an engine shaded itself
    /// (with [`ShaftsPass::over`]): each pixel's light scattered toward the eye in front
    /// of the first surface (shafts (1)'s second term, the objects still casting their
    /// shadows and ending the rays), and in alpha the haze's transmittance to that
    /// surface (the mean over the pixel's rays), which dims what the engine drew there.
    pub fn haze_over(
        gpu: &Gpu,
        scene: &Scene,
        pipelines: std::sync::Arc<ShaftsPipelines>,
    ) -> Result<Self, GpuError> {
        GpuShafts::upload(gpu, scene, pipelines, false)
    }

    /// Uploads `scene`, drawing its surfaces' own light where `surfaces`.
    fn upload(
        gpu: &Gpu,
        scene: &Scene,
        pipelines: std::sync::Arc<ShaftsPipelines>,
        surfaces: bool,
    ) -> Result<Self, GpuError> {
        let camera = &scene.camera;
        let (w, h, k) = (camera.width, camera.height, camera.supersampling);
        let (tan_half_width, tan_half_height) = camera.pinhole("the sample planes")?;
        let lights = scene.light_count() as u32;
        let size = scene.planes.shadow_map;
        gpu.check_texture_side("the image width", w, "camera.width")?;
        gpu.check_texture_side("the image height", h, "camera.height")?;
        gpu.check_texture_side("the light maps", lights.max(1), "the number of lights")?;
        // The maps, the rays' ends and the picture on the device and back, beside the
        // scene's files, before any of them is made.
        let maps = lights.max(1) as u64 * (size as u64).pow(2) * 4;
        let ends_bytes = w as u64 * h as u64 * (k * k) as u64 * 4;
        scene.beside_files(|| {
            atmo::budget::check(
                &format!("the light shafts' maps and {w} x {h} picture on the GPU"),
                maps + ends_bytes + w as u64 * h as u64 * crate::device::PICTURE_BYTES_PER_PIXEL,
                "camera.width, camera.height, render.supersampling or render.shadow_map",
            )
        })?;
        let geometry = Geometry::of(scene);
        let depth = gpu.output("the shadow maps", maps, "render.shadow_map")?;
        let extents = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("the lit volumes' extents"),
            size: 40 * lights.max(1) as u64,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let derived = gpu.output(
            "the planes",
            4 * (PLANE_FLOATS * lights.max(1) as u64 + 4),
            "the number of lights",
        )?;
        let n = AttenuationTable::SIZE as u32;
        let attenuation_texture = gpu.texture_2d(
            "the attenuation table",
            (n, n),
            wgpu::TextureFormat::R32Float,
            wgpu::TextureUsages::STORAGE_BINDING | wgpu::TextureUsages::TEXTURE_BINDING,
        );
        let attenuation_view = attenuation_texture.create_view(&Default::default());
        let pixels = w as u64 * h as u64;
        let ends = gpu.output(
            "the rays' ends",
            ends_bytes,
            "camera.width, camera.height or render.supersampling",
        )?;
        let out = gpu.output("the picture", pixels * 16, "camera.width or camera.height")?;
        let params = ShaftsParams {
            position: v4(camera.position, scene.far_m()),
            forward: v4(camera.forward, tan_half_width),
            right: v4(camera.right, tan_half_height),
            up: v4(camera.up, 1.0 / (k * k) as f32),
            haze_min: v4(
                scene.haze.bounds.map_or(Vec3::ZERO, |b| b.min),
                scene.haze.extinction,
            ),
            haze_max: v4(
                scene.haze.bounds.map_or(Vec3::ZERO, |b| b.max),
                scene.haze.scattering(),
            ),
            width: w,
            height: h,
            supersampling: k,
            lights,
            planes: scene.planes.planes,
            sub_planes: scene.planes.sub_planes,
            shadow_size: size,
            haze_box: scene.haze.bounds.is_some() as u32,
            objects: scene.objects.list.len() as u32,
            nodes_at: geometry.nodes_at,
            triangles_at: geometry.triangles_at,
            phase_size: PhaseTable::SIZE as u32,
            light_map_size: IntensityMap::SIZE as u32,
            attenuation_size: AttenuationTable::SIZE as u32,
            surfaces: surfaces as u32,
            pad1: 0,
        };
        let uniform = gpu.uniform("the shafts' parameters", &params);
        let light_records = gpu.storage(
            "the lights",
            bytemuck::cast_slice(&geometry.lights),
            "the number of lights",
        )?;
        let geometry_buffer = gpu.storage(
            "the objects, meshes and gobos",
            bytemuck::cast_slice(&geometry.values),
            "the mesh sizes or the gobo images",
        )?;
        let phase = PhaseTable::new(&scene.haze);
        let phase_texture =
            gpu.float_texture("the phase table", &phase.values, PhaseTable::SIZE as u32, 1);
        // Each light's map, row after row (see GpuLight::map_row).
        let mut maps: Vec<f32> = scene
            .lights()
            .flat_map(|l| l.intensity_map.values.iter().copied())
            .collect();
        if maps.is_empty() {
            maps = vec![0.0; IntensityMap::SIZE];
        }
        let map_rows = (maps.len() / IntensityMap::SIZE) as u32;
        gpu.check_texture_side(
            "the lights' maps (rows)",
            map_rows,
            "the number of lights with measured profiles that are not rotationally symmetric",
        )?;
        let map_texture =
            gpu.float_texture("the light maps", &maps, IntensityMap::SIZE as u32, map_rows);
        let target = gpu.texture_2d(
            "the planes",
            (w, h),
            wgpu::TextureFormat::Rgba32Float,
            wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
        );
        let phase_view = phase_texture.create_view(&Default::default());
        let map_view = map_texture.create_view(&Default::default());
        let [group, render_group] =
            [&pipelines.compute_layout, &pipelines.render_layout].map(|layout| {
                gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some("shafts"),
                    layout,
                    entries: &[
                        entry(0, uniform.as_entire_binding()),
                        entry(1, light_records.as_entire_binding()),
                        entry(2, geometry_buffer.as_entire_binding()),
                        entry(3, wgpu::BindingResource::TextureView(&phase_view)),
                        entry(4, wgpu::BindingResource::TextureView(&map_view)),
                        entry(5, depth.as_entire_binding()),
                        entry(6, extents.as_entire_binding()),
                        entry(7, derived.as_entire_binding()),
                        entry(8, ends.as_entire_binding()),
                        entry(9, out.as_entire_binding()),
                        entry(10, wgpu::BindingResource::TextureView(&attenuation_view)),
                    ],
                })
            });
        let attenuation_group = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("the attenuation table"),
            layout: &pipelines.attenuation.get_bind_group_layout(0),
            entries: &[
                entry(0, uniform.as_entire_binding()),
                entry(7, derived.as_entire_binding()),
                entry(11, wgpu::BindingResource::TextureView(&attenuation_view)),
            ],
        });
        let mut extents_init = Vec::new();
        for _ in 0..lights {
            let (lo, hi, zero) = (
                encode(f32::INFINITY),
                encode(f32::NEG_INFINITY),
                encode(0.0),
            );
            extents_init.extend([lo, hi, zero, zero, lo, lo, lo, hi, hi, hi]);
        }
        Ok(GpuShafts {
            params,
            extents_init,
            extents,
            out,
            group,
            render_group,
            attenuation_group,
            pipelines,
            target,
        })
    }

    /// The picture, as `SamplePlanes::new(scene).render()` on the CPU with every pixel
    /// computed (`render.adaptive = false`; the GPU has no adaptive sampling): the passes
    /// submitted, timed where the device can, and the picture read back.
    pub fn render(&self, gpu: &Gpu, method: ShaftsMethod) -> Result<Rendered, GpuError> {
        let gpu_ms = gpu.run("the light shafts", |encoder| {
            self.encode(gpu, encoder, method)
        })?;
        let p = &self.params;
        let frame = gpu.read_with("the light shafts", &self.out, 0, self.out.size(), |bytes| {
            crate::frame_of(p.width, p.height, bytes)
        })?;
        Ok(Rendered { frame, gpu_ms })
    }

    /// Records the passes into the caller's `encoder` and sets `pass` to draw their
    /// picture: the scene drawn into the caller's target with no read-back. The
    /// picture is the scene camera's size; record `pass`'s draw into a render pass
    /// whose colour attachment has `pass`'s format, after this encoder's passes.
    pub fn prepare(
        &self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        pass: &mut ShaftsPass,
        method: ShaftsMethod,
    ) -> Result<(), GpuError> {
        self.encode(gpu, encoder, method);
        let (width, height) = (self.params.width, self.params.height);
        let shown = pass.shown.unwrap_or([width, height]);
        let params = ShaftsFrameParams {
            corner: pass.corner.map(|c| c as f32),
            exposure: pass.exposure,
            width,
            height,
            pad0: 0,
            shown: shown.map(|s| s as f32),
        };
        gpu.queue
            .write_buffer(&pass.params, 0, bytemuck::bytes_of(&params));
        // Bindings the device refuses are an error here, not a frame that draws nothing.
        let group = gpu.scoped("the shafts' picture pass", || {
            gpu.bind_group(
                &pass.pipeline.get_bind_group_layout(0),
                &[
                    pass.params.as_entire_binding(),
                    self.out.as_entire_binding(),
                ],
            )
        })?;
        pass.group = Some(group);
        Ok(())
    }

    /// Records every pass of the frame into `encoder`, the picture ending in `out`.
    fn encode(&self, gpu: &Gpu, encoder: &mut wgpu::CommandEncoder, method: ShaftsMethod) {
        let p = &self.params;
        gpu.queue
            .write_buffer(&self.extents, 0, bytemuck::cast_slice(&self.extents_init));
        let view = self.target.create_view(&Default::default());
        let composite_group = gpu.bind_group(
            &self.pipelines.composite.get_bind_group_layout(0),
            &[
                wgpu::BindingResource::TextureView(&view),
                self.out.as_entire_binding(),
            ],
        );
        {
            let mut pass = encoder.begin_compute_pass(&Default::default());
            pass.set_bind_group(0, &self.group, &[]);
            if p.lights > 0 {
                pass.set_pipeline(&self.pipelines.shadow);
                let groups = p.shadow_size.div_ceil(8);
                pass.dispatch_workgroups(groups, groups, p.lights);
            }
            pass.set_pipeline(&self.pipelines.prepare);
            pass.dispatch_workgroups(1, 1, 1);
            pass.set_pipeline(&self.pipelines.attenuation);
            pass.set_bind_group(0, &self.attenuation_group, &[]);
            let groups = p.attenuation_size.div_ceil(16);
            pass.dispatch_workgroups(groups, groups, 1);
            pass.set_bind_group(0, &self.group, &[]);
            pass.set_pipeline(&self.pipelines.surface);
            pass.dispatch_workgroups(p.width.div_ceil(8), p.height.div_ceil(8), 1);
            if method == ShaftsMethod::Compute {
                pass.set_pipeline(&self.pipelines.compute);
                pass.dispatch_workgroups(p.width.div_ceil(8), p.height.div_ceil(8), 1);
            }
        }
        if method == ShaftsMethod::Planes {
            {
                let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some("sample planes"),
                    color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                        view: &view,
                        depth_slice: None,
                        resolve_target: None,
                        ops: wgpu::Operations {
                            load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                            store: wgpu::StoreOp::Store,
                        },
                    })],
                    ..Default::default()
                });
                pass.set_pipeline(&self.pipelines.planes);
                pass.set_bind_group(0, &self.render_group, &[]);
                let quads = p.lights * p.planes * p.supersampling * p.supersampling;
                pass.draw(0..6, 0..quads);
            }
            let mut pass = encoder.begin_compute_pass(&Default::default());
            pass.set_pipeline(&self.pipelines.composite);
            pass.set_bind_group(0, &composite_group, &[]);
            pass.dispatch_workgroups(p.width.div_ceil(8), p.height.div_ceil(8), 1);
        }
    }
}

/// The shafts' picture drawn into a caller's colour target of one format: a
/// full-screen triangle reading the picture [`GpuShafts::prepare`] recorded, pixel for
/// pixel from [`ShaftsPass::corner`] (linear radiance times [`ShaftsPass::exposure`];
/// an `*Srgb` format encodes it on store), in place of what the target holds
/// ([`ShaftsPass::new`]) or over it ([`ShaftsPass::over`]). Made once and kept: its
/// pipeline is compiled here.
pub struct ShaftsPass {
    pipeline: wgpu::RenderPipeline,
    params: wgpu::Buffer,
    /// What the next draw reads, set by [`GpuShafts::prepare`].
    group: Option<wgpu::BindGroup>,
    /// Multiplies the radiance written.
    pub exposure: f32,
    /// The target's pixel where the picture's (0, 0) goes.
    pub corner: [u32; 2],
    /// The picture's size on the target, pixels, where it is drawn larger than it is
    /// (a scene camera of a fraction of the target's resolution, read bilinearly);
    /// `None`: pixel for pixel.
    pub shown: Option<[u32; 2]>,
}

impl ShaftsPass {
    /// The pass for colour targets of `format`, writing the picture in place of what
    /// they hold: refused by name where the device cannot render to it.
    pub fn new(gpu: &Gpu, format: wgpu::TextureFormat) -> Result<Self, GpuError> {
        ShaftsPass::made(gpu, format.into(), 1)
    }

    /// The pass for colour targets of `format` with `samples` samples a pixel holding a
    /// scene, drawing the haze of [`GpuShafts::haze_over`] over it: `dst T + S` (the
    /// target's colour dimmed by the haze's transmittance, plus its light; the target's
    /// alpha kept).
    pub fn over(gpu: &Gpu, format: wgpu::TextureFormat, samples: u32) -> Result<Self, GpuError> {
        let blend = wgpu::BlendState {
            color: wgpu::BlendComponent {
                src_factor: wgpu::BlendFactor::One,
                dst_factor: wgpu::BlendFactor::SrcAlpha,
                operation: wgpu::BlendOperation::Add,
            },
            alpha: wgpu::BlendComponent {
                src_factor: wgpu::BlendFactor::Zero,
                dst_factor: wgpu::BlendFactor::One,
                operation: wgpu::BlendOperation::Add,
            },
        };
        let target = wgpu::ColorTargetState {
            format,
            blend: Some(blend),
            write_mask: wgpu::ColorWrites::ALL,
        };
        ShaftsPass::made(gpu, target, samples)
    }

    fn made(gpu: &Gpu, target: wgpu::ColorTargetState, samples: u32) -> Result<Self, GpuError> {
        let module = wgsl::module(gpu, "screen.wgsl shafts_frame.wgsl")?;
        let pipeline = gpu.screen_pipeline(
            "the shafts' picture pass",
            &module,
            None,
            &[Some(target)],
            None,
            samples,
        )?;
        Ok(ShaftsPass {
            pipeline,
            params: gpu.uniform(
                "the shafts' picture",
                &<ShaftsFrameParams as bytemuck::Zeroable>::zeroed(),
            ),
            group: None,
            exposure: 1.0,
            corner: [0, 0],
            shown: None,
        })
    }

    /// Records the picture into `pass` (nothing before a [`GpuShafts::prepare`]).
    pub fn draw(&self, pass: &mut wgpu::RenderPass<'_>) {
        crate::display::draw_screen(pass, &self.pipeline, self.group.as_ref());
    }
}

fn v4(v: Vec3, w: f32) -> [f32; 4] {
    [v.x, v.y, v.z, w]
}

/// A float as a u32 whose unsigned order is the float's (shafts_shadow.wgsl's `encode`).
fn encode(f: f32) -> u32 {
    let b = f.to_bits();
    if b & 0x8000_0000 != 0 {
        !b
    } else {
        b | 0x8000_0000
    }
}

fn entry(binding: u32, resource: wgpu::BindingResource<'_>) -> wgpu::BindGroupEntry<'_> {
    wgpu::BindGroupEntry { binding, resource }
}

/// The layout of shafts_common.wgsl's bindings: for the compute passes, or read-only
/// for the render pass (whose vertex stage reads the lit volumes' boxes).
fn bind_group_layout(gpu: &Gpu, read_only: bool) -> wgpu::BindGroupLayout {
    let visible = if read_only {
        wgpu::ShaderStages::VERTEX | wgpu::ShaderStages::FRAGMENT
    } else {
        wgpu::ShaderStages::COMPUTE
    };
    let buffer =
        |binding: u32, ty: wgpu::BufferBindingType, visibility| wgpu::BindGroupLayoutEntry {
            binding,
            visibility,
            ty: wgpu::BindingType::Buffer {
                ty,
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        };
    let storage = |binding: u32, only_read: bool| {
        buffer(
            binding,
            wgpu::BufferBindingType::Storage {
                read_only: only_read || read_only,
            },
            visible,
        )
    };
    let texture = |binding: u32| wgpu::BindGroupLayoutEntry {
        binding,
        visibility: visible,
        ty: wgpu::BindingType::Texture {
            sample_type: wgpu::TextureSampleType::Float { filterable: false },
            view_dimension: wgpu::TextureViewDimension::D2,
            multisampled: false,
        },
        count: None,
    };
    gpu.device
        .create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("shafts"),
            entries: &[
                buffer(0, wgpu::BufferBindingType::Uniform, visible),
                storage(1, true),
                storage(2, true),
                texture(3),
                texture(4),
                storage(5, false),
                storage(6, false),
                storage(7, false),
                storage(8, false),
                storage(9, false),
                texture(10),
            ],
        })
}

/// The scene's static data as the shaders read it.
struct Geometry {
    lights: Vec<GpuLight>,
    /// Objects, nodes, triangles, cone lists and gobo texels (see shafts_common.wgsl).
    values: Vec<[f32; 4]>,
    nodes_at: u32,
    triangles_at: u32,
}

impl Geometry {
    fn of(scene: &Scene) -> Geometry {
        let list = &scene.objects.list;
        let bits = |u: u32| f32::from_bits(u);
        let (mut nodes, mut triangles) = (Vec::new(), Vec::new());
        let mut values: Vec<[f32; 4]> = Vec::with_capacity(4 * list.len());
        for object in list {
            let (kind, a, b, c) = match &object.shape {
                Shape::Plane { point, normal } => {
                    (OBJECT_PLANE, v4(*point, 0.0), v4(*normal, 0.0), [0.0; 4])
                }
                Shape::Rect {
                    corner,
                    edge_a,
                    edge_b,
                } => (
                    OBJECT_RECT,
                    v4(*corner, 0.0),
                    v4(*edge_a, 0.0),
                    v4(*edge_b, 0.0),
                ),
                Shape::Sphere { center, radius } => {
                    (OBJECT_SPHERE, v4(*center, *radius), [0.0; 4], [0.0; 4])
                }
                Shape::Box(aabb) => (OBJECT_BOX, v4(aabb.min, 0.0), v4(aabb.max, 0.0), [0.0; 4]),
                Shape::Mesh(mesh) => {
                    let root = (nodes.len() / 2) as u32;
                    let first = (triangles.len() / 3) as u32;
                    for (bounds, start, count) in mesh.nodes() {
                        nodes.push(v4(bounds.min, bits(start)));
                        nodes.push(v4(bounds.max, bits(count)));
                    }
                    for t in mesh.triangles() {
                        triangles.extend(t.iter().map(|v| v4(*v, 0.0)));
                    }
                    (
                        OBJECT_MESH,
                        [bits(root), bits(first), 0.0, 0.0],
                        [0.0; 4],
                        [0.0; 4],
                    )
                }
            };
            let flags = if object.casts_shadow {
                0
            } else {
                OBJECT_NO_SHADOW
            };
            values.extend([a, b, c, v4(object.albedo, bits(kind | flags))]);
        }
        let nodes_at = values.len() as u32;
        values.extend(nodes);
        let triangles_at = values.len() as u32;
        values.extend(triangles);
        // Where each light's rows start in the light-map texture.
        let mut map_row_next = 0u32;
        let lights = scene
            .lights()
            .map(|light| {
                let cone = scene.objects.indices_in_cone(light);
                let cone_at = values.len() as u32;
                values.extend(
                    cone.chunks(4)
                        .map(|c| std::array::from_fn(|i| bits(c.get(i).copied().unwrap_or(0)))),
                );
                let (gobo, gobo_at, gobo_width, gobo_height) = match &light.gobo {
                    None => (GOBO_NONE, 0, 0, 0),
                    Some(g) => {
                        let at = values.len() as u32;
                        values.extend((0..g.srgb().len()).map(|k| v4(g.texel(k), 0.0)));
                        let sampling = match g.sampling {
                            Sampling::Nearest => GOBO_NEAREST,
                            Sampling::Bilinear => GOBO_BILINEAR,
                        };
                        let (w, h) = g.size();
                        (sampling, at, w as u32, h as u32)
                    }
                };
                let map = &light.intensity_map;
                let m = light.light_from_world;
                let (beam_half, falloff) = match &light.profile {
                    Profile::Beam {
                        beam_half,
                        falloff: Falloff::Linear,
                    } => (*beam_half, FALLOFF_LINEAR),
                    Profile::Beam {
                        beam_half,
                        falloff: Falloff::Smooth,
                    } => (*beam_half, FALLOFF_SMOOTH),
                    Profile::Measured(_) => (0.0, FALLOFF_MEASURED),
                };
                let map_row = map_row_next;
                map_row_next += map.rows as u32;
                GpuLight {
                    position: v4(light.position, light.tan_field()),
                    x_axis: v4(m.row(0), map.q_beam),
                    y_axis: v4(m.row(1), map.scale),
                    z_axis: v4(m.row(2), light.tan_beam()),
                    intensity: v4(light.intensity, beam_half),
                    field_half: light.field_half,
                    falloff,
                    gobo,
                    gobo_at,
                    gobo_width,
                    gobo_height,
                    cone_at,
                    cone_count: cone.len() as u32,
                    map_row,
                    map_rows: map.rows as u32,
                    gobo_cos: light.gobo.as_ref().map_or(1.0, |g| g.rotation.cos()),
                    gobo_sin: light.gobo.as_ref().map_or(0.0, |g| g.rotation.sin()),
                }
            })
            .collect();
        Geometry {
            lights,
            values,
            nodes_at,
            triangles_at,
        }
    }
}
