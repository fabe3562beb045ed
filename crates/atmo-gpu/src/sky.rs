//! The sky on the GPU, two ways, each ending in the same picture pass, a [`SkyPass`]
//! (`sky_frame.wgsl`, perspective or fisheye, as `atmo::sky::frame::SkyPicture` on the
//! CPU) that draws into any colour target, the caller's own included:
//!
//! - [`GpuSkyTable`], from the skylight table (sky 4.2): the table's factors live in
//!   storage buffers; per frame the CPU interpolates the few hundred `t_k` (sky (17))
//!   and one compute pass sums the terms of every view direction into the map.
//! - [`GpuSkyModel`], by the shell method (sky 3): a model's sun-independent maps
//!   (`atmo::sky::shells::export`) live in one storage buffer; per sun one compute pass a grid
//!   sums every view ray's shell crossings into the skylight map and the ground map.

use std::borrow::Borrow;

use atmo::atmosphere::spectrum::SpectrumToRgb;
use atmo::sky::aerial::{AerialRays, Froxels};
use atmo::sky::frame::{sky_from_world, sun_disc_rgb, GridLookup, View};
use atmo::sky::shells::export::RayArrays;
use atmo::sky::table::SkylightTable;
use atmo::sky::{DirectionGrid, SkyModel};
use atmo::view::{Camera, PixelBasis, Sun};
use glam::Vec3;

use crate::display::cleared_pass;
use crate::wgsl;
use crate::{gpu_struct, Gpu, GpuError, Rendered};

gpu_struct! {
    /// The map pass's sizes.
    pub struct SkyMapParams in "sky_map.wgsl" {
        /// Rows: 3 channels x view directions.
        rows: u32,
        /// Terms stored (`t_k` per frame).
        terms: u32,
        /// View directions per channel.
        directions: u32,
        pad: u32,
    }
}

gpu_struct! {
    /// The frame pass's camera, sun and map lookup (see sky_frame.wgsl).
    pub struct SkyFrameParams in "sky_frame.wgsl" {
        origin: [f32; 4],
        right: [f32; 4],
        up: [f32; 4],
        sun_direction: [f32; 4],
        sun_rgb: [f32; 4],
        sun_horizontal: [f32; 4],
        lookup: [f32; 4],
        y_last: f32,
        ground_below: f32,
        radius: f32,
        fisheye: u32,
        width: u32,
        height: u32,
        azimuths: u32,
        sun_radius: f32,
        pixel: f32,
        has_ground: u32,
        ground_y_last: f32,
        ground_azimuths: u32,
        ground_lookup: [f32; 4],
        corner: [f32; 2],
        exposure: f32,
        depth: f32,
    }
}

gpu_struct! {
    /// The shell pass's sun, grid, constants and where each region of the model's
    /// buffer starts (see sky_shells.wgsl).
    pub struct ShellParams in "sky_shells.wgsl" {
        sun: [f32; 4],
        grid: [f32; 4],
        bottom: f32,
        top: f32,
        sun_radius: f32,
        ground_albedo: f32,
        lanes: u32,
        multiple: u32,
        shells: u32,
        light_entries: u32,
        mu_size: u32,
        r_size: u32,
        sun_bins: u32,
        sun_bins_a: f32,
        rayleigh_kind: u32,
        rayleigh_g: f32,
        mie_kind: u32,
        mie_g: f32,
        rays_at: u32,
        samples_at: u32,
        rayleigh_at: u32,
        mie_at: u32,
        ground_at: u32,
        shells_at: u32,
        light_at: u32,
        irradiance_at: u32,
        transmittance_at: u32,
        moments_at: u32,
        rgb_at: u32,
        aerosol_at: u32,
        ground_light_at: u32,
        aerosols: u32,
        pad0: u32,
        pad1: u32,
    }
}

gpu_struct! {
    /// The aerial pass's sun and where the marked rays' regions start (see
    /// sky_shells.wgsl).
    pub struct AerialParams in "sky_shells.wgsl" {
        white: [f32; 4],
        sin_sun: f32,
        columns: u32,
        slices: u32,
        /// Froxel columns across the picture.
        width: u32,
        rows_at: u32,
        samples_at: u32,
        rayleigh_at: u32,
        mie_at: u32,
        marks_at: u32,
        pad1: u32,
        pad2: u32,
        pad3: u32,
    }
}

/// The aerial perspective's froxels on the GPU ([`atmo::sky::aerial`]): the marked rays
/// of an [`AerialRays`] uploaded once; per sun and camera, one invocation per froxel
/// column reads its row's ray at its angle to the sun, as the CPU does.
pub struct GpuAerial {
    rays: AerialRays,
    marked: wgpu::Buffer,
    params: AerialParams,
    pipeline: wgpu::ComputePipeline,
}

