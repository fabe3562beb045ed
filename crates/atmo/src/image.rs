//! Float frame buffers, exposure, tone mapping, and PNG / OpenEXR files written
//! atomically (to a temporary name in the same folder, then renamed), so a failed or
//! interrupted run never leaves a half-written picture.

use std::io::Write;
use std::path::Path;

use glam::Vec3;
use image::ImageResult;
#[cfg(any(feature = "png", feature = "exr"))]
use image::{ExtendedColorType, ImageEncoder};
use rayon::prelude::*;

use crate::error::{check_range, Error, Result};

/// How linear radiance becomes a displayable value in [0, 1] before sRGB encoding.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ToneMap {
    /// Clamp at 1: what the 8-bit displays of the papers did.
    Clamp,
    /// `1 - exp(-x)`, as Bruneton's (2017) demo: never saturates, keeps hue.
    #[default]
    Exponential,
    /// Narkowicz's fit of the ACES filmic curve.
    Aces,
}

impl ToneMap {
    /// The tone-mapped value of the exposed linear value `x >= 0`.
    #[inline]
    pub fn apply(self, x: f32) -> f32 {
        let x = x.max(0.0);
        match self {
            ToneMap::Clamp => x.min(1.0),
            ToneMap::Exponential => 1.0 - (-x).exp(),
            ToneMap::Aces => {
                // Past 1e18 the squares would overflow to infinity over infinity (NaN,
                // shown black); the curve is 1 there long since.
                let x = x.min(1e18);
                ((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14)).clamp(0.0, 1.0)
            }
        }
    }

    /// The exposed linear value whose tone-mapped value is `y` in [0, 1): the inverse
    /// of [`ToneMap::apply`] where it is one-to-one.
    pub fn invert(self, y: f32) -> f32 {
        let y = y.max(0.0);
        match self {
            ToneMap::Clamp => y,
            ToneMap::Exponential => -(-y).ln_1p(),
            ToneMap::Aces => {
                // (2.51 - 2.43 y) x^2 + (0.03 - 0.59 y) x - 0.14 y = 0, positive root.
                let (a, b, c) = (2.51 - 2.43 * y, 0.03 - 0.59 * y, -0.14 * y);
                (-b + (b * b - 4.0 * a * c).sqrt()) / (2.0 * a)
            }
        }
    }
}

/// How linear radiance becomes the value a display shows, in [0, 1]: times `exposure`,
/// through the tone map, then sRGB-encoded (8-bit files round it to 1/255 steps).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Display {
    /// Multiplies radiance before the tone map.
    pub exposure: f32,
    /// The tone map.
    pub tone: ToneMap,
}

impl Display {
    /// The displayed value of linear radiance `x`.
    #[inline]
    pub fn value(&self, x: f32) -> f32 {
        srgb_encode(self.tone.apply(x * self.exposure))
    }
}

/// The 8-bit level of every linear value under one [`Display`], found by a table
/// instead of an `exp` and a `powf` per value: the levels of
/// `(display.value(x) * 255 + 0.5) as u8` (see [`Levels::exact`]), many times
/// faster, which is what lets a window show a CPU-drawn frame each frame.
///
/// Written here, not taken from a crate: the point is exactness to atmo's own curves
/// (any exposure, any [`ToneMap`]). The displayed level never falls as radiance rises,
/// so level `k` begins at one radiance, `starts[k]`; non-negative floats order as their
/// bits do, so a value's top bits pick a bucket whose first level is tabled, and two
/// comparisons of bits (no branch) step to the value's level within the bucket.
///
/// Why two are enough: a bucket is 2^-8 (0.39 %) of its values wide, and two levels'
/// starts are at least 0.66 % apart in radiance (a level is 1/255 of the encoded value
/// v, at least 0.39 % of it; v grows no faster than x^0.59 under the sRGB curve's 1/2.4
/// power and ACES, whose steepest relative slope is 1.41, and at most as x in the
/// curve's linear toe, where the levels are over 10 % apart): one start a bucket, at
/// most, with room.
#[derive(Debug, Clone)]
pub struct Levels {
    display: Display,
    /// The bits of the least value shown at level `k` (for `k` in 1..=255), 0 for
    /// level 0, and `u32::MAX` past 255 (twice: the two steps of a lookup then need
    /// no bounds check, nor does the bucket's index into an array of its size).
    starts: [u32; 258],
    /// The level of each bucket's least value: bucket `b` holds the values whose bits
    /// shifted by [`Levels::SHIFT`] are `b`.
    buckets: Box<[u8; Levels::BUCKETS]>,
}

