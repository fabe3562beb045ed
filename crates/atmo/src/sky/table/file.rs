//! The `.atmo-sky` file of a [`SkylightTable`]: little-endian, checksummed, read with
//! full validation (a truncated, altered or foreign file is an error naming the
//! problem, never a panic or a wrong sky).
//!
//! Layout, version 2 (`u32`, `f64` ... little-endian; `f16` IEEE half):
//!
//! | field | type |
//! | --- | --- |
//! | magic | 8 bytes `atmo-sky` |
//! | version | `u32` = 2 (1: the same layout; its order is never 0) |
//! | atmosphere | `u32` length + UTF-8 TOML (as `Atmosphere::to_toml`) |
//! | shells, directions L, scattering directions, sun bins, order (0: all) | 5 x `u32` |
//! | multiple Mie | `u8` 0 or 1 |
//! | longest interval, m | `f64` |
//! | sun steps M, lowest sun elevation (rad), density at the horizon | `u32`, `f64`, `f64` |
//! | altitude steps N, highest altitude (m), spacing power | `u32`, `f64`, `f64` |
//! | epsilon, exposure, tone map (0 clamp, 1 exponential, 2 ACES), sRGB-encoded (0, 1) | `f32`, `f32`, `u8`, `u8` |
//! | largest error at the grid points, units of epsilon | `f32` |
//! | terms computed K, singular values | `u32`, K x `f32` |
//! | term counts T, rows R, G, B x `[elevation][azimuth]` | 3 L*L x `u16`, each <= K |
//! | fixed-point steps of `s_k` and `t_k`, k < max T | 2 max T x `f32` |
//! | length of the packed tables, then the zlib stream | `u32`, bytes |
//!
//! The packed tables inflate to `n` `i16` values stored as `n` low bytes then `n` high
//! bytes: first `t_k sigma_k / step`, `[k][altitude][sun]` for k < max T, each run of
//! suns as differences from the previous sun (the first from 0, wrapping); then
//! `s_k / step` of the rows in order of decreasing T, k after k (sum of T values).
//! | CRC-32 of every byte before it | `u32` |

use std::io::{Read, Write};
use std::path::Path;

use flate2::read::ZlibDecoder;
use flate2::write::ZlibEncoder;
use flate2::Compression;

use super::factors::{dequantize, to_fixed, Factors};
use super::{ErrorBound, SkylightTable, TableSettings, CHANNELS};
use crate::atmosphere::Atmosphere;
use crate::error::{Error, Result};
use crate::files::write_atomically;
use crate::image::{Display, ToneMap};
use crate::sky::shells::Order;
use crate::sky::SkySettings;

/// The first bytes of every table file.
pub const MAGIC: &[u8; 8] = b"atmo-sky";

/// The version this build writes; it reads it and version 1, which differs only in
/// that its order is never 0 ("all").
pub const VERSION: u32 = 2;