impl GpuAerial {
    /// Uploads `rays` (made by `sky`'s model) for `sky`'s device.
    pub fn new<M: Borrow<SkyModel>>(
        gpu: &Gpu,
        sky: &GpuSkyModel<M>,
        rays: AerialRays,
    ) -> Result<Self, GpuError> {
        let arrays = rays.arrays();
        if arrays.lanes != sky.sky_params.lanes as usize {
            return Err(atmo::Error::Invalid(
                "the aerial rays were made for another atmosphere than the sky's".into(),
            )
            .into());
        }
        let mut data: Vec<[f32; 4]> = Vec::new();
        let mut at = |values: &[[f32; 4]]| {
            let start = data.len() as u32;
            data.extend_from_slice(values);
            start
        };
        let params = AerialParams {
            white: [0.0; 4],
            sin_sun: 0.0,
            columns: 0,
            slices: rays.slices_m().len() as u32,
            width: 0,
            rows_at: at(&arrays.rows),
            samples_at: at(&arrays.samples),
            rayleigh_at: at(&arrays.rayleigh),
            mie_at: at(&arrays.mie),
            marks_at: at(&arrays.marks),
            pad1: 0,
            pad2: 0,
            pad3: 0,
        };
        let marked = gpu.storage(
            "the aerial rays",
            bytemuck::cast_slice(&data),
            "aerial rows or slices",
        )?;
        let module = wgsl::module(gpu, "sky_shells.wgsl")?;
        Ok(GpuAerial {
            rays,
            marked,
            params,
            pipeline: gpu.compute_pipeline(&module, "aerial_main", None)?,
        })
    }

    /// The marked rays uploaded (the CPU's froxels come from them too).
    pub fn rays(&self) -> &AerialRays {
        &self.rays
    }

    /// Records into `encoder` the froxels of `camera` (one column per pixel: a coarse
    /// camera, e.g. 32 columns across) for `sun`, written into `targets` (made for the
    /// camera's size and these rays' slices): no read-back, for a caller's shader to
    /// sample at its pixel and distance.
    pub fn prepare<M: Borrow<SkyModel>>(
        &self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        sky: &GpuSkyModel<M>,
        sun: Sun,
        camera: &Camera,
        targets: &AerialTextures,
    ) -> Result<(), GpuError> {
        let slices = self.rays.slices_m().len() as u32;
        if targets.size != (camera.width, camera.height, slices) {
            return Err(atmo::Error::Invalid(format!(
                "the aerial textures are {:?} froxels, the camera and the rays ask for {:?}",
                targets.size,
                (camera.width, camera.height, slices)
            ))
            .into());
        }
        let columns: Vec<[f32; 2]> = self
            .rays
            .columns(sun, camera)
            .into_iter()
            .map(|(row, nu)| [row as f32, nu as f32])
            .collect();
        let atmosphere = sky.model().atmosphere();
        let solar: Vec<f32> = atmosphere
            .solar_irradiance
            .iter()
            .map(|&e| e as f32)
            .collect();
        let white = sky.to_rgb.rgb(&solar);
        let params = AerialParams {
            white: [white[0], white[1], white[2], 0.0],
            sin_sun: sun.elevation().sin() as f32,
            columns: columns.len() as u32,
            width: camera.width,
            ..self.params
        };
        let uniform = gpu.uniform("the aerial pass", &params);
        let column_buffer = gpu.storage(
            "the froxel columns",
            bytemuck::cast_slice(&columns),
            "the camera's width and height",
        )?;
        let views = [&targets.inscatter, &targets.transmittance]
            .map(|t| t.create_view(&Default::default()));
        // Bindings 0 and 1 are the shell pass's; 2 (its map) is not read here.
        let mut entries: Vec<wgpu::BindGroupEntry> = [
            (0, &sky.uniforms[0]),
            (1, &sky.data),
            (3, &uniform),
            (4, &self.marked),
            (5, &column_buffer),
        ]
        .into_iter()
        .map(|(binding, buffer)| wgpu::BindGroupEntry {
            binding,
            resource: buffer.as_entire_binding(),
        })
        .collect();
        entries.extend(
            views
                .iter()
                .zip([6, 7])
                .map(|(view, binding)| wgpu::BindGroupEntry {
                    binding,
                    resource: wgpu::BindingResource::TextureView(view),
                }),
        );
        let group = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("the aerial pass"),
            layout: &self.pipeline.get_bind_group_layout(0),
            entries: &entries,
        });
        let mut pass = encoder.begin_compute_pass(&Default::default());
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &group, &[]);
        pass.dispatch_workgroups((columns.len() as u32).div_ceil(64), 1, 1);
        Ok(())
    }

    /// The froxels of `camera` for `sun`, as [`AerialRays::froxels`] gives them: the
    /// pass of [`GpuAerial::prepare`] into textures of its own, read back.
    pub fn froxels<M: Borrow<SkyModel>>(
        &self,
        gpu: &Gpu,
        sky: &GpuSkyModel<M>,
        sun: Sun,
        camera: &Camera,
    ) -> Result<Froxels, GpuError> {
        let size = (
            camera.width,
            camera.height,
            self.rays.slices_m().len() as u32,
        );
        let targets = AerialTextures::new(gpu, size)?;
        gpu.scoped("the aerial pass", || {
            let mut encoder = gpu
                .device
                .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                    label: Some("the aerial pass"),
                });
            self.prepare(gpu, &mut encoder, sky, sun, camera, &targets)?;
            gpu.queue.submit([encoder.finish()]);
            Ok::<(), GpuError>(())
        })??;
        let read = |texture: &wgpu::Texture| -> Result<Vec<Vec3>, GpuError> {
            let bytes = gpu.read_texture_layers("the froxels", texture, size)?;
            let values: &[f32] = bytemuck::cast_slice(&bytes);
            Ok(values
                .chunks(4)
                .map(|v| Vec3::new(v[0], v[1], v[2]))
                .collect())
        };
        Ok(Froxels {
            width: camera.width,
            height: camera.height,
            slices_m: self.rays.slices_m().to_vec(),
            inscatter: read(&targets.inscatter)?,
            transmittance: read(&targets.transmittance)?,
        })
    }
}

