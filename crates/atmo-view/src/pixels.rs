//! The window's own pixels, for a picture drawn on the CPU: its 8-bit levels go
//! straight into a buffer that softbuffer hands to the window system (on X11 as shared
//! memory), and the panel's layer, read back from the adapter whenever egui redraws
//! it, is blended over it on the CPU.
//!
//! Why not the adapter's surface: on a machine without a GPU that surface is
//! lavapipe's, and Mesa 22.3 (Debian 12) presents it on X11 by sending the whole
//! image through the X connection (`xcb_put_image`, no shared memory): 4.5-5 ms of a
//! core for 1280 x 720 on top of the copies into and out of the swapchain image,
//! against under a millisecond through shared memory (docs/view.md, "Where it draws").

use std::num::NonZeroU32;
use std::sync::Arc;

use anyhow::{anyhow, Result};
use winit::window::Window;

/// The panel's layer on the CPU: its rectangle in the window (x, y, width, height,
/// pixels) and the layer's premultiplied texels there, row by row, in the order
/// blue, green, red, alpha.
#[derive(Debug, Clone, PartialEq)]
pub struct PanelPixels {
    pub rect: [u32; 4],
    pub texels: Vec<[u8; 4]>,
}

/// A window shown through its own pixels.
pub struct WindowPixels {
    surface: softbuffer::Surface<Arc<Window>, Arc<Window>>,
    size: (u32, u32),
    /// The panel as last drawn.
    pub panel: Option<PanelPixels>,
}

impl WindowPixels {
    /// The pixels of `window`, `size` of them.
    pub fn new(window: Arc<Window>, size: (u32, u32)) -> Result<WindowPixels> {
        let context = softbuffer::Context::new(window.clone())
            .map_err(|e| anyhow!("cannot reach the window system's pixels: {e}"))?;
        let surface = softbuffer::Surface::new(&context, window)
            .map_err(|e| anyhow!("cannot draw into the window's pixels: {e}"))?;
        let mut pixels = WindowPixels {
            surface,
            size: (0, 0),
            panel: None,
        };
        pixels.resize(size)?;
        Ok(pixels)
    }

    /// Follows the window to `size` pixels.
    pub fn resize(&mut self, (width, height): (u32, u32)) -> Result<()> {
        let (Some(w), Some(h)) = (NonZeroU32::new(width), NonZeroU32::new(height)) else {
            return Ok(());
        };
        self.surface
            .resize(w, h)
            .map_err(|e| anyhow!("cannot resize the window's pixels: {e}"))?;
        self.size = (width, height);
        Ok(())
    }

    /// Shows `texels` (the picture's 8-bit levels at the window's size, blue, green,
    /// red, alpha; black where `None`) with the panel over them where `panel` is shown.
    pub fn show(&mut self, window: &Window, texels: Option<&[u8]>, panel: bool) -> Result<()> {
        let mut buffer = self
            .surface
            .buffer_mut()
            .map_err(|e| anyhow!("the window's pixels: {e}"))?;
        put_texels(&mut buffer, texels);
        if let Some(layer) = self.panel.as_ref().filter(|_| panel) {
            blend_panel(&mut buffer, self.size.0, layer);
        }
        window.pre_present_notify();
        buffer
            .present()
            .map_err(|e| anyhow!("cannot show the window's pixels: {e}"))
    }
}

/// `texels` (blue, green, red, alpha, as many as `pixels`) into `pixels` as `0RGB`;
/// black where there are none.
fn put_texels(pixels: &mut [u32], texels: Option<&[u8]>) {
    match texels.filter(|t| t.len() == 4 * pixels.len()) {
        Some(texels) => {
            for (pixel, t) in pixels.iter_mut().zip(texels.as_chunks::<4>().0) {
                *pixel = u32::from_le_bytes([t[0], t[1], t[2], 0]);
            }
        }
        None => pixels.fill(0),
    }
}

/// Blends the panel's premultiplied texels over `pixels` (`0RGB`, rows `width` long)
/// within its rectangle, as the adapter's premultiplied-alpha blend does into an 8-bit
/// target: `panel + pixel (1 - alpha)` per channel, rounded.
fn blend_panel(pixels: &mut [u32], width: u32, panel: &PanelPixels) {
    let [x, y, w, _] = panel.rect;
    if w == 0 {
        return;
    }
    for (row, texels) in panel.texels.chunks_exact(w as usize).enumerate() {
        let start = (y as usize + row) * width as usize + x as usize;
        let Some(line) = pixels.get_mut(start..start + w as usize) else {
            return;
        };
        for (pixel, &[b, g, r, a]) in line.iter_mut().zip(texels) {
            if a == 0 && (b | g | r) == 0 {
                continue;
            }
            let keep = 255 - a as u32;
            let under = pixel.to_le_bytes();
            let over =
                |src: u8, dst: u8| (src as u32 + (dst as u32 * keep + 127) / 255).min(255) as u8;
            *pixel =
                u32::from_le_bytes([over(b, under[0]), over(g, under[1]), over(r, under[2]), 0]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A picture's texels become `0RGB` pixels; none, or the wrong count, black.
    #[test]
    fn texels_go_into_the_pixels_as_0rgb() {
        let mut pixels = vec![7u32; 2];
        put_texels(&mut pixels, Some(&[1, 2, 3, 255, 40, 50, 60, 255]));
        assert_eq!(pixels, [0x0003_0201, 0x003c_3228]);
        put_texels(&mut pixels, Some(&[1, 2, 3, 255]));
        assert_eq!(pixels, [0, 0]);
    }

    /// Opaque, half-covering and clear texels of a 2 x 2 panel at (1, 1) of a 4 x 3
    /// picture: the panel replaces, halves or leaves the pixel, and nothing outside
    /// its rectangle changes.
    #[test]
    fn the_panel_is_blended_over_its_rectangle_alone() {
        let grey = 0x0064_6464u32; // 100 in each channel
        let mut pixels = vec![grey; 12];
        let panel = PanelPixels {
            rect: [1, 1, 2, 2],
            texels: vec![
                [10, 20, 30, 255],
                [50, 50, 50, 128],
                [0, 0, 0, 0],
                [0, 0, 0, 255],
            ],
        };
        blend_panel(&mut pixels, 4, &panel);
        // 50 + 100 x 127 / 255 = 99.8, rounded 100.
        let half = 50 + (100 * 127 + 127) / 255;
        let want = |x: usize, y: usize| match (x, y) {
            (1, 1) => 0x001e_140a,
            (2, 1) => half * 0x0001_0101,
            (1, 2) => grey,
            (2, 2) => 0,
            _ => grey,
        };
        for (k, p) in pixels.iter().enumerate() {
            assert_eq!(*p, want(k % 4, k / 4), "pixel ({}, {})", k % 4, k / 4);
        }
    }
}