impl SkylightTable {
    /// The file's bytes.
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut w = Vec::new();
        w.extend_from_slice(MAGIC);
        put_u32(&mut w, VERSION);
        put_settings(&mut w, &self.atmosphere, &self.settings);
        let s = &self.settings;
        put_f32(&mut w, self.grid_error);
        let f = &self.factors;
        put_u32(&mut w, f.sigma.len() as u32);
        f.sigma.iter().for_each(|&x| put_f32(&mut w, x));
        f.terms
            .iter()
            .for_each(|&t| w.extend_from_slice(&t.to_le_bytes()));
        f.s_step
            .iter()
            .chain(&f.t_step)
            .for_each(|&x| put_f32(&mut w, x));
        // t_k as differences along the sun (smooth there), then s_k; deflated.
        let mut q = Vec::with_capacity(f.t.len() + f.s.len());
        let cols = s.sun_steps * s.altitude_steps;
        for (k, t) in f.t.chunks(cols).enumerate() {
            for run in t.chunks(s.sun_steps) {
                let mut previous = 0i16;
                for &x in run {
                    let v = to_fixed(x, f.t_step[k]);
                    q.push(v.wrapping_sub(previous));
                    previous = v;
                }
            }
        }
        let mut values = f.s.iter();
        for (k, &n) in f.used.iter().enumerate() {
            q.extend(
                values
                    .by_ref()
                    .take(n as usize)
                    .map(|&x| to_fixed(x, f.s_step[k])),
            );
        }
        let packed = pack(&q);
        put_u32(&mut w, packed.len() as u32);
        w.extend_from_slice(&packed);
        seal(w)
    }

    /// Writes the table to `path` atomically (a temporary file renamed when complete).
    pub fn write(&self, path: &Path) -> Result<()> {
        write_bytes(path, &self.to_bytes())
    }

    /// Reads and validates a table file.
    pub fn read(path: &Path) -> Result<Self> {
        let bytes = crate::files::read_bounded(path, "table file", crate::files::DATA_LIMIT_BYTES)?;
        Self::from_bytes(&bytes, &path.display().to_string())
    }

    /// Parses and validates the bytes of a table file; `origin` names it in errors.
    pub fn from_bytes(bytes: &[u8], origin: &str) -> Result<Self> {
        let (_, mut r) = open(
            bytes,
            MAGIC,
            VERSION,
            origin,
            "an atmo sky table (it does not start with 'atmo-sky'); make one with `atmo \
             precompute sky`",
        )?;
        Self::parse(&mut r, origin).map_err(|e| in_file(e, origin))
    }

    fn parse(r: &mut Reader, origin: &str) -> Result<Self> {
        let (atmosphere, settings) = parse_settings(r, origin)?;
        let grid_error = r.f32("grid error")?;
        if !(0.0..=1.0).contains(&grid_error) {
            return Err(Error::Invalid(format!(
                "grid error {grid_error} outside [0, 1] epsilon"
            )));
        }
        let rows = settings.sky.directions.pow(2);
        let cols = settings.sun_steps * settings.altitude_steps;
        let factors = read_factors(r, CHANNELS * rows, cols, settings.sun_steps)?;
        if r.at != r.bytes.len() {
            return Err(Error::Invalid(format!(
                "{} unexpected bytes after the tables",
                r.bytes.len() - r.at
            )));
        }
        Ok(SkylightTable {
            sun: settings.sun_axis(),
            altitude: settings.altitude_axis(),
            atmosphere,
            settings,
            grid_error,
            factors,
        })
    }
}

/// Writes `bytes` to `path` atomically (a temporary file renamed when complete).
pub(super) fn write_bytes(path: &Path, bytes: &[u8]) -> Result<()> {
    write_atomically(path, |w| {
        std::io::Write::write_all(w, bytes).map_err(Error::io_at(path))
    })
}

/// `w` with its CRC-32 appended: what [`open`] checks.
pub(super) fn seal(mut w: Vec<u8>) -> Vec<u8> {
    let crc = crc32fast::hash(&w);
    put_u32(&mut w, crc);
    w
}

/// The checksummed body of a file that starts with `magic` and a version from 1 to
/// `newest`, after the version; `what` says what the file should be, for the error when
/// the magic differs. Errors name `origin`.
pub(super) fn open<'a>(
    bytes: &'a [u8],
    magic: &[u8; 8],
    newest: u32,
    origin: &str,
    what: &str,
) -> Result<(u32, Reader<'a>)> {
    let fail = |message: String| Error::Parse {
        path: origin.to_string(),
        message,
    };
    if bytes.len() < magic.len() || &bytes[..magic.len()] != magic {
        return Err(fail(format!("not {what}")));
    }
    let body = bytes
        .len()
        .checked_sub(4)
        .filter(|&n| n >= 12)
        .ok_or_else(|| fail("truncated: too short to hold a header and a checksum".into()))?;
    let version = u32::from_le_bytes(bytes[8..12].try_into().expect("4 bytes"));
    if !(1..=newest).contains(&version) {
        return Err(fail(format!(
            "file version {version}; this atmo reads versions 1 to {newest}"
        )));
    }
    let stored = u32::from_le_bytes(bytes[body..].try_into().expect("4 bytes"));
    if crc32fast::hash(&bytes[..body]) != stored {
        return Err(fail(
            "damaged: the checksum does not match (the file was truncated or altered)".into(),
        ));
    }
    Ok((
        version,
        Reader {
            bytes: &bytes[..body],
            at: 12,
        },
    ))
}