/// The aerial perspective's froxels as two 3-D RGBA f32 textures of
/// `(columns across, columns down, slices)`: the in-scattered radiance (linear sRGB, the
/// sky's units) and the transmittance, which [`GpuAerial::prepare`] writes and a
/// caller's shader samples (linear filtering of f32 textures needs the device's
/// `FLOAT32_FILTERABLE`): a surface `d` m away at a pixel is seen as `T L + S`.
pub struct AerialTextures {
    pub inscatter: wgpu::Texture,
    pub transmittance: wgpu::Texture,
    /// Columns across, columns down, slices.
    pub size: (u32, u32, u32),
}

impl AerialTextures {
    /// Textures for `size` froxels (checked against the device's 3-D texture limit).
    pub fn new(gpu: &Gpu, size: (u32, u32, u32)) -> Result<Self, GpuError> {
        let side = size.0.max(size.1).max(size.2) as u64;
        let max = gpu.limits().max_texture_dimension_3d as u64;
        gpu.check_limit(
            "the aerial textures",
            side,
            max,
            "max_texture_dimension_3d",
            "the froxel grid",
        )?;
        let [inscatter, transmittance] =
            ["the aerial in-scatter", "the aerial transmittance"].map(|label| {
                gpu.device.create_texture(&wgpu::TextureDescriptor {
                    label: Some(label),
                    size: wgpu::Extent3d {
                        width: size.0,
                        height: size.1,
                        depth_or_array_layers: size.2,
                    },
                    mip_level_count: 1,
                    sample_count: 1,
                    dimension: wgpu::TextureDimension::D3,
                    format: wgpu::TextureFormat::Rgba32Float,
                    usage: wgpu::TextureUsages::STORAGE_BINDING
                        | wgpu::TextureUsages::TEXTURE_BINDING
                        | wgpu::TextureUsages::COPY_SRC,
                    view_formats: &[],
                })
            });
        Ok(AerialTextures {
            inscatter,
            transmittance,
            size,
        })
    }
}

/// The colour target a [`SkyPass`] draws into, and the depth buffer it tests against.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SkyTarget {
    /// The colour attachment's format. Linear radiance (W m^-2 sr^-1 as linear sRGB)
    /// times [`SkyPass::exposure`] is written; an `*Srgb` format encodes it on store.
    pub format: wgpu::TextureFormat,
    /// The depth attachment, if the pass has one: the sky is drawn only where it is
    /// still at the far plane (no depth is written).
    pub depth: Option<DepthTarget>,
}

/// A depth attachment's format and convention.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DepthTarget {
    pub format: wgpu::TextureFormat,
    /// Reversed z: the far plane at depth 0 (else at 1).
    pub reversed_z: bool,
}

impl SkyTarget {
    /// What the headless renders draw into and read back: RGBA f32, no depth.
    pub const HEADLESS: SkyTarget = SkyTarget {
        format: wgpu::TextureFormat::Rgba32Float,
        depth: None,
    };
}

