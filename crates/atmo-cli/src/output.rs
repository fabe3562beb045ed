//! Writing what the commands make: animations as frames, in chunks a render farm can
//! split, and an animated PNG (pictures are written by `atmo::image::Frame::write`).
//!
//! An animation's folder holds `frame_000000.png` ... (or `.exr`) and `atmo-frames.json`,
//! the manifest: the frame count, rate, size, format and display, and a fingerprint of
//! the command (its flags and the bytes of every file it names). Each frame is written
//! atomically (a temporary renamed when complete), so a frame file that exists is
//! whole; a frame that exists and decodes at the right size is kept, not drawn again,
//! so a killed or requeued run resumes. Chunks of one animation (`--frames A..B`) may
//! write into one folder at once; a run whose manifest differs from the folder's is
//! refused before it draws anything. A whole run also writes `animation.png`;
//! `atmo assemble` makes it from the chunks' frames.

use std::ffi::OsString;
use std::ops::Range;
use std::path::{Path, PathBuf};

use atmo::files::{check_folder, write_atomically};
use atmo::image::{Display, Frame, ToneMap};
use atmo::Error;
use clap::{Args, ValueEnum};
use indicatif::{ProgressBar, ProgressStyle};
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};

/// The manifest's file name in an animation's folder.
pub const MANIFEST: &str = "atmo-frames.json";

/// The animated PNG a whole run writes beside its frames.
pub const ANIMATION: &str = "animation.png";

/// Which frames of an animation a run draws, and their format: `--frames A..B` and
/// `--frame K` for a render farm's chunks.
#[derive(Args, Clone, Debug, Default)]
pub struct Chunk {
    /// Draw only frames A..B of the animation (from A up to, not including, B; A..=B
    /// includes B), numbered from 0, into the folder -o, which chunks may share.
    /// Frames there already are kept. `atmo assemble` makes the animated PNG.
    #[arg(long, value_name = "A..B", value_parser = parse_frames, requires = "animate", conflicts_with_all = ["frame", "chunk"])]
    pub frames: Option<Range<usize>>,
    /// Draw only frame K (from 0) of the animation.
    #[arg(long, value_name = "K", requires = "animate", conflicts_with = "chunk")]
    pub frame: Option<usize>,
    /// Draw only chunk K of N (K from 1 to N) of the animation's frames, split in runs
    /// as even as they can be: what a job array's task K draws
    /// (`--chunk $SLURM_ARRAY_TASK_ID/$SLURM_ARRAY_TASK_COUNT` with `--array=1-N`).
    #[arg(long, value_name = "K/N", value_parser = crate::args::parse_part, requires = "animate")]
    pub chunk: Option<(usize, usize)>,
    /// The frames' files: 8-bit sRGB PNG, or linear EXR (radiance, for compositing).
    #[arg(long, value_enum, default_value_t = FrameFormat::Png, requires = "animate")]
    pub frame_format: FrameFormat,
}

/// The file format of an animation's frames.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, ValueEnum, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum FrameFormat {
    #[default]
    Png,
    Exr,
}

impl FrameFormat {
    fn extension(self) -> &'static str {
        match self {
            FrameFormat::Png => "png",
            FrameFormat::Exr => "exr",
        }
    }
}

/// `A..B` (B excluded) or `A..=B` (B included), A < B after that.
fn parse_frames(s: &str) -> Result<Range<usize>, String> {
    let number = |t: &str| {
        t.trim()
            .parse::<usize>()
            .map_err(|e| format!("`{t}`: {e} (write the frames as A..B or A..=B)"))
    };
    let (a, b) = if let Some((a, b)) = s.split_once("..=") {
        (number(a)?, number(b)?.saturating_add(1))
    } else if let Some((a, b)) = s.split_once("..") {
        (number(a)?, number(b)?)
    } else {
        return Err(format!(
            "`{s}`: write the frames as A..B or A..=B, e.g. 0..24"
        ));
    };
    if a >= b {
        return Err(format!("`{s}` holds no frame"));
    }
    Ok(a..b)
}

