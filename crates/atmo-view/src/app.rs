//! The window: winit's event loop, the surface, the egui panel, the frame loop, and
//! screenshots.

use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

use anyhow::{Context, Result};
use atmo::image::TexelOrder;
use atmo::Error;
use atmo_gpu::device::choose_adapter;
use atmo_gpu::display::{cleared_pass, loaded_pass, DisplayPass};
use atmo_gpu::{Gpu, GpuError};
use winit::application::ApplicationHandler;
use winit::dpi::PhysicalSize;
use winit::event::{ElementState, KeyEvent, MouseButton, WindowEvent};
use winit::event_loop::{ActiveEventLoop, EventLoop};
use winit::keyboard::{KeyCode, PhysicalKey};
use winit::window::{Window, WindowId};

use crate::input::{Input, Key};
use crate::layer::PanelLayer;
use crate::pixels::WindowPixels;
use crate::{Mode, Options, Picture};

/// `eprintln!` that never panics: where standard error fails (a full disk behind
/// `2> file`) the message is lost and the window goes on.
macro_rules! note {
    ($($arg:tt)*) => {{
        let _ = writeln!(std::io::stderr(), $($arg)*);
    }};
}

/// Opens the window and runs until it is closed or [`Options::frames`] are drawn. Bad
/// input found before the window is up (a script naming a parameter the mode lacks,
/// no display, no adapter) is an `atmo::Error`; once it is up, a refused edit is shown
/// in the window and the last good state stays.
pub fn run(options: Options, mode: Box<dyn Mode>) -> Result<Timings> {
    mode.check_script(&options.script)?;
    if let Some(path) = &options.screenshot {
        atmo::image::ImageKind::of(path)?;
    }
    let event_loop = EventLoop::new().map_err(|e| {
        Error::Invalid(format!(
            "cannot open a window ({e}): atmo view needs a display (DISPLAY); on a \
             machine without one, run it under xvfb-run"
        ))
    })?;
    let mut app = App {
        options,
        mode: Some(mode),
        window: None,
        error: None,
        timings: Timings::default(),
    };
    event_loop.run_app(&mut app)?;
    if let Some(mode) = app
        .window
        .as_mut()
        .map(|w| &mut w.mode)
        .or(app.mode.as_mut())
    {
        match mode.close() {
            Ok(figures) => app.timings.figures = figures,
            Err(e) => {
                app.error.get_or_insert(e);
            }
        }
    }
    match app.error {
        Some(e) => Err(e),
        None => Ok(app.timings),
    }
}

/// What each frame took, ms, in order: from one frame's start to the next's (drawing,
/// display and presentation), and the method's own draw on the frames where it drew
/// (on the GPU backend, the recording of its passes; their execution falls in the
/// frame time). A frame where nothing the mode shows changed keeps its picture and has
/// no method time.
#[derive(Debug, Clone, Default)]
pub struct Timings {
    pub frame_ms: Vec<f64>,
    pub method_ms: Vec<f64>,
    /// The mode's own figures at the end ([`crate::Mode::close`]).
    pub figures: crate::Figures,
}

struct App {
    options: Options,
    /// The mode, until the window is up.
    mode: Option<Box<dyn Mode>>,
    window: Option<Running>,
    /// What ended the run, reported once the loop returns.
    error: Option<anyhow::Error>,
    timings: Timings,
}