/// The picture pass, shared by the table and the model, made for one [`SkyTarget`]:
/// a full-screen triangle that a caller records into its own render pass with
/// [`SkyPass::draw`], after a sky's `prepare` has recorded the maps it reads.
///
/// One pass holds one view: to draw two views in one submission, make two passes.
pub struct SkyPass {
    pipeline: wgpu::RenderPipeline,
    params: wgpu::Buffer,
    /// Bound as the ground map when there is none.
    no_ground: wgpu::Buffer,
    /// What the next draw reads, set by a sky's `prepare`.
    group: Option<wgpu::BindGroup>,
    /// The far plane's depth: 1, or 0 for reversed z.
    far: f32,
    /// Multiplies the radiance written (1 for the headless renders).
    pub exposure: f32,
    /// The target's pixel where the view's pixel (0, 0) is, for a viewport that does not
    /// start at the target's corner.
    pub corner: [u32; 2],
}

impl SkyPass {
    /// The pipeline for `target`: refused by name where the device cannot render to its
    /// format.
    pub fn new(gpu: &Gpu, target: SkyTarget) -> Result<Self, GpuError> {
        let module = wgsl::module(gpu, "sky_frame.wgsl")?;
        let depth_stencil = target.depth.map(|d| wgpu::DepthStencilState {
            format: d.format,
            depth_write_enabled: Some(false),
            depth_compare: Some(if d.reversed_z {
                wgpu::CompareFunction::GreaterEqual
            } else {
                wgpu::CompareFunction::LessEqual
            }),
            stencil: Default::default(),
            bias: Default::default(),
        });
        let pipeline = gpu.screen_pipeline(
            "the sky's picture pass",
            &module,
            None,
            &[Some(target.format.into())],
            depth_stencil,
        )?;
        Ok(SkyPass {
            pipeline,
            params: gpu.uniform(
                "sky frame",
                &<SkyFrameParams as bytemuck::Zeroable>::zeroed(),
            ),
            no_ground: gpu.storage("no ground map", &[0; 16], "")?,
            group: None,
            far: if target.depth.is_some_and(|d| d.reversed_z) {
                0.0
            } else {
                1.0
            },
            exposure: 1.0,
            corner: [0, 0],
        })
    }

    /// Sets what the next draw shows: `inputs` seen in `view` with `sun`.
    fn set(&mut self, gpu: &Gpu, inputs: &FrameInputs, sun: Sun, view: &View) {
        let mut params = frame_params(inputs, sun, view);
        params.corner = self.corner.map(|c| c as f32);
        params.exposure = self.exposure;
        params.depth = self.far;
        gpu.queue
            .write_buffer(&self.params, 0, bytemuck::bytes_of(&params));
        let ground = inputs.ground.as_ref().map_or(&self.no_ground, |(g, _)| *g);
        self.group = Some(gpu.bind_group(
            &self.pipeline.get_bind_group_layout(0),
            &[
                self.params.as_entire_binding(),
                inputs.sky.as_entire_binding(),
                ground.as_entire_binding(),
            ],
        ));
    }

    /// Records the sky into `pass`, whose colour (and depth) attachments are the
    /// [`SkyTarget`]'s; nothing before a sky's `prepare`.
    pub fn draw(&self, pass: &mut wgpu::RenderPass<'_>) {
        crate::display::draw_screen(pass, &self.pipeline, self.group.as_ref());
    }
}

/// What the picture pass reads: the maps, their grids, and the sun's disc.
struct FrameInputs<'m> {
    sky: &'m wgpu::Buffer,
    sky_grid: DirectionGrid,
    /// The ground map and its grid, below `ground_below` rad (a model's).
    ground: Option<(&'m wgpu::Buffer, DirectionGrid)>,
    ground_below: f64,
    /// Linear sRGB radiance of the sun's disc, and its angular radius (rad).
    sun_rgb: [f32; 3],
    sun_radius: f64,
}