impl Chunk {
    /// The frames this run draws of an animation of `count`; all without a chunk.
    fn range(&self, count: usize) -> atmo::Result<Range<usize>> {
        let (flag, range) = match (&self.frames, self.frame, self.chunk) {
            (Some(r), _, _) => ("--frames", r.clone()),
            (None, Some(k), _) => ("--frame", k..k + 1),
            (None, None, Some((k, n))) => {
                if n > count {
                    return Err(Error::Invalid(format!(
                        "--chunk {}/{n}: {n} chunks of an animation of {count} frames; allowed \
                         1 to {count} chunks",
                        k + 1
                    )));
                }
                return Ok(count * k / n..count * (k + 1) / n);
            }
            (None, None, None) => return Ok(0..count),
        };
        if range.end > count {
            return Err(Error::Invalid(format!(
                "{flag} {}..{}: the animation has frames 0..{count} (0 to {})",
                range.start,
                range.end,
                count - 1
            )));
        }
        Ok(range)
    }

    fn is_whole(&self) -> bool {
        self.frames.is_none() && self.frame.is_none() && self.chunk.is_none()
    }
}

/// What an animation's folder holds: the same in every chunk's run, or the run is
/// refused.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Manifest {
    /// The atmo version that drew the frames.
    pub atmo: String,
    /// The command (`sky`, `shafts`, `clouds`).
    pub command: String,
    /// SHA-256 of the command's flags (less the chunk, output and memory limit) and of
    /// the bytes of every file they name, hex.
    pub fingerprint: String,
    /// Frames in the whole animation, and its rate, frames/s.
    pub frames: usize,
    pub fps: u16,
    /// Pixels.
    pub width: u32,
    pub height: u32,
    pub format: FrameFormat,
    /// The display of the PNG frames and of the animated PNG.
    pub exposure: f32,
    pub tone: String,
}

/// The most frames an animation may have: frames are named `frame_000000` to
/// `frame_999999`, six digits that sort in order (a million frames is 11.6 hours at 24
/// a second).
pub const MAX_FRAMES: usize = 1_000_000;

impl Manifest {
    /// The file name of frame `k` (below `MAX_FRAMES`, a million).
    pub fn frame_name(&self, k: usize) -> String {
        format!("frame_{k:06}.{}", self.format.extension())
    }

    fn display(&self) -> atmo::Result<Display> {
        let tone = match self.tone.as_str() {
            "exponential" => ToneMap::Exponential,
            "aces" => ToneMap::Aces,
            "clamp" => ToneMap::Clamp,
            other => {
                return Err(Error::Invalid(format!(
                    "tone = \"{other}\": allowed exponential, aces, clamp"
                )))
            }
        };
        Ok(Display {
            exposure: self.exposure,
            tone,
        })
    }

    /// Reads `folder`'s manifest, if it has one.
    pub fn read(folder: &Path) -> atmo::Result<Option<Manifest>> {
        let path = folder.join(MANIFEST);
        if !path.exists() {
            return Ok(None);
        }
        let text = atmo::files::read_text(&path, "frame manifest", 1 << 20)?;
        Manifest::parse(&text, &path.display().to_string()).map(Some)
    }

    /// A manifest's text, checked: its display, at least one frame, a frame's size
    /// within the pictures' limits and the budget (`origin` names it in messages).
    pub fn parse(text: &str, origin: &str) -> atmo::Result<Manifest> {
        let bad = |message: String| Error::Parse {
            path: origin.to_string(),
            message,
        };
        let manifest: Manifest = serde_json::from_str(text).map_err(|e| bad(e.to_string()))?;
        manifest.display().map_err(|e| bad(e.to_string()))?;
        if manifest.frames == 0 || manifest.frames > MAX_FRAMES {
            return Err(bad(format!(
                "frames = {} is out of range: allowed 1 to {MAX_FRAMES}",
                manifest.frames
            )));
        }
        Frame::check_size(manifest.width, manifest.height).map_err(|e| bad(e.to_string()))?;
        Ok(manifest)
    }

    /// Whether frame `k` is in `folder` whole: it decodes, at the manifest's size.
    fn has_frame(&self, folder: &Path, k: usize) -> bool {
        read_frame(&folder.join(self.frame_name(k)), self).is_ok()
    }
}

