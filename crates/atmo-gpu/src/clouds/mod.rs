//! Clouds on the GPU (clouds 3.3 and 2.2): the 3-D intensity buffer filled
//! order-independently by a compute pass (every particle adds its `log G` with integer
//! atomics, then each column is summed along the light), and the particles drawn back
//! to front as billboards that look the buffer up trilinearly. Translates
//! `atmo::clouds::buffer` and `atmo::clouds::render`; the buffer lives on the GPU
//! between the light pass and the draw, so a moving sun costs one light pass and a
//! moving camera none with the octaves. The transfer table (every order by default,
//! as on the CPU) needs each blob's optical depth toward the eye, which billboards
//! blended in hardware cannot sum along their pixel as the CPU does: it is read from a
//! second buffer lit from the eye along each pixel's ray (the particles as seen from
//! the camera, [`eye_resolution`]), one light pass more when the camera moves.
//! [`GpuClouds::render`] reads the picture back (the stills); [`GpuClouds::prepare`]
//! records the draw into the caller's encoder and a
//! [`CloudsPass`] puts the cloud over the caller's own target, with no read-back.

use std::cell::{Cell, OnceCell, RefCell};

use atmo::clouds::buffer::{IntensityBuffer, LightFrame, Splat};
use atmo::clouds::particles::Particle;
use atmo::clouds::render::{dims_the_sky, CloudLight};
use atmo::clouds::shadow::CloudShadow;
use atmo::clouds::sky_light::{SkyDimming, VERTICAL_RESOLUTION};
use atmo::clouds::transfer::{CloudDepths, TransferTable};
use atmo::image::Frame;
use atmo::view::Camera;
use glam::Vec3;

use crate::wgsl;
use crate::{gpu_struct, Gpu, GpuError, Rendered};

mod frames;
mod pass;
mod solve;

use frames::*;
pub use pass::CloudsPass;
pub use solve::SolveParams;
use solve::{GpuSolve, SolvePipelines};

gpu_struct! {
    /// A particle as the shaders read it (32 bytes).
    pub struct GpuParticle in "clouds_common.wgsl" {
        /// Centre (m) and radius (m).
        position_radius: [f32; 4],
        /// Extinction coefficient at the centre, 1/m.
        density: f32,
        albedo: f32,
        /// The optical depth above the centre and the cloud's whole depth on that
        /// vertical (`atmo::clouds::sky_light::vertical_depths`, made on the GPU), for
        /// the sky's light inside the cloud; 0 until a draw with that light needs them.
        sky_depth: f32,
        sky_column: f32,
        /// The least optical depth from the centre out of the cloud along the six axes
        /// (`atmo::clouds::CloudDepths::out`, made on the GPU), for the transfer
        /// table; `f32::MAX` until a light pass along an axis has made it.
        out_depth: f32,
        /// The cloud's greatest optical depth through the centre along the three axes
        /// (`atmo::clouds::CloudDepths::thickness`, made with `out_depth`); 0 until then.
        thickness: f32,
        pad1: u32,
        pad2: u32,
    }
}

gpu_struct! {
    /// The light pass's frame and the buffer's grid (see `atmo::clouds::buffer`).
    pub struct BufferFrame in "clouds_common.wgsl" {
        /// Rows of world-to-buffer axes.
        x_axis: [f32; 4],
        y_axis: [f32; 4],
        z_axis: [f32; 4],
        /// The grid's smallest corner and its voxel size, buffer axes, m.
        min: [f32; 4],
        voxel: [f32; 4],
        resolution: u32,
        particles: u32,
        /// 1: `Splat::Pieces`, 0: `Splat::Whole`.
        pieces: u32,
        /// `p(l, l) / 4 pi` as f32 bits.
        forward_bits: u32,
    }
}

gpu_struct! {
    /// The draw's camera and lighting (see clouds_draw.wgsl).
    pub struct DrawParams in "clouds_common.wgsl clouds_lookup.wgsl clouds_draw.wgsl" {
        position: [f32; 4],
        forward: [f32; 4],
        right: [f32; 4],
        up: [f32; 4],
        to_sun: [f32; 4],
        sun: [f32; 4],
        /// The sky's light the droplets scatter toward the eye, as nine harmonics
        /// (atmo::clouds::SkyLight::scattered), RGB.
        sky: [[f32; 4]; 9],
        /// The sky's light inside the cloud from above and below against outside
        /// (atmo::clouds::SkyDimming), RGB; `sky_above`'s w: the extrapolation length.
        sky_above: [f32; 4],
        sky_below: [f32; 4],
        haze_transmittance: [f32; 4],
        haze_inscatter: [f32; 4],
        /// The octaves' attenuation, contribution, eccentricity and depth scale.
        octaves: [f32; 4],
        /// The slab's diffuse light: its weight and extrapolation length (unused zw).
        diffuse: [f32; 4],
        width: u32,
        height: u32,
        octave_count: u32,
        /// Where the grid lit from the eye starts in the intensity buffer, f32s, and the
        /// scale across its rays (`seen_from`'s `s`).
        eye_base: u32,
        eye_scale: f32,
        pad1: u32,
        pad2: u32,
        pad3: u32,
        /// The transfer solve's grid: cell `(0, 0, 0)`'s centre (m) and the cells' side
        /// (w, m), and the cells along x, y and z.
        solve_centre: [f32; 4],
        solve_dims: [u32; 4],
    }
}

