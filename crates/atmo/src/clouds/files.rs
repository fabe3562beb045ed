//! Particle files: CSV to read and write by hand, and a compact binary for large clouds.
//!
//! CSV: a header line `x,y,z,radius,density` or `x,y,z,radius,density,albedo`, then one
//! particle a line (metres, 1/m); blank lines and lines starting with `#` are skipped;
//! without the albedo column every particle gets `default_albedo`.
//!
//! Binary (`.atmo-particles`), little-endian: the 8 bytes `ATMOPART`, a `u32` version
//! (1), a `u32` particle count, a `u32` flag (1 when an albedo follows each particle),
//! then per particle the `f32`s `x y z radius density [albedo]`.

use std::io::Write;
use std::path::Path;

use glam::Vec3;

use super::particles::Particle;
use crate::error::{Error, Result};
use crate::files::write_atomically;

const MAGIC: &[u8; 8] = b"ATMOPART";

/// Largest distance of a particle from the origin, m.
pub const MAX_POSITION_M: f32 = 1e7;
/// Largest particle radius, m.
pub const MAX_RADIUS_M: f32 = 1e5;
/// Largest peak density times radius: an optical depth of 0.84 x this through the centre.
pub const MAX_DENSITY_RADIUS: f32 = 100.0;

/// Checks one particle's numbers, naming `at` (file and line, or index) on error: what a
/// file's reader and any other source of particles (the Python package) hold them to.
pub fn check(p: &Particle, at: &str) -> Result<()> {
    let fields = [
        ("x", p.position.x),
        ("y", p.position.y),
        ("z", p.position.z),
        ("radius", p.radius),
        ("density", p.density),
        ("albedo", p.albedo),
    ];
    for (name, v) in fields {
        if !v.is_finite() {
            return Err(Error::Invalid(format!(
                "{at}: {name} = {v} is not a finite number"
            )));
        }
    }
    // The ranges the arithmetic holds: positions and sizes where f32 keeps a metre's
    // precision over the buffer, and at most an optical depth of about 84 through a
    // particle's centre (density x radius <= 100; e^-84 is opaque to any display), which
    // the GPU's fixed-point light pass sums without overflow.
    if p.position.abs().max_element() > MAX_POSITION_M {
        return Err(Error::out_of_range(
            &format!("{at}: x, y, z"),
            format!("{:?}", p.position.to_array()),
            &format!("[-{MAX_POSITION_M:e}, {MAX_POSITION_M:e}] m"),
        ));
    }
    if !(p.radius > 0.0 && p.radius <= MAX_RADIUS_M) {
        return Err(Error::out_of_range(
            &format!("{at}: radius"),
            p.radius,
            &format!("(0, {MAX_RADIUS_M:e}] m"),
        ));
    }
    if !(p.density >= 0.0 && p.density * p.radius <= MAX_DENSITY_RADIUS) {
        return Err(Error::out_of_range(
            &format!("{at}: density"),
            p.density,
            &format!(
                "[0, {}] 1/m at radius {} m (density x radius <= {MAX_DENSITY_RADIUS}: opaque)",
                MAX_DENSITY_RADIUS / p.radius,
                p.radius
            ),
        ));
    }
    if !(0.0..=1.0).contains(&p.albedo) {
        return Err(Error::out_of_range(
            &format!("{at}: albedo"),
            p.albedo,
            "[0, 1]",
        ));
    }
    Ok(())
}

/// The particles of a CSV text; `origin` names it in messages.
pub fn parse_csv(text: &str, origin: &str, default_albedo: f32) -> Result<Vec<Particle>> {
    // At most a particle a line, less the header: charged before any is parsed.
    super::particles::check_count(text.lines().count().saturating_sub(1), origin)?;
    let mut lines = text
        .lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.trim()))
        .filter(|(_, l)| !l.is_empty() && !l.starts_with('#'));
    let (header_line, header) = lines
        .next()
        .ok_or_else(|| Error::Invalid(format!("{origin}: no header line and no particles")))?;
    let columns: Vec<&str> = header.split(',').map(str::trim).collect();
    let with_albedo = match columns.as_slice() {
        ["x", "y", "z", "radius", "density"] => false,
        ["x", "y", "z", "radius", "density", "albedo"] => true,
        _ => {
            return Err(Error::Invalid(format!(
                "{origin}:{header_line}: the header is `{header}`; expected `x,y,z,radius,density` or `x,y,z,radius,density,albedo`"
            )))
        }
    };
    let mut particles = Vec::new();
    for (line, text) in lines {
        let at = format!("{origin}:{line}");
        let values: Vec<f32> = text
            .split(',')
            .map(|v| {
                v.trim()
                    .parse::<f32>()
                    .map_err(|_| Error::Invalid(format!("{at}: `{}` is not a number", v.trim())))
            })
            .collect::<Result<_>>()?;
        if values.len() != columns.len() {
            return Err(Error::Invalid(format!(
                "{at}: {} values, the header has {}",
                values.len(),
                columns.len()
            )));
        }
        let p = Particle {
            position: Vec3::new(values[0], values[1], values[2]),
            radius: values[3],
            density: values[4],
            albedo: if with_albedo {
                values[5]
            } else {
                default_albedo
            },
        };
        check(&p, &at)?;
        particles.push(p);
    }
    if particles.is_empty() {
        return Err(Error::Invalid(format!("{origin}: no particles")));
    }
    Ok(particles)
}