/// Frame `path` as 8-bit sRGB at the manifest's size and display.
fn read_frame(path: &Path, manifest: &Manifest) -> atmo::Result<Vec<u8>> {
    let bytes = atmo::files::read_bounded(path, "frame", atmo::files::DATA_LIMIT_BYTES)?;
    atmo::budget::beside(bytes.len() as u64, "the file", || {
        frame_from_bytes(&bytes, &path.display().to_string(), manifest)
    })
}

/// A frame file's `bytes` (`origin` names it) as 8-bit sRGB, refused unless it is of
/// the manifest's format and size; a PNG's size is read from its header and checked
/// before its pixels are allocated (a 150-byte file claiming 100,000^2 pixels asked
/// for 30 GB and aborted).
pub fn frame_from_bytes(bytes: &[u8], origin: &str, manifest: &Manifest) -> atmo::Result<Vec<u8>> {
    let size = (manifest.width, manifest.height);
    let bad = |message: String| Error::Image {
        path: PathBuf::from(origin),
        message,
    };
    let wrong_size = |got: (u32, u32)| {
        Error::Invalid(format!(
            "{origin}: {} x {} where the animation's frames are {} x {}",
            got.0, got.1, size.0, size.1
        ))
    };
    match manifest.format {
        FrameFormat::Exr => {
            let frame = Frame::exr_from_bytes(bytes, origin)?;
            if (frame.width, frame.height) != size {
                return Err(wrong_size((frame.width, frame.height)));
            }
            let display = manifest.display()?;
            Ok(frame.to_srgb8(display.exposure, display.tone))
        }
        FrameFormat::Png => {
            let mut reader = png::Decoder::new(std::io::Cursor::new(bytes))
                .read_info()
                .map_err(|e| bad(e.to_string()))?;
            let info = reader.info();
            if (info.width, info.height) != size {
                return Err(wrong_size((info.width, info.height)));
            }
            if info.color_type != png::ColorType::Rgb || info.bit_depth != png::BitDepth::Eight {
                return Err(bad("not an 8-bit RGB frame".into()));
            }
            let mut buffer = vec![0; reader.output_buffer_size().unwrap_or(0)];
            let info = reader
                .next_frame(&mut buffer)
                .map_err(|e| bad(e.to_string()))?;
            buffer.truncate(info.buffer_size());
            Ok(buffer)
        }
    }
}

/// The fingerprint of this run's command: SHA-256 of its arguments, less those that do
/// not change the pictures (the chunk, the output, the memory limit), and of the bytes
/// of every argument that names a file. Files a scene refers to are not read: change
/// one and render into a new folder.
fn fingerprint(argv: impl IntoIterator<Item = OsString>) -> String {
    const SKIPPED: [&str; 7] = [
        "--frames",
        "--frame",
        "--chunk",
        "-o",
        "--output",
        "--memory-limit",
        "--frame-format",
    ];
    let mut hash = Sha256::new();
    let mut argv = argv.into_iter().skip(1);
    while let Some(arg) = argv.next() {
        let text = arg.to_string_lossy();
        if SKIPPED.contains(&text.as_ref()) {
            argv.next();
            continue;
        }
        if SKIPPED.iter().any(|s| {
            text.strip_prefix(s)
                .is_some_and(|rest| rest.starts_with('=') || (*s == "-o" && !rest.is_empty()))
        }) {
            continue;
        }
        hash.update((arg.len() as u64).to_le_bytes());
        hash.update(arg.as_encoded_bytes());
        let path = Path::new(&arg);
        if path.is_file() {
            if let Ok(bytes) =
                atmo::files::read_bounded(path, "input", atmo::files::DATA_LIMIT_BYTES)
            {
                hash.update((bytes.len() as u64).to_le_bytes());
                hash.update(&bytes);
            }
        }
    }
    hash.finalize().iter().map(|b| format!("{b:02x}")).collect()
}

/// An animation to write: `count` frames at `fps`, `size` pixels, shown through
/// `display` in its PNGs, into `folder`, the frames `chunk` selects.
pub struct Animation<'a> {
    pub command: &'a str,
    pub folder: &'a Path,
    pub count: usize,
    pub fps: u16,
    pub size: (u32, u32),
    pub display: Display,
    pub chunk: &'a Chunk,
}