impl Levels {
    /// Bits below a bucket's: 15 keeps 8 of the mantissa's 23 (64 K buckets).
    const SHIFT: u32 = 15;
    /// The bits of +infinity: every non-negative value's bits are at most these.
    const INFINITY: u32 = 0x7f80_0000;
    /// Buckets up to infinity's.
    const BUCKETS: usize = (Self::INFINITY >> Self::SHIFT) as usize + 1;

    /// The table of `display` (a fraction of a millisecond to make).
    pub fn new(display: Display) -> Self {
        let level = |bits: u32| Self::exact(display, f32::from_bits(bits));
        let mut starts = [u32::MAX; 258];
        starts[0] = 0;
        for k in 1..=255u32 {
            // The least bits shown at `k` or above, by bisection between the last start
            // and infinity; none when even infinity is shown below `k`.
            let (mut low, mut high) = (starts[k as usize - 1], Self::INFINITY);
            if (level(high) as u32) < k {
                break;
            }
            while low < high {
                let middle = low + (high - low) / 2;
                if level(middle) as u32 >= k {
                    high = middle;
                } else {
                    low = middle + 1;
                }
            }
            starts[k as usize] = low;
        }
        let mut buckets = Box::new([0u8; Self::BUCKETS]);
        let mut k = 0;
        for (b, bucket) in buckets.iter_mut().enumerate() {
            let first = (b as u32) << Self::SHIFT;
            while first >= starts[k + 1] {
                k += 1;
            }
            *bucket = k as u8;
        }
        Levels {
            display,
            starts,
            buckets,
        }
    }

    /// The display this table is of.
    pub fn display(&self) -> Display {
        self.display
    }

    /// The level of `x` as the formula gives it, without the table (which agrees with
    /// it but for values within an ulp or two of a level's start, where the formula's
    /// rounding may jitter between two levels).
    #[inline]
    pub fn exact(display: Display, x: f32) -> u8 {
        (display.value(x) * 255.0 + 0.5).clamp(0.0, 255.0) as u8
    }

    /// The texels of `pixels` in `order` (alpha 255) into `texels` (as many).
    pub fn texels(&self, pixels: &[Vec3], order: TexelOrder, texels: &mut [[u8; 4]]) {
        for (t, p) in texels.iter_mut().zip(pixels) {
            let [r, g, b] = [self.level(p.x), self.level(p.y), self.level(p.z)];
            *t = match order {
                TexelOrder::Rgba => [r, g, b, 255],
                TexelOrder::Bgra => [b, g, r, 255],
            };
        }
    }

    /// The level of `x` (negative and NaN: 0, as the tone maps take them).
    #[inline]
    pub fn level(&self, x: f32) -> u8 {
        let bits = if x > 0.0 {
            x.to_bits().min(Self::INFINITY)
        } else {
            0
        };
        let mut k = self.buckets[(bits >> Self::SHIFT) as usize] as usize;
        k += (bits >= self.starts[k + 1]) as usize;
        k += (bits >= self.starts[k + 1]) as usize;
        k as u8
    }
}