/// The picture pass's parameters (the CPU's `SkyPicture` and `PixelBasis`).
fn frame_params(inputs: &FrameInputs, sun: Sun, view: &View) -> SkyFrameParams {
    let lookup = GridLookup::new(&inputs.sky_grid);
    let direction = sky_from_world(sun.toward());
    let rgb = inputs.sun_rgb;
    let (sin_a, cos_a) = sun.azimuth().sin_cos();
    let v4 = |v: Vec3| [v.x, v.y, v.z, 0.0];
    let basis = view.camera.pixel_basis().rotated(sky_from_world);
    let (sun_radius, pixel) = (inputs.sun_radius as f32, basis.pixel_angle());
    let ground = inputs.ground.as_ref().map(|(_, g)| GridLookup::new(g));
    let mut p = SkyFrameParams {
        origin: [0.0; 4],
        right: [0.0; 4],
        up: [0.0; 4],
        sun_direction: [
            direction.x,
            direction.y,
            direction.z,
            (sun_radius + pixel).cos(),
        ],
        sun_rgb: [rgb[0], rgb[1], rgb[2], view.sun_disc as u32 as f32],
        sun_horizontal: [sin_a as f32, cos_a as f32, 0.0, 0.0],
        lookup: [lookup.x_scale, lookup.y_min, lookup.y_scale, lookup.x_last],
        y_last: lookup.y_last,
        ground_below: inputs.ground_below as f32,
        radius: 1.0,
        fisheye: 0,
        width: view.camera.width,
        height: view.camera.height,
        azimuths: lookup.azimuths as u32,
        sun_radius,
        pixel,
        has_ground: ground.is_some() as u32,
        ground_y_last: ground.map_or(1.0, |g| g.y_last),
        ground_azimuths: ground.map_or(2, |g| g.azimuths as u32),
        ground_lookup: ground.map_or([0.0; 4], |g| [g.x_scale, g.y_min, g.y_scale, g.x_last]),
        corner: [0.0; 2],
        exposure: 1.0,
        depth: 1.0,
    };
    match basis {
        PixelBasis::Perspective { origin, right, up } => {
            (p.origin, p.right, p.up) = (v4(origin), v4(right), v4(up));
        }
        PixelBasis::Fisheye {
            centre,
            radius,
            forward,
            right,
            up,
        } => {
            (p.origin, p.right, p.up) = (v4(forward), v4(right), v4(up));
            p.fisheye = 1;
            p.radius = radius;
            p.sun_horizontal[2] = centre.x;
            p.sun_horizontal[3] = centre.y;
        }
    }
    p
}

/// A skylight table uploaded, with its map pass; `T` is the table borrowed
/// (`&SkylightTable`) or owned (`SkylightTable`, `Arc<SkylightTable>`).
pub struct GpuSkyTable<T: Borrow<SkylightTable>> {
    table: T,
    s: wgpu::Buffer,
    order: wgpu::Buffer,
    used: wgpu::Buffer,
    /// `t_k`, written per frame.
    coefficients: wgpu::Buffer,
    /// The map pass's sizes.
    params: wgpu::Buffer,
    /// The skylight map, written by the map pass, read by the picture pass.
    map: wgpu::Buffer,
    rows: u32,
    map_pass: wgpu::ComputePipeline,
}

impl<T: Borrow<SkylightTable>> GpuSkyTable<T> {
    /// Uploads `table`'s factors (refused above the device's buffer limits).
    pub fn new(gpu: &Gpu, table: T) -> Result<Self, GpuError> {
        let f = table.borrow().factors();
        let setting = "the table's directions or epsilon";
        let s = gpu.storage("the table's s_k", bytemuck::cast_slice(f.s), setting)?;
        let order = gpu.storage(
            "the table's row order",
            bytemuck::cast_slice(f.order),
            setting,
        )?;
        let used = gpu.storage(
            "the table's term use",
            bytemuck::cast_slice(f.used),
            setting,
        )?;
        let coefficients = gpu.storage(
            "t_k",
            bytemuck::cast_slice(&vec![0f32; f.used.len()]),
            setting,
        )?;
        let map_bytes = (f.directions * 3 * 4) as u64;
        let map = gpu.output("the skylight map", map_bytes, setting)?;
        let map_module = wgsl::module(gpu, "sky_map.wgsl")?;
        let params = SkyMapParams {
            rows: f.order.len() as u32,
            terms: f.used.len() as u32,
            directions: f.directions as u32,
            pad: 0,
        };
        Ok(GpuSkyTable {
            table,
            s,
            order,
            used,
            coefficients,
            params: gpu.uniform("sky map", &params),
            map,
            rows: params.rows,
            map_pass: gpu.compute_pipeline(&map_module, "main", None)?,
        })
    }

    /// The table drawn.
    pub fn table(&self) -> &SkylightTable {
        self.table.borrow()
    }

    /// Writes `t_k` for a sun at `sun_elevation` rad seen from `altitude_m` (refused
    /// outside the table's ranges) and records the map pass.
    fn record_map(
        &self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        sun_elevation: f64,
        altitude_m: f64,
    ) -> Result<(), GpuError> {
        let coefficients = self.table().coefficients(sun_elevation, altitude_m)?;
        gpu.queue
            .write_buffer(&self.coefficients, 0, bytemuck::cast_slice(&coefficients));
        let group = gpu.bind_group(
            &self.map_pass.get_bind_group_layout(0),
            &[
                self.params.as_entire_binding(),
                self.s.as_entire_binding(),
                self.order.as_entire_binding(),
                self.used.as_entire_binding(),
                self.coefficients.as_entire_binding(),
                self.map.as_entire_binding(),
            ],
        );
        let mut pass = encoder.begin_compute_pass(&Default::default());
        pass.set_pipeline(&self.map_pass);
        pass.set_bind_group(0, &group, &[]);
        pass.dispatch_workgroups(self.rows.div_ceil(64), 1, 1);
        Ok(())
    }