/// Workgroup size of the compute passes (the shaders' `@workgroup_size(64)`).
const GROUP: u32 = 64;

/// The most voxels a side of the buffer lit from the eye that the transfer table's
/// depth toward the eye is read from ([`eye_resolution`]).
pub const EYE_RESOLUTION: u32 = 256;

/// Voxels a side of the buffer lit from the eye for a picture of `width` x `height`:
/// about one across four pixels, from 64 to [`EYE_RESOLUTION`]. Coarser, a blob's light
/// takes the grid's squares: on the window's 960 x 600 view of the 60,134-particle
/// cumulus, 128 shows them, 192 faintly, 256 not.
pub fn eye_resolution(width: u32, height: u32) -> u32 {
    (width.max(height) / 4).clamp(64, EYE_RESOLUTION)
}

/// A cloud on the GPU: its particles, its intensity buffer, the passes.
pub struct GpuClouds {
    particles: Vec<Particle>,
    particle_buffer: wgpu::Buffer,
    resolution: u32,
    /// ln Gamma, `[x][z][y]` (fixed-point increments during the light pass): the sun's
    /// grid, then from `eye_offset` (bytes) the grid lit from the eye.
    cells: wgpu::Buffer,
    eye_offset: u64,
    /// The light pass's frame, once it has run.
    frame: Option<BufferFrame>,
    /// The grid lit from the eye that `cells` holds, if any.
    eye: Cell<Option<EyeGrid>>,
    /// The buffer lit along an axis ([`VERTICAL_RESOLUTION`]^3) the particles' depths
    /// are read from (for the sky's light, the vertical's), and whether their records
    /// hold the vertical's.
    sky_cells: wgpu::Buffer,
    sky_depths: Cell<bool>,
    /// Whether the particles' records hold their depths out of the cloud.
    out_depths: Cell<bool>,
    splat: wgpu::ComputePipeline,
    prefix: wgpu::ComputePipeline,
    depths_pass: wgpu::ComputePipeline,
    /// The billboards, the orders past the first by the octaves, by the table and by
    /// the transfer solve.
    draw: [wgpu::RenderPipeline; 3],
    /// The transfer solve's passes (made when a draw first needs them), its buffers
    /// for the particles where they are, and what the draws bind without one.
    solve_pipelines: OnceCell<SolvePipelines>,
    solve: RefCell<Option<GpuSolve>>,
    no_solve: wgpu::Buffer,
    /// What the draws bind without a scene in front: one texel of `f32::MAX`.
    no_scene: wgpu::TextureView,
    /// [`GpuClouds::render`]'s composite, into an RGBA f32 picture (a cell: `render`
    /// reads the cloud while it prepares the pass).
    composite: RefCell<CloudsPass>,
}

