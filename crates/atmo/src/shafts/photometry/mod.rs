//! Photometric files: a luminaire's measured luminous intensity over direction, read
//! from IES LM-63 files (the 1986, 1991, 1995, 2002 and 2019 editions) and EULUMDAT
//! (`.ldt`) files, for a spotlight whose profile is measured rather than drawn from a
//! beam and a field angle (the `I_l` of shafts (2)).
//!
//! Both formats give type C photometry: candela at vertical angles `gamma` from the
//! photometric axis (0 along the beam) in half-planes `C` around it. In atmo's light
//! space (see [`super::spotlight`]) `C = 0` lies along the light's `x` and `C = 90`
//! along its `y`, so that seen from behind the lamp `C` turns counterclockwise, as LM-63
//! has it seen from above a downlight. A file gives part of the circle of `C` and says
//! how the rest follows by symmetry ([`Symmetry`]).
//!
//! Between the measured angles the intensity is linear in `gamma` and in `C` (bilinear):
//! neither format prescribes a scheme, linear is what lighting programs use, and it never
//! overshoots a measured value. Past the last vertical angle the file measured the
//! intensity is zero.
//!
//! Every malformed file is an error naming the file and the line (of the header, the
//! counts or the numbers), never a panic: the readers are fuzzed (`fuzz/`).

use crate::error::{Error, Result};

mod eulumdat;
mod ies;

/// Which part of the circle of `C` a file measured and how the rest follows.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Symmetry {
    /// One half-plane serves every `C`: rotationally symmetric.
    Rotational,
    /// Half-planes over `C` in [0, 90], mirrored into the other quadrants.
    Quadrants,
    /// Half-planes over [0, 180], mirrored about the 0-180 plane.
    Plane0To180,
    /// Half-planes over [90, 270], mirrored about the 90-270 plane.
    Plane90To270,
    /// Half-planes around the whole circle; between the last and 360 + the first the
    /// intensity is linear across the wrap.
    Full,
}

/// The brightest a photometric file may make a light, cd: ten times the brightest
/// searchlights (about 1e9 cd); past it the light's arithmetic leaves f32.
pub const MAX_CANDELA: f64 = 1e10;

/// A measured intensity distribution, type C, in candela.
#[derive(Debug, Clone, PartialEq)]
pub struct Photometry {
    /// Vertical angles `gamma`, degrees, increasing from 0 (along the beam axis) to at
    /// most 180.
    pub vertical: Vec<f32>,
    /// The measured half-planes' `C`, degrees, increasing, within the part of [0, 360]
    /// that `symmetry` names.
    pub horizontal: Vec<f32>,
    /// Candela, half-plane after half-plane: `candela[h * vertical.len() + v]`.
    pub candela: Vec<f32>,
    /// How the half-planes cover the circle.
    pub symmetry: Symmetry,
}

/// The most angles a file may list along either axis: ten times the finest goniometer's
/// (a 0.1 degree step over 180 degrees makes 1,801), and with it the values' memory
/// bounded before anything is allocated.
pub const MAX_ANGLES: usize = 20_000;

/// The most candela values a file may hold (a 0.5 degree grid over the whole sphere has
/// 260,000).
pub const MAX_VALUES: usize = 2_000_000;

impl Photometry {
    /// What the angles and candela hold, bytes.
    pub fn bytes(&self) -> u64 {
        4 * (self.vertical.len() + self.horizontal.len() + self.candela.len()) as u64
    }

    /// The intensity toward vertical angle `gamma` in half-plane `c`, both degrees,
    /// candela: bilinear between the measured angles, zero past the last vertical angle.
    pub fn candela_at(&self, gamma: f32, c: f32) -> f32 {
        let planes = self.horizontal.len();
        if planes == 1 || self.symmetry == Symmetry::Rotational {
            return self.along(0, gamma);
        }
        let c = self.fold(c);
        let h = &self.horizontal;
        // The two half-planes around c and the weight of the second; with the whole
        // circle measured, the last plane and the first (360 on) bracket the wrap.
        let (a, b, w) = if c < h[0] || c > h[planes - 1] {
            let span = h[0] + 360.0 - h[planes - 1];
            let past = if c > h[planes - 1] {
                c - h[planes - 1]
            } else {
                c + 360.0 - h[planes - 1]
            };
            (planes - 1, 0, past / span)
        } else {
            let i = h.partition_point(|&x| x <= c).clamp(1, planes - 1) - 1;
            (i, i + 1, (c - h[i]) / (h[i + 1] - h[i]))
        };
        let w = w.clamp(0.0, 1.0);
        self.along(a, gamma) * (1.0 - w) + self.along(b, gamma) * w
    }