    /// The skylight map (linear sRGB, `[elevation][azimuth]` over the table's grid), as
    /// `SkylightTable::map` gives it on the CPU, and the GPU time of its pass (ms) where
    /// the adapter has timestamps.
    pub fn map(
        &self,
        gpu: &Gpu,
        sun_elevation: f64,
        altitude_m: f64,
    ) -> Result<(Vec<Vec3>, Option<f64>), GpuError> {
        let mut recorded = Ok(());
        let gpu_ms = gpu.run("the skylight map", |encoder| {
            recorded = self.record_map(gpu, encoder, sun_elevation, altitude_m);
        })?;
        recorded?;
        let bytes = gpu.read("the skylight map", &self.map, 0, self.map.size())?;
        let values: &[f32] = bytemuck::cast_slice(&bytes);
        Ok((values.chunks(3).map(Vec3::from_slice).collect(), gpu_ms))
    }

    /// Records this frame's skylight map for `sun` seen from `altitude_m` into
    /// `encoder` and sets `pass` to draw it in `view`: what a renderer does each frame,
    /// before recording [`SkyPass::draw`] in a render pass of the same encoder (or a
    /// later one). Nothing is read back.
    pub fn prepare(
        &self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        pass: &mut SkyPass,
        sun: Sun,
        altitude_m: f64,
        view: &View,
    ) -> Result<(), GpuError> {
        self.record_map(gpu, encoder, sun.elevation(), altitude_m)?;
        let atmosphere = self.table().atmosphere();
        let grid = self.table().grid(altitude_m);
        let inputs = FrameInputs {
            sky: &self.map,
            ground_below: grid.elevation_min,
            sky_grid: grid,
            ground: None,
            sun_rgb: sun_disc_rgb(atmosphere, altitude_m, sun.elevation()),
            sun_radius: atmosphere.sun_angular_radius,
        };
        pass.set(gpu, &inputs, sun, view);
        Ok(())
    }

    /// The picture of `view` for `sun` seen from `altitude_m`, read back: map pass and
    /// picture pass in one submission, as `SkyPicture::from_table(..).render(view)` on
    /// the CPU.
    pub fn render(
        &self,
        gpu: &Gpu,
        pass: &mut SkyPass,
        sun: Sun,
        altitude_m: f64,
        view: &View,
    ) -> Result<Rendered, GpuError> {
        picture(gpu, pass, view, |encoder, pass| {
            self.prepare(gpu, encoder, pass, sun, altitude_m, view)
        })
    }
}

/// A sky model uploaded: its sun-independent maps in one buffer, the shell pass, and the
/// skylight and ground maps it fills per sun; `M` is the model borrowed (`&SkyModel`)
/// or owned.
pub struct GpuSkyModel<M: Borrow<SkyModel>> {
    model: M,
    data: wgpu::Buffer,
    /// The shell pass's parameters without the sun, for the sky's and the ground's rays.
    sky_params: ShellParams,
    ground_params: ShellParams,
    sky_grid: DirectionGrid,
    ground_grid: DirectionGrid,
    sky_map: wgpu::Buffer,
    ground_map: wgpu::Buffer,
    shells: wgpu::ComputePipeline,
    /// The shell pass's parameters of the sky's and the ground's grids, written per sun.
    uniforms: [wgpu::Buffer; 2],
    /// The sun disc's spectrum to linear sRGB, made once (it integrates the CMFs).
    to_rgb: SpectrumToRgb,
}