impl GpuClouds {
    /// Uploads `particles` and allocates a `resolution`^3 buffer (and the
    /// [`EYE_RESOLUTION`]^3 grid lit from the eye after it): refused above the CPU's
    /// budget and the device's buffer limits, before anything is allocated.
    pub fn new(gpu: &Gpu, particles: &[Particle], resolution: usize) -> Result<Self, GpuError> {
        IntensityBuffer::check_resolution(resolution)?;
        // The eye's grid bound at an offset the device allows.
        let alignment = gpu.limits().min_storage_buffer_offset_alignment as u64;
        let eye_offset = ((resolution as u64).pow(3) * 4).next_multiple_of(alignment);
        let bytes = eye_offset + (EYE_RESOLUTION as u64).pow(3) * 4;
        let limits = gpu.limits();
        for (limit, name) in [
            (
                limits.max_storage_buffer_binding_size,
                "max_storage_buffer_binding_size",
            ),
            (limits.max_buffer_size, "max_buffer_size"),
        ] {
            gpu.check_limit(
                &format!("a {resolution}^3 intensity buffer"),
                bytes,
                limit,
                name,
                "buffer.resolution",
            )?;
        }
        let particle_buffer = gpu.storage(
            "the particles",
            bytemuck::cast_slice(&records(particles)),
            "the particle count",
        )?;
        let cells = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("the intensity buffer"),
            size: bytes,
            usage: wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::COPY_SRC
                | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let sky_cells = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("the buffer lit along an axis"),
            size: (VERTICAL_RESOLUTION as u64).pow(3) * 4,
            // Cleared before each of its light passes.
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let module = |pass: &str| wgsl::module(gpu, &format!("clouds_common.wgsl {pass}"));
        let light = module("clouds_light.wgsl")?;
        let prefix = module("clouds_prefix.wgsl")?;
        let draw = module("clouds_lookup.wgsl clouds_draw.wgsl")?;
        let depths_pass = module("clouds_lookup.wgsl clouds_sky_depths.wgsl")?;
        let over = |fragment| {
            gpu.blended_pipeline_of(
                fragment,
                &draw,
                None,
                wgpu::BlendComponent {
                    src_factor: wgpu::BlendFactor::One,
                    dst_factor: wgpu::BlendFactor::OneMinusSrcAlpha,
                    operation: wgpu::BlendOperation::Add,
                },
                2,
            )
        };
        Ok(GpuClouds {
            composite: RefCell::new(CloudsPass::new(gpu, wgpu::TextureFormat::Rgba32Float, 1)?),
            particles: particles.to_vec(),
            particle_buffer,
            resolution: resolution as u32,
            cells,
            eye_offset,
            frame: None,
            eye: Cell::new(None),
            sky_cells,
            sky_depths: Cell::new(false),
            out_depths: Cell::new(false),
            splat: gpu.compute_pipeline(&light, "main", None)?,
            prefix: gpu.compute_pipeline(&prefix, "main", None)?,
            depths_pass: gpu.compute_pipeline(&depths_pass, "main", None)?,
            // Premultiplied "over": E_k = S_k + T_k E_{k-1}; into the picture and into
            // the higher octaves' target. By the octaves, the transfer table, the solve.
            draw: [
                over("fragment")?,
                over("fragment_table")?,
                over("fragment_solve")?,
            ],
            solve_pipelines: OnceCell::new(),
            solve: RefCell::new(None),
            no_solve: gpu.storage("no transfer solve", &[0; 16], "the particle count")?,
            no_scene: gpu
                .float_texture("no scene", &[f32::MAX], 1, 1)
                .create_view(&Default::default()),
        })
    }

    /// Moves the particles (the same number of them, e.g. carried by the wind): the
    /// next light pass and draw see them where they are now. Particles where they already
    /// are change nothing: the light pass and the sky's depths made for them stay (a
    /// caller that passes the particles with every moved sun does not pay for them).
    pub fn move_particles(&mut self, gpu: &Gpu, particles: &[Particle]) -> Result<(), GpuError> {
        if particles.len() != self.particles.len() {
            return Err(atmo::Error::Invalid(format!(
                "{} particles where the cloud has {}; make a new GpuClouds",
                particles.len(),
                self.particles.len()
            ))
            .into());
        }
        if particles == self.particles.as_slice() {
            return Ok(());
        }
        gpu.queue.write_buffer(
            &self.particle_buffer,
            0,
            bytemuck::cast_slice(&records(particles)),
        );
        self.particles.copy_from_slice(particles);
        self.frame = None;
        self.eye.set(None);
        self.sky_depths.set(false);
        self.out_depths.set(false);
        *self.solve.borrow_mut() = None;
        Ok(())
    }

    /// The light pass for a sun in the direction `to_sun` (any length), as
    /// `IntensityBuffer::update`; returns the GPU time where timestamps exist, ms.
    pub fn light(
        &mut self,
        gpu: &Gpu,
        to_sun: Vec3,
        forward: f32,
        splat: Splat,
    ) -> Result<Option<f64>, GpuError> {
        let mut made = Ok(());
        let time = gpu.run("the clouds' light pass", |encoder| {
            made = self.record_light_pass(gpu, encoder, to_sun, forward, splat);
        })?;
        made?;
        Ok(time)
    }

    /// The light pass of [`GpuClouds::light`] recorded into the caller's `encoder`, for
    /// a program that submits its own frames: draws prepared after it read it.
    pub fn record_light_pass(
        &mut self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        to_sun: Vec3,
        forward: f32,
        splat: Splat,
    ) -> Result<(), GpuError> {
        let frame = frame_of(&self.particles, to_sun, forward, splat, self.resolution)?;
        let params = gpu.uniform("the buffer frame", &frame);
        self.record_light(
            gpu,
            encoder,
            &frame,
            &params,
            &self.particle_buffer,
            self.sun_cells(),
        );
        self.frame = Some(frame);
        Ok(())
    }

