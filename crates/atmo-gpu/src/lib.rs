//! atmo's methods on the GPU with wgpu: the sky from the skylight table or by the
//! shell method ([`sky`]), light shafts by sample planes ([`shafts`]) and clouds
//! through the 3-D intensity buffer ([`clouds`]). Each translates the CPU method of the
//! `atmo` crate, which stays the reference: the tests hold every pipeline's pictures to
//! the CPU's within half a level of 255 RMS.
//!
//! # In a program of one's own
//!
//! The sky draws into the caller's device, encoder and render pass, with no read-back:
//! [`Gpu::from_device`] wraps the caller's device and queue; a [`sky::SkyPass`] is
//! made once for the caller's colour format (and depth buffer, so that the sky fills
//! only what is still at the far plane); each frame a sky's `prepare` records its maps
//! into the caller's encoder, and [`sky::SkyPass::draw`] records one full-screen
//! triangle into the caller's render pass. [`display::DisplayPass`] tone-maps an HDR
//! picture onto an LDR target the same way. `examples/embed.rs` is a whole program,
//! whose own ground is also lit by atmo's sun and sky (`atmo::sky::lighting`) and hazed
//! by its aerial perspective: [`sky::GpuAerial::prepare`] records the froxels' compute
//! pass into the caller's encoder, writing two 3-D textures ([`sky::AerialTextures`])
//! that its own shader samples.
//!
//! ```no_run
//! # fn frame(device: wgpu::Device, queue: wgpu::Queue, info: wgpu::AdapterInfo,
//! #          colour: &wgpu::TextureView, depth: &wgpu::TextureView)
//! #          -> Result<(), atmo_gpu::GpuError> {
//! use atmo::sky::{SkyModel, SkySettings, View};
//! use atmo::view::{Camera, Fov, Sun};
//! use atmo_gpu::sky::{DepthTarget, GpuSkyModel, SkyPass, SkyTarget};
//!
//! // Once: atmo on the program's device, the sky uploaded, the pass for its targets.
//! let gpu = atmo_gpu::Gpu::from_device(device.clone(), queue.clone(), info)?;
//! let model = SkyModel::new(&atmo::Atmosphere::earth(), &SkySettings::default(), 2.0)?;
//! let sky = GpuSkyModel::new(&gpu, model)?;
//! let depth_target = DepthTarget { format: wgpu::TextureFormat::Depth32Float, reversed_z: false };
//! let target = SkyTarget { format: wgpu::TextureFormat::Rgba16Float, depth: Some(depth_target), samples: 1 };
//! let mut sky_pass = SkyPass::new(&gpu, target)?;
//!
//! // Each frame: the camera in atmo's world frame (+y up, metres), the sun.
//! let eye = glam::Vec3::new(0.0, 2.0, 0.0);
//! let camera = Camera::look_at(eye, eye + glam::Vec3::NEG_Z, glam::Vec3::Y, Fov::Vertical(60.0), (1280, 720))?;
//! let view = View { camera, sun_disc: true };
//! let sun = Sun::from_degrees(10.0, 180.0)?;
//! let mut encoder = device.create_command_encoder(&Default::default());
//! sky.prepare(&gpu, &mut encoder, &mut sky_pass, sun, &view)?;
//! {
//!     let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
//!         color_attachments: &[Some(wgpu::RenderPassColorAttachment {
//!             view: colour, depth_slice: None, resolve_target: None,
//!             ops: wgpu::Operations { load: wgpu::LoadOp::Load, store: wgpu::StoreOp::Store },
//!         })],
//!         depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
//!             view: depth,
//!             depth_ops: Some(wgpu::Operations { load: wgpu::LoadOp::Load, store: wgpu::StoreOp::Store }),
//!             stencil_ops: None,
//!         }),
//!         ..Default::default()
//!     });
//!     // ... the program's own draws, then:
//!     sky_pass.draw(&mut pass);
//! }
//! queue.submit([encoder.finish()]);
//! # Ok(()) }
//! ```
//!
//! What a frame costs on the GPU, per pass (counted at the default settings; docs/gpu.md
//! has the counts for every method and the times measured on a software adapter): the
//! table's map pass, 12,288 invocations summing 23 terms on average; the shell method's
//! map pass, 4,096 + 2,048 invocations (sky and ground) of 35 and 16 shell samples;
//! the picture pass, one bilinear lookup (4 texels) and a few transcendentals per pixel,
//! 2.07 M at 1920 x 1080. The headless renders (`render`, read back as an
//! `atmo::image::Frame`) are one user of this path, `atmo view` another.
//!
//! The shafts draw into the caller's target the same way: [`shafts::ShaftsPipelines`]
//! compiles the passes once, [`shafts::GpuShafts::with_pipelines`] uploads a scene (again
//! when it changes), [`shafts::GpuShafts::prepare`] records the frame's passes into the
//! caller's encoder and [`shafts::ShaftsPass::draw`] writes the picture (linear radiance
//! times its exposure, the scene camera's size from its corner) into the caller's
//! render pass:
//!
//! ```no_run
//! # fn frame(gpu: &atmo_gpu::Gpu, scene: &atmo::shafts::Scene, target: &wgpu::TextureView)
//! #          -> Result<(), atmo_gpu::GpuError> {
//! use atmo_gpu::shafts::{GpuShafts, ShaftsMethod, ShaftsPass, ShaftsPipelines};
//!
//! // Once.
//! let pipelines = ShaftsPipelines::new(gpu)?;
//! let mut pass = ShaftsPass::new(gpu, wgpu::TextureFormat::Rgba16Float)?;
//! // When the scene changes (a light moved, the camera orbited).
//! let shafts = GpuShafts::with_pipelines(gpu, scene, pipelines.clone())?;
//! // Each frame it is drawn.
//! let mut encoder = gpu.device.create_command_encoder(&Default::default());
//! shafts.prepare(gpu, &mut encoder, &mut pass, ShaftsMethod::Planes)?;
//! {
//!     let mut render = atmo_gpu::display::cleared_pass(&mut encoder, target, "shafts", wgpu::Color::BLACK);
//!     pass.draw(&mut render);
//! }
//! gpu.queue.submit([encoder.finish()]);
//! # Ok(()) }
//! ```
//!
//! The clouds, after [`clouds::GpuClouds::light`], likewise: [`clouds::GpuClouds::prepare`]
//! records the billboards and [`clouds::CloudsPass::draw`] puts the cloud over what the
//! caller's target holds (premultiplied over, the higher octaves added on the GPU).
//!
//! The shafts' passes, per frame (docs/gpu.md counts them on the example scenes): the shadow
//! maps, one ray a texel (5 x 512^2 for the five-light stage); the planes' extents (one
//! invocation) and the attenuation table (1024^2); the surfaces, one ray a sub-pixel;
//! the sample planes, one quad a light, plane and sub-pixel ray over its lit rectangle,
//! each fragment summing `sub_planes` samples (14.8 M fragments, 89 M samples for the
//! stage at 720 x 480); the composite and the picture pass, one invocation a pixel.
//!
//! Shaders are WGSL under `shaders/`, one per pass, composed by [`wgsl::source`] after
//! a prelude of constants generated from the Rust and the WGSL twins of the library's
//! shared functions (each tested against its Rust original). Parameter structs are
//! declared once with [`gpu_struct!`], `#[repr(C)]` and `Pod`, and mirrored in WGSL; a
//! test checks each against naga's layout of the shader's struct.

