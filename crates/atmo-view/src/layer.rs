//! The panel as a layer of its own: egui draws it into a texture only when it may look
//! different (a person acts on it, egui asks, or [`REFRESH`] has passed), and every
//! frame shows that texture over the picture, within the panel's rectangle alone.
//!
//! Why: on a software adapter (lavapipe, the only one on a machine without a GPU)
//! rasterising egui's few thousand small triangles took 15-30 ms a frame (measured:
//! `atmo view sky --table ... --backend cpu`, 54 ms a frame with the panel against 34 ms
//! with it hidden), more than the sky itself; compositing the cached layer costs one
//! texel read and a blend per pixel of the panel's rectangle. For the same reason the
//! panel's window casts no shadow (egui's soft shadow is a wide band of blended
//! triangles: a third of a redraw of the stage's panel, 27 against 19 ms of the frame's
//! present), and values that change on their own are refreshed four times a second.

use std::time::{Duration, Instant};

use atmo_gpu::display::cleared_pass;
use atmo_gpu::{Gpu, GpuError};

use crate::pixels::PanelPixels;

/// How stale the panel may get while nobody touches it: the values it shows (the
/// altitude of a flight, the frame time) are redrawn at least this often.
pub const REFRESH: Duration = Duration::from_millis(250);

/// Points around the panel's window that it may draw on: its stroke (it casts no
/// shadow, [`no_shadows`]).
const MARGIN_POINTS: f32 = 2.0;

/// egui's style without the windows' and popups' shadows (see the module's doc).
pub fn no_shadows(style: &mut egui::Style) {
    style.visuals.window_shadow = egui::epaint::Shadow::NONE;
    style.visuals.popup_shadow = egui::epaint::Shadow::NONE;
}

/// The panel's texture (the window's size and format, premultiplied alpha, transparent
/// outside the panel) and the pass that puts it over a frame.
pub struct PanelLayer {
    texture: wgpu::Texture,
    view: wgpu::TextureView,
    pipeline: wgpu::RenderPipeline,
    group: wgpu::BindGroup,
    /// The panel's pixels (x, y, width, height) in the window, once drawn.
    rect: Option<[u32; 4]>,
    /// When the layer is to be drawn again; `None`: at the next frame.
    next: Option<Instant>,
}

impl PanelLayer {
    /// A layer for a window of `size` pixels whose surface has `format`.
    pub fn new(gpu: &Gpu, format: wgpu::TextureFormat, size: (u32, u32)) -> Result<Self, GpuError> {
        let source = atmo_gpu::wgsl::source("screen.wgsl") + include_str!("panel_layer.wgsl");
        let module = gpu.shader("panel_layer.wgsl", &source)?;
        let pipeline = gpu.screen_pipeline(
            "the panel layer",
            &module,
            None,
            &[Some(wgpu::ColorTargetState {
                format,
                blend: Some(wgpu::BlendState::PREMULTIPLIED_ALPHA_BLENDING),
                write_mask: wgpu::ColorWrites::ALL,
            })],
            None,
            1,
        )?;
        let texture = gpu.texture_2d(
            "the panel layer",
            (size.0, size.1),
            format,
            wgpu::TextureUsages::RENDER_ATTACHMENT
                | wgpu::TextureUsages::TEXTURE_BINDING
                | wgpu::TextureUsages::COPY_SRC,
        );
        let view = texture.create_view(&Default::default());
        let group = gpu.bind_group(
            &pipeline.get_bind_group_layout(0),
            &[wgpu::BindingResource::TextureView(&view)],
        );
        Ok(PanelLayer {
            texture,
            view,
            pipeline,
            group,
            rect: None,
            next: None,
        })
    }

    /// Whether the layer is to be drawn again at `now`.
    pub fn due(&self, now: Instant) -> bool {
        self.next.is_none_or(|next| now >= next)
    }

    /// Asks for the layer to be drawn at the next frame.
    pub fn invalidate(&mut self) {
        self.next = None;
    }

    /// Whether the window's pixel `(x, y)` is over the panel (or its shadow).
    pub fn covers(&self, (x, y): (f64, f64)) -> bool {
        self.rect.is_some_and(|[left, top, width, height]| {
            let (x, y) = (x - left as f64, y - top as f64);
            (0.0..width as f64).contains(&x) && (0.0..height as f64).contains(&y)
        })
    }