/// Where the frames go.
enum Screen {
    /// The adapter's surface: a picture on the GPU, shown by the display pass or
    /// (levels made on the CPU) copied in.
    Surface(wgpu::Surface<'static>),
    /// The window's own pixels: a picture drawn on the CPU ([`crate::pixels`]).
    Pixels(WindowPixels),
}

/// The window once it is up.
struct Running {
    window: Arc<Window>,
    screen: Screen,
    /// The surface's configuration; with [`Screen::Pixels`], the window's size and the
    /// panel layer's format.
    config: wgpu::SurfaceConfiguration,
    gpu: Gpu,
    mode: Box<dyn Mode>,
    picture: Picture,
    display: DisplayPass,
    /// The surface's texel order where it takes copies of 8-bit texels: a frame drawn
    /// on the CPU is copied into it, levels made on the CPU (else it goes through the
    /// display pass).
    direct: Option<TexelOrder>,
    /// The panel, drawn by egui only when it may have changed.
    layer: PanelLayer,
    egui: egui_winit::State,
    egui_renderer: egui_wgpu::Renderer,
    /// Inputs from the window since the last frame.
    pending: Vec<Input>,
    /// Where the left button went down over the picture, while it is down.
    drag_from: Option<(f64, f64)>,
    /// The light the right button aims, while it is down.
    aiming: Option<usize>,
    cursor: (f64, f64),
    frame: u64,
    show_panel: bool,
    /// The last refusal or failure, shown in the panel.
    message: Option<String>,
    /// The last screenshot's still command.
    still: Option<String>,
    /// A screenshot asked for, taken after this frame's draw.
    shot: Option<PathBuf>,
    last_frame: Option<Instant>,
    frame_ms: f64,
    /// The method's time on the last frame it drew, and whether this frame drew.
    method_ms: f64,
    drew: bool,
}

impl ApplicationHandler for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.window.is_some() {
            return;
        }
        let Some(mode) = self.mode.take() else {
            return;
        };
        match open(event_loop, &self.options, mode) {
            Ok(running) => self.window = Some(running),
            Err(e) => {
                self.error = Some(e);
                event_loop.exit();
            }
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _: WindowId, event: WindowEvent) {
        let Some(r) = &mut self.window else { return };
        let response = r.egui.on_window_event(&r.window, &event);
        let consumed = response.consumed;
        if let WindowEvent::CursorMoved { position, .. } = event {
            r.cursor = (position.x, position.y);
        }
        // What egui must see drawn: an event it took or one over the panel (a pointer
        // elsewhere is the picture's; the layer's refresh clears a hover left behind).
        if response.repaint && (consumed || r.layer.covers(r.cursor)) {
            r.layer.invalidate();
        }
        match event {
            WindowEvent::CloseRequested => event_loop.exit(),
            WindowEvent::Resized(size) => r.resize(size),
            WindowEvent::RedrawRequested => match r.frame(&self.options) {
                Ok(more) => {
                    // The first frame has no predecessor to time from.
                    if r.frame > 1 {
                        self.timings.frame_ms.push(r.frame_ms);
                    }
                    if r.drew {
                        self.timings.method_ms.push(r.method_ms);
                    }
                    if !more {
                        event_loop.exit();
                    }
                }
                Err(e) => {
                    self.error = Some(e);
                    event_loop.exit();
                }
            },
            WindowEvent::KeyboardInput {
                event:
                    KeyEvent {
                        physical_key: PhysicalKey::Code(code),
                        state: ElementState::Pressed,
                        ..
                    },
                ..
            } if !consumed => {
                if let Some(key) = key_of(code) {
                    r.pending.push(Input::Key(key));
                }
            }
            WindowEvent::MouseInput {
                state,
                button: MouseButton::Left,
                ..
            } => {
                r.drag_from = (state == ElementState::Pressed
                    && !r.egui.egui_ctx().egui_wants_pointer_input())
                .then_some(r.cursor);
            }
            WindowEvent::MouseInput {
                state,
                button: MouseButton::Right,
                ..
            } => {
                let free = !r.egui.egui_ctx().egui_wants_pointer_input();
                r.aiming = r
                    .mode
                    .aimed_light()
                    .filter(|_| free && state == ElementState::Pressed);
                if let Some(light) = r.aiming {
                    r.pending
                        .push(Input::Aim(light, r.cursor.0 as f32, r.cursor.1 as f32));
                }
            }
            WindowEvent::CursorMoved { position, .. } => {
                if let Some(light) = r.aiming {
                    r.pending
                        .push(Input::Aim(light, position.x as f32, position.y as f32));
                }
                if let Some((x, y)) = r.drag_from {
                    r.pending.push(Input::Drag(
                        (position.x - x) as f32,
                        (position.y - y) as f32,
                    ));
                    r.drag_from = Some(r.cursor);
                }
            }
            _ => {}
        }
    }

    fn about_to_wait(&mut self, _: &ActiveEventLoop) {
        if let Some(r) = &self.window {
            r.window.request_redraw();
        }
    }
}

