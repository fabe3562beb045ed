//! EULUMDAT (`.ldt`) files.

use super::*;

impl Photometry {
    /// Reads a EULUMDAT file (the `.ldt` format of European luminaire makers: one field
    /// a line, intensities in cd per 1000 lm of lamp flux); `origin` names it in
    /// messages. Candela are the values times the first lamp set's total flux / 1000
    /// and the file's conversion factor.
    pub fn from_eulumdat(text: &str, origin: &str) -> Result<Photometry> {
        let fail = |line: usize, why: String| Error::Parse {
            path: format!("EULUMDAT file {origin}"),
            message: format!("line {line}: {why}"),
        };
        // The lines' list, 16 bytes a line, counted before it is made.
        crate::budget::check(
            &format!("the lines of EULUMDAT file {origin}"),
            16 * text.lines().count() as u64,
            "the file's length",
        )?;
        let lines: Vec<&str> = text.lines().map(str::trim).collect();
        // Field `n` (1-based, as the format's description numbers its lines).
        let field = |n: usize| {
            lines.get(n - 1).copied().ok_or_else(|| {
                fail(
                    lines.len().max(1),
                    format!(
                        "the file ends at line {} where line {n} is needed",
                        lines.len()
                    ),
                )
            })
        };
        // A number; some writers use a decimal comma.
        let number = |n: usize, what: &str| -> Result<f32> {
            let word = field(n)?;
            parse_number(&word.replace(',', "."), what)
                .map_err(|_| fail(n, format!("the {what} is `{word}`, not a number")))
        };
        let count = |n: usize, what: &str, lo: usize, hi: usize| -> Result<usize> {
            whole(number(n, what)?, what, lo, hi).map_err(|why| fail(n, why))
        };
        let isym = count(3, "symmetry indicator Isym", 0, 4)?;
        let mc = count(4, "number of C planes Mc", 1, MAX_ANGLES)?;
        let ng = count(6, "number of gamma angles Ng", 1, MAX_ANGLES)?;
        // Lines 13 to 23: dimensions, flux fractions; 24: the conversion factor.
        let conversion = number(24, "conversion factor for luminous intensities")?;
        if conversion <= 0.0 {
            return Err(fail(
                24,
                format!("the conversion factor is {conversion}: allowed > 0"),
            ));
        }
        let sets = count(26, "number of standard sets of lamps", 1, 20)?;
        // Per set: number of lamps, lamp type, total flux, colour, CRI, watts (blocks
        // of `sets` lines each).
        let flux_line = 27 + 2 * sets;
        let flux = number(flux_line, "total luminous flux of the lamps")?;
        if flux <= 0.0 {
            return Err(fail(
                flux_line,
                format!("the lamps' total flux is {flux} lm: allowed > 0"),
            ));
        }
        // Then 10 direct ratios, the Mc C angles, the Ng gamma angles, the intensities.
        let c_line = 27 + 6 * sets + 10;
        let g_line = c_line + mc;
        let i_line = g_line + ng;
        let list = |start: usize, n: usize, what: &str| -> Result<Vec<f32>> {
            (0..n).map(|k| number(start + k, what)).collect()
        };
        let c_angles = list(c_line, mc, "C angle")?;
        let vertical = list(g_line, ng, "gamma angle")?;
        increasing(&c_angles, "C angle", 0.0, 360.0).map_err(|why| fail(c_line, why))?;
        // The half-planes the intensities are given for.
        let (symmetry, range) = match isym {
            0 => (Symmetry::Full, (0.0, 360.0)),
            1 => (Symmetry::Rotational, (0.0, 0.0)),
            2 => (Symmetry::Plane0To180, (0.0, 180.0)),
            3 => (Symmetry::Plane90To270, (90.0, 270.0)),
            _ => (Symmetry::Quadrants, (0.0, 90.0)),
        };
        let horizontal: Vec<f32> = if isym == 1 {
            vec![0.0]
        } else {
            c_angles
                .iter()
                .copied()
                .filter(|c| *c >= range.0 && *c <= range.1)
                .collect()
        };
        if horizontal.is_empty()
            || (symmetry != Symmetry::Full
                && symmetry != Symmetry::Rotational
                && horizontal.len() < 2)
        {
            return Err(fail(
                c_line,
                format!(
                    "Isym {isym} takes the C planes from {} to {} degrees, and the C angles \
                     hold {} of them",
                    range.0,
                    range.1,
                    horizontal.len()
                ),
            ));
        }
        let n = horizontal.len() * ng;
        if n > MAX_VALUES {
            return Err(fail(
                i_line,
                format!("{n} intensities are above the limit of {MAX_VALUES}"),
            ));
        }
        let candela = list(i_line, n, "luminous intensity")?;
        if let Some(extra) = lines[(i_line + n - 1).min(lines.len())..]
            .iter()
            .position(|l| !l.is_empty())
        {
            let at = i_line + n + extra;
            return Err(fail(
                at,
                format!(
                    "`{}` follows the last of the {n} intensities that Isym {isym}, Mc {mc} and \
                     Ng {ng} make: the counts and the values disagree",
                    lines[at - 1]
                ),
            ));
        }
        Photometry {
            vertical,
            horizontal,
            candela,
            symmetry,
        }
        .validated(&fail, [g_line, c_line, i_line], flux / 1000.0 * conversion)
    }
}