pub mod backend;
pub mod clouds;
pub mod cloudscape;
pub mod device;
pub mod display;
pub mod layout;
pub mod shafts;
pub mod sky;
pub mod wgsl;

pub use backend::Backend;
pub use device::Gpu;
/// The wgpu atmo-gpu is built on, for a caller to name its types by the same version.
pub use wgpu;

/// A frame and, where the adapter has timestamp queries, the GPU time it took, ms.
pub struct Rendered {
    pub frame: atmo::image::Frame,
    pub gpu_ms: Option<f64>,
}

/// What can go wrong on the GPU, with what to do about it.
#[derive(Debug, thiserror::Error)]
pub enum GpuError {
    /// `hint` says what to do: the variable that hides the drivers, or what to install.
    #[error("no GPU adapter found; {hint}")]
    NoAdapter { hint: String },
    #[error("no GPU adapter matches {wanted:?}; found: {found}")]
    NoMatch { wanted: String, found: String },
    #[error(
        "the GPU adapter {adapter} lacks {missing}; choose another adapter or render on the CPU"
    )]
    MissingFeature { adapter: String, missing: String },
    #[error("could not open the GPU device: {0}")]
    Device(String),
    #[error("{what} needs {needed} but the GPU's {limit} is {max}; lower {setting}")]
    OverLimit {
        what: String,
        needed: u64,
        limit: String,
        max: u64,
        setting: String,
    },
    #[error("the GPU ran out of memory in {0}; lower the resolution or render on the CPU")]
    OutOfMemory(String),
    #[error("the GPU device was lost in {what} ({reason}); try again or render on the CPU")]
    DeviceLost { what: String, reason: String },
    #[error("GPU error in {what}: {message}")]
    Internal { what: String, message: String },
    #[error(transparent)]
    Atmo(#[from] atmo::Error),
}

/// A frame of `width` x `height` from RGBA f32 pixels read back, alpha dropped.
pub(crate) fn frame_of(width: u32, height: u32, bytes: &[u8]) -> atmo::image::Frame {
    let mut frame = atmo::image::Frame::new(width, height);
    rgb_of(bytes, &mut frame.pixels);
    frame
}

/// `pixels` from RGBA f32 `bytes`, their alpha left out.
pub(crate) fn rgb_of(bytes: &[u8], pixels: &mut [glam::Vec3]) {
    for (pixel, v) in pixels.iter_mut().zip(bytes.as_chunks::<16>().0) {
        let v: [f32; 4] = bytemuck::pod_read_unaligned(v);
        *pixel = glam::Vec3::new(v[0], v[1], v[2]);
    }
}