/// The viewer's key for a physical key.
fn key_of(code: KeyCode) -> Option<Key> {
    Some(match code {
        KeyCode::KeyR => Key::Climb,
        KeyCode::KeyF => Key::Descend,
        KeyCode::Equal | KeyCode::NumpadAdd => Key::Faster,
        KeyCode::Minus | KeyCode::NumpadSubtract => Key::Slower,
        KeyCode::ArrowLeft => Key::SunLeft,
        KeyCode::ArrowRight => Key::SunRight,
        KeyCode::ArrowUp => Key::SunUp,
        KeyCode::ArrowDown => Key::SunDown,
        KeyCode::Space => Key::Animate,
        KeyCode::KeyS => Key::Save,
        KeyCode::KeyW => Key::Wind,
        KeyCode::KeyP => Key::Screenshot,
        KeyCode::KeyE => Key::ScreenshotExr,
        KeyCode::Tab => Key::Panel,
        _ => return None,
    })
}

/// The order of the channels of an 8-bit surface format that stores what it is given
/// (whether it is called sRGB or not, the bytes are the encoded levels).
fn texel_order(format: wgpu::TextureFormat) -> Option<TexelOrder> {
    match format {
        wgpu::TextureFormat::Bgra8Unorm | wgpu::TextureFormat::Bgra8UnormSrgb => {
            Some(TexelOrder::Bgra)
        }
        wgpu::TextureFormat::Rgba8Unorm | wgpu::TextureFormat::Rgba8UnormSrgb => {
            Some(TexelOrder::Rgba)
        }
        _ => None,
    }
}

/// A GPU error found while opening the window: what the user can act on is bad input.
fn opening(e: GpuError) -> anyhow::Error {
    match e {
        GpuError::Atmo(e) => e.into(),
        GpuError::NoAdapter { .. } | GpuError::NoMatch { .. } | GpuError::MissingFeature { .. } => {
            Error::Invalid(format!("{e} (--adapter names another)")).into()
        }
        e => e.into(),
    }
}

/// The window, its surface and device, the mode and the panel.
fn open(
    event_loop: &ActiveEventLoop,
    options: &Options,
    mut mode: Box<dyn Mode>,
) -> Result<Running> {
    let (width, height) = options.size;
    let attributes = Window::default_attributes()
        .with_title("atmo view")
        .with_inner_size(PhysicalSize::new(width, height));
    let window = Arc::new(
        event_loop
            .create_window(attributes)
            .context("cannot create the window")?,
    );
    let instance = wgpu::Instance::new(wgpu::InstanceDescriptor::new_with_display_handle_from_env(
        Box::new(event_loop.owned_display_handle()),
    ));
    let surface = instance
        .create_surface(window.clone())
        .context("cannot draw into the window")?;
    let adapter =
        choose_adapter(&instance, options.adapter.as_deref(), Some(&surface)).map_err(opening)?;
    let gpu = Gpu::open(&adapter).map_err(opening)?;
    let on_gpu = options.backend.runs_on(&gpu);
    note!(
        "atmo: the window on {}; the picture drawn on the {}",
        gpu.describe(),
        if on_gpu { "GPU" } else { "CPU" }
    );
    mode.draw_on_gpu(on_gpu);
    let size = window.inner_size();
    let mut config = surface
        .get_default_config(&adapter, size.width.max(1), size.height.max(1))
        .context("the adapter cannot present to this window")?;
    // A scripted run draws as fast as it can; a person's, at the display's rate.
    if options.frames.is_some() {
        config.present_mode = wgpu::PresentMode::AutoNoVsync;
    }
    let copies = surface.get_capabilities(&adapter).usages;
    let direct =
        texel_order(config.format).filter(|_| copies.contains(wgpu::TextureUsages::COPY_DST));
    // A picture drawn on the CPU goes into the window's own pixels where the window
    // system gives them; else, as a GPU picture, through the adapter's surface.
    let pixels = (!on_gpu)
        .then(|| WindowPixels::new(window.clone(), (config.width, config.height)))
        .and_then(|made| {
            made.map_err(|e| note!("atmo view: {e}; shown through the adapter instead"))
                .ok()
        });
    let screen = match pixels {
        Some(pixels) => {
            // The panel's layer in the order of the window's pixels, blended as stored.
            config.format = wgpu::TextureFormat::Bgra8Unorm;
            Screen::Pixels(pixels)
        }
        None => {
            if direct.is_some() {
                config.usage |= wgpu::TextureUsages::COPY_DST;
            }
            surface.configure(&gpu.device, &config);
            Screen::Surface(surface)
        }
    };
    let display = DisplayPass::new(&gpu, config.format).map_err(opening)?;
    let layer =
        PanelLayer::new(&gpu, config.format, (config.width, config.height)).map_err(opening)?;
    let picture = Picture::new(&gpu, (config.width, config.height)).map_err(opening)?;
    let context = egui::Context::default();
    context.all_styles_mut(crate::layer::no_shadows);
    let egui = egui_winit::State::new(
        context,
        egui::ViewportId::ROOT,
        &window,
        Some(window.scale_factor() as f32),
        None,
        Some(gpu.limits().max_texture_dimension_2d as usize),
    );
    let egui_renderer = egui_wgpu::Renderer::new(&gpu.device, config.format, Default::default());
    Ok(Running {
        window,
        screen,
        config,
        gpu,
        mode,
        picture,
        display,
        direct,
        layer,
        egui,
        egui_renderer,
        pending: Vec::new(),
        drag_from: None,
        aiming: None,
        cursor: (0.0, 0.0),
        frame: 0,
        show_panel: true,
        message: None,
        still: None,
        shot: None,
        last_frame: None,
        frame_ms: 0.0,
        method_ms: 0.0,
        drew: false,
    })
}