    /// The sun's grid in `cells`.
    fn sun_cells(&self) -> wgpu::BufferBinding<'_> {
        grid(&self.cells, 0, self.resolution)
    }

    /// The grid lit from the eye a draw from `camera` reads: the one kept where the
    /// camera and the picture's size are those it was made for, else the particles seen
    /// from the eye and the frame of their light pass.
    fn eye_for(&self, camera: &Camera) -> Result<Eye, GpuError> {
        let pose = [camera.position, camera.forward, camera.right, camera.up];
        let size = (camera.width, camera.height);
        if let Some(grid) = self
            .eye
            .get()
            .filter(|kept| kept.pose == pose && kept.size == size)
        {
            return Ok(Eye { grid, seen: None });
        }
        let (particles, scale) = seen_from(&self.particles, camera);
        let n = eye_resolution(size.0, size.1);
        let frame = frame_of(&particles, Vec3::NEG_Z, 0.0, Splat::Pieces, n)?;
        Ok(Eye {
            grid: EyeGrid {
                frame,
                scale,
                pose,
                size,
            },
            seen: Some(particles),
        })
    }

    /// Records a light pass of `frame` (uploaded as `params`) of the particles' records
    /// `particles` into `cells` (sized for its grid).
    fn record_light(
        &self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        frame: &BufferFrame,
        params: &wgpu::Buffer,
        particles: &wgpu::Buffer,
        cells: wgpu::BufferBinding<'_>,
    ) {
        let splat_group = gpu.bind_group(
            &self.splat.get_bind_group_layout(0),
            &[
                params.as_entire_binding(),
                particles.as_entire_binding(),
                wgpu::BindingResource::Buffer(cells.clone()),
            ],
        );
        let prefix_group = gpu.bind_group(
            &self.prefix.get_bind_group_layout(0),
            &[
                params.as_entire_binding(),
                wgpu::BindingResource::Buffer(cells.clone()),
            ],
        );
        encoder.clear_buffer(cells.buffer, cells.offset, cells.size.map(u64::from));
        let mut pass = encoder.begin_compute_pass(&Default::default());
        pass.set_pipeline(&self.splat);
        pass.set_bind_group(0, &splat_group, &[]);
        // One workgroup a particle.
        let (x, y) = groups(gpu, frame.particles);
        pass.dispatch_workgroups(x, y, 1);
        pass.set_pipeline(&self.prefix);
        pass.set_bind_group(0, &prefix_group, &[]);
        let (x, y) = groups(gpu, (frame.resolution * frame.resolution).div_ceil(GROUP));
        pass.dispatch_workgroups(x, y, 1);
    }

    /// Each particle's depths in the cloud as the draws read them
    /// (`atmo::clouds::CloudDepths::of`, made on the GPU): made now where no draw has
    /// needed them yet.
    pub fn depths(&self, gpu: &Gpu) -> Result<CloudDepths, GpuError> {
        let mut made = Ok(());
        gpu.run("the particles' depths", |encoder| {
            made = self.record_missing_depths(gpu, encoder, true, true);
        })?;
        made?;
        let size = self.particle_buffer.size();
        let bytes = gpu.read("the particles", &self.particle_buffer, 0, size)?;
        let records: &[GpuParticle] = bytemuck::cast_slice(&bytes);
        Ok(CloudDepths {
            vertical: records
                .iter()
                .map(|r| [r.sky_depth, r.sky_column])
                .collect(),
            out: records.iter().map(|r| r.out_depth).collect(),
            thickness: records.iter().map(|r| r.thickness).collect(),
        })
    }

    /// Records the particles' depths a draw needs that their records lack: down the
    /// vertical for the sky's light (`sky`), out of the cloud for the table (`out`:
    /// along the other two axes, then the vertical's again, whose depths the records
    /// keep).
    fn record_missing_depths(
        &self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        sky: bool,
        out: bool,
    ) -> Result<(), GpuError> {
        let axes: &[Vec3] = match (self.sky_depths.get(), self.out_depths.get()) {
            (_, false) if out => &[Vec3::X, Vec3::Z, Vec3::Y],
            (false, _) if sky => &[Vec3::Y],
            _ => &[],
        };
        for &axis in axes {
            self.record_depths(gpu, encoder, axis)?;
        }
        self.sky_depths
            .set(self.sky_depths.get() || !axes.is_empty());
        self.out_depths
            .set(self.out_depths.get() || axes.len() == 3);
        Ok(())
    }

    /// Records what puts each particle's depths along `axis` into its record
    /// (`atmo::clouds::CloudDepths::of`, on the GPU): a light pass along it into
    /// [`VERTICAL_RESOLUTION`]^3, read at the particles' centres: the depth from the lit
    /// side and the column's (the sky's light reads the vertical's), and the depth out
    /// made the least of its own and this axis's.
    fn record_depths(
        &self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        axis: Vec3,
    ) -> Result<(), GpuError> {
        let frame = frame_of(
            &self.particles,
            axis,
            0.0,
            Splat::Pieces,
            VERTICAL_RESOLUTION as u32,
        )?;
        let params = gpu.uniform("the depths' buffer frame", &frame);
        let cells = grid(&self.sky_cells, 0, VERTICAL_RESOLUTION as u32);
        self.record_light(gpu, encoder, &frame, &params, &self.particle_buffer, cells);
        let group = gpu.bind_group(
            &self.depths_pass.get_bind_group_layout(0),
            &[
                params.as_entire_binding(),
                self.particle_buffer.as_entire_binding(),
                self.sky_cells.as_entire_binding(),
            ],
        );
        let mut pass = encoder.begin_compute_pass(&Default::default());
        pass.set_pipeline(&self.depths_pass);
        pass.set_bind_group(0, &group, &[]);
        let (x, y) = groups(gpu, frame.particles.div_ceil(GROUP));
        pass.dispatch_workgroups(x, y, 1);
        Ok(())
    }

    /// The buffer's `ln Gamma`, `[x][z][y]`, as `IntensityBuffer::log_gamma`.
    pub fn log_gamma(&self, gpu: &Gpu) -> Result<Vec<f32>, GpuError> {
        let bytes = gpu.read(
            "the intensity buffer",
            &self.cells,
            0,
            (self.resolution as u64).pow(3) * 4,
        )?;
        Ok(bytemuck::cast_slice(&bytes).to_vec())
    }

    /// The cloud seen by `camera` over `background` (or black), as
    /// `atmo::clouds::render::render`: [`GpuClouds::prepare`] and a [`CloudsPass`] over
    /// the background, submitted and read back (the same recording a program of one's
    /// own makes). An error before the first light pass.
    pub fn render(
        &self,
        gpu: &Gpu,
        camera: &Camera,
        light: &CloudLight,
        background: Option<&Frame>,
    ) -> Result<Rendered, GpuError> {
        let (w, h) = (camera.width, camera.height);
        if let Some(b) = background {
            if (b.width, b.height) != (w, h) {
                return Err(atmo::Error::Invalid(format!(
                    "the background is {} x {}, the camera's image {w} x {h}",
                    b.width, b.height
                ))
                .into());
            }
        }
        gpu.check_picture("the cloud frame", (w, h), "the image size")?;
        let target = target_texture(gpu, w, h, background);
        let view = target.create_view(&Default::default());
        let mut composite = self.composite.borrow_mut();
        let mut prepared = Ok(());
        let gpu_ms = gpu.run("the cloud draw", |encoder| {
            prepared = self.prepare(gpu, encoder, &mut composite, camera, light);
            let mut pass =
                crate::display::loaded_pass(encoder, &view, "the cloud over the background");
            composite.draw(&mut pass);
        });
        prepared?;
        let gpu_ms = gpu_ms?;
        let frame = gpu.read_frame("the cloud frame", &target, (w, h))?;
        Ok(Rendered { frame, gpu_ms })
    }

    /// Records the cloud seen by `camera` into the caller's `encoder` and sets `pass`
    /// to draw it, with its higher octaves, over what the caller's target holds: no
    /// read-back. The picture is the camera's size; record `pass`'s draw into a render
    /// pass whose colour attachment has `pass`'s format, after this encoder's passes.
    /// An error before the first light pass.
    pub fn prepare(
        &self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        pass: &mut CloudsPass,
        camera: &Camera,
        light: &CloudLight,
    ) -> Result<(), GpuError> {
        light.scattering.validate()?;
        if let Some(settings) = light.scattering.diffusion() {
            self.record_solve(gpu, encoder, settings, light, camera.position)?;
        }
        let dimming = light.ambient.dimming(&light.scattering.octaves());
        let scene = pass.scene_depth.as_ref().unwrap_or(&self.no_scene);
        let billboards = self.billboards(gpu, camera, light, &dimming, scene)?;
        // The sky's light inside the cloud and the transfer table need each particle's
        // depths: made once for particles where they are.
        let table = light.scattering.table().is_some();
        self.record_missing_depths(gpu, encoder, dims_the_sky(light), table)?;
        // The grid lit from the eye, again where the eye has moved.
        if let Some(Eye {
            grid: eye,
            seen: Some(particles),
        }) = &billboards.eye
        {
            // A buffer of this eye's own (not the last eye's of the submission, as a
            // queue write to one kept buffer would be for two cameras a frame).
            let seen = gpu.storage(
                "the particles seen from the eye",
                bytemuck::cast_slice(&records(particles)),
                "the particle count",
            )?;
            let params = gpu.uniform("the eye's buffer frame", &eye.frame);
            let cells = grid(&self.cells, self.eye_offset, eye.frame.resolution);
            self.record_light(gpu, encoder, &eye.frame, &params, &seen, cells);
            self.eye.set(Some(*eye));
        }
        let size = (camera.width, camera.height);
        let [picture, higher] = match pass.targets.take() {
            Some((s, targets)) if s == size => targets,
            _ => [(); 2].map(|_| target_texture(gpu, size.0, size.1, None)),
        };
        let views = [&picture, &higher].map(|t| t.create_view(&Default::default()));
        for view in &views {
            drop(crate::display::cleared_pass(
                encoder,
                view,
                "the cloud's targets",
                wgpu::Color::TRANSPARENT,
            ));
        }
        self.record(encoder, &billboards, &views);
        let params = CompositeParams {
            corner: pass.corner.map(|c| c as f32),
            exposure: pass.exposure,
            depth_scale: light.scattering.blob_octaves().depth_scale,
            higher: (light.scattering.blob_octaves().count > 1) as u32,
            pad0: 0,
            pad1: 0,
            pad2: 0,
        };
        gpu.queue
            .write_buffer(&pass.params, 0, bytemuck::bytes_of(&params));
        // Bindings the device refuses are an error here, not a frame that draws nothing.
        let group = gpu.scoped("the clouds' composite", || {
            gpu.bind_group(
                &pass.layout,
                &[
                    pass.params.as_entire_binding(),
                    wgpu::BindingResource::TextureView(&views[0]),
                    wgpu::BindingResource::TextureView(&views[1]),
                ],
            )
        })?;
        pass.group = Some(group);
        pass.targets = Some((size, [picture, higher]));
        Ok(())
    }

    /// Records the transfer solve a draw from `eye` reads: the solve again where the sun
    /// or its light pass has changed since the last (from the last solution where the
    /// grid is the same), and the light toward the eye again where either has moved.
    /// An error before the first light pass.
    fn record_solve(
        &self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        settings: atmo::clouds::Diffusion,
        light: &CloudLight,
        eye: Vec3,
    ) -> Result<(), GpuError> {
        let frame = self.frame.ok_or_else(|| {
            atmo::Error::Invalid("the clouds need a light pass before they are drawn".into())
        })?;
        if self.solve_pipelines.get().is_none() {
            let made = SolvePipelines::new(gpu)?;
            let _ = self.solve_pipelines.set(made);
        }
        let pipelines = self.solve_pipelines.get().expect("made above");
        let mut kept = self.solve.borrow_mut();
        if !kept
            .as_ref()
            .is_some_and(|s| s.settings == settings && s.phase() == light.phase)
        {
            *kept = Some(GpuSolve::new(
                gpu,
                pipelines,
                &self.particles,
                settings,
                light.phase,
                &self.cells,
            )?);
        }
        let solve = kept.as_mut().expect("made above");
        if solve.sun != Some((light.to_sun, frame, light.ambient)) {
            solve.record_solve(
                gpu,
                pipelines,
                encoder,
                &frame,
                light.to_sun,
                &light.ambient,
            );
        }
        if solve.eye != Some(eye) {
            solve.record_toward(gpu, pipelines, encoder, eye);
        }
        Ok(())
    }

    /// The transfer solve of `light` (its scattering must be one) and its light toward
    /// `eye`, now, in a submission of its own: what a draw would otherwise make first
    /// (again where the sun, its light pass or the eye has moved since the last; nothing
    /// where none has). Returns the GPU time where timestamps exist, ms. An error before
    /// the first light pass.
    pub fn solve(&self, gpu: &Gpu, light: &CloudLight, eye: Vec3) -> Result<Option<f64>, GpuError> {
        let settings = light.scattering.diffusion().ok_or_else(|| {
            atmo::Error::Invalid("scattering: a solve needs Scattering::Solve".into())
        })?;
        light.scattering.validate()?;
        let mut made = Ok(());
        let ms = gpu.run("the transfer solve", |encoder| {
            made = self.record_solve(gpu, encoder, settings, light, eye);
        })?;
        made?;
        Ok(ms)
    }

    /// The conjugate-gradient iterations of the last transfer solve (read back; 0
    /// before one), as `atmo::clouds::DiffuseLight::iterations`.
    pub fn solve_iterations(&self, gpu: &Gpu) -> Result<u32, GpuError> {
        match self.solve.borrow().as_ref() {
            Some(solve) => solve.iterations(gpu),
            None => Ok(0),
        }
    }

    /// The light each cell of the transfer solve's grid sends toward the eye of the
    /// last draw with it: the sun's, as `atmo::clouds::DiffuseLight::toward`, and the
    /// sky's (RGB), as `DiffuseLight::sky_toward` (read back; empty before one).
    pub fn solved_toward(&self, gpu: &Gpu) -> Result<Vec<[f32; 4]>, GpuError> {
        match self.solve.borrow().as_ref() {
            Some(solve) => {
                let bytes = gpu.read(
                    "the light toward the eye",
                    &solve.seen,
                    0,
                    solve.seen.size(),
                )?;
                Ok(bytemuck::cast_slice(&bytes).to_vec())
            }
            None => Ok(Vec::new()),
        }
    }

    /// What drawing the cloud seen by `camera` needs: the particles sorted by depth on
    /// the CPU (farthest first), the draw's parameters and bindings, checked.
    fn billboards(
        &self,
        gpu: &Gpu,
        camera: &Camera,
        light: &CloudLight,
        dimming: &SkyDimming,
        scene: &wgpu::TextureView,
    ) -> Result<Billboards, GpuError> {
        let frame = self.frame.ok_or_else(|| {
            atmo::Error::Invalid("the clouds need a light pass before they are drawn".into())
        })?;
        let (w, h) = (camera.width, camera.height);
        gpu.check_texture_side("the image width", w, "the width")?;
        gpu.check_texture_side("the image height", h, "the height")?;
        // Farthest first; ties in reverse index order, the CPU's front-to-back reversed.
        let depth: Vec<f32> = self
            .particles
            .iter()
            .map(|p| camera.depth(p.position))
            .collect();
        let mut order: Vec<u32> = (0..self.particles.len() as u32)
            .filter(|&k| depth[k as usize] > self.particles[k as usize].reach())
            .collect();
        order.sort_by(|&a, &b| {
            depth[b as usize]
                .total_cmp(&depth[a as usize])
                .then(b.cmp(&a))
        });
        let order_buffer = gpu.storage(
            "the draw order",
            bytemuck::cast_slice(&order),
            "the particle count",
        )?;
        let (tan_half_width, tan_half_height) = camera.pinhole("the clouds' billboards")?;
        let octaves = light.scattering.blob_octaves();
        let focal = 0.5 * h as f32 / tan_half_height;
        let v4 = |v: Vec3, w: f32| [v.x, v.y, v.z, w];
        let sky = light
            .ambient
            .scattered(light.phase, &light.scattering.octaves());
        // With the table, the grid lit from the eye along each pixel's ray.
        let table = light.scattering.table();
        let eye = match table {
            Some(_) => Some(self.eye_for(camera)?),
            None => None,
        };
        // With the solve, its grid and the light toward the eye it made.
        let solve = self.solve.borrow();
        let solved = solve
            .as_ref()
            .filter(|_| light.scattering.diffusion().is_some());
        let solve_grid = solved.map_or(([0.0; 4], [0; 4]), |s| s.draw_grid());
        let mode = match (table, solved) {
            (Some(_), _) => 1,
            (None, Some(_)) => 2,
            (None, None) => 0,
        };
        // The phase function's code and parameter (functions.wgsl's phase_function).
        let (kind, g) = light.phase.code();
        let params = DrawParams {
            position: v4(camera.position, focal),
            forward: v4(camera.forward, tan_half_width),
            right: v4(camera.right, tan_half_height),
            up: v4(camera.up, 0.0),
            to_sun: v4(light.to_sun, kind as f32),
            sun: v4(light.sun, g as f32),
            sky: sky.harmonics.map(|h| v4(h, 0.0)),
            sky_above: v4(dimming.above, dimming.extrapolation),
            sky_below: v4(dimming.below, 0.0),
            haze_transmittance: v4(light.haze.transmittance, 0.0),
            haze_inscatter: v4(light.haze.inscatter, 0.0),
            octaves: [
                octaves.attenuation,
                octaves.contribution,
                octaves.eccentricity,
                octaves.depth_scale,
            ],
            diffuse: [octaves.diffuse, octaves.extrapolation, 0.0, 0.0],
            width: w,
            height: h,
            octave_count: octaves.count,
            eye_base: (self.eye_offset / 4) as u32,
            eye_scale: eye.as_ref().map_or(1.0, |eye| eye.grid.scale),
            pad1: 0,
            pad2: 0,
            pad3: 0,
            solve_centre: solve_grid.0,
            solve_dims: solve_grid.1,
        };
        let params = gpu.uniform("the cloud draw", &params);
        let frame_buffer = gpu.uniform("the buffer frame", &frame);
        // Without the table, the sun's frame and the fitted table stand in, unread.
        let eye_buffer = gpu.uniform(
            "the eye's buffer frame",
            &eye.as_ref().map_or(frame, |eye| eye.grid.frame),
        );
        let table_buffer = gpu.storage(
            "the transfer table",
            bytemuck::cast_slice(&table.unwrap_or(&TransferTable::FITTED).values),
            "the transfer table",
        )?;
        let group = gpu.bind_group(
            &self.draw[mode].get_bind_group_layout(0),
            &[
                params.as_entire_binding(),
                frame_buffer.as_entire_binding(),
                self.particle_buffer.as_entire_binding(),
                order_buffer.as_entire_binding(),
                self.cells.as_entire_binding(),
                eye_buffer.as_entire_binding(),
                table_buffer.as_entire_binding(),
                solved
                    .map_or(&self.no_solve, |s| &s.seen)
                    .as_entire_binding(),
                wgpu::BindingResource::TextureView(scene),
            ],
        );
        Ok(Billboards {
            group,
            count: order.len() as u32,
            eye,
            mode,
        })
    }

    /// Records the billboards into the picture's and the higher octaves' targets.
    fn record(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        billboards: &Billboards,
        views: &[wgpu::TextureView; 2],
    ) {
        let attachments = views.each_ref().map(|view| {
            Some(wgpu::RenderPassColorAttachment {
                view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Load,
                    store: wgpu::StoreOp::Store,
                },
            })
        });
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("billboards"),
            color_attachments: &attachments,
            ..Default::default()
        });
        pass.set_pipeline(&self.draw[billboards.mode]);
        pass.set_bind_group(0, &billboards.group, &[]);
        pass.draw(0..6, 0..billboards.count);
    }
}