impl<M: Borrow<SkyModel>> GpuSkyModel<M> {
    /// Uploads `model`'s maps; an error for a model the GPU cannot evaluate yet
    /// (aerosols in the higher orders) or above the device's limits.
    pub fn new(gpu: &Gpu, model: M) -> Result<Self, GpuError> {
        let arrays = model.borrow().arrays().ok_or_else(|| {
            atmo::Error::Invalid(
                "molecules with a phase other than Rayleigh's in the higher orders are \
                 drawn on the CPU only; render this model on the CPU"
                    .into(),
            )
        })?;
        let mut data: Vec<[f32; 4]> = Vec::new();
        let mut at = |values: &[[f32; 4]]| {
            let start = data.len() as u32;
            data.extend_from_slice(values);
            start
        };
        let shells: Vec<[f32; 4]> = arrays
            .shell_radius
            .iter()
            .zip(arrays.light_mu_low.iter().zip(&arrays.light_scale))
            .map(|(&r, (&low, &scale))| [r, low, scale, 0.0])
            .collect();
        let rgb: Vec<[f32; 4]> = arrays
            .to_rgb
            .iter()
            .flat_map(|lane| lane.map(|[r, g, b]| [r, g, b, 0.0]))
            .collect();
        let common = ShellParams {
            sun: [0.0; 4],
            grid: [0.0; 4],
            bottom: arrays.bottom_m,
            top: arrays.top_m,
            sun_radius: arrays.sun_radius,
            ground_albedo: arrays.ground_albedo,
            lanes: arrays.lanes as u32,
            multiple: arrays.multiple as u32,
            shells: shells.len() as u32,
            light_entries: arrays.light_map_entries as u32,
            mu_size: arrays.mu_size as u32,
            r_size: arrays.r_size as u32,
            sun_bins: arrays.sun_bins as u32,
            sun_bins_a: arrays.sun_bins_a,
            rayleigh_kind: arrays.rayleigh_phase.kind,
            rayleigh_g: arrays.rayleigh_phase.g,
            mie_kind: arrays.mie_phase.kind,
            mie_g: arrays.mie_phase.g,
            rays_at: 0,
            samples_at: 0,
            rayleigh_at: 0,
            mie_at: 0,
            ground_at: 0,
            shells_at: at(&shells),
            light_at: at(&arrays.light_map),
            irradiance_at: at(&arrays.irradiance),
            transmittance_at: at(&arrays.transmittance),
            moments_at: at(&arrays.moments),
            rgb_at: at(&rgb),
            aerosol_at: at(&arrays.aerosol_table),
            ground_light_at: at(&arrays.ground_irradiance),
            aerosols: !arrays.aerosol_table.is_empty() as u32,
            pad0: 0,
            pad1: 0,
        };
        let mut of = |rays: &RayArrays| {
            let records: Vec<[f32; 4]> = (0..rays.origin_r.len())
                .map(|j| {
                    [
                        f32::from_bits(rays.ray_start[j]),
                        f32::from_bits(rays.ray_start[j + 1]),
                        rays.origin_r[j],
                        rays.ground_distance[j],
                    ]
                })
                .collect();
            let samples: Vec<[f32; 4]> = (0..rays.shell.len())
                .flat_map(|s| {
                    [
                        [
                            f32::from_bits(rays.shell[s]),
                            rays.between[s],
                            rays.altitude[s],
                            rays.distance[s],
                        ],
                        [rays.mu[s], 0.0, 0.0, 0.0],
                    ]
                })
                .collect();
            let g = &rays.grid;
            ShellParams {
                grid: [
                    g.elevation_min as f32,
                    g.elevation_max as f32,
                    g.azimuths as f32,
                    g.elevations as f32,
                ],
                rays_at: at(&records),
                samples_at: at(&samples),
                rayleigh_at: at(&rays.rayleigh),
                mie_at: at(&rays.mie),
                ground_at: at(&rays.ground),
                ..common
            }
        };
        let sky_params = of(&arrays.sky);
        let ground_params = of(&arrays.ground_rays);
        let bytes = bytemuck::cast_slice(&data);
        let buffer = gpu.storage("the sky model's maps", bytes, "shells or directions")?;
        let map = |grid: &DirectionGrid, what: &str| {
            gpu.output(
                what,
                (grid.azimuths * grid.elevations * 12) as u64,
                "directions",
            )
        };
        let module = wgsl::module(gpu, "sky_shells.wgsl")?;
        let to_rgb = SpectrumToRgb::new(&model.borrow().atmosphere().wavelengths_nm);
        Ok(GpuSkyModel {
            to_rgb,
            model,
            data: buffer,
            sky_params,
            ground_params,
            sky_map: map(&arrays.sky.grid, "the skylight map")?,
            ground_map: map(&arrays.ground_rays.grid, "the ground map")?,
            sky_grid: arrays.sky.grid,
            ground_grid: arrays.ground_rays.grid,
            shells: gpu.compute_pipeline(&module, "main", None)?,
            uniforms: [
                gpu.uniform("the shell pass (sky)", &sky_params),
                gpu.uniform("the shell pass (ground)", &ground_params),
            ],
        })
    }

    /// The model drawn.
    pub fn model(&self) -> &SkyModel {
        self.model.borrow()
    }

    /// Records the shell pass of both grids for a sun at `sun_elevation` rad.
    fn record_maps(&self, gpu: &Gpu, encoder: &mut wgpu::CommandEncoder, sun_elevation: f64) {
        let (sin_s, cos_s) = sun_elevation.sin_cos();
        for (params, map, grid, uniform) in [
            (
                &self.sky_params,
                &self.sky_map,
                &self.sky_grid,
                &self.uniforms[0],
            ),
            (
                &self.ground_params,
                &self.ground_map,
                &self.ground_grid,
                &self.uniforms[1],
            ),
        ] {
            let params = ShellParams {
                sun: [sin_s as f32, cos_s as f32, 0.0, 0.0],
                ..*params
            };
            gpu.queue
                .write_buffer(uniform, 0, bytemuck::bytes_of(&params));
            let group = gpu.bind_group(
                &self.shells.get_bind_group_layout(0),
                &[
                    uniform.as_entire_binding(),
                    self.data.as_entire_binding(),
                    map.as_entire_binding(),
                ],
            );
            let mut pass = encoder.begin_compute_pass(&Default::default());
            pass.set_pipeline(&self.shells);
            pass.set_bind_group(0, &group, &[]);
            pass.dispatch_workgroups(
                (grid.azimuths as u32).div_ceil(8),
                (grid.elevations as u32).div_ceil(8),
                1,
            );
        }
    }