/// What a run of [`write_animation`] did.
pub struct Written {
    /// Frames drawn, and frames of the chunk kept from an earlier run.
    pub drawn: usize,
    pub kept: usize,
    /// The animated PNG, written by a whole run.
    pub animation: Option<PathBuf>,
}

/// Writes the frames of `animation`'s chunk that the folder does not hold yet, each
/// drawn by `fill` (given the frame number and a frame to draw into) and written
/// atomically; then, for a whole run, `animation.png`, the animated PNG of every frame.
/// A bar on the terminal counts the frames (nothing is drawn where stderr is not a
/// terminal). Everything about the folder is checked before the first frame is drawn.
pub fn write_animation(
    animation: &Animation,
    mut fill: impl FnMut(usize, &mut Frame) -> anyhow::Result<()>,
) -> anyhow::Result<Written> {
    let folder = animation.folder;
    if folder.extension().is_some_and(|e| e == "png" || e == "exr") {
        return Err(Error::Invalid(format!(
            "{}: with --animate, -o names a folder for the frames",
            folder.display()
        ))
        .into());
    }
    let range = animation.chunk.range(animation.count)?;
    let (width, height) = animation.size;
    let manifest = Manifest {
        atmo: env!("CARGO_PKG_VERSION").into(),
        command: animation.command.into(),
        fingerprint: fingerprint(std::env::args_os()),
        frames: animation.count,
        fps: animation.fps,
        width,
        height,
        format: animation.chunk.frame_format,
        exposure: animation.display.exposure,
        tone: match animation.display.tone {
            ToneMap::Exponential => "exponential",
            ToneMap::Aces => "aces",
            ToneMap::Clamp => "clamp",
        }
        .into(),
    };
    prepare_folder(folder, &manifest)?;
    let bar = ProgressBar::new(range.len() as u64).with_style(
        ProgressStyle::with_template("[{bar:32}] {pos}/{len} frames, {elapsed} elapsed, ETA {eta}")
            .expect("valid template")
            .progress_chars("=> "),
    );
    let (mut drawn, mut kept) = (0, 0);
    let mut frame = Frame::new(width, height);
    for k in range.clone() {
        bar.set_position((k - range.start) as u64);
        if manifest.has_frame(folder, k) {
            kept += 1;
            continue;
        }
        fill(k, &mut frame).map_err(|e| e.context(format!("frame {k}")))?;
        frame.write(
            &folder.join(manifest.frame_name(k)),
            animation.display.exposure,
            animation.display.tone,
        )?;
        drawn += 1;
    }
    bar.finish_and_clear();
    let animation_png = if animation.chunk.is_whole() {
        let path = folder.join(ANIMATION);
        write_apng(&[folder], &manifest, &path)?;
        Some(path)
    } else {
        None
    };
    Ok(Written {
        drawn,
        kept,
        animation: animation_png,
    })
}

/// Says on stderr what a run of [`write_animation`] into `folder` did since `start`.
pub fn report(folder: &Path, written: &Written, start: std::time::Instant) {
    let seconds = start.elapsed().as_secs_f64();
    let kept = match written.kept {
        0 => String::new(),
        n => format!(", {n} kept from an earlier run"),
    };
    match &written.animation {
        Some(apng) => note!(
            "atmo: {}{kept} and {} in {seconds:.2} s",
            frames_drawn(written.drawn),
            apng.display()
        ),
        None => note!(
            "atmo: {}{kept} into {} in {seconds:.2} s; `atmo assemble` makes the \
             animation once every chunk is done",
            frames_drawn(written.drawn),
            folder.display()
        ),
    }
}

fn frames_drawn(n: usize) -> String {
    match n {
        1 => "1 frame drawn".into(),
        n => format!("{n} frames drawn"),
    }
}