/// A draw of the billboards: its bindings, how many particles are in front, the grid
/// lit from the eye it reads (with the table), and its pipeline's index in `draw`.
struct Billboards {
    group: wgpu::BindGroup,
    count: u32,
    eye: Option<Eye>,
    mode: usize,
}

/// The grid lit from the eye along each pixel's ray: its light pass's frame, the scale
/// across of the particles [`seen_from`] the camera, and the camera's position and axes
/// and the picture's size it was made for.
#[derive(Clone, Copy, PartialEq)]
struct EyeGrid {
    frame: BufferFrame,
    scale: f32,
    pose: [Vec3; 4],
    size: (u32, u32),
}

/// A draw's grid lit from the eye, and the particles seen from the eye where it must be
/// made (`None`: the one `cells` holds).
struct Eye {
    grid: EyeGrid,
    seen: Option<Vec<Particle>>,
}

gpu_struct! {
    /// The composite's parameters (see clouds_composite.wgsl).
    pub struct CompositeParams in "screen.wgsl clouds_composite.wgsl" {
        corner: [f32; 2],
        exposure: f32,
        depth_scale: f32,
        higher: u32,
        pad0: u32,
        pad1: u32,
        pad2: u32,
    }
}

/// The particles as the shaders read them.
fn records(particles: &[Particle]) -> Vec<GpuParticle> {
    particles
        .iter()
        .map(|p| GpuParticle {
            position_radius: [p.position.x, p.position.y, p.position.z, p.radius],
            density: p.density,
            albedo: p.albedo,
            sky_depth: 0.0,
            sky_column: 0.0,
            out_depth: f32::MAX,
            thickness: 0.0,
            pad1: 0,
            pad2: 0,
        })
        .collect()
}