/// `pixels`, a `from` (width, height) picture, stretched to `to` by bilinear
/// interpolation with `lerp(a, b, weight of b)`, pixel centres on pixel centres (edges
/// clamped), rows in parallel: one loop for a frame's radiances and for 8-bit texels.
pub fn stretched<T: Copy + Default + Send + Sync>(
    pixels: &[T],
    from: (u32, u32),
    to: (u32, u32),
    lerp: impl Fn(T, T, f32) -> T + Sync,
) -> Vec<T> {
    let (w, h) = (from.0 as usize, from.1 as usize);
    assert_eq!(pixels.len(), w * h, "a {w} x {h} picture");
    // A coordinate of the target's pixel centre in the source's pixels: the two
    // neighbours and the weight of the second.
    let axis = |to: u32, from: usize| -> Vec<(usize, usize, f32)> {
        (0..to)
            .map(|i| {
                let x = ((i as f32 + 0.5) * from as f32 / to as f32 - 0.5)
                    .clamp(0.0, (from - 1) as f32);
                let i0 = (x as usize).min(from - 1);
                (i0, (i0 + 1).min(from - 1), x - i0 as f32)
            })
            .collect()
    };
    let (xs, ys) = (axis(to.0, w), axis(to.1, h));
    let mut out = vec![T::default(); to.0 as usize * to.1 as usize];
    // Each target row: the two source rows mixed once per source pixel, then that row
    // stretched (one `lerp` a target pixel where a previewed picture has many more
    // target than source pixels).
    out.par_chunks_mut(to.0 as usize).zip(&ys).for_each_init(
        || Vec::with_capacity(w),
        |mixed, (row, &(y0, y1, fy))| {
            let (r0, r1) = (&pixels[y0 * w..][..w], &pixels[y1 * w..][..w]);
            mixed.clear();
            mixed.extend(r0.iter().zip(r1).map(|(&a, &b)| lerp(a, b, fy)));
            for (p, &(x0, x1, fx)) in row.iter_mut().zip(&xs) {
                *p = lerp(mixed[x0], mixed[x1], fx);
            }
        },
    );
    out
}

/// The inverse of [`srgb_encode`].
#[inline]
pub fn srgb_decode(v: f32) -> f32 {
    if v <= 0.040_45 {
        v / 12.92
    } else {
        ((v + 0.055) / 1.055).powf(2.4)
    }
}

/// The linear value of every 8-bit sRGB value, `srgb_decode(v / 255)`, made once. A
/// caller decoding many values takes the table once (each access to it checks that
/// it is made).
pub fn srgb8_table() -> &'static [f32; 256] {
    static TABLE: std::sync::LazyLock<[f32; 256]> =
        std::sync::LazyLock::new(|| std::array::from_fn(|v| srgb_decode(v as f32 / 255.0)));
    &TABLE
}

/// The sRGB transfer function of a linear value in [0, 1].
#[inline]
pub fn srgb_encode(v: f32) -> f32 {
    if v <= 0.003_130_8 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    }
}

/// The kind of file a path names, by its extension.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ImageKind {
    /// 8-bit sRGB after exposure and tone map.
    Png,
    /// Linear float radiance (linear sRGB primaries), no exposure or tone map.
    Exr,
}

impl ImageKind {
    /// The kind of `path`, or an error naming the allowed extensions.
    pub fn of(path: &Path) -> Result<Self> {
        match path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase)
            .as_deref()
        {
            Some("png") if cfg!(feature = "png") => Ok(ImageKind::Png),
            Some("exr") if cfg!(feature = "exr") => Ok(ImageKind::Exr),
            Some(e @ ("png" | "exr")) => Err(Error::Invalid(format!(
                "{}: .{e} files need atmo's `{e}` feature, which this build leaves out",
                path.display()
            ))),
            _ => Err(Error::out_of_range(
                "output file extension",
                path.display(),
                ".png or .exr",
            )),
        }
    }
}

/// The order of an 8-bit texel's colour channels (alpha last).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TexelOrder {
    Rgba,
    Bgra,
}

/// A picture in linear sRGB radiance (the atmosphere's irradiance units per sr).
#[derive(Debug, Clone, PartialEq)]
pub struct Frame {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Row-major pixels, top row first.
    pub pixels: Vec<Vec3>,
}