    /// The largest intensity the file gives, candela.
    pub fn peak(&self) -> f32 {
        self.candela.iter().fold(0.0, |m, &c| m.max(c))
    }

    /// The vertical angle, degrees, from which on the intensity is zero in every
    /// half-plane: the angle after the last non-zero value (where the linear
    /// interpolation reaches zero), or the last angle if it is lit.
    pub fn reach(&self) -> f32 {
        let nv = self.vertical.len();
        let last_lit = self
            .candela
            .chunks_exact(nv)
            .filter_map(|plane| plane.iter().rposition(|&c| c > 0.0))
            .max()
            .unwrap_or(0);
        self.vertical[(last_lit + 1).min(nv - 1)]
    }

    /// Half-plane `h` at vertical angle `gamma`, linear between its angles.
    fn along(&self, h: usize, gamma: f32) -> f32 {
        let v = &self.vertical;
        let n = v.len();
        let plane = &self.candela[h * n..(h + 1) * n];
        if gamma <= v[0] {
            return plane[0];
        }
        if gamma > v[n - 1] {
            return 0.0;
        }
        let i = v.partition_point(|&x| x <= gamma).clamp(1, n - 1) - 1;
        let w = (gamma - v[i]) / (v[i + 1] - v[i]);
        plane[i] * (1.0 - w) + plane[i + 1] * w
    }

    /// `c` (any degrees) folded into the measured part of the circle by the symmetry.
    fn fold(&self, c: f32) -> f32 {
        let c = c.rem_euclid(360.0);
        match self.symmetry {
            Symmetry::Rotational | Symmetry::Full => c,
            Symmetry::Quadrants => {
                let c = if c > 180.0 { 360.0 - c } else { c };
                if c > 90.0 {
                    180.0 - c
                } else {
                    c
                }
            }
            Symmetry::Plane0To180 => {
                if c > 180.0 {
                    360.0 - c
                } else {
                    c
                }
            }
            Symmetry::Plane90To270 => {
                if c < 90.0 {
                    180.0 - c
                } else if c > 270.0 {
                    540.0 - c
                } else {
                    c
                }
            }
        }
    }

    /// Checks what both readers need of the angles and values; `lines` names where
    /// each list began in the file for the messages.
    /// The candela are then scaled by `scale` (multipliers and lamp flux), so that
    /// messages quote the file's own numbers.
    fn validated(
        mut self,
        fail: &dyn Fn(usize, String) -> Error,
        lines: [usize; 3],
        scale: f32,
    ) -> Result<Self> {
        let [v_line, h_line, c_line] = lines;
        increasing(&self.vertical, "vertical angle", 0.0, 180.0)
            .map_err(|why| fail(v_line, why))?;
        increasing(&self.horizontal, "horizontal angle", 0.0, 360.0)
            .map_err(|why| fail(h_line, why))?;
        if self.vertical[0] != 0.0 {
            return Err(fail(
                v_line,
                format!(
                    "the vertical angles start at {} degrees: a spotlight sends its light \
                     forward of its axis, so they must start at 0 (type C, 0 along the beam)",
                    self.vertical[0]
                ),
            ));
        }
        if self.vertical.len() < 2 {
            return Err(fail(
                v_line,
                "one vertical angle gives no profile: at least 2 are needed".into(),
            ));
        }
        if let Some(k) = self
            .candela
            .iter()
            .position(|c| !(c.is_finite() && *c >= 0.0))
        {
            return Err(fail(
                c_line,
                format!(
                    "candela value {} (number {} of the values) is not a finite number >= 0",
                    self.candela[k],
                    k + 1
                ),
            ));
        }
        if self.peak() <= 0.0 {
            return Err(fail(
                c_line,
                "every candela value is 0: the file gives no light".into(),
            ));
        }
        // The file's values times its multipliers: past what any luminaire gives, the
        // light's arithmetic overflows (a multiplier of 1e35 gave a picture of NaN).
        let peak = self.peak() as f64 * scale as f64;
        if peak > MAX_CANDELA {
            return Err(fail(
                c_line,
                format!(
                    "the candela values times the file's multipliers reach {peak:.3e} cd: \
                     allowed at most {MAX_CANDELA:.0e} cd (ten times the brightest \
                     searchlights)"
                ),
            ));
        }
        for c in &mut self.candela {
            *c *= scale;
        }
        Ok(self)
    }
}

