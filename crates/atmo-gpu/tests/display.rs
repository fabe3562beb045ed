//! The display pass against `atmo::image::Display`: a CPU frame uploaded, shown into a
//! target at an offset, read back.

mod common;

use atmo::image::{Display, Frame, ToneMap};
use atmo_gpu::display::{cleared_pass, picture_texture, write_frame, DisplayPass};
use common::gpu;
use glam::Vec3;

#[test]
fn the_display_pass_shows_a_frame_as_the_png_writer_does() {
    let Some(gpu) = gpu() else { return };
    // Radiance from 0 to 40 over the frame, different per channel.
    let mut frame = Frame::new(40, 24);
    for (i, p) in frame.pixels.iter_mut().enumerate() {
        let t = i as f32 / 960.0;
        *p = Vec3::new(40.0 * t, 4.0 * t * t, 0.5 * (1.0 - t));
    }
    let picture = picture_texture(&gpu, 40, 24).unwrap();
    write_frame(&gpu, &picture, &frame);
    // A linear-stored target: the pass encodes sRGB itself, as the PNG writer does.
    let target = picture_texture(&gpu, 48, 28).unwrap();
    let target_view = target.create_view(&Default::default());
    for tone in [ToneMap::Clamp, ToneMap::Exponential, ToneMap::Aces] {
        let display = Display {
            exposure: 0.3,
            tone,
        };
        let mut pass = DisplayPass::new(&gpu, wgpu::TextureFormat::Rgba32Float).unwrap();
        pass.display = display;
        pass.corner = [5, 3];
        pass.prepare(&gpu, &picture.create_view(&Default::default()));
        gpu.run("display", |encoder| {
            pass.draw(&mut cleared_pass(
                encoder,
                &target_view,
                "display",
                wgpu::Color::BLUE,
            ));
        })
        .unwrap();
        let bytes = gpu.read_texture("display", &target, 48, 28).unwrap();
        let texels: &[[f32; 4]] = bytemuck::cast_slice(&bytes);
        for y in 0..28u32 {
            for x in 0..48u32 {
                let got = Vec3::from_slice(&texels[(y * 48 + x) as usize][..3]);
                let inside = (5..45).contains(&x) && (3..27).contains(&y);
                let want = if inside {
                    frame.pixels[((y - 3) * 40 + x - 5) as usize].map(|v| display.value(v))
                } else {
                    Vec3::Z
                };
                assert!(
                    (got - want).abs().max_element() < 1e-5,
                    "{tone:?} at ({x}, {y}): {got} vs {want}"
                );
            }
        }
    }
}
