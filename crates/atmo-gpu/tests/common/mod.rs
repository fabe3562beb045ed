//! What every GPU test shares: the device, and the comparison with the CPU path.

#![allow(dead_code)] // each test binary uses its own part

use atmo::image::{Display, Frame, LevelErrors, ToneMap};
use atmo_gpu::{Gpu, GpuError};

/// The adapter the tests run on (`WGPU_ADAPTER_NAME` picks one), or `None` where there
/// is none, outside CI: in CI (`CI=true`) a missing adapter fails the test, so a broken
/// driver install cannot pass silently.
pub fn gpu() -> Option<Gpu> {
    match Gpu::new(None) {
        Ok(gpu) => Some(gpu),
        Err(GpuError::NoAdapter { .. }) if std::env::var("CI").as_deref() != Ok("true") => {
            skip("no GPU adapter (install mesa-vulkan-drivers)");
            None
        }
        Err(e) => panic!("GPU setup failed: {e}"),
    }
}

/// Says on the terminal, past the test harness's capture (which takes only the print
/// macros), that the running test skipped `what`: a line `atmo-test: skipped TEST:
/// WHY` that the test run shows and `.ci/run` counts into its closing line.
pub fn skip(why: &str) {
    use std::io::Write as _;
    let test = std::thread::current()
        .name()
        .unwrap_or("a test")
        .to_string();
    let _ = writeln!(std::io::stderr(), "atmo-test: skipped {test}: {why}");
}

/// The bound: RMS at most 0.5 and max at most 2 levels of 255 after the same
/// tone map.
pub fn assert_close(gpu: &Frame, cpu: &Frame, exposure: f32, what: &str) -> LevelErrors {
    let display = Display {
        exposure,
        tone: ToneMap::Exponential,
    };
    let e = gpu.level_errors(cpu, display).unwrap();
    eprintln!(
        "{what}: GPU vs CPU RMS {:.3}, max {:.3} levels",
        e.rms, e.max
    );
    assert!(
        e.rms <= 0.5 && e.max <= 2.0,
        "{what}: GPU vs CPU RMS {:.3}, max {:.3} levels (bound: RMS 0.5, max 2)",
        e.rms,
        e.max
    );
    e
}

/// Mean displayed level of a frame: a picture that is not black.
pub fn mean_level(frame: &Frame, exposure: f32) -> f64 {
    let display = Display {
        exposure,
        tone: ToneMap::Exponential,
    };
    let sum: f64 = frame
        .pixels
        .iter()
        .map(|p| (0..3).map(|c| display.value(p[c]) as f64).sum::<f64>())
        .sum();
    255.0 * sum / (3.0 * frame.pixels.len() as f64)
}

/// A pass that draws into a caller's render pass ([`atmo_gpu::shafts::ShaftsPass`],
/// [`atmo_gpu::clouds::CloudsPass`]).
pub trait Draws {
    fn draw_into(&self, render: &mut wgpu::RenderPass<'_>);
}

impl Draws for atmo_gpu::shafts::ShaftsPass {
    fn draw_into(&self, render: &mut wgpu::RenderPass<'_>) {
        self.draw(render);
    }
}

impl Draws for atmo_gpu::clouds::CloudsPass {
    fn draw_into(&self, render: &mut wgpu::RenderPass<'_>) {
        self.draw(render);
    }
}

/// What a pass draws over a `width` x `height` picture cleared to grey `behind`, read
/// back as RGBA: `make` gets the encoder (for what the pass records first) and the
/// target's format, and gives the pass.
pub fn drawn_over<P: Draws>(
    gpu: &Gpu,
    (width, height): (u32, u32),
    behind: f64,
    make: impl FnOnce(&mut wgpu::CommandEncoder, wgpu::TextureFormat) -> P,
) -> Vec<[f32; 4]> {
    let target = atmo_gpu::display::picture_texture(gpu, width, height).unwrap();
    let view = target.create_view(&Default::default());
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    let pass = make(&mut encoder, target.format());
    {
        let colour = wgpu::Color {
            r: behind,
            g: behind,
            b: behind,
            a: 1.0,
        };
        let mut render = atmo_gpu::display::cleared_pass(&mut encoder, &view, "behind", colour);
        pass.draw_into(&mut render);
    }
    gpu.queue.submit([encoder.finish()]);
    let bytes = gpu
        .read_texture("the picture", &target, width, height)
        .unwrap();
    bytemuck::cast_slice(&bytes).to_vec()
}