/// A content error of the file `origin` as a parse error naming it.
pub(super) fn in_file(e: Error, origin: &str) -> Error {
    match e {
        Error::Invalid(message) => Error::Parse {
            path: origin.to_string(),
            message,
        },
        other => other,
    }
}

/// Writes the atmosphere and the settings, the part every table and every part of a
/// split precompute begins with (the layout's rows from the atmosphere to the sRGB flag).
pub(super) fn put_settings(w: &mut Vec<u8>, atmosphere: &Atmosphere, s: &TableSettings) {
    let toml = atmosphere.to_toml();
    put_u32(w, toml.len() as u32);
    w.extend_from_slice(toml.as_bytes());
    let sky = &s.sky;
    for v in [
        sky.shells,
        sky.directions,
        sky.scattering_directions,
        sky.sun_bins,
        // 0 for every order (version 2).
        match sky.order {
            Order::Through(n) => n as usize,
            Order::All => 0,
        },
    ] {
        put_u32(w, v as u32);
    }
    w.push(sky.multiple_mie as u8);
    put_f64(w, sky.max_interval_m);
    put_u32(w, s.sun_steps as u32);
    put_f64(w, s.min_sun_elevation);
    put_f64(w, s.sun_horizon_density);
    put_u32(w, s.altitude_steps as u32);
    put_f64(w, s.max_altitude_m);
    put_f64(w, s.altitude_power);
    put_f32(w, s.bound.epsilon);
    put_f32(w, s.bound.display.exposure);
    w.push(match s.bound.display.tone {
        ToneMap::Clamp => 0,
        ToneMap::Exponential => 1,
        ToneMap::Aces => 2,
    });
    w.push(s.bound.srgb as u8);
}

/// Reads what [`put_settings`] wrote, validated.
pub(super) fn parse_settings(r: &mut Reader, origin: &str) -> Result<(Atmosphere, TableSettings)> {
    let toml_len = r.u32("atmosphere length")? as usize;
    let toml = std::str::from_utf8(r.take(toml_len, "atmosphere")?)
        .map_err(|_| Error::Invalid("the atmosphere is not UTF-8".into()))?;
    let atmosphere = Atmosphere::from_toml_str(toml, &format!("{origin} (atmosphere)"))?;
    let mut sky = SkySettings {
        shells: r.u32("shells")? as usize,
        directions: r.u32("directions")? as usize,
        scattering_directions: r.u32("scattering directions")? as usize,
        sun_bins: r.u32("sun bins")? as usize,
        order: match r.u32("order")? {
            0 => Order::All,
            n => Order::Through(n),
        },
        ..SkySettings::default()
    };
    sky.multiple_mie = match r.take(1, "multiple Mie")?[0] {
        0 => false,
        1 => true,
        v => return Err(Error::Invalid(format!("multiple Mie flag {v}, not 0 or 1"))),
    };
    sky.max_interval_m = r.f64("longest interval")?;
    let sun_steps = r.u32("sun steps")? as usize;
    let min_sun_elevation = r.f64("lowest sun elevation")?;
    let sun_horizon_density = r.f64("sun density at the horizon")?;
    let altitude_steps = r.u32("altitude steps")? as usize;
    let max_altitude_m = r.f64("highest altitude")?;
    let altitude_power = r.f64("altitude spacing power")?;
    let epsilon = r.f32("epsilon")?;
    let exposure = r.f32("exposure")?;
    let tone = match r.take(1, "tone map")?[0] {
        0 => ToneMap::Clamp,
        1 => ToneMap::Exponential,
        2 => ToneMap::Aces,
        v => return Err(Error::Invalid(format!("tone map {v}, not 0, 1 or 2"))),
    };
    let srgb = match r.take(1, "sRGB flag")?[0] {
        0 => false,
        1 => true,
        v => return Err(Error::Invalid(format!("sRGB flag {v}, not 0 or 1"))),
    };
    let settings = TableSettings {
        sky,
        sun_steps,
        min_sun_elevation,
        sun_horizon_density,
        altitude_steps,
        max_altitude_m,
        altitude_power,
        bound: ErrorBound {
            epsilon,
            display: Display { exposure, tone },
            srgb,
        },
    };
    // The fields only: a part's merge and a precompute check their memory themselves.
    settings.check_fields(&atmosphere)?;
    Ok((atmosphere, settings))
}