impl Frame {
    /// What a frame holds a pixel, bytes: linear RGB, an f32 each.
    pub const BYTES_PER_PIXEL: u64 = 12;

    /// What a `width` x `height` frame holds, bytes.
    pub fn bytes_of(width: u32, height: u32) -> u64 {
        width as u64 * height as u64 * Self::BYTES_PER_PIXEL
    }

    /// Checks that a `width` x `height` frame is allowed, before anything is allocated.
    pub fn check_size(width: u32, height: u32) -> Result<()> {
        check_range("width", width as f64, 1.0, 16384.0)?;
        check_range("height", height as f64, 1.0, 16384.0)?;
        crate::budget::check(
            &format!("a {width} x {height} frame"),
            Self::bytes_of(width, height),
            "width or height",
        )
    }

    /// A black frame.
    pub fn new(width: u32, height: u32) -> Self {
        Frame {
            width,
            height,
            pixels: vec![Vec3::ZERO; width as usize * height as usize],
        }
    }

    /// 8-bit sRGB bytes after multiplying by `exposure` and tone mapping.
    pub fn to_srgb8(&self, exposure: f32, tone: ToneMap) -> Vec<u8> {
        let levels = Levels::new(Display { exposure, tone });
        self.pixels
            .iter()
            .flat_map(|p| p.to_array())
            .map(|v| levels.level(v))
            .collect()
    }

    /// The frame as 4-byte texels of `levels`, `order` their channels' order (alpha
    /// 255), into `texels` (resized): what an 8-bit texture of a display takes, rows
    /// in parallel.
    pub fn to_texels(&self, levels: &Levels, order: TexelOrder, texels: &mut Vec<[u8; 4]>) {
        let width = self.width as usize;
        texels.resize(self.pixels.len(), [0; 4]);
        texels
            .par_chunks_mut(width)
            .zip(self.pixels.par_chunks(width))
            .for_each(|(row, pixels)| levels.texels(pixels, order, row));
    }

    /// The frame stretched to `width` x `height` by bilinear interpolation
    /// ([`stretched`]): a preview drawn at a fraction of a window's size, shown at the
    /// window's.
    pub fn upscaled(&self, width: u32, height: u32) -> Frame {
        Frame {
            width,
            height,
            pixels: stretched(
                &self.pixels,
                (self.width, self.height),
                (width, height),
                |a, b, t| a.lerp(b, t),
            ),
        }
    }

    /// Writes the frame to `path` (.png or .exr), atomically. A frame with a NaN or
    /// infinite value is refused, never written: no picture atmo writes holds one.
    pub fn write(&self, path: &Path, exposure: f32, tone: ToneMap) -> Result<()> {
        let kind = ImageKind::of(path)?;
        let bad = self.non_finite();
        if bad > 0 {
            return Err(Error::Invalid(format!(
                "{}: not written, the picture has {bad} of {} values that are not finite \
                 (NaN or infinite); the inputs are outside what the arithmetic holds",
                path.display(),
                3 * self.pixels.len()
            )));
        }
        let encode_error = |e: image::ImageError| Error::Image {
            path: path.to_path_buf(),
            message: e.to_string(),
        };
        crate::files::write_atomically(path, |w| match kind {
            ImageKind::Png => self.encode_png(w, exposure, tone).map_err(encode_error),
            ImageKind::Exr => self.encode_exr(w).map_err(encode_error),
        })
    }

    #[cfg(feature = "png")]
    fn encode_png(&self, w: impl Write, exposure: f32, tone: ToneMap) -> ImageResult<()> {
        image::codecs::png::PngEncoder::new(w).write_image(
            &self.to_srgb8(exposure, tone),
            self.width,
            self.height,
            ExtendedColorType::Rgb8,
        )
    }

    #[cfg(feature = "exr")]
    fn encode_exr(&self, w: impl Write + std::io::Seek) -> ImageResult<()> {
        // The pixels as they are (three f32 each), not a copy: a copy made an EXR
        // output hold 20 bytes a pixel where the frame is charged 12.
        image::codecs::openexr::OpenExrEncoder::new(w).write_image(
            bytemuck::cast_slice(&self.pixels),
            self.width,
            self.height,
            ExtendedColorType::Rgb32F,
        )
    }

