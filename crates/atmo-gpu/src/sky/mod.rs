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

mod aerial;
mod renderer;
mod shells;
mod table;

pub use aerial::{AerialTextures, GpuAerial, AERIAL_LIGHT_WGSL};
pub use renderer::{GpuSky, Prepared, SkyRenderer, SkySource};
pub use shells::GpuSkyModel;
pub use table::GpuSkyTable;

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

/// The colour target a [`SkyPass`] draws into, and the depth buffer it tests against.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SkyTarget {
    /// The colour attachment's format. Linear radiance (W m^-2 sr^-1 as linear sRGB)
    /// times [`SkyPass::exposure`] is written; an `*Srgb` format encodes it on store.
    pub format: wgpu::TextureFormat,
    /// The depth attachment, if the pass has one: the sky is drawn only where it is
    /// still at the far plane (no depth is written).
    pub depth: Option<DepthTarget>,
    /// Samples a pixel of the attachments (multisampling; 1 without): each sample
    /// passes or fails the depth test on its own, so the sky's edge against a mesh is
    /// as smooth as the mesh's.
    pub samples: u32,
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
        samples: 1,
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
            target.samples,
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
    gpu.check_picture("the sky frame", (width, height), "the image size")?;
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
    Ok(Rendered {
        frame: gpu.read_frame("the sky frame", &texture, (width, height))?,
        gpu_ms,
    })
}
