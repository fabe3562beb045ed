//! atmo's methods on the GPU with wgpu, headless: the sky from the skylight table
//! ([`sky`]), light shafts by sample planes ([`shafts`]) and clouds through the 3-D
//! intensity buffer ([`clouds`]). Each translates the CPU method of the `atmo` crate,
//! which stays the reference: the tests hold every pipeline's pictures to the CPU's
//! within half a level of 255 RMS.
//!
//! Shaders are WGSL under `shaders/`, one per pass, composed by [`wgsl::source`] after
//! a prelude of constants generated from the Rust and the WGSL twins of the library's
//! shared functions (each tested against its Rust original). Parameter structs are
//! declared once with [`gpu_struct!`], `#[repr(C)]` and `Pod`, and mirrored in WGSL; a
//! test checks each against naga's layout of the shader's struct.

pub mod clouds;
pub mod device;
pub mod display;
pub mod layout;
pub mod shafts;
pub mod sky;
pub mod wgsl;

pub use device::Gpu;

/// A frame and, where the adapter has timestamp queries, the GPU time it took, ms.
pub struct Rendered {
    pub frame: atmo::image::Frame,
    pub gpu_ms: Option<f64>,
}

/// What can go wrong on the GPU, with what to do about it.
#[derive(Debug, thiserror::Error)]
pub enum GpuError {
    #[error("no GPU adapter found; install mesa-vulkan-drivers for a software one, or render on the CPU")]
    NoAdapter,
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

/// A frame of `width` x `height` from RGBA f32 pixels, alpha dropped.
pub(crate) fn frame_of(width: u32, height: u32, bytes: &[u8]) -> atmo::image::Frame {
    let values: &[f32] = bytemuck::cast_slice(bytes);
    let mut frame = atmo::image::Frame::new(width, height);
    for (pixel, v) in frame.pixels.iter_mut().zip(values.chunks(4)) {
        *pixel = glam::Vec3::new(v[0], v[1], v[2]);
    }
    frame
}