    /// Without the feature, [`ImageKind::of`] has refused the file before this.
    #[cfg(not(feature = "png"))]
    fn encode_png(&self, _: impl Write, _: f32, _: ToneMap) -> ImageResult<()> {
        unreachable!("ImageKind::of refuses .png without the png feature")
    }

    /// Without the feature, [`ImageKind::of`] has refused the file before this.
    #[cfg(not(feature = "exr"))]
    fn encode_exr(&self, _: impl Write + std::io::Seek) -> ImageResult<()> {
        unreachable!("ImageKind::of refuses .exr without the exr feature")
    }
}

impl Frame {
    /// How many channel values are NaN or infinite.
    pub fn non_finite(&self) -> usize {
        self.pixels
            .iter()
            .map(|p| p.to_array().iter().filter(|v| !v.is_finite()).count())
            .sum()
    }
}

/// How far two pictures are apart as a display shows them, in 8-bit levels (0-255,
/// not rounded): after the same exposure, tone map and sRGB curve.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LevelErrors {
    /// Root mean square over all pixels and channels.
    pub rms: f64,
    /// Largest.
    pub max: f64,
}

/// The largest block (a tile, or a run of scan lines) the EXR file `bytes` declares,
/// bytes: the decoder reserves a block's declared size before it reads it, so a small
/// file declaring huge tiles took 796 MB (found by the `exr` fuzz target). 0 where the
/// header does not read (the decoder then refuses the file).
#[cfg(feature = "exr")]
fn exr_block_bytes(bytes: &[u8]) -> u64 {
    use exr::meta::BlockDescription;
    let Ok(meta) = exr::meta::MetaData::read_from_buffered(std::io::Cursor::new(bytes), false)
    else {
        return 0;
    };
    meta.headers
        .iter()
        .map(|h| {
            let pixels = match h.blocks {
                BlockDescription::Tiles(t) => {
                    (t.tile_size.0 as u64).saturating_mul(t.tile_size.1 as u64)
                }
                BlockDescription::ScanLines => {
                    h.compression.scan_lines_per_block() as u64 * h.layer_size.0 as u64
                }
            };
            pixels.saturating_mul(h.channels.bytes_per_pixel as u64)
        })
        .max()
        .unwrap_or(0)
}

impl Frame {
    /// Reads linear radiance from an OpenEXR file (as [`Frame::write`] writes it).
    pub fn read_exr(path: &Path) -> Result<Frame> {
        if ImageKind::of(path)? != ImageKind::Exr {
            return Err(Error::out_of_range(
                "input file extension",
                path.display(),
                ".exr (linear radiance; 8-bit PNG has lost it)",
            ));
        }
        let bytes = crate::files::read_bounded(path, "picture", crate::files::DATA_LIMIT_BYTES)?;
        // Decoded beside the file's bytes, which are held until it is done.
        crate::budget::beside(bytes.len() as u64, "the file", || {
            Frame::exr_from_bytes(&bytes, &path.display().to_string())
        })
    }

    /// What the frame holds, bytes.
    pub fn bytes(&self) -> u64 {
        Self::bytes_of(self.width, self.height)
    }

    #[cfg(not(feature = "exr"))]
    pub fn exr_from_bytes(_bytes: &[u8], origin: &str) -> Result<Frame> {
        Err(Error::Invalid(format!(
            "{origin}: this build of atmo reads no EXR (the `exr` feature is off)"
        )))
    }

