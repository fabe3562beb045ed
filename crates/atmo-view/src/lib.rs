//! atmo's viewer: a window (winit + wgpu) that draws a [`Mode`] every frame as its
//! parameters change, with a panel (egui) holding them, so that what a user finds in
//! the window is written back as the still command that reproduces it. The modes: the
//! sky ([`sky`], the parameters of `atmo sky`: sun, altitude, camera), the stage
//! ([`stage`], a shafts scene file whose lights and camera are edited live, the edits
//! those of `atmo shafts --set`) and the clouds ([`clouds`], the sun moved and the
//! camera orbited around a cloud of `atmo clouds`).
//!
//! The picture ([`Picture`]) is drawn by the same code as the stills: on the GPU
//! through `atmo_gpu` into an RGBA f32 texture (the sky's [`SkyPass`] recorded into
//! this program's encoder), which `atmo_gpu`'s display pass tone-maps onto the window's
//! surface; or on the CPU by `atmo`'s methods into a frame, whose 8-bit levels (those
//! the still writes to PNG, by [`atmo::image::Levels`]) go into the window's own pixels
//! (softbuffer; the surface where the window system gives none).
//! A screenshot reads the picture back (or takes the CPU's frame) and writes it as the
//! stills do, so a screenshot and the still command's file can be compared level for
//! level.
//!
//! Runs without a person: [`Options::frames`] draws that many frames and saves the
//! last ([`Options::screenshot`]); a [`Script`] replays key presses, mouse drags and
//! panel edits at given frames.
//!
//! [`SkyPass`]: atmo_gpu::sky::SkyPass

mod app;
pub mod clouds;
pub use atmo::view::input;
mod layer;
mod panel;
mod pixels;
pub mod sky;
pub mod stage;

pub use atmo_gpu::Backend;
use std::path::{Path, PathBuf};

use anyhow::Result;
use atmo::image::{stretched, Display, Frame, Levels, TexelOrder};
use atmo_gpu::display::{cleared_pass, loaded_pass, picture_texture, write_frame, DisplayPass};
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
        picture: &mut Picture,
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
    /// Ends the mode when the window closes (the stage writes its DMX recording) and
    /// gives its own figures for `--timings`.
    fn close(&mut self) -> Result<Figures> {
        Ok(Figures::default())
    }
}