fn read_factors(r: &mut Reader, rows: usize, cols: usize, sun_steps: usize) -> Result<Factors> {
    let rank = r.u32("terms computed")? as usize;
    if rank == 0 || rank > rows.min(cols) {
        return Err(Error::Invalid(format!(
            "{rank} terms computed, allowed 1 to {}",
            rows.min(cols)
        )));
    }
    let sigma = (0..rank)
        .map(|_| r.f32("singular values"))
        .collect::<Result<Vec<_>>>()?;
    if let Some(bad) = sigma.iter().find(|x| !(x.is_finite() && **x >= 0.0)) {
        return Err(Error::Invalid(format!(
            "singular value {bad} is not a finite number >= 0"
        )));
    }
    let terms = (0..rows)
        .map(|_| {
            let b = r.take(2, "term counts")?;
            Ok(u16::from_le_bytes([b[0], b[1]]))
        })
        .collect::<Result<Vec<_>>>()?;
    if let Some(&t) = terms.iter().find(|&&t| t as usize > rank) {
        return Err(Error::Invalid(format!(
            "a direction uses {t} terms of the {rank} computed"
        )));
    }
    let (order, used) = Factors::layout(&terms);
    let most = used.len();
    let steps = (0..2 * most)
        .map(|_| r.f32("fixed-point steps"))
        .collect::<Result<Vec<_>>>()?;
    if let Some(bad) = steps.iter().find(|x| !(x.is_finite() && **x > 0.0)) {
        return Err(Error::Invalid(format!(
            "fixed-point step {bad} is not a positive number"
        )));
    }
    let (s_step, t_step) = (steps[..most].to_vec(), steps[most..].to_vec());
    let s_len: usize = used.iter().map(|&n| n as usize).sum();
    let packed_len = r.u32("packed tables length")? as usize;
    let q = unpack(r.take(packed_len, "packed tables")?, most * cols + s_len)?;
    let (q_t, q_s) = q.split_at(most * cols);
    let mut t = Vec::with_capacity(most * cols);
    for (k, run) in q_t.chunks(sun_steps).enumerate() {
        let step = t_step[k * sun_steps / cols];
        let mut value = 0i16;
        t.extend(run.iter().map(|&d| {
            value = value.wrapping_add(d);
            dequantize(value, step)
        }));
    }
    let mut s = Vec::with_capacity(s_len);
    let mut rest = q_s;
    for (&n, &step) in used.iter().zip(&s_step) {
        let (these, others) = rest.split_at(n as usize);
        s.extend(these.iter().map(|&v| dequantize(v, step)));
        rest = others;
    }
    // Values, not only bytes: a table whose checksum holds may still have been made to
    // draw infinity (sum over the terms of s_k t_k); real tables stay below 1e6.
    let max_abs = |v: &[f32]| v.iter().fold(0.0f64, |m, &x| m.max(x.abs() as f64));
    let largest = max_abs(&s) * max_abs(&t) * most as f64;
    if largest.is_nan() || largest >= 1e30 {
        return Err(Error::Invalid(format!(
            "the tables' values reach {largest:e}, past what a sky can draw in f32"
        )));
    }
    Ok(Factors {
        s_step,
        t_step,
        sigma,
        terms,
        order,
        used,
        s,
        t,
    })
}