    /// The picture in the EXR file `bytes` (named `origin` in messages), RGB as linear
    /// radiance. Its size is checked against the pictures' limits and the memory
    /// budget ([`Frame::check_size`], and the decoder's own copy) before it is decoded.
    #[cfg(feature = "exr")]
    pub fn exr_from_bytes(bytes: &[u8], origin: &str) -> Result<Frame> {
        use image::ImageDecoder as _;
        let bad =
            |e: image::ImageError| Error::Invalid(format!("{origin}: cannot read the image: {e}"));
        let decoder = image::codecs::openexr::OpenExrDecoder::new(std::io::Cursor::new(bytes))
            .map_err(bad)?;
        let (width, height) = decoder.dimensions();
        Frame::check_size(width, height)?;
        crate::budget::check(
            &format!("{origin} ({width} x {height})"),
            decoder.total_bytes() + width as u64 * height as u64 * 24 + exr_block_bytes(bytes),
            "the picture's size",
        )?;
        let rgb = image::DynamicImage::from_decoder(decoder)
            .map_err(bad)?
            .to_rgb32f();
        Ok(Frame {
            width: rgb.width(),
            height: rgb.height(),
            pixels: rgb.pixels().map(|p| Vec3::from(p.0)).collect(),
        })
    }

    /// The difference from `other` (same size) in 8-bit levels under `display`.
    pub fn level_errors(&self, other: &Frame, display: Display) -> Result<LevelErrors> {
        if (self.width, self.height) != (other.width, other.height) {
            return Err(Error::Invalid(format!(
                "the pictures differ in size: {} x {} and {} x {}",
                self.width, self.height, other.width, other.height
            )));
        }
        // A NaN or infinite value has no level: a picture with one is refused, never
        // measured (NaN would compare as 0 and call it identical).
        for (which, frame) in [("first", self), ("second", other)] {
            let bad = frame.non_finite();
            if bad > 0 {
                return Err(Error::Invalid(format!(
                    "the {which} picture has {bad} of {} values that are not finite (NaN or \
                     infinite); it cannot be compared",
                    3 * frame.pixels.len()
                )));
            }
        }
        Ok(self.level_errors_over(other, display, 0..self.pixels.len()))
    }

