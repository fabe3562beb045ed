//! `atmo compare`: how far two renders are apart, in 8-bit levels.

use std::path::PathBuf;

use anyhow::Result;
use atmo::files::check_folder;
use atmo::image::{Display, Frame, ImageKind};
use clap::Args;

use crate::args::ToneMapArg;

#[derive(Args)]
pub struct CompareArgs {
    /// First picture (.exr, linear radiance).
    a: PathBuf,
    /// Second picture (.exr), e.g. the reference.
    b: PathBuf,
    /// Also write a difference image: |A - B| in 8-bit levels after the display below,
    /// times 10 (white = 25.5 levels or more). Without it only the figures are printed.
    #[arg(short, long, value_name = "FILE.png")]
    output: Option<PathBuf>,
    /// Exposure the levels are measured after.
    #[arg(long, default_value_t = 1.0)]
    exposure: f32,
    /// Tone map the levels are measured after.
    #[arg(long, value_enum, default_value_t = ToneMapArg::Exponential)]
    tone_map: ToneMapArg,
}

pub fn run(args: CompareArgs) -> Result<()> {
    atmo::error::check_positive("--exposure", args.exposure as f64, 1e12)?;
    if let Some(output) = &args.output {
        if ImageKind::of(output)? != ImageKind::Png {
            return Err(
                atmo::Error::out_of_range("--output", output.display(), "a .png file").into(),
            );
        }
        check_folder(output)?;
    }
    let a = Frame::read_exr(&args.a)?;
    // The second beside the first, which is held with it.
    let b = atmo::budget::beside(a.bytes(), "the first picture", || Frame::read_exr(&args.b))?;
    let display = Display {
        exposure: args.exposure,
        tone: args.tone_map.into(),
    };
    let levels = a.level_errors(&b, display)?;
    let mut difference = Frame::new(a.width, a.height);
    let (mut sum, mut sum_b, mut max) = (0.0f64, 0.0f64, 0.0f64);
    for ((d, pa), pb) in difference.pixels.iter_mut().zip(&a.pixels).zip(&b.pixels) {
        for c in 0..3 {
            let diff = (pa[c] - pb[c]) as f64;
            sum += diff * diff;
            sum_b += (pb[c] as f64).powi(2);
            max = max.max(diff.abs());
            d[c] = 10.0 * (display.value(pa[c]) - display.value(pb[c])).abs();
        }
    }
    if let Some(output) = &args.output {
        // Already in display units: written with exposure 1, clamped.
        difference
            .pixels
            .iter_mut()
            .for_each(|p| *p = p.map(atmo::image::srgb_decode));
        difference.write(output, 1.0, atmo::image::ToneMap::Clamp)?;
    }
    let n = 3.0 * a.pixels.len() as f64;
    outln!(
        "levels (8-bit, after exposure {} and the {:?} tone map): rms {:.3} ({:.3} % of 255), max {:.2}",
        args.exposure,
        display.tone,
        levels.rms,
        100.0 * levels.rms / 255.0,
        levels.max
    );
    outln!(
        "linear: rms {:.4e} ({:.3} % of B's rms), max {:.4e}",
        (sum / n).sqrt(),
        100.0 * (sum / sum_b.max(1e-300)).sqrt(),
        max
    );
    if let Some(output) = &args.output {
        outln!("difference image: {}", output.display());
    }
    Ok(())
}