impl Running {
    fn resize(&mut self, size: PhysicalSize<u32>) {
        if size.width == 0 || size.height == 0 {
            return;
        }
        (self.config.width, self.config.height) = (size.width, size.height);
        match &mut self.screen {
            Screen::Surface(surface) => surface.configure(&self.gpu.device, &self.config),
            Screen::Pixels(pixels) => {
                if let Err(e) = pixels.resize((size.width, size.height)) {
                    self.message = Some(e.to_string());
                }
            }
        }
        let made = Picture::new(&self.gpu, (size.width, size.height)).and_then(|picture| {
            let layer = PanelLayer::new(&self.gpu, self.config.format, (size.width, size.height))?;
            Ok((picture, layer))
        });
        match made {
            Ok((picture, layer)) => (self.picture, self.layer) = (picture, layer),
            Err(e) => self.message = Some(e.to_string()),
        }
    }

    /// Draws one frame: the inputs of this frame, the picture, the panel; after the
    /// last of [`Options::frames`], the screenshot. `false` when the run is over.
    fn frame(&mut self, options: &Options) -> Result<bool> {
        let inputs: Vec<Input> = options
            .script
            .at(self.frame)
            .cloned()
            .chain(self.pending.drain(..))
            .collect();
        for input in inputs {
            self.apply(&input);
        }
        if let Err(e) = self.mode.update() {
            self.refuse(e);
        }
        let mut encoder = self
            .gpu
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("a frame"),
            });
        let start = Instant::now();
        // Previews while the picture changes, but never the last frame of a run nor
        // one a screenshot is taken of.
        let whole = options.frames == Some(self.frame + 1) || self.shot.is_some();
        self.picture.preview = Some(options.preview).filter(|&k| k > 1 && !whole);
        // The window's texels alone, where that is all it takes of this frame (a surface
        // of another size than the picture's takes the frame, uploaded).
        let fits = (self.config.width, self.config.height) == self.picture.size;
        let order = match self.screen {
            Screen::Pixels(_) => Some(TexelOrder::Bgra),
            Screen::Surface(_) => self.direct.filter(|_| fits),
        };
        self.picture.texels_only = order.filter(|_| !whole);
        let drawn = self.mode.draw(&self.gpu, &mut encoder, &mut self.picture);
        self.drew = matches!(drawn, Ok(true));
        if self.drew {
            self.method_ms = start.elapsed().as_secs_f64() * 1e3;
        }
        if let Err(e) = drawn {
            self.refuse(e);
        }
        self.show(encoder)?;
        // After the frame's commands are submitted: a GPU picture is read back whole.
        if let Some(path) = self.shot.take() {
            if let Err(e) = self.screenshot(&path) {
                self.refuse(e);
            }
        }
        let now = Instant::now();
        if let Some(last) = self.last_frame.replace(now) {
            self.frame_ms = (now - last).as_secs_f64() * 1e3;
        }
        self.frame += 1;
        if options.frames == Some(self.frame) {
            if let Some(path) = &options.screenshot {
                self.screenshot(path)?;
            }
            return Ok(false);
        }
        Ok(true)
    }

    fn apply(&mut self, input: &Input) {
        match input {
            Input::Key(Key::Panel) => {
                self.show_panel = !self.show_panel;
                self.layer.invalidate();
            }
            Input::Key(key @ (Key::Screenshot | Key::ScreenshotExr)) => {
                let kind = if *key == Key::Screenshot {
                    "png"
                } else {
                    "exr"
                };
                // Taken once this frame's picture is drawn, whole.
                self.shot = Some(PathBuf::from(format!("atmo-view-{:04}.{kind}", self.frame)));
            }
            input => {
                if let Err(e) = self.mode.apply(input) {
                    self.refuse(e);
                }
            }
        }
    }

    /// Shows a refusal in the panel and on stderr; the state stays as it was.
    fn refuse(&mut self, e: anyhow::Error) {
        note!("atmo view: {e:#}");
        self.message = Some(format!("{e:#}"));
        self.layer.invalidate();
    }

    /// Writes the picture to `path` as the still command would (atomically), and prints
    /// that command on stdout.
    fn screenshot(&mut self, path: &Path) -> Result<()> {
        let frame = self.picture.read(&self.gpu)?;
        let display = self.mode.display();
        frame.write(path, display.exposure, display.tone)?;
        let still = self.mode.still_command(path, self.picture.size);
        let mut stdout = std::io::stdout().lock();
        writeln!(stdout, "{still}")
            .and_then(|()| stdout.flush())
            .context("standard output: the still's command")?;
        self.still = Some(still);
        self.layer.invalidate();
        Ok(())
    }

    /// The picture in the window, the panel over it; the frame's commands submitted.
    fn show(&mut self, encoder: wgpu::CommandEncoder) -> Result<()> {
        match self.screen {
            Screen::Surface(_) => self.show_on_surface(encoder),
            Screen::Pixels(_) => self.show_in_pixels(encoder),
        }
    }

    /// [`Running::show`] through the window's own pixels: the panel, where it is due,
    /// drawn into its layer and read back; the picture's levels and the panel's layer
    /// put into the pixels on the CPU.
    fn show_in_pixels(&mut self, mut encoder: wgpu::CommandEncoder) -> Result<()> {
        let redraw = self.show_panel && self.layer.due(Instant::now());
        let extra = if redraw {
            self.draw_panel(&mut encoder)
        } else {
            Vec::new()
        };
        self.gpu
            .queue
            .submit(extra.into_iter().chain([encoder.finish()]));
        let Screen::Pixels(pixels) = &mut self.screen else {
            unreachable!("shown through the window's pixels")
        };
        if redraw {
            pixels.panel = self.layer.read(&self.gpu)?;
        }
        let texels = self.picture.texels(self.mode.display(), TexelOrder::Bgra);
        pixels.show(&self.window, texels, self.show_panel)
    }

    /// [`Running::show`] on the adapter's surface: a CPU frame's levels copied, or the
    /// texture through the display pass.
    fn show_on_surface(&mut self, mut encoder: wgpu::CommandEncoder) -> Result<()> {
        let Screen::Surface(surface) = &self.screen else {
            unreachable!("shown on the surface")
        };
        let texture = match surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(t)
            | wgpu::CurrentSurfaceTexture::Suboptimal(t) => t,
            wgpu::CurrentSurfaceTexture::Outdated | wgpu::CurrentSurfaceTexture::Lost => {
                surface.configure(&self.gpu.device, &self.config);
                self.gpu.queue.submit([encoder.finish()]);
                return Ok(());
            }
            other => {
                // Occluded or timed out: the picture is drawn, nothing shown this time.
                note!("atmo view: the window's surface: {other:?}");
                self.gpu.queue.submit([encoder.finish()]);
                return Ok(());
            }
        };
        let target = texture.texture.create_view(&Default::default());
        self.display.display = self.mode.display();
        let copied =
            self.picture
                .put_onto(&self.gpu, &texture.texture, self.direct, &mut self.display);
        let extra = if self.show_panel && self.layer.due(Instant::now()) {
            self.draw_panel(&mut encoder)
        } else {
            Vec::new()
        };
        {
            let mut pass = if copied {
                loaded_pass(&mut encoder, &target, "the window")
            } else {
                let mut pass =
                    cleared_pass(&mut encoder, &target, "the window", wgpu::Color::BLACK);
                self.display.draw(&mut pass);
                pass
            };
            if self.show_panel {
                self.layer.draw(&mut pass);
            }
        }
        self.gpu
            .queue
            .submit(extra.into_iter().chain([encoder.finish()]));
        self.window.pre_present_notify();
        self.gpu.queue.present(texture);
        Ok(())
    }

    /// Runs egui and records its drawing of the panel into the layer; the command
    /// buffers egui needs submitted before `encoder` come back. The panel's edits are
    /// inputs of the next frame, applied as any other.
    fn draw_panel(&mut self, encoder: &mut wgpu::CommandEncoder) -> Vec<wgpu::CommandBuffer> {
        let raw = self.egui.take_egui_input(&self.window);
        let context = self.egui.egui_ctx().clone();
        let (mut edits, mut window) = (Vec::new(), None);
        let output = context.run_pass(raw, |ctx| (edits, window) = self.panel(ctx));
        self.egui
            .handle_platform_output(&self.window, output.platform_output);
        let primitives = context.tessellate(output.shapes, output.pixels_per_point);
        let screen = egui_wgpu::ScreenDescriptor {
            size_in_pixels: [self.config.width, self.config.height],
            pixels_per_point: output.pixels_per_point,
        };
        // egui's texture changes: each applied (its deltas must not be dropped unread).
        let mut textures = output.textures_delta;
        for (id, deltas) in textures.set.drain() {
            for delta in &deltas {
                self.egui_renderer
                    .update_texture(&self.gpu.device, &self.gpu.queue, id, delta);
            }
        }
        let extra = self.egui_renderer.update_buffers(
            &self.gpu.device,
            &self.gpu.queue,
            encoder,
            &primitives,
            &screen,
        );
        let repaint = output
            .viewport_output
            .get(&egui::ViewportId::ROOT)
            .map_or(crate::layer::REFRESH, |v| v.repaint_delay);
        let renderer = &self.egui_renderer;
        self.layer
            .record(encoder, window, output.pixels_per_point, repaint, |pass| {
                renderer.render(pass, &primitives, &screen)
            });
        for id in textures.free.drain() {
            self.egui_renderer.free_texture(&id);
        }
        self.pending.extend(edits);
        extra
    }

    /// The panel: the mode's parameters, the times, the last message and still command;
    /// its edits and the rectangle it covers, points.
    fn panel(&mut self, ctx: &egui::Context) -> (Vec<Input>, Option<egui::Rect>) {
        let mut edits = Vec::new();
        let shown = egui::Window::new(self.mode.title())
            .default_width(300.0)
            .show(ctx, |ui| {
                edits = self.mode.panel(ui);
                ui.separator();
                ui.label(format!(
                    "frame {:.1} ms, method {:.1} ms ({})",
                    self.frame_ms,
                    self.method_ms,
                    self.gpu.describe()
                ));
                ui.horizontal(|ui| {
                    ui.label("screenshot and still command:");
                    if ui.button("PNG (P)").clicked() {
                        edits.push(Input::Key(Key::Screenshot));
                    }
                    if ui.button("EXR (E)").clicked() {
                        edits.push(Input::Key(Key::ScreenshotExr));
                    }
                });
                if let Some(still) = &self.still {
                    ui.label(egui::RichText::new(still).monospace().small());
                }
                if let Some(message) = &self.message {
                    ui.colored_label(egui::Color32::from_rgb(255, 120, 100), message);
                }
                ui.label(format!(
                    "{}; P / E: screenshot (PNG / EXR); Tab: panel",
                    self.mode.help()
                ));
            });
        (edits, shown.map(|s| s.response.rect))
    }
}