/// A dispatch of `count` workgroups as (x, y), within the device's limit a dimension.
fn groups(gpu: &Gpu, count: u32) -> (u32, u32) {
    let max = gpu.limits().max_compute_workgroups_per_dimension;
    (count.min(max), count.div_ceil(max))
}

/// An RGBA f32 render target of `w` x `h`, holding `background` (or black), that a
/// [`CloudsPass`] can read.
pub(crate) fn target_texture(
    gpu: &Gpu,
    w: u32,
    h: u32,
    background: Option<&Frame>,
) -> wgpu::Texture {
    let size = wgpu::Extent3d {
        width: w,
        height: h,
        depth_or_array_layers: 1,
    };
    let texture = gpu.texture_2d(
        "target",
        (w, h),
        wgpu::TextureFormat::Rgba32Float,
        wgpu::TextureUsages::RENDER_ATTACHMENT
            | wgpu::TextureUsages::TEXTURE_BINDING
            | wgpu::TextureUsages::COPY_SRC
            | wgpu::TextureUsages::COPY_DST,
    );
    let pixels: Vec<[f32; 4]> = match background {
        Some(b) => b.pixels.iter().map(|p| [p.x, p.y, p.z, 0.0]).collect(),
        None => vec![[0.0; 4]; (w * h) as usize],
    };
    gpu.queue.write_texture(
        texture.as_image_copy(),
        bytemuck::cast_slice(&pixels),
        wgpu::TexelCopyBufferLayout {
            offset: 0,
            bytes_per_row: Some(w * 16),
            rows_per_image: None,
        },
        size,
    );
    texture
}

/// The cloud's shadow map as an R32 float texture (`resolution`^2, the optical depth of
/// the whole cloud along the sun's ray through each texel), for an engine to project
/// onto its terrain with [`CloudShadow::uv_rows`] and a linear sampler: the sunlight
/// reaching a point beneath the cloud is `exp(-depth)` of the sun's, plus
/// [`atmo::clouds::shadow::SCATTERED_DOWN`] of what it takes out
/// ([`CloudShadow::sunlight`]). Made again when the sun or the particles move.
pub fn shadow_texture(gpu: &Gpu, shadow: &CloudShadow) -> wgpu::Texture {
    let n = shadow.resolution as u32;
    gpu.float_texture("the cloud's shadow", &shadow.depth, n, n)
}