    /// Fills the skylight and ground maps for a sun at `sun_elevation` rad, on the GPU
    /// only (what a renderer does each frame); the GPU time, where timed, ms.
    pub fn maps_timed(&self, gpu: &Gpu, sun_elevation: f64) -> Result<Option<f64>, GpuError> {
        gpu.run("the shell pass", |encoder| {
            self.record_maps(gpu, encoder, sun_elevation)
        })
    }

    /// The skylight map and the ground map (linear sRGB, `[elevation][azimuth]`) for a
    /// sun at `sun_elevation` rad, as `SkyModel::skylight_map` and `ground_map` give
    /// them on the CPU, converted to RGB.
    pub fn maps(&self, gpu: &Gpu, sun_elevation: f64) -> Result<[Vec<Vec3>; 2], GpuError> {
        self.maps_timed(gpu, sun_elevation)?;
        let read = |map: &wgpu::Buffer| -> Result<Vec<Vec3>, GpuError> {
            let bytes = gpu.read("the shell maps", map, 0, map.size())?;
            let values: &[f32] = bytemuck::cast_slice(&bytes);
            Ok(values.chunks(3).map(Vec3::from_slice).collect())
        };
        Ok([read(&self.sky_map)?, read(&self.ground_map)?])
    }

    /// Records this frame's skylight and ground maps for `sun` into `encoder` and sets
    /// `pass` to draw them in `view` (seen from the model's altitude, whatever the
    /// camera's height): what a renderer does each frame, before recording
    /// [`SkyPass::draw`]. Nothing is read back.
    pub fn prepare(
        &self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        pass: &mut SkyPass,
        sun: Sun,
        view: &View,
    ) -> Result<(), GpuError> {
        self.record_maps(gpu, encoder, sun.elevation());
        let model = self.model();
        let atmosphere = model.atmosphere();
        let mut spectrum = vec![0.0f32; atmosphere.channels()];
        model.sun_radiance(sun.elevation(), &mut spectrum);
        let inputs = FrameInputs {
            sky: &self.sky_map,
            sky_grid: self.sky_grid.clone(),
            ground: Some((&self.ground_map, self.ground_grid.clone())),
            ground_below: -atmo::atmosphere::geometry::horizon_dip(
                atmosphere.bottom_radius_m,
                model.altitude_m(),
            ),
            sun_rgb: self.to_rgb.rgb(&spectrum),
            sun_radius: atmosphere.sun_angular_radius,
        };
        pass.set(gpu, &inputs, sun, view);
        Ok(())
    }

    /// The picture of `view` for `sun`, read back, as
    /// `SkyPicture::new(model, sun).render(view)` on the CPU.
    pub fn render(
        &self,
        gpu: &Gpu,
        pass: &mut SkyPass,
        sun: Sun,
        view: &View,
    ) -> Result<Rendered, GpuError> {
        picture(gpu, pass, view, |encoder, pass| {
            self.prepare(gpu, encoder, pass, sun, view)
        })
    }
}

/// Records `prepare` (the passes that fill the maps and set `pass`) and the picture pass
/// into a texture of the view's size in one submission, and reads the picture back.
fn picture(
    gpu: &Gpu,
    pass: &mut SkyPass,
    view: &View,
    prepare: impl FnOnce(&mut wgpu::CommandEncoder, &mut SkyPass) -> Result<(), GpuError>,
) -> Result<Rendered, GpuError> {
    let (width, height) = (view.camera.width, view.camera.height);
    for side in [width, height] {
        gpu.check_texture_side("the sky frame", side, "the image size")?;
    }
    let texture = gpu.texture_2d(
        "the sky frame",
        (width, height),
        SkyTarget::HEADLESS.format,
        wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
    );
    let target = texture.create_view(&Default::default());
    let mut prepared = Ok(());
    let gpu_ms = gpu.run("the sky frame", |encoder| {
        prepared = prepare(encoder, pass);
        pass.draw(&mut cleared_pass(
            encoder,
            &target,
            "the sky frame",
            wgpu::Color::BLACK,
        ));
    })?;
    prepared?;
    let bytes = gpu.read_texture("the sky frame", &texture, width, height)?;
    Ok(Rendered {
        frame: crate::frame_of(width, height, &bytes),
        gpu_ms,
    })
}