/// A mode's own figures at the end of a run ([`Mode::close`]), by name: single values,
/// and series (ms) that `--timings` gives as median and 95th percentile as it gives the
/// frame times.
#[derive(Debug, Clone, Default)]
pub struct Figures {
    pub values: Vec<(&'static str, f64)>,
    pub series: Vec<(&'static str, Vec<f64>)>,
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
    /// Where the method runs; the window itself always shows through the GPU's surface
    /// ([`Backend::runs_on`] its adapter).
    pub backend: Backend,
    /// The adapter, by part of its name or a backend (see `atmo_gpu::Gpu::new`).
    pub adapter: Option<String>,
    /// While a picture drawn on the CPU keeps changing (a drag, a slider, a show
    /// playing) it may be drawn at 1/`preview` of the window's size in each direction
    /// and stretched, and whole once it stops (the first frame without a change);
    /// 1: always whole. The last frame of [`Options::frames`] is always whole.
    pub preview: u32,
}

/// The picture a mode draws each frame, the window's size: on the GPU, linear radiance
/// in an RGBA f32 texture; on the CPU, a frame ([`Picture::frame`]).
pub struct Picture {
    pub texture: wgpu::Texture,
    pub view: wgpu::TextureView,
    /// Width and height, pixels.
    pub size: (u32, u32),
    /// A mode whose picture changed since it last drew may draw it this frame at
    /// 1/`k` of the size in each direction (`Some(k)`, the CPU's methods; see
    /// [`Options::preview`]), then must draw it whole at the next frame without one.
    pub preview: Option<u32>,
    /// The window takes this frame's picture as 8-bit texels in this order and nothing
    /// else of it (no screenshot, no upload): a CPU method may draw the texels alone
    /// ([`Picture::draw_cpu_texels`]).
    pub texels_only: Option<TexelOrder>,
    /// The frame drawn on the CPU, while the picture is one.
    cpu: Option<CpuFrame>,
}

/// A frame drawn on the CPU and how far it has reached the window: its 8-bit texels
/// for a surface that takes copies (made again only when the frame or the display
/// changed: an idle frame re-sends them), or the f32 texture.
struct CpuFrame {
    /// What was drawn: at the picture's size, or smaller (a preview, stretched on its
    /// way to the window).
    frame: Frame,
    /// The texels of `frame` under `levels` at the picture's size, unless
    /// `texels_stale`.
    texels: Vec<[u8; 4]>,
    /// A preview's texels before they are stretched.
    small: Vec<[u8; 4]>,
    levels: Option<Levels>,
    /// The frame was drawn since its texels were made / since it was uploaded.
    texels_stale: bool,
    upload_stale: bool,
    /// Set where the texels were drawn alone ([`Picture::draw_cpu_texels`]): their
    /// display and order; `frame` is not the picture then.
    texels_of: Option<(Display, TexelOrder)>,
}

impl Picture {
    fn new(gpu: &Gpu, size: (u32, u32)) -> Result<Picture, GpuError> {
        let texture = picture_texture(gpu, size.0, size.1)?;
        let view = texture.create_view(&Default::default());
        Ok(Picture {
            texture,
            view,
            size,
            preview: None,
            texels_only: None,
            cpu: None,
        })
    }

    /// Draws the picture on the CPU: whole (`draw` at the picture's size), or where
    /// [`Picture::preview`] allows and `changed`, at a fraction of it and stretched.
    /// `true` when what was drawn is a preview, to be drawn whole later.
    pub fn draw_cpu(
        &mut self,
        changed: bool,
        draw: impl FnOnce((u32, u32)) -> Result<Frame>,
    ) -> Result<bool> {
        let (width, height) = self.size;
        match self.preview.filter(|&k| changed && k > 1) {
            Some(k) => {
                *self.drawn() = draw((width.div_ceil(k), height.div_ceil(k)))?;
                Ok(true)
            }
            None => {
                *self.drawn() = draw(self.size)?;
                Ok(false)
            }
        }
    }

    /// Draws the picture on the CPU at its size under `display`: only its 8-bit texels
    /// (`texels(levels, order, texels)`, row by row) where the window takes nothing else
    /// this frame ([`Picture::texels_only`]), else the frame of radiances (`whole`).
    /// Texels drawn alone leave no frame behind, so a mode that draws them draws every
    /// frame (the sky): a later frame's screenshot, display or upload has its own draw.
    pub fn draw_cpu_texels(
        &mut self,
        display: Display,
        whole: impl FnOnce(&mut Frame),
        texels: impl FnOnce(&Levels, TexelOrder, &mut [[u8; 4]]),
    ) {
        let Some(order) = self.texels_only else {
            return whole(self.frame());
        };
        let n = (self.size.0 * self.size.1) as usize;
        self.frame();
        let cpu = self.cpu.as_mut().expect("made by frame()");
        let levels = cpu.levels_of(display);
        cpu.texels.resize(n, [0; 4]);
        texels(&levels, order, &mut cpu.texels);
        cpu.levels = Some(levels);
        cpu.texels_of = Some((display, order));
        cpu.texels_stale = false;
    }

    /// The frame a CPU method draws the picture into (the picture's size; what was
    /// drawn last, or black when new): the picture is this frame from now on.
    pub fn frame(&mut self) -> &mut Frame {
        let (width, height) = self.size;
        let frame = self.drawn();
        if (frame.width, frame.height) != (width, height) {
            *frame = Frame::new(width, height);
        }
        frame
    }

    /// The CPU's frame, of any size (at the picture's, or a preview's), marked to be
    /// sent to the window again: the picture is this frame from now on.
    fn drawn(&mut self) -> &mut Frame {
        let cpu = self.cpu.get_or_insert_with(|| CpuFrame {
            frame: Frame::new(0, 0),
            texels: Vec::new(),
            small: Vec::new(),
            levels: None,
            texels_stale: true,
            upload_stale: true,
            texels_of: None,
        });
        (cpu.texels_stale, cpu.upload_stale, cpu.texels_of) = (true, true, None);
        &mut cpu.frame
    }

    /// Records a render pass into the picture, cleared to black, in which `draw`
    /// records its draws: the picture is the texture from now on.
    pub fn draw(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        draw: impl FnOnce(&mut wgpu::RenderPass<'_>),
    ) {
        self.cpu = None;
        let mut pass = cleared_pass(encoder, &self.view, "the picture", wgpu::Color::BLACK);
        draw(&mut pass);
    }

    /// Records a render pass over the picture as it is (what was written into it stays
    /// behind), in which `draw` records its draws.
    pub fn draw_over(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        draw: impl FnOnce(&mut wgpu::RenderPass<'_>),
    ) {
        self.cpu = None;
        let mut pass = loaded_pass(encoder, &self.view, "over the picture");
        draw(&mut pass);
    }

    /// Puts the picture onto `target` (a window's surface texture; `order` its texels'
    /// where it takes copies of them) as `display` shows it: `true` when a CPU frame's
    /// levels were written into it (to be submitted with the next commands; what the
    /// target held is gone, draws go over it), `false` when `display` is made ready to
    /// draw the texture (a GPU picture, or a target that takes no copies).
    ///
    /// Why the copy: 4 bytes a pixel, levels made on the CPU, where the display pass
    /// reads 16 and tone-maps each on the adapter, which on a software one takes
    /// milliseconds of the same two cores a frame.
    pub(crate) fn put_onto(
        &mut self,
        gpu: &Gpu,
        target: &wgpu::Texture,
        order: Option<TexelOrder>,
        display: &mut DisplayPass,
    ) -> bool {
        let size = target.size();
        let fits = (size.width, size.height) == self.size;
        let texels = match order {
            Some(order) if fits => self.texels(display.display, order),
            _ => None,
        };
        match texels {
            Some(texels) => {
                gpu.queue.write_texture(
                    target.as_image_copy(),
                    texels,
                    wgpu::TexelCopyBufferLayout {
                        offset: 0,
                        bytes_per_row: Some(4 * size.width),
                        rows_per_image: None,
                    },
                    size,
                );
                true
            }
            None => {
                self.upload(gpu);
                display.prepare(gpu, &self.view);
                false
            }
        }
    }

    /// The CPU's frame as 4-byte texels in `order` under `display`, made again only
    /// where the frame or the display changed; `None` when the picture is the GPU's.
    pub(crate) fn texels(&mut self, display: Display, order: TexelOrder) -> Option<&[u8]> {
        let cpu = self.cpu.as_mut()?;
        if let Some(drawn) = cpu.texels_of {
            // Drawn as texels alone: those, or nothing (no frame to make others from).
            return (drawn == (display, order)).then_some(cpu.texels.as_flattened());
        }
        let levels = cpu.levels_of(display);
        if cpu.texels_stale {
            let drawn = (cpu.frame.width, cpu.frame.height);
            if drawn == self.size {
                cpu.frame.to_texels(&levels, order, &mut cpu.texels);
            } else {
                // A preview: its levels stretched, which spares making and encoding
                // the whole frame's radiances for a picture shown for a moment.
                cpu.frame.to_texels(&levels, order, &mut cpu.small);
                cpu.texels = stretched(&cpu.small, drawn, self.size, lerp_texel);
            }
            cpu.texels_stale = false;
        }
        cpu.levels = Some(levels);
        Some(cpu.texels.as_flattened())
    }

    /// Uploads the CPU's frame into the texture where it changed, for a surface that
    /// takes no copies (the display pass shows the texture).
    fn upload(&mut self, gpu: &Gpu) {
        if let Some(cpu) = self.cpu.as_mut().filter(|cpu| cpu.upload_stale) {
            write_frame(gpu, &self.texture, &cpu.whole(self.size));
            cpu.upload_stale = false;
        }
    }

    /// The picture: the CPU's frame, or the texture read back.
    fn read(&self, gpu: &Gpu) -> Result<Frame, GpuError> {
        if let Some(cpu) = &self.cpu {
            if cpu.texels_of.is_some() {
                return Err(GpuError::Internal {
                    what: "the screenshot".into(),
                    message: "the picture was drawn as 8-bit texels alone".into(),
                });
            }
            return Ok(cpu.whole(self.size));
        }
        let (width, height) = self.size;
        gpu.read_frame("the screenshot", &self.texture, (width, height))
    }
}

impl CpuFrame {
    /// The levels table of `display`, taken out (to be put back): the one kept if it
    /// is of `display`, else a new one, the texels then stale.
    fn levels_of(&mut self, display: Display) -> Levels {
        match self.levels.take() {
            Some(levels) if levels.display() == display => levels,
            _ => {
                self.texels_stale = true;
                Levels::new(display)
            }
        }
    }

    /// The frame at the picture's `size`: a preview stretched.
    fn whole(&self, (width, height): (u32, u32)) -> Frame {
        if (self.frame.width, self.frame.height) == (width, height) {
            self.frame.clone()
        } else {
            self.frame.upscaled(width, height)
        }
    }
}

/// `a + t (b - a)` for each of a texel's four 8-bit channels, rounded, `t` in [0, 1]
/// taken to 1/256: the four at once, in 16-bit lanes of one integer (no lane exceeds
/// 255 x 256 + 128), a quarter of the work of a float per channel.
#[inline]
fn lerp_texel(a: [u8; 4], b: [u8; 4], t: f32) -> [u8; 4] {
    const LANES: u64 = 0x00ff_00ff_00ff_00ff;
    let spread = |x: [u8; 4]| {
        let x = u32::from_le_bytes(x) as u64;
        (x & 0xff) | (x & 0xff00) << 8 | (x & 0xff_0000) << 16 | (x & 0xff00_0000) << 24
    };
    let w = (t * 256.0 + 0.5) as u64;
    let y = ((spread(a) * (256 - w) + spread(b) * w + 0x0080_0080_0080_0080) >> 8) & LANES;
    let packed = (y & 0xff) | (y >> 8) & 0xff00 | (y >> 16) & 0xff_0000 | (y >> 24) & 0xff00_0000;
    (packed as u32).to_le_bytes()
}

/// The adapter the tests draw on; `None` (the test passes untried) only off CI on a
/// machine without one.
#[cfg(test)]
pub(crate) fn test_gpu() -> Option<Gpu> {
    match Gpu::new(None) {
        Ok(gpu) => Some(gpu),
        Err(GpuError::NoAdapter { .. }) if std::env::var("CI").as_deref() != Ok("true") => None,
        Err(e) => panic!("GPU setup failed: {e}"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use atmo::image::ToneMap;

    /// Texels drawn alone are what the window gets for their display and order, and
    /// nothing for another or for a screenshot; without `texels_only` the frame is
    /// drawn.
    #[test]
    fn texels_drawn_alone_stand_for_the_picture_only_as_drawn() {
        let Some(gpu) = test_gpu() else { return };
        let mut picture = Picture::new(&gpu, (3, 2)).unwrap();
        let display = Display {
            exposure: 1.0,
            tone: ToneMap::Clamp,
        };
        let draw = |picture: &mut Picture| {
            picture.draw_cpu_texels(
                display,
                |frame| frame.pixels.fill(glam::Vec3::splat(0.5)),
                |levels, order, texels| {
                    assert_eq!(order, TexelOrder::Bgra);
                    texels.fill([levels.level(0.25), 1, 2, 255]);
                },
            )
        };
        picture.texels_only = Some(TexelOrder::Bgra);
        draw(&mut picture);
        let low = Levels::new(display).level(0.25);
        let texels = picture.texels(display, TexelOrder::Bgra).unwrap().to_vec();
        assert_eq!(texels, [low, 1, 2, 255].repeat(6));
        assert!(picture.texels(display, TexelOrder::Rgba).is_none());
        assert!(picture.read(&gpu).is_err(), "no frame to save");
        picture.texels_only = None;
        draw(&mut picture);
        assert_eq!(
            picture.read(&gpu).unwrap().pixels,
            vec![glam::Vec3::splat(0.5); 6]
        );
        let half = Levels::new(display).level(0.5);
        let texels = picture.texels(display, TexelOrder::Rgba).unwrap().to_vec();
        assert_eq!(texels, [half, half, half, 255].repeat(6));
    }

    /// A picture that changed is drawn small and stretched where previews are allowed,
    /// whole where not or once it stops changing.
    #[test]
    fn previews_are_drawn_small_while_the_picture_changes() {
        let Some(gpu) = test_gpu() else { return };
        let mut picture = Picture::new(&gpu, (10, 6)).unwrap();
        let mut asked = Vec::new();
        let mut draw = |picture: &mut Picture, changed| {
            picture
                .draw_cpu(changed, |size| {
                    asked.push(size);
                    let mut frame = Frame::new(size.0, size.1);
                    frame.pixels.fill(glam::Vec3::splat(size.0 as f32));
                    Ok(frame)
                })
                .unwrap()
        };
        picture.preview = Some(4);
        assert!(draw(&mut picture, true), "a preview");
        // Shown at the picture's size: the small frame's levels, stretched.
        let display = Display {
            exposure: 0.25,
            tone: ToneMap::Clamp,
        };
        let level = Levels::new(display).level(3.0);
        let texels = picture.texels(display, TexelOrder::Rgba).unwrap();
        assert_eq!(texels.len(), 4 * 10 * 6);
        assert!(texels.chunks(4).all(|t| t == [level, level, level, 255]));
        assert_eq!(
            picture.read(&gpu).unwrap().pixels,
            vec![glam::Vec3::splat(3.0); 60]
        );
        assert!(!draw(&mut picture, false), "whole once it stops changing");
        picture.preview = None;
        assert!(
            !draw(&mut picture, true),
            "whole where previews are not allowed"
        );
        assert_eq!(asked, [(3, 2), (10, 6), (10, 6)]);
        let frame = &picture.cpu.as_ref().unwrap().frame;
        assert_eq!((frame.width, frame.height), (10, 6));
    }

    /// Texels are interpolated channel by channel as a float would be, to a level.
    #[test]
    fn texels_are_interpolated_channel_by_channel() {
        let (a, b) = ([0, 255, 100, 7], [255, 0, 101, 200]);
        for k in 0..=64 {
            let t = k as f32 / 64.0;
            let got = lerp_texel(a, b, t);
            for c in 0..4 {
                let want = a[c] as f32 + (b[c] as f32 - a[c] as f32) * t;
                assert!((got[c] as f32 - want).abs() <= 0.51, "{t}: {got:?}");
            }
        }
        assert_eq!(lerp_texel(a, b, 0.0), a);
        assert_eq!(lerp_texel(a, b, 1.0), b);
    }

    /// A frame drawn on the CPU reaches an 8-bit target as the still's PNG levels,
    /// copied or through the display pass, and is encoded again when it or the display
    /// changes.
    #[test]
    fn a_cpu_frame_reaches_the_target_as_the_stills_levels() {
        let Some(gpu) = test_gpu() else { return };
        let (w, h) = (7, 3);
        let format = wgpu::TextureFormat::Bgra8Unorm;
        let target = gpu.texture_2d(
            "a window's surface, as a test makes one",
            (w, h),
            format,
            wgpu::TextureUsages::RENDER_ATTACHMENT
                | wgpu::TextureUsages::COPY_DST
                | wgpu::TextureUsages::COPY_SRC,
        );
        let mut display = DisplayPass::new(&gpu, format).unwrap();
        let mut picture = Picture::new(&gpu, (w, h)).unwrap();
        let fill = |picture: &mut Picture, scale: f32| {
            for (k, p) in picture.frame().pixels.iter_mut().enumerate() {
                *p = scale * glam::Vec3::new(k as f32, 0.5 * k as f32, 0.1) / 10.0;
            }
        };
        // What the still writes, in the target's order.
        let still = |picture: &mut Picture, display: Display| -> Vec<u8> {
            let rgb = picture.frame().to_srgb8(display.exposure, display.tone);
            rgb.chunks(3)
                .flat_map(|c| [c[2], c[1], c[0], 255])
                .collect()
        };
        let read = |target: &wgpu::Texture| gpu.read_texture("the target", target, w, h).unwrap();
        for (scale, exposure, tone) in [
            (1.0, 1.0, ToneMap::Clamp),
            (1.0, 0.3, ToneMap::Exponential),
            (2.0, 0.3, ToneMap::Exponential),
            (2.0, 0.3, ToneMap::Aces),
        ] {
            display.display = Display { exposure, tone };
            fill(&mut picture, scale);
            let expected = still(&mut picture, display.display);
            assert!(picture.put_onto(&gpu, &target, Some(TexelOrder::Bgra), &mut display));
            assert_eq!(read(&target), expected, "{scale} {exposure} {tone:?}");
            // A target that takes no copies: the display pass, within a level.
            assert!(!picture.put_onto(&gpu, &target, None, &mut display));
            gpu.run("the display pass", |encoder| {
                let mut pass = cleared_pass(
                    encoder,
                    &target.create_view(&Default::default()),
                    "t",
                    wgpu::Color::BLACK,
                );
                display.draw(&mut pass);
            })
            .unwrap();
            for (a, b) in read(&target).iter().zip(&expected) {
                assert!(a.abs_diff(*b) <= 1, "{a} {b}");
            }
        }
        // The screenshot is the frame itself.
        assert_eq!(
            &picture.read(&gpu).unwrap(),
            &picture.cpu.as_ref().unwrap().frame
        );
        // Drawn on the GPU, the picture is the texture again: no texels to copy.
        picture.draw_over(
            &mut gpu.device.create_command_encoder(&Default::default()),
            |_| {},
        );
        assert!(!picture.put_onto(&gpu, &target, Some(TexelOrder::Bgra), &mut display));
    }
}