pub(super) fn put_u32(w: &mut Vec<u8>, v: u32) {
    w.extend_from_slice(&v.to_le_bytes());
}

/// Fixed-point values as stored: all low bytes, then all high bytes (the high bytes of
/// small differences are alike), deflated. A 30 % smaller file than the raw values.
fn pack(values: &[i16]) -> Vec<u8> {
    let mut planes: Vec<u8> = values.iter().map(|v| v.to_le_bytes()[0]).collect();
    planes.extend(values.iter().map(|v| v.to_le_bytes()[1]));
    let mut encoder = ZlibEncoder::new(Vec::new(), Compression::best());
    encoder.write_all(&planes).expect("writing to memory");
    encoder.finish().expect("writing to memory")
}

/// The `count` values [`pack`] packed, or an error if the bytes do not inflate to them.
fn unpack(bytes: &[u8], count: usize) -> Result<Vec<i16>> {
    let mut planes = Vec::with_capacity(2 * count);
    ZlibDecoder::new(bytes)
        .take(2 * count as u64 + 1)
        .read_to_end(&mut planes)
        .map_err(|e| Error::Invalid(format!("the tables do not decompress: {e}")))?;
    if planes.len() != 2 * count {
        return Err(Error::Invalid(format!(
            "the tables decompress to {} bytes, not {}",
            planes.len(),
            2 * count
        )));
    }
    let (low, high) = planes.split_at(count);
    Ok(low
        .iter()
        .zip(high)
        .map(|(&l, &h)| i16::from_le_bytes([l, h]))
        .collect())
}

pub(super) fn put_f32(w: &mut Vec<u8>, v: f32) {
    w.extend_from_slice(&v.to_le_bytes());
}

fn put_f64(w: &mut Vec<u8>, v: f64) {
    w.extend_from_slice(&v.to_le_bytes());
}

/// A cursor over the checksummed bytes; running past the end names what was missing.
pub(super) struct Reader<'a> {
    bytes: &'a [u8],
    pub(super) at: usize,
}

impl Reader<'_> {
    /// How many bytes the body holds.
    pub(super) fn bytes_len(&self) -> usize {
        self.bytes.len()
    }

    pub(super) fn take(&mut self, n: usize, what: &str) -> Result<&[u8]> {
        let end = self.at.checked_add(n).filter(|&e| e <= self.bytes.len());
        let end = end.ok_or_else(|| {
            Error::Invalid(format!("ends inside the {what} (at byte {})", self.at))
        })?;
        let out = &self.bytes[self.at..end];
        self.at = end;
        Ok(out)
    }

    pub(super) fn u32(&mut self, what: &str) -> Result<u32> {
        Ok(u32::from_le_bytes(
            self.take(4, what)?.try_into().expect("4 bytes"),
        ))
    }

    pub(super) fn f32(&mut self, what: &str) -> Result<f32> {
        let v = f32::from_le_bytes(self.take(4, what)?.try_into().expect("4 bytes"));
        finite(v as f64, what).map(|_| v)
    }

    pub(super) fn f64(&mut self, what: &str) -> Result<f64> {
        let v = f64::from_le_bytes(self.take(8, what)?.try_into().expect("8 bytes"));
        finite(v, what).map(|_| v)
    }
}

fn finite(v: f64, what: &str) -> Result<()> {
    if v.is_finite() {
        Ok(())
    } else {
        Err(Error::Invalid(format!("the {what} is not a finite number")))
    }
}
