//! atmo's viewer: a window (winit + wgpu) that draws a [`Mode`] every frame as its
//! parameters change, with a panel (egui) holding them, so that what a user finds in
//! the window is written back as the still command that reproduces it. The modes: the
//! sky ([`sky`], the parameters of `atmo sky`: sun, altitude, camera), the stage
//! ([`stage`], a shafts scene file whose lights and camera are edited live, the edits
//! those of `atmo shafts --set`) and the clouds ([`clouds`], the sun moved and the
//! camera orbited around a cloud of `atmo clouds`).
//!
//! The picture is drawn into an RGBA f32 texture ([`Picture`]) by the same code as the
//! stills: on the GPU through `atmo_gpu` (the sky's [`SkyPass`] recorded into this
//! program's encoder), or on the CPU by `atmo`'s methods and uploaded; then
//! `atmo_gpu`'s display pass tone-maps it onto the window's surface.
//! A screenshot reads the picture back and writes it as the stills do, so a
//! screenshot and the still command's file can be compared level for level.
//!
//! Runs without a person: [`Options::frames`] draws that many frames and saves the
//! last ([`Options::screenshot`]); a [`Script`] replays key presses, mouse drags and
//! panel edits at given frames.
//!
//! [`SkyPass`]: atmo_gpu::sky::SkyPass

mod app;
pub mod clouds;
pub mod input;
mod layer;
mod panel;
pub mod sky;
pub mod stage;

use std::path::{Path, PathBuf};

use anyhow::Result;
use atmo::image::{Display, Frame};
use atmo_gpu::display::{cleared_pass, loaded_pass, picture_texture};
use atmo_gpu::{Gpu, GpuError};

pub use app::{run, Timings};
pub use input::{Input, Key, Script};

/// What the window shows, and how a user changes it.
pub trait Mode {
    /// The panel's title, the still command's name (`atmo sky`).
    fn title(&self) -> &'static str;
    /// Refuses, before the window opens, a script's edit the mode can never take.
    fn check_script(&self, script: &Script) -> atmo::Result<()>;
    /// Draws with the GPU's method if `on_gpu`, else the CPU's.
    fn draw_on_gpu(&mut self, on_gpu: bool);
    /// Applies `input`; an input that would make the parameters invalid is refused
    /// (the error says why) and the last good ones stay.
    fn apply(&mut self, input: &Input) -> Result<()>;
    /// Advances a frame: an animation, a file changed on disk. An error is shown and
    /// the last good state stays.
    fn update(&mut self) -> Result<()>;
    /// Draws the picture into `picture`, on the mode's backend: `true` when it drew,
    /// `false` when nothing it shows changed and the picture stays as it was.
    fn draw(
        &mut self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        picture: &Picture,
    ) -> Result<bool>;
    /// How the picture is shown (and written as PNG).
    fn display(&self) -> Display;
    /// The still command that draws this picture to `output` at `size`.
    fn still_command(&self, output: &Path, size: (u32, u32)) -> String;
    /// The panel's widgets; edits come back as inputs, applied like any other.
    fn panel(&mut self, ui: &mut egui::Ui) -> Vec<Input>;
    /// The keys and mouse, in a line.
    fn help(&self) -> &'static str;
    /// The light a right-button drag aims ([`Input::Aim`]), if the mode has lights.
    fn aimed_light(&self) -> Option<usize> {
        None
    }
}

/// The limit of an orbit above and below the point looked at, degrees.
const ORBIT_PITCH_LIMIT_DEG: f32 = 85.0;

/// A camera at `camera` moved about the point `look_at`: `yaw_deg` around the vertical
/// (clockwise seen from above, x east and z south), `pitch_deg` up (held within 85 deg
/// of the horizontal), its distance times `scale`. The stage's and the clouds' orbit.
pub fn orbit(
    camera: glam::Vec3,
    look_at: glam::Vec3,
    yaw_deg: f32,
    pitch_deg: f32,
    scale: f32,
) -> glam::Vec3 {
    let offset = camera - look_at;
    let distance = offset.length();
    let pitch = ((offset.y / distance).asin().to_degrees() + pitch_deg)
        .clamp(-ORBIT_PITCH_LIMIT_DEG, ORBIT_PITCH_LIMIT_DEG)
        .to_radians();
    let yaw = offset.x.atan2(offset.z) + yaw_deg.to_radians();
    let direction = glam::Vec3::new(
        pitch.cos() * yaw.sin(),
        pitch.sin(),
        pitch.cos() * yaw.cos(),
    );
    look_at + direction * (distance * scale)
}

/// Where the method runs; the window itself always shows through the GPU's surface.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Backend {
    /// A hardware GPU's method when the window's adapter is one, else the CPU's (a
    /// software adapter such as llvmpipe is slower than atmo's CPU path).
    Auto,
    /// The GPU's method, on any adapter.
    Gpu,
    /// The CPU's method (rayon over every core); the frame is uploaded and shown.
    Cpu,
}

/// How the viewer runs.
#[derive(Debug, Clone)]
pub struct Options {
    /// The window's inner size, pixels: the picture's.
    pub size: (u32, u32),
    /// Draw this many frames, save the last to [`Options::screenshot`] and close.
    pub frames: Option<u64>,
    /// Where the last frame goes (.png or .exr) when [`Options::frames`] is set.
    pub screenshot: Option<PathBuf>,
    /// Inputs replayed at given frames.
    pub script: Script,
    pub backend: Backend,
    /// The adapter, by part of its name or a backend (see `atmo_gpu::Gpu::new`).
    pub adapter: Option<String>,
}

/// The picture a mode draws each frame: linear radiance, RGBA f32, the window's size.
pub struct Picture {
    pub texture: wgpu::Texture,
    pub view: wgpu::TextureView,
    /// Width and height, pixels.
    pub size: (u32, u32),
}

impl Picture {
    fn new(gpu: &Gpu, size: (u32, u32)) -> Result<Picture, GpuError> {
        let texture = picture_texture(gpu, size.0, size.1)?;
        let view = texture.create_view(&Default::default());
        Ok(Picture {
            texture,
            view,
            size,
        })
    }

    /// Records a render pass into the picture, cleared to black, in which `draw`
    /// records its draws.
    pub fn draw(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        draw: impl FnOnce(&mut wgpu::RenderPass<'_>),
    ) {
        let mut pass = cleared_pass(encoder, &self.view, "the picture", wgpu::Color::BLACK);
        draw(&mut pass);
    }

    /// Records a render pass over the picture as it is (what was written into it stays
    /// behind), in which `draw` records its draws.
    pub fn draw_over(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        draw: impl FnOnce(&mut wgpu::RenderPass<'_>),
    ) {
        let mut pass = loaded_pass(encoder, &self.view, "over the picture");
        draw(&mut pass);
    }

    /// The picture read back.
    fn read(&self, gpu: &Gpu) -> Result<Frame, GpuError> {
        let (width, height) = self.size;
        let bytes = gpu.read_texture("the screenshot", &self.texture, width, height)?;
        Ok(atmo_gpu::frame_of(width, height, &bytes))
    }
}