    /// Records egui's drawing of the panel into the layer (cleared first): `draw`
    /// records into the pass. `window` is the panel's rectangle in points, `points`
    /// pixels a point; egui asks to be run again in `repaint` at the latest.
    pub fn record(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        window: Option<egui::Rect>,
        points: f32,
        repaint: Duration,
        draw: impl FnOnce(&mut wgpu::RenderPass<'static>),
    ) {
        let mut pass = cleared_pass(
            encoder,
            &self.view,
            "the panel layer",
            wgpu::Color::TRANSPARENT,
        )
        .forget_lifetime();
        draw(&mut pass);
        let (width, height) = (self.texture.width(), self.texture.height());
        self.rect = window.map(|rect| {
            let rect = rect.expand(MARGIN_POINTS) * points;
            let left = (rect.min.x.floor().max(0.0) as u32).min(width);
            let top = (rect.min.y.floor().max(0.0) as u32).min(height);
            let right = (rect.max.x.ceil().max(0.0) as u32).clamp(left, width);
            let bottom = (rect.max.y.ceil().max(0.0) as u32).clamp(top, height);
            [left, top, right - left, bottom - top]
        });
        self.next = Some(Instant::now() + repaint.min(REFRESH));
    }

    /// The layer's texels within the panel's rectangle, read back (after what drew it
    /// was submitted), for a window shown through its own pixels; `None` before the
    /// panel was drawn or where it covers nothing.
    pub fn read(&self, gpu: &Gpu) -> Result<Option<PanelPixels>, GpuError> {
        let Some(rect @ [x, y, w, h]) = self.rect.filter(|r| r[2] > 0 && r[3] > 0) else {
            return Ok(None);
        };
        let origin = wgpu::Origin3d { x, y, z: 0 };
        let bytes = gpu.read_texture_region("the panel layer", &self.texture, origin, (w, h, 1))?;
        let texels = bytes
            .as_chunks::<4>()
            .0
            .iter()
            .map(|t| [t[0], t[1], t[2], t[3]])
            .collect();
        Ok(Some(PanelPixels { rect, texels }))
    }

    /// Records the layer over what `pass` (into the window's surface) holds, within the
    /// panel's rectangle.
    pub fn draw(&self, pass: &mut wgpu::RenderPass<'_>) {
        let Some([x, y, width, height]) = self.rect.filter(|r| r[2] > 0 && r[3] > 0) else {
            return;
        };
        pass.set_scissor_rect(x, y, width, height);
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &self.group, &[]);
        pass.draw(0..3, 0..1);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use atmo::image::{Display, Frame, ToneMap};
    use atmo_gpu::display::{picture_texture, write_frame, DisplayPass};

    #[test]
    fn the_layer_is_put_over_the_frame_within_the_panel_and_redrawn_when_due() {
        let Some(gpu) = crate::test_gpu() else {
            return;
        };
        let (w, h) = (32, 24);
        let format = wgpu::TextureFormat::Rgba32Float;
        let mut layer = PanelLayer::new(&gpu, format, (w, h)).unwrap();
        assert!(layer.due(Instant::now()), "a new layer is drawn at once");
        // The "panel": an opaque 0.25 everywhere in the layer, shown through the display
        // pass (clamped, sRGB-encoded: the target stores what it is given).
        let mut grey = Frame::new(w, h);
        grey.pixels.fill(glam::Vec3::splat(0.25));
        let picture = picture_texture(&gpu, w, h).unwrap();
        write_frame(&gpu, &picture, &grey);
        let mut panel = DisplayPass::new(&gpu, format).unwrap();
        panel.display = Display {
            exposure: 1.0,
            tone: ToneMap::Clamp,
        };
        panel.prepare(&gpu, &picture.create_view(&Default::default()));
        let target = picture_texture(&gpu, w, h).unwrap();
        let target_view = target.create_view(&Default::default());
        let blue = wgpu::Color {
            r: 0.0,
            g: 0.0,
            b: 1.0,
            a: 1.0,
        };
        // A window from (20, 20) to (40, 32) points at a quarter pixel a point: with its
        // stroke's 2 points, the pixels [4, 11) x [4, 9).
        let window = egui::Rect::from_min_max(egui::pos2(20.0, 20.0), egui::pos2(40.0, 32.0));
        gpu.run("the layer", |encoder| {
            layer.record(encoder, Some(window), 0.25, Duration::MAX, |pass| {
                panel.draw(pass)
            });
            let mut pass = cleared_pass(encoder, &target_view, "the frame", blue);
            layer.draw(&mut pass);
        })
        .unwrap();
        assert!(!layer.due(Instant::now()), "drawn: not due for {REFRESH:?}");
        assert!(layer.due(Instant::now() + REFRESH));
        layer.invalidate();
        assert!(layer.due(Instant::now()));
        let frame = gpu.read_frame("the frame", &target, (w, h)).unwrap();
        let encoded = atmo::image::srgb_encode(0.25);
        for (x, y, inside) in [
            (4, 4, true),
            (10, 8, true),
            (3, 4, false),
            (4, 3, false),
            (11, 8, false),
            (10, 9, false),
        ] {
            let want = if inside {
                glam::Vec3::splat(encoded)
            } else {
                glam::Vec3::Z
            };
            let got = frame.pixels[(y * w + x) as usize];
            assert!((got - want).abs().max_element() < 1e-5, "({x}, {y}): {got}");
            assert_eq!(layer.covers((x as f64 + 0.5, y as f64 + 0.5)), inside);
        }
    }
}