/// Makes `folder` for the frames of `manifest`, or checks that the one there holds
/// frames of the same animation, and writes the manifest where it is missing.
fn prepare_folder(folder: &Path, manifest: &Manifest) -> atmo::Result<()> {
    check_folder(folder)?;
    if folder.exists() && !folder.is_dir() {
        return Err(Error::Invalid(format!(
            "{}: with --animate, -o names a folder for the frames, and this is a file",
            folder.display()
        )));
    }
    std::fs::create_dir_all(folder).map_err(Error::io_at(folder))?;
    match Manifest::read(folder)? {
        Some(there) if there == *manifest => Ok(()),
        Some(there) => Err(Error::Invalid(format!(
            "{}: holds the frames of another animation ({}); draw into another folder, or \
             remove that one",
            folder.display(),
            differences(&there, manifest)
        ))),
        None => {
            let stray = std::fs::read_dir(folder)
                .map_err(Error::io_at(folder))?
                .flatten()
                .any(|e| e.file_name().to_string_lossy().starts_with("frame_"));
            if stray {
                return Err(Error::Invalid(format!(
                    "{}: holds frames without a {MANIFEST}: draw into another folder, or \
                     remove them",
                    folder.display()
                )));
            }
            let path = folder.join(MANIFEST);
            let text = serde_json::to_string_pretty(manifest).expect("a manifest serializes");
            write_atomically(&path, |w| {
                std::io::Write::write_all(w, text.as_bytes()).map_err(Error::io_at(&path))
            })
        }
    }
}

/// What differs between two manifests, in words.
fn differences(a: &Manifest, b: &Manifest) -> String {
    let mut out = Vec::new();
    if a.command != b.command || a.fingerprint != b.fingerprint || a.atmo != b.atmo {
        out.push(format!(
            "another command, scene or atmo version: {} {} {}... against {} {} {}...",
            a.command,
            a.atmo,
            &a.fingerprint[..a.fingerprint.len().min(12)],
            b.command,
            b.atmo,
            &b.fingerprint[..b.fingerprint.len().min(12)]
        ));
    }
    if a.frames != b.frames || a.fps != b.fps {
        out.push(format!(
            "{} frames at {}/s against {} at {}/s",
            a.frames, a.fps, b.frames, b.fps
        ));
    }
    if (a.width, a.height) != (b.width, b.height) {
        out.push(format!(
            "{} x {} against {} x {}",
            a.width, a.height, b.width, b.height
        ));
    }
    if a.format != b.format || a.exposure != b.exposure || a.tone != b.tone {
        out.push(format!(
            "{:?} frames at exposure {} ({}) against {:?} at {} ({})",
            a.format, a.exposure, a.tone, b.format, b.exposure, b.tone
        ));
    }
    out.join("; ")
}

/// Writes `path`, the animated PNG of every frame of `manifest`, taken from `folders`
/// (the first that holds a frame gives it); every frame must be there, whole.
fn write_apng(folders: &[&Path], manifest: &Manifest, path: &Path) -> atmo::Result<()> {
    let locate = |k: usize| -> atmo::Result<PathBuf> {
        folders
            .iter()
            .map(|f| f.join(manifest.frame_name(k)))
            .find(|f| f.exists())
            .ok_or_else(|| {
                Error::Invalid(format!(
                    "frame {k} ({}) is missing: the animation has frames 0..{}",
                    manifest.frame_name(k),
                    manifest.frames
                ))
            })
    };
    let png_error = |e: png::EncodingError| Error::Image {
        path: path.to_path_buf(),
        message: e.to_string(),
    };
    // Every frame found before the file is begun: a missing one is named at once.
    for k in 0..manifest.frames {
        locate(k)?;
    }
    write_atomically(path, |w| {
        let mut encoder = png::Encoder::new(w, manifest.width, manifest.height);
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(png::BitDepth::Eight);
        encoder
            .set_animated(manifest.frames as u32, 0)
            .map_err(png_error)?;
        encoder
            .set_frame_delay(1, manifest.fps)
            .map_err(png_error)?;
        let mut writer = encoder.write_header().map_err(png_error)?;
        for k in 0..manifest.frames {
            let rgb = read_frame(&locate(k)?, manifest)?;
            writer.write_image_data(&rgb).map_err(png_error)?;
        }
        writer.finish().map_err(png_error)
    })
}