/// `word` as a finite number, or why not (`what` names it).
fn parse_number(word: &str, what: &str) -> std::result::Result<f32, String> {
    match word.parse::<f32>() {
        Ok(x) if x.is_finite() => Ok(x),
        _ => Err(format!("the {what} is `{word}`, not a number")),
    }
}

/// `x` as a count in `[lo, hi]`, or why not (`what` names it).
fn whole(x: f32, what: &str, lo: usize, hi: usize) -> std::result::Result<usize, String> {
    if x.fract() != 0.0 || x < lo as f32 || x > hi as f32 {
        Err(format!(
            "the {what} is {x}: allowed a whole number in [{lo}, {hi}]"
        ))
    } else {
        Ok(x as usize)
    }
}

/// Checks that `angles` rise strictly within `[lo, hi]`.
fn increasing(angles: &[f32], what: &str, lo: f32, hi: f32) -> std::result::Result<(), String> {
    for (k, &a) in angles.iter().enumerate() {
        if !(a >= lo && a <= hi) {
            return Err(format!(
                "{what} {a} (number {}) is outside [{lo}, {hi}] degrees",
                k + 1
            ));
        }
        if k > 0 && a <= angles[k - 1] {
            return Err(format!(
                "{what}s must increase: {a} (number {}) follows {}",
                k + 1,
                angles[k - 1]
            ));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An LM-63 file with `header` as its first line (none if empty), `ballast` its
    /// ballast line, and the angle and candela lines given.
    fn ies(header: &str, ballast: &str, counts: &str, angles_and_values: &str) -> String {
        let first = if header.is_empty() {
            String::new()
        } else {
            format!("{header}\n")
        };
        format!(
            "{first}[TEST] made by hand\n[MANUFAC] atmo\nTILT=NONE\n{counts}\n{ballast}\n{angles_and_values}\n"
        )
    }

    /// Rotationally symmetric: 1 lamp, -1 lm (absolute), multiplier 2; 5 vertical
    /// angles, 1 horizontal; type C; metres; then 0 to 40 degrees.
    fn symmetric(header: &str, ballast: &str) -> String {
        ies(
            header,
            ballast,
            "1 -1 2.0 5 1 1 2 0.1 0.1 0.2",
            "0 10 20 30 40\n0\n1000 900 500 100 0",
        )
    }

    #[test]
    fn a_symmetric_ies_file_gives_its_candela_times_the_multiplier_and_ballast() {
        let p = Photometry::from_ies(&symmetric("IESNA:LM-63-2002", "0.5 1.0 100"), "t").unwrap();
        assert_eq!(p.symmetry, Symmetry::Rotational);
        // The values times the multiplier (2) and the ballast factor (0.5).
        for (gamma, want) in [(0.0, 1000.0), (10.0, 900.0), (30.0, 100.0), (40.0, 0.0)] {
            assert_eq!(p.candela_at(gamma, 123.0), want, "{gamma}");
        }
        // Linear between, zero past the last angle, the same in every half-plane.
        assert!((p.candela_at(15.0, 0.0) - 700.0).abs() < 1e-3);
        assert!((p.candela_at(25.0, 270.0) - 300.0).abs() < 1e-3);
        assert_eq!(p.candela_at(45.0, 0.0), 0.0);
        assert_eq!(p.peak(), 1000.0);
        // The light ends where the last non-zero value's next angle is.
        assert_eq!(p.reach(), 40.0);
    }

    #[test]
    fn every_edition_of_lm63_is_read_and_the_lamp_factor_only_before_2002() {
        let ballast = "1.0 0.5 100";
        for (header, factor) in [
            ("", 0.5),
            ("IESNA91", 0.5),
            ("IESNA:LM-63-1995", 0.5),
            ("IESNA:LM-63-2002", 1.0),
            ("IES:LM-63-2019", 1.0),
        ] {
            let p = Photometry::from_ies(&symmetric(header, ballast), "t").unwrap();
            assert_eq!(p.candela_at(0.0, 0.0), 2000.0 * factor, "{header:?}");
        }
    }

    #[test]
    fn tilt_data_and_commas_are_read() {
        let text = "IESNA:LM-63-1995\nTILT=INCLUDE\n1\n3\n0, 45, 90\n1.0, 0.9, 0.8\n\
                    1 1000 1 3 1 1 2 0 0 0\n1 1 50\n0, 5, 10\n0\n300, 200, 0\n";
        let p = Photometry::from_ies(text, "t").unwrap();
        assert_eq!(p.candela_at(5.0, 0.0), 200.0);
        assert_eq!(p.reach(), 10.0);
    }

    /// Two half-planes of different widths: C in `planes`, the first `a`, the rest `b`.
    fn planes(horizontal: &str, n: usize, values: &[&str]) -> Photometry {
        let text = ies(
            "IESNA:LM-63-2002",
            "1 1 10",
            &format!("1 -1 1 3 {n} 1 2 0 0 0"),
            &format!("0 10 20\n{horizontal}\n{}", values.join("\n")),
        );
        Photometry::from_ies(&text, "t").unwrap()
    }

    #[test]
    fn the_symmetries_of_lm63_fill_the_circle() {
        // Quadrants: 0 and 90 measured.
        let q = planes("0 90", 2, &["100 50 0", "300 150 0"]);
        assert_eq!(q.symmetry, Symmetry::Quadrants);
        for (c, mirror) in [(120.0, 60.0), (200.0, 20.0), (300.0, 60.0), (-30.0, 30.0)] {
            assert!(
                (q.candela_at(0.0, c) - q.candela_at(0.0, mirror)).abs() < 1e-3,
                "{c}"
            );
        }
        assert!((q.candela_at(0.0, 45.0) - 200.0).abs() < 1e-3);
        assert_eq!(q.candela_at(10.0, 270.0), 150.0);
        // Bilateral about 0-180.
        let b = planes("0 90 180", 3, &["100 0 0", "200 0 0", "400 0 0"]);
        assert_eq!(b.symmetry, Symmetry::Plane0To180);
        assert_eq!(b.candela_at(0.0, 270.0), 200.0);
        assert!((b.candela_at(0.0, 225.0) - 300.0).abs() < 1e-3);
        // Bilateral about 90-270 (LM-63-1995).
        let c = planes("90 180 270", 3, &["100 0 0", "200 0 0", "400 0 0"]);
        assert_eq!(c.symmetry, Symmetry::Plane90To270);
        assert_eq!(c.candela_at(0.0, 0.0), 200.0);
        assert!((c.candela_at(0.0, 45.0) - 150.0).abs() < 1e-3);
        assert!((c.candela_at(0.0, 315.0) - 300.0).abs() < 1e-3);
        // The whole circle, short of 360: linear across the wrap.
        let f = planes("0 120 240", 3, &["100 0 0", "200 0 0", "400 0 0"]);
        assert_eq!(f.symmetry, Symmetry::Full);
        assert!((f.candela_at(0.0, 300.0) - 250.0).abs() < 1e-3);
        assert!((f.candela_at(0.0, -60.0) - 250.0).abs() < 1e-3);
        assert!((f.candela_at(0.0, 60.0) - 150.0).abs() < 1e-3);
    }

    /// The message for `text`, which must be refused.
    fn refused(text: &str) -> String {
        Photometry::from_ies(text, "bad.ies")
            .expect_err("the file should be refused")
            .to_string()
    }

    #[test]
    fn malformed_ies_files_are_errors_naming_the_line() {
        let good = symmetric("IESNA:LM-63-2002", "1 1 100");
        assert!(Photometry::from_ies(&good, "t").is_ok());
        // Line numbers: 1 header, 2-3 keywords, 4 TILT, 5 counts, 6 ballast, 7 vertical
        // angles, 8 horizontal, 9 candela.
        let cases: Vec<(String, &str)> = vec![
            (String::new(), "line 1: no `TILT=` line"),
            (
                good.replace("TILT=NONE", "TILT"),
                "line 4: the TILT line needs",
            ),
            (
                good.replace("1 -1 2.0 5 1", "1 -1 2.0 5.5 1"),
                "line 5: the number of vertical angles is 5.5",
            ),
            (
                good.replace("1 -1 2.0 5 1", "1 -1 2.0 0 1"),
                "line 5: the number of vertical angles is 0",
            ),
            (
                good.replace("2.0 5 1 1 2", "2.0 5 1 2 2"),
                "line 5: photometric type 2 (B) is not read",
            ),
            (
                good.replace("5 1 1 2 0.1", "5 1 1 3 0.1"),
                "line 5: the units type is 3",
            ),
            (
                good.replace("1 -1 2.0", "1 -1 0"),
                "line 5: the candela multiplier is 0",
            ),
            // A multiplier that reads, times values that read: past any luminaire (it
            // gave a picture of NaN).
            (
                good.replace("1 -1 2.0", "1 -1 1e35"),
                "line 9: the candela values times the file's multipliers reach 1.000e38 cd: allowed at most 1e10 cd",
            ),
            (
                good.replace("1 1 100", "0 1 100"),
                "line 6: the ballast factor",
            ),
            (
                good.replace("1000 900", "1000 nine"),
                "line 9: the candela value number 2 of 5 is `nine`",
            ),
            (
                good.replace("500 100 0", "500 100"),
                "line 9: the file ends where the candela value number 5 of 5",
            ),
            (
                good.replace("100 0\n", "100 0 7\n"),
                "line 9: `7` follows the last of the 5 x 1 candela values",
            ),
            (
                good.replace("0 10 20 30 40", "0 10 30 20 40"),
                "line 7: vertical angles must increase: 20 (number 4) follows 30",
            ),
            (
                good.replace("0 10 20 30 40", "90 100 110 120 130"),
                "line 7: the vertical angles start at 90",
            ),
            (
                good.replace("0 10 20 30 40", "0 10 20 30 190"),
                "line 7: vertical angle 190 (number 5) is outside [0, 180]",
            ),
            (
                good.replace("900 500", "-900 500"),
                "line 9: candela value -900",
            ),
            (
                good.replace("1000 900 500 100 0", "0 0 0 0 0"),
                "line 9: every candela value is 0",
            ),
            (
                good.replace("5 1 1 2", "2000 2000 1 2"),
                "above the limit of 2000000",
            ),
        ];
        for (text, want) in cases {
            let got = refused(&text);
            assert!(got.contains(want), "want {want:?}, got {got:?}");
            assert!(got.starts_with("IES file bad.ies: line "), "{got}");
        }
        // Horizontal angles that make no LM-63 symmetry.
        let text = ies("", "1 1 1", "1 -1 1 2 2 1 2 0 0 0", "0 10\n0 45\n1 0 1 0");
        assert!(refused(&text).contains("line 7: horizontal angles from 0 to 45 degrees"));
    }

    /// A EULUMDAT file: `isym`, `mc` C planes `dc` apart, gamma 0 to 30 by 10, lamps
    /// of 2000 lm, conversion factor 1, and `intensities` (cd/klm), one a line.
    fn ldt(isym: u32, mc: usize, dc: f32, intensities: &[f32]) -> String {
        let mut lines: Vec<String> = vec![
            "atmo".into(),
            "1".into(),
            isym.to_string(),
            mc.to_string(),
            dc.to_string(),
            "4".into(),
            "10".into(),
            "report".into(),
            "test luminaire".into(),
            "T-1".into(),
            "test.ldt".into(),
            "2026-12-02".into(),
        ];
        lines.extend(["100", "100", "50", "80", "80", "0", "0", "0", "0"].map(String::from));
        lines.extend(["100", "80", "1.0", "0", "1"].map(String::from));
        lines.extend(["1", "LED", "2000", "3000", "90", "25"].map(String::from));
        lines.extend((0..10).map(|k| format!("0.{k}")));
        lines.extend((0..mc).map(|k| (k as f32 * dc).to_string()));
        lines.extend((0..4).map(|k| (10 * k).to_string()));
        lines.extend(intensities.iter().map(|i| i.to_string().replace('.', ",")));
        lines.join("\r\n") + "\r\n"
    }

    #[test]
    fn eulumdat_files_give_candela_per_klm_times_the_lamp_flux() {
        let p =
            Photometry::from_eulumdat(&ldt(1, 1, 0.0, &[500.0, 400.5, 100.0, 0.0]), "t").unwrap();
        assert_eq!(p.symmetry, Symmetry::Rotational);
        // cd/klm times 2000 lm / 1000.
        assert_eq!(p.candela_at(0.0, 77.0), 1000.0);
        assert_eq!(p.candela_at(10.0, 0.0), 801.0);
        assert_eq!(p.reach(), 30.0);
        // Isym 4: C0 to C90 of 24 planes 15 apart, mirrored into every quadrant.
        let quad: Vec<f32> = (0..7)
            .flat_map(|c| [100.0 + c as f32 * 10.0, 50.0, 0.0, 0.0])
            .collect();
        let q = Photometry::from_eulumdat(&ldt(4, 24, 15.0, &quad), "t").unwrap();
        assert_eq!(q.symmetry, Symmetry::Quadrants);
        assert_eq!(q.horizontal.len(), 7);
        assert_eq!(q.candela_at(0.0, 90.0), 2.0 * 160.0);
        assert_eq!(q.candela_at(0.0, 270.0), 2.0 * 160.0);
        assert_eq!(q.candela_at(0.0, 195.0), 2.0 * 110.0);
        // Isym 3: C90 to C270 (13 planes of 24).
        let half: Vec<f32> = (0..13).flat_map(|c| [c as f32, 0.0, 0.0, 0.0]).collect();
        let h = Photometry::from_eulumdat(&ldt(3, 24, 15.0, &half), "t").unwrap();
        assert_eq!(h.symmetry, Symmetry::Plane90To270);
        assert_eq!(h.candela_at(0.0, 90.0), 0.0);
        assert_eq!(h.candela_at(0.0, 0.0), 2.0 * 6.0);
        assert_eq!(h.candela_at(0.0, 300.0), 2.0 * 10.0);
        // Isym 0: all 24 planes; 345 to 360 wraps.
        let all: Vec<f32> = (0..24).flat_map(|c| [c as f32, 0.0, 0.0, 0.0]).collect();
        let f = Photometry::from_eulumdat(&ldt(0, 24, 15.0, &all), "t").unwrap();
        assert!((f.candela_at(0.0, 352.5) - 23.0).abs() < 1e-4);
    }

    #[test]
    fn malformed_eulumdat_files_are_errors_naming_the_line() {
        let good = ldt(1, 1, 0.0, &[500.0, 400.0, 100.0, 0.0]);
        assert!(Photometry::from_eulumdat(&good, "t").is_ok());
        let lines: Vec<&str> = good.lines().collect();
        let with = |k: usize, value: &str| {
            let mut l = lines.clone();
            l[k - 1] = value;
            l.join("\n")
        };
        // Line 29 is the lamps' flux, 43 the C angle, 44-47 the gammas, 48-51 the
        // intensities.
        let cases = [
            (with(3, "5"), "line 3: the symmetry indicator Isym is 5"),
            (with(4, "x"), "line 4: the number of C planes Mc is `x`"),
            (with(24, "0"), "line 24: the conversion factor is 0"),
            (with(29, "-5"), "line 29: the lamps' total flux is -5"),
            // A flux that reads, past any lamp (the light would overflow to NaN).
            (
                with(29, "1e38"),
                "line 48: the candela values times the file's multipliers reach",
            ),
            (
                with(46, "5"),
                "line 44: vertical angles must increase: 5 (number 3) follows 10",
            ),
            (
                with(49, "-1"),
                "line 48: candela value -1 (number 2 of the values)",
            ),
            (
                lines[..49].join("\n"),
                "line 49: the file ends at line 49 where line 50 is needed",
            ),
            (
                good.clone() + "7\n",
                "line 52: `7` follows the last of the 4 intensities",
            ),
            (
                String::new(),
                "line 1: the file ends at line 0 where line 3 is needed",
            ),
        ];
        for (text, want) in cases {
            let got = Photometry::from_eulumdat(&text, "bad.ldt")
                .expect_err(want)
                .to_string();
            assert!(got.contains(want), "want {want:?}, got {got:?}");
            assert!(got.starts_with("EULUMDAT file bad.ldt: line "), "{got}");
        }
        // Isym 2 with C angles that hold one plane of 0 to 180.
        let text = ldt(2, 1, 0.0, &[500.0, 400.0, 100.0, 0.0]);
        let got = Photometry::from_eulumdat(&text, "bad.ldt")
            .unwrap_err()
            .to_string();
        assert!(
            got.contains("Isym 2 takes the C planes from 0 to 180"),
            "{got}"
        );
    }
}