/// The particles of a binary file's bytes.
pub fn parse_binary(bytes: &[u8], origin: &str) -> Result<Vec<Particle>> {
    let fail = |why: String| Error::Invalid(format!("{origin}: {why}"));
    if bytes.len() < 20 || &bytes[..8] != MAGIC {
        return Err(fail(
            "not an atmo particle file (no ATMOPART header)".into(),
        ));
    }
    let word = |at: usize| u32::from_le_bytes(bytes[at..at + 4].try_into().expect("4 bytes"));
    let (version, count, flags) = (word(8), word(12) as usize, word(16));
    if version != 1 {
        return Err(fail(format!(
            "version {version}; this atmo reads version 1"
        )));
    }
    if flags > 1 {
        return Err(fail(format!("flags = {flags}; allowed 0 or 1")));
    }
    let floats = if flags == 1 { 6 } else { 5 };
    let body = &bytes[20..];
    if count == 0 {
        return Err(fail("no particles".into()));
    }
    super::particles::check_count(count, origin)?;
    if body.len() != count * floats * 4 {
        return Err(fail(format!(
            "{} bytes of particles for {count} particles of {} bytes each",
            body.len(),
            floats * 4
        )));
    }
    body.chunks_exact(floats * 4)
        .enumerate()
        .map(|(i, chunk)| {
            let v: Vec<f32> = chunk
                .as_chunks::<4>()
                .0
                .iter()
                .map(|b| f32::from_le_bytes(*b))
                .collect();
            let p = Particle {
                position: Vec3::new(v[0], v[1], v[2]),
                radius: v[3],
                density: v[4],
                albedo: if floats == 6 { v[5] } else { 1.0 },
            };
            check(&p, &format!("{origin}: particle {i}"))?;
            Ok(p)
        })
        .collect()
}

/// Reads a particle file: binary if it starts with `ATMOPART`, CSV otherwise.
pub fn read(path: &Path, default_albedo: f32) -> Result<Vec<Particle>> {
    let bytes = crate::files::read_bounded(path, "particle file", crate::files::DATA_LIMIT_BYTES)?;
    let origin = path.display().to_string();
    if bytes.starts_with(MAGIC) {
        parse_binary(&bytes, &origin)
    } else {
        let text = String::from_utf8(bytes).map_err(|_| {
            Error::Invalid(format!(
                "{origin}: neither UTF-8 CSV nor an atmo particle file"
            ))
        })?;
        parse_csv(&text, &origin, default_albedo)
    }
}

/// Writes `particles` to `path`, atomically: binary if it ends in `.atmo-particles`,
/// CSV otherwise.
pub fn write(path: &Path, particles: &[Particle]) -> Result<()> {
    let binary = path.extension().is_some_and(|e| e == "atmo-particles");
    let io = Error::io_at(path);
    write_atomically(path, |w| {
        if binary {
            w.write_all(MAGIC).map_err(io)?;
            for word in [1u32, particles.len() as u32, 1] {
                w.write_all(&word.to_le_bytes()).map_err(io)?;
            }
            for p in particles {
                for v in [
                    p.position.x,
                    p.position.y,
                    p.position.z,
                    p.radius,
                    p.density,
                    p.albedo,
                ] {
                    w.write_all(&v.to_le_bytes()).map_err(io)?;
                }
            }
        } else {
            writeln!(w, "x,y,z,radius,density,albedo").map_err(io)?;
            for p in particles {
                writeln!(
                    w,
                    "{},{},{},{},{},{}",
                    p.position.x, p.position.y, p.position.z, p.radius, p.density, p.albedo
                )
                .map_err(io)?;
            }
        }
        Ok(())
    })
}
