//! IES LM-63 files (the 1986, 1991, 1995, 2002 and 2019 editions).

use super::*;

/// The numbers of a text after a given line, with the line each came from, read as
/// they are needed: LM-63's values may run across lines as the writer likes, separated
/// by blanks or commas.
pub(super) struct Numbers<'a> {
    pub(super) words: std::iter::Peekable<Box<dyn Iterator<Item = (usize, &'a str)> + 'a>>,
    /// The line of the last number taken.
    pub(super) last_line: usize,
    pub(super) origin: &'a str,
}

impl<'a> Numbers<'a> {
    pub(super) fn new(
        lines: impl Iterator<Item = (usize, &'a str)> + 'a,
        origin: &'a str,
    ) -> Numbers<'a> {
        let words: Box<dyn Iterator<Item = (usize, &'a str)> + 'a> =
            Box::new(lines.flat_map(|(n, line)| {
                line.split(|c: char| c.is_whitespace() || c == ',')
                    .filter(|w| !w.is_empty())
                    .map(move |w| (n, w))
            }));
        Numbers {
            words: words.peekable(),
            last_line: 1,
            origin,
        }
    }

    /// The next number, named `what` in messages.
    pub(super) fn number(&mut self, what: &str) -> Result<f32> {
        let Some((line, word)) = self.words.next() else {
            return Err(ies_error(
                self.origin,
                self.last_line,
                format!("the file ends where the {what} should be"),
            ));
        };
        self.last_line = line;
        parse_number(word, what).map_err(|why| ies_error(self.origin, line, why))
    }

    /// The next number as a count in `[lo, hi]`.
    pub(super) fn count(&mut self, what: &str, lo: usize, hi: usize) -> Result<usize> {
        let x = self.number(what)?;
        whole(x, what, lo, hi).map_err(|why| ies_error(self.origin, self.last_line, why))
    }

    /// The next `n` numbers.
    pub(super) fn list(&mut self, n: usize, what: &str) -> Result<Vec<f32>> {
        (0..n)
            .map(|k| self.number(&format!("{what} number {} of {n}", k + 1)))
            .collect()
    }

    /// The line of the next number (or of the last, at the end).
    pub(super) fn line(&mut self) -> usize {
        self.words.peek().map_or(self.last_line, |w| w.0)
    }
}

pub(super) fn ies_error(origin: &str, line: usize, why: String) -> Error {
    Error::Parse {
        path: format!("IES file {origin}"),
        message: format!("line {line}: {why}"),
    }
}

impl Photometry {
    /// Reads an IES LM-63 file (1986 without a first line, `IESNA91`, `IESNA:LM-63-1995`,
    /// `IESNA:LM-63-2002`, `IES:LM-63-2019`); `origin` names it in messages.
    ///
    /// Candela are the file's values times its candela multiplier and ballast factor
    /// (and, before 2002, its ballast-lamp factor; from 2002 on that number is "future
    /// use" and then the file generation type, not a factor). Only type C photometry is
    /// taken (types A and B are for floodlights and vehicle lamps, measured about other
    /// axes). Tilt data (`TILT=INCLUDE`) are read and checked but not applied: they say
    /// how the lamp's output changes when the luminaire is tilted from its measured
    /// position, a correction for lamps whose output depends on burning position.
    pub fn from_ies(text: &str, origin: &str) -> Result<Photometry> {
        let fail = |line: usize, why: String| ies_error(origin, line, why);
        let mut lines = text.lines().enumerate().map(|(k, l)| (k + 1, l.trim()));
        let first = text
            .lines()
            .next()
            .unwrap_or("")
            .trim()
            .to_ascii_uppercase();
        // Before 2002 the second number of the ballast line is a factor on the candela.
        let lamp_factor_applies = !(first.contains("LM-63-2002") || first.contains("LM-63-2019"));
        // The keyword lines end at the TILT line.
        let tilt = loop {
            match lines.next() {
                None => {
                    return Err(fail(
                        text.lines().count().max(1),
                        "no `TILT=` line: this is not an IES LM-63 file".into(),
                    ))
                }
                Some((n, line)) if line.to_ascii_uppercase().starts_with("TILT") => {
                    let value = line.split_once('=').map(|(_, v)| v.trim());
                    match value {
                        Some(v) if !v.is_empty() => break (n, v.to_ascii_uppercase()),
                        _ => {
                            return Err(fail(
                                n,
                                "the TILT line needs `=NONE`, `=INCLUDE` or `=<file>`".into(),
                            ))
                        }
                    }
                }
                Some(_) => {}
            }
        };
        let mut numbers = Numbers::new(lines, origin);
        if tilt.1 == "INCLUDE" {
            numbers.count("lamp-to-luminaire geometry", 1, 3)?;
            let n = numbers.count("number of tilt angles", 0, MAX_ANGLES)?;
            let angles_line = numbers.line();
            let angles = numbers.list(n, "tilt angle")?;
            increasing(&angles, "tilt angle", 0.0, 90.0).map_err(|why| fail(angles_line, why))?;
            let factors_line = numbers.line();
            let factors = numbers.list(n, "tilt multiplying factor")?;
            if let Some(f) = factors.iter().find(|f| **f < 0.0) {
                return Err(fail(
                    factors_line,
                    format!("tilt multiplying factor {f} is negative"),
                ));
            }
        }
        let _lamps = numbers.number("number of lamps")?;
        let _lumens = numbers.number("lumens per lamp")?;
        let multiplier_line = numbers.line();
        let multiplier = numbers.number("candela multiplier")?;
        if multiplier <= 0.0 {
            return Err(fail(
                multiplier_line,
                format!("the candela multiplier is {multiplier}: allowed > 0"),
            ));
        }
        let nv = numbers.count("number of vertical angles", 1, MAX_ANGLES)?;
        let nh = numbers.count("number of horizontal angles", 1, MAX_ANGLES)?;
        if nv * nh > MAX_VALUES {
            return Err(fail(
                numbers.line(),
                format!(
                    "{nv} vertical by {nh} horizontal angles make {} values, above the limit of {MAX_VALUES}",
                    nv * nh
                ),
            ));
        }
        let type_line = numbers.line();
        match numbers.count("photometric type", 1, 3)? {
            1 => {}
            t => {
                return Err(fail(
                    type_line,
                    format!(
                        "photometric type {t} ({}) is not read: atmo reads type C (1), the \
                         photometry of spotlights and stage luminaires",
                        if t == 2 { "B" } else { "A" }
                    ),
                ))
            }
        }
        numbers.count("units type", 1, 2)?;
        for what in ["luminaire width", "luminaire length", "luminaire height"] {
            numbers.number(what)?;
        }
        let ballast_line = numbers.line();
        let ballast = numbers.number("ballast factor")?;
        let lamp_factor = numbers.number("ballast-lamp photometric factor")?;
        numbers.number("input watts")?;
        let factor = ballast
            * if lamp_factor_applies {
                lamp_factor
            } else {
                1.0
            };
        if factor <= 0.0 {
            return Err(fail(
                ballast_line,
                format!(
                    "the ballast factor (times the ballast-lamp factor) is {factor}: allowed > 0"
                ),
            ));
        }
        let v_line = numbers.line();
        let vertical = numbers.list(nv, "vertical angle")?;
        let h_line = numbers.line();
        let horizontal = numbers.list(nh, "horizontal angle")?;
        let c_line = numbers.line();
        let candela = numbers.list(nv * nh, "candela value")?;
        if let Some((line, word)) = numbers.words.next() {
            return Err(fail(
                line,
                format!(
                    "`{word}` follows the last of the {nv} x {nh} candela values: the counts \
                     and the values disagree"
                ),
            ));
        }
        let symmetry = ies_symmetry(&horizontal).map_err(|why| fail(h_line, why))?;
        Photometry {
            vertical,
            horizontal,
            candela,
            symmetry,
        }
        .validated(&fail, [v_line, h_line, c_line], multiplier * factor)
    }
}

/// The symmetry LM-63 reads from the first and last horizontal angle.
pub(super) fn ies_symmetry(h: &[f32]) -> std::result::Result<Symmetry, String> {
    let (first, last) = (h[0], h[h.len() - 1]);
    Ok(match (first, last) {
        _ if h.len() == 1 => Symmetry::Rotational,
        (f, l) if f == 0.0 && l == 90.0 => Symmetry::Quadrants,
        (f, l) if f == 0.0 && l == 180.0 => Symmetry::Plane0To180,
        (f, l) if f == 90.0 && l == 270.0 => Symmetry::Plane90To270,
        (f, l) if f == 0.0 && l > 180.0 && l <= 360.0 => Symmetry::Full,
        _ => {
            return Err(format!(
                "horizontal angles from {first} to {last} degrees: LM-63 allows one angle \
                 (symmetric about the axis), 0 to 90, 0 to 180, 90 to 270, or 0 to more \
                 than 180 (up to 360)"
            ))
        }
    })
}