    /// [`Frame::level_errors`] over the pixels of index `pixels` only (row-major), for
    /// pictures of the same size checked to be finite: the error of one kind of pixel
    /// (surfaces, haze) told apart from the rest.
    pub fn level_errors_over(
        &self,
        other: &Frame,
        display: Display,
        pixels: impl IntoIterator<Item = usize>,
    ) -> LevelErrors {
        let (mut sum, mut max, mut n) = (0.0f64, 0.0f64, 0usize);
        for k in pixels {
            let (a, b) = (self.pixels[k], other.pixels[k]);
            for c in 0..3 {
                let d = 255.0 * (display.value(a[c]) - display.value(b[c])) as f64;
                sum += d * d;
                max = max.max(d.abs());
            }
            n += 3;
        }
        LevelErrors {
            rms: (sum / n.max(1) as f64).sqrt(),
            max,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Found by the `exr` fuzz target: 460 bytes whose header declares tiles the
    /// decoder reserved 796 MB for, past the budget; they are charged now.
    #[test]
    #[cfg(feature = "exr")]
    fn an_exr_is_charged_for_the_blocks_its_header_declares() {
        let huge = include_bytes!("../../../fuzz/corpus/exr/huge-tiles.exr");
        assert!(
            exr_block_bytes(huge) >= 796_262_784,
            "{}",
            exr_block_bytes(huge)
        );
        let sky = include_bytes!("../../../fuzz/corpus/exr/sky-8x4.exr");
        let frame = Frame::exr_from_bytes(sky, "sky").unwrap();
        assert_eq!((frame.width, frame.height), (8, 4));
        // Its blocks: a few scan lines of RGB floats.
        assert!(exr_block_bytes(sky) < 1 << 20, "{}", exr_block_bytes(sky));
    }

    #[test]
    fn tone_maps_are_monotone_and_bounded() {
        for t in [ToneMap::Clamp, ToneMap::Exponential, ToneMap::Aces] {
            let mut prev = -1.0;
            for k in 0..100 {
                let v = t.apply(k as f32 * 0.1);
                assert!((0.0..=1.0).contains(&v) && v >= prev, "{t:?}");
                prev = v;
            }
        }
        assert!((srgb_encode(1.0) - 1.0).abs() < 1e-6);
        assert!((srgb_encode(0.5) - 0.7354).abs() < 1e-3);
    }

    #[test]
    fn the_levels_table_gives_the_files_levels_exactly() {
        for tone in [ToneMap::Clamp, ToneMap::Exponential, ToneMap::Aces] {
            for exposure in [0.15, 0.6, 1.0, 7.3] {
                let display = Display { exposure, tone };
                let levels = Levels::new(display);
                let check = |x: f32| {
                    assert_eq!(
                        levels.level(x),
                        Levels::exact(display, x),
                        "{tone:?} exposure {exposure} at {x:e}"
                    )
                };
                // Either side of every level's start, where a slip would show first.
                // There the formula's own rounding may jitter between two levels for an
                // ulp (0.14498337 at 0.15 ACES: 29, the next float 28, then 29): the
                // table gives the formula's level within two ulps.
                for &start in levels.starts.iter().filter(|&&s| s < u32::MAX) {
                    for bits in start.saturating_sub(2)..=start + 2 {
                        let near = (bits.saturating_sub(2)..=bits + 2)
                            .map(|b| Levels::exact(display, f32::from_bits(b)));
                        let level = levels.level(f32::from_bits(bits));
                        assert!(near.into_iter().any(|l| l == level), "{tone:?} {bits}");
                    }
                }
                // 1e-8 to 1e4 in ratios of 1.0001, and what is not a radiance.
                let mut x = 1e-8f32;
                while x < 1e4 {
                    check(x);
                    x *= 1.0001;
                }
                for x in [0.0, -0.0, -1.0, f32::NAN, f32::INFINITY, f32::MAX, 1e-40] {
                    check(x);
                }
                // The argument for two steps: one start a bucket at most.
                let buckets: Vec<u32> = levels.starts[1..]
                    .iter()
                    .filter(|&&s| s < u32::MAX)
                    .map(|s| s >> Levels::SHIFT)
                    .collect();
                assert!(
                    buckets.windows(2).all(|b| b[0] < b[1]),
                    "{tone:?} {exposure}"
                );
            }
        }
        // Every level is reached: the table is not all one value.
        let levels = Levels::new(Display {
            exposure: 1.0,
            tone: ToneMap::Clamp,
        });
        assert_eq!(levels.level(1.0), 255);
        assert_eq!(levels.level(0.5), 188);
        assert_eq!(levels.level(0.0), 0);
    }

    #[test]
    fn texels_hold_the_levels_in_the_order_asked() {
        let mut frame = Frame::new(3, 2);
        frame.pixels[4] = Vec3::new(1.0, 0.5, 0.0);
        let levels = Levels::new(Display {
            exposure: 1.0,
            tone: ToneMap::Clamp,
        });
        let mut texels = Vec::new();
        frame.to_texels(&levels, TexelOrder::Rgba, &mut texels);
        assert_eq!(texels.len(), 6);
        assert_eq!(texels[4], [255, 188, 0, 255]);
        assert_eq!(texels[0], [0, 0, 0, 255]);
        frame.to_texels(&levels, TexelOrder::Bgra, &mut texels);
        assert_eq!(texels[4], [0, 188, 255, 255]);
    }

    #[test]
    fn an_upscaled_frame_keeps_a_linear_ramp_and_the_values_at_the_centres() {
        // A ramp in x and y: bilinear interpolation reproduces it exactly between the
        // outermost centres, and clamps beyond them.
        let mut small = Frame::new(4, 3);
        for (k, p) in small.pixels.iter_mut().enumerate() {
            let (x, y) = ((k % 4) as f32, (k / 4) as f32);
            *p = Vec3::new(x, y, x + 10.0 * y);
        }
        let big = small.upscaled(16, 12);
        assert_eq!((big.width, big.height), (16, 12));
        for y in 0..12 {
            for x in 0..16 {
                // The big pixel's centre in the small frame's pixels.
                let sx = ((x as f32 + 0.5) / 4.0 - 0.5).clamp(0.0, 3.0);
                let sy = ((y as f32 + 0.5) / 4.0 - 0.5).clamp(0.0, 2.0);
                let p = big.pixels[y * 16 + x];
                assert!(
                    (p - Vec3::new(sx, sy, sx + 10.0 * sy)).abs().max_element() < 1e-5,
                    "{x} {y}: {p}"
                );
            }
        }
        // The same size: the frame itself.
        assert_eq!(small.upscaled(4, 3), small);
    }

    #[test]
    fn inverses_undo_the_tone_maps_and_the_srgb_curve() {
        for tone in [ToneMap::Clamp, ToneMap::Exponential, ToneMap::Aces] {
            for k in 0..200 {
                let y = k as f32 / 200.0;
                assert!(
                    (tone.apply(tone.invert(y)) - y).abs() < 2e-6,
                    "{tone:?} {y}"
                );
                assert!((srgb_encode(srgb_decode(y)) - y).abs() < 2e-6, "{y}");
            }
        }
    }

    #[test]
    fn png_and_exr_round_trip_and_no_temporary_is_left() {
        let dir = std::env::temp_dir().join(format!("atmo-image-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let mut f = Frame::new(3, 2);
        f.pixels[4] = Vec3::new(0.5, 1.0, 2.0);
        f.write(&dir.join("a.png"), 1.0, ToneMap::Clamp).unwrap();
        f.write(&dir.join("a.exr"), 1.0, ToneMap::Clamp).unwrap();
        let png = image::open(dir.join("a.png")).unwrap().to_rgb8();
        assert_eq!((png.width(), png.height()), (3, 2));
        assert_eq!(png.get_pixel(1, 1).0, [188, 255, 255]);
        let exr = image::open(dir.join("a.exr")).unwrap().to_rgb32f();
        assert_eq!(exr.get_pixel(1, 1).0, [0.5, 1.0, 2.0]);
        assert!(f.write(&dir.join("a.jpg"), 1.0, ToneMap::Clamp).is_err());
        let names: Vec<_> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        assert_eq!(names.len(), 2, "{names:?}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn oversized_frames_are_refused_before_allocation() {
        assert!(Frame::check_size(0, 10).is_err());
        assert!(Frame::check_size(16384, 16384)
            .unwrap_err()
            .to_string()
            .contains("budget"));
        assert!(Frame::check_size(1920, 1080).is_ok());
    }

    #[test]
    fn pictures_with_nan_or_infinity_are_refused_not_called_identical() {
        let display = Display {
            exposure: 1.0,
            tone: ToneMap::Exponential,
        };
        let black = Frame::new(4, 3);
        let mut nan = Frame::new(4, 3);
        nan.pixels.iter_mut().for_each(|p| *p = Vec3::NAN);
        let mut one_inf = Frame::new(4, 3);
        one_inf.pixels[5].y = f32::NEG_INFINITY;
        assert_eq!(
            (nan.non_finite(), one_inf.non_finite(), black.non_finite()),
            (36, 1, 0)
        );
        let e = nan.level_errors(&black, display).unwrap_err().to_string();
        assert!(e.contains("first picture has 36 of 36"), "{e}");
        let e = black
            .level_errors(&one_inf, display)
            .unwrap_err()
            .to_string();
        assert!(e.contains("second picture has 1 of 36"), "{e}");
        assert_eq!(black.level_errors(&black, display).unwrap().rms, 0.0);
        // Nor is such a picture ever written.
        let dir = std::env::temp_dir().join(format!("atmo-nan-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        for name in ["nan.exr", "nan.png"] {
            let e = one_inf
                .write(&dir.join(name), 1.0, ToneMap::Clamp)
                .unwrap_err();
            assert!(
                e.to_string().contains("1 of 36 values that are not finite"),
                "{e}"
            );
        }
        assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 0);
        std::fs::remove_dir_all(dir).unwrap();
    }
}
