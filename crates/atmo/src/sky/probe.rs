//! Directions to probe the sky along (`atmo sky --probe`): a CSV file with the header
//! `azimuth_deg,elevation_deg`, then one direction a line, azimuth from the sun's.

use std::path::Path;

use crate::error::{Error, Result};

/// Reads a probe file through the bounded reader ([`crate::files::TEXT_LIMIT_BYTES`]).
pub fn read_directions(path: &Path) -> Result<Vec<(f64, f64)>> {
    let text = crate::files::read_text(path, "probe file", crate::files::TEXT_LIMIT_BYTES)?;
    parse_directions(&text, &path.display().to_string())
}

/// The (azimuth from the sun, elevation) pairs in degrees of a probe file's text;
/// `origin` names it in messages, which give the line. Every value is finite and every
/// elevation in [-90, 90].
pub fn parse_directions(text: &str, origin: &str) -> Result<Vec<(f64, f64)>> {
    let bad = |line: usize, message: String| Error::Parse {
        path: format!("{origin}:{line}"),
        message,
    };
    let mut lines = text
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty());
    match lines.next() {
        Some((_, header)) if header.trim().replace(' ', "") == "azimuth_deg,elevation_deg" => {}
        _ => {
            return Err(bad(
                1,
                "the first line must be the header `azimuth_deg,elevation_deg`".into(),
            ))
        }
    }
    let mut directions = Vec::new();
    for (k, line) in lines {
        let fields: Vec<&str> = line.split(',').map(str::trim).collect();
        let parse = |s: &str| s.parse::<f64>().ok().filter(|v| v.is_finite());
        match fields.as_slice() {
            [a, e] => match (parse(a), parse(e)) {
                (Some(a), Some(e)) if (-90.0..=90.0).contains(&e) => directions.push((a, e)),
                (Some(_), Some(e)) => {
                    return Err(bad(
                        k + 1,
                        format!("elevation_deg = {e} is out of range: allowed [-90, 90]"),
                    ))
                }
                _ => return Err(bad(k + 1, format!("expected two numbers, found `{line}`"))),
            },
            _ => {
                return Err(bad(
                    k + 1,
                    format!("expected `azimuth_deg,elevation_deg`, found `{line}`"),
                ))
            }
        }
    }
    if directions.is_empty() {
        return Err(bad(1, "no directions after the header".into()));
    }
    Ok(directions)
}

#[cfg(test)]
mod tests {
    use super::parse_directions;

    #[test]
    fn directions_are_read_by_line_and_bad_ones_named() {
        let ok = parse_directions("azimuth_deg, elevation_deg\n10,20\n\n-30, -5\n", "p.csv");
        assert_eq!(ok.unwrap(), [(10.0, 20.0), (-30.0, -5.0)]);
        for (text, wanted) in [
            ("x,y\n1,2\n", "p.csv:1: the first line must be the header"),
            ("azimuth_deg,elevation_deg\n", "p.csv:1: no directions"),
            (
                "azimuth_deg,elevation_deg\n1,2\n3,95\n",
                "p.csv:3: elevation_deg = 95",
            ),
            (
                "azimuth_deg,elevation_deg\nnan,2\n",
                "p.csv:2: expected two numbers",
            ),
            (
                "azimuth_deg,elevation_deg\n1,2,3\n",
                "p.csv:2: expected `azimuth_deg",
            ),
        ] {
            let e = parse_directions(text, "p.csv").unwrap_err().to_string();
            assert!(e.starts_with(wanted), "{e}");
        }
    }
}