/// `atmo assemble`: the animated PNG of the frames that the chunks of one animation
/// wrote into `folders`, after checking they are all there, whole, and of one manifest.
pub fn assemble(folders: &[PathBuf], output: &Path) -> anyhow::Result<usize> {
    if !output
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("png") || e.eq_ignore_ascii_case("apng"))
    {
        return Err(Error::out_of_range(
            "-o",
            output.display(),
            ".png or .apng (an animated PNG; for video, encode the frames with ffmpeg)",
        )
        .into());
    }
    check_folder(output)?;
    let mut manifest: Option<(Manifest, &Path)> = None;
    for folder in folders {
        let there = Manifest::read(folder)?.ok_or_else(|| {
            Error::Invalid(format!(
                "{}: no {MANIFEST}: not a folder of atmo's frames",
                folder.display()
            ))
        })?;
        match &manifest {
            Some((first, from)) if *first != there => {
                return Err(Error::Invalid(format!(
                    "{} and {} hold frames of different animations ({})",
                    from.display(),
                    folder.display(),
                    differences(first, &there)
                ))
                .into())
            }
            Some(_) => {}
            None => manifest = Some((there, folder)),
        }
    }
    let Some((manifest, _)) = manifest else {
        return Err(Error::Invalid("no folders of frames to assemble".into()).into());
    };
    let folders: Vec<&Path> = folders.iter().map(PathBuf::as_path).collect();
    write_apng(&folders, &manifest, output)?;
    Ok(manifest.frames)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn argv(words: &[&str]) -> Vec<OsString> {
        words.iter().map(OsString::from).collect()
    }

    #[test]
    fn frame_ranges_are_read_as_written() {
        assert_eq!(parse_frames("0..24"), Ok(0..24));
        assert_eq!(parse_frames("12..=23"), Ok(12..24));
        assert!(parse_frames("5..5").unwrap_err().contains("no frame"));
        assert!(parse_frames("7").unwrap_err().contains("A..B"));
        assert!(parse_frames("-1..4").is_err());
        let chunk = Chunk {
            frames: Some(40..50),
            ..Chunk::default()
        };
        let e = chunk.range(48).unwrap_err().to_string();
        assert!(
            e.contains("--frames 40..50") && e.contains("0 to 47"),
            "{e}"
        );
        assert_eq!(Chunk::default().range(48).unwrap(), 0..48);
        // Chunks cover every frame once, in order.
        let chunk = |k, n| Chunk {
            chunk: Some((k, n)),
            ..Chunk::default()
        };
        let ranges: Vec<_> = (0..5).map(|k| chunk(k, 5).range(48).unwrap()).collect();
        assert_eq!(ranges, [0..9, 9..19, 19..28, 28..38, 38..48]);
        let e = chunk(0, 49).range(48).unwrap_err().to_string();
        assert!(e.contains("allowed 1 to 48 chunks"), "{e}");
    }

    #[test]
    fn the_fingerprint_ignores_the_chunk_and_the_output_only() {
        let base = fingerprint(argv(&["atmo", "shafts", "x.toml", "--animate"]));
        for same in [
            &[
                "atmo",
                "shafts",
                "x.toml",
                "--animate",
                "--frames",
                "0..4",
                "-o",
                "a",
            ][..],
            &["atmo", "shafts", "x.toml", "--animate", "--frame=3", "-ob"],
            &[
                "atmo",
                "shafts",
                "x.toml",
                "--animate",
                "--output=c",
                "--memory-limit",
                "1G",
            ],
        ] {
            assert_eq!(fingerprint(argv(same)), base, "{same:?}");
        }
        for other in [
            &["atmo", "shafts", "y.toml", "--animate"][..],
            &["atmo", "shafts", "x.toml", "--animate", "--fps", "30"],
        ] {
            assert_ne!(fingerprint(argv(other)), base, "{other:?}");
        }
        // A named file's bytes count, not only its name.
        let dir = std::env::temp_dir().join(format!("atmo-fingerprint-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let file = dir.join("scene.toml");
        let with = |text: &str| {
            std::fs::write(&file, text).unwrap();
            fingerprint(argv(&["atmo", "shafts", file.to_str().unwrap()]))
        };
        assert_ne!(with("a = 1"), with("a = 2"));
        std::fs::remove_dir_all(dir).unwrap();
    }
}
