//! Writing what the commands make: animations as frames and an animated PNG (pictures
//! are written by `atmo::image::Frame::write`).

use std::path::Path;

use atmo::files::{check_folder, write_atomically, write_folder_atomically};
use atmo::image::{Display, Frame};
use atmo::Error;
use indicatif::{ProgressBar, ProgressStyle};

/// Writes the frames `fill` draws (given the frame number and a `size` frame to draw
/// into) into the folder `folder` as `frame-0000.png` ... and `animation.png`, an
/// animated PNG at `fps` frames/s. They are written into a temporary folder that becomes
/// `folder` at the end (or whose files move into it, where it exists), so an
/// interrupted or failed run leaves no partial frames. A bar on the terminal counts the
/// frames (nothing is drawn where stderr is not a terminal). Returns the animation's
/// path.
pub fn write_animation(
    folder: &Path,
    frames: usize,
    fps: u16,
    (width, height): (u32, u32),
    display: Display,
    mut fill: impl FnMut(usize, &mut Frame) -> anyhow::Result<()>,
) -> anyhow::Result<std::path::PathBuf> {
    if folder.extension().is_some_and(|e| e == "png" || e == "exr") {
        return Err(Error::Invalid(format!(
            "{}: with --animate, -o names a folder for the frames",
            folder.display()
        ))
        .into());
    }
    check_folder(folder)?;
    // A frame's own error, kept whole (it may not be atmo's) while the files are dropped.
    let mut failed: Option<anyhow::Error> = None;
    let written = write_folder_atomically(folder, |tmp| {
        let apng = tmp.join("animation.png");
        let png_error = |e: png::EncodingError| Error::Image {
            path: apng.clone(),
            message: e.to_string(),
        };
        write_atomically(&apng, |w| {
            let mut encoder = png::Encoder::new(w, width, height);
            encoder.set_color(png::ColorType::Rgb);
            encoder.set_depth(png::BitDepth::Eight);
            encoder.set_animated(frames as u32, 0).map_err(png_error)?;
            encoder.set_frame_delay(1, fps).map_err(png_error)?;
            let mut writer = encoder.write_header().map_err(png_error)?;
            let mut frame = Frame::new(width, height);
            let bar = ProgressBar::new(frames as u64).with_style(
                ProgressStyle::with_template(
                    "[{bar:32}] {pos}/{len} frames, {elapsed} elapsed, ETA {eta}",
                )
                .expect("valid template")
                .progress_chars("=> "),
            );
            for k in 0..frames {
                bar.set_position(k as u64);
                if let Err(e) = fill(k, &mut frame) {
                    let message = format!("frame {k}: {e:#}");
                    failed = Some(e);
                    return Err(Error::Invalid(message));
                }
                frame.write(
                    &tmp.join(format!("frame-{k:04}.png")),
                    display.exposure,
                    display.tone,
                )?;
                writer
                    .write_image_data(&frame.to_srgb8(display.exposure, display.tone))
                    .map_err(png_error)?;
            }
            bar.finish_and_clear();
            writer.finish().map_err(png_error)
        })
    });
    match (written, failed) {
        (_, Some(e)) => Err(e),
        (Err(e), None) => Err(e.into()),
        (Ok(()), None) => Ok(folder.join("animation.png")),
    }
}
