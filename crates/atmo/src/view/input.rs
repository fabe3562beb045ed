//! What a user does to the picture, from the window or from a script: the one path by
//! which the viewer's state changes, so that a scripted run and a person at the window
//! reach the same pictures. Here, not in the viewer's crate, so that the script reader
//! is fuzzed without a window system (docs/fuzzing.md).

use std::path::Path;

use crate::Error;

/// One thing a user does.
#[derive(Debug, Clone, PartialEq)]
pub enum Input {
    /// A key pressed.
    Key(Key),
    /// The mouse dragged over the picture by (x right, y down) pixels.
    Drag(f32, f32),
    /// Light `.0` aimed at what the picture shows at pixel (x right, y down) from its
    /// top-left corner (the stage; a right-button drag).
    Aim(usize, f32, f32),
    /// A panel edit: the parameter that the still command's flag `--NAME` sets, to the
    /// value as the flag would read it (`set sun-elevation 12.5`); on the stage a key of
    /// the scene file to a TOML value, as `--set` takes it (`set
    /// spotlight[0].intensity 5000`), or `time`.
    Set(String, String),
}

/// The keys the viewer answers; the stage reads the sky's keys its own way (see each).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Key {
    /// R: climb one step; on the stage, the camera a step nearer what it looks at.
    Climb,
    /// F: descend one step; on the stage, a step farther.
    Descend,
    /// `+` (or `=`): double the step.
    Faster,
    /// `-`: halve the step.
    Slower,
    /// Left and Right arrows: the sun's azimuth by -5 and +5 deg; on the stage, the
    /// camera orbits by -5 and +5 deg.
    SunLeft,
    SunRight,
    /// Up and Down arrows: the sun's elevation by +1 and -1 deg; on the stage, the
    /// camera's orbit up and down by 5 deg.
    SunUp,
    SunDown,
    /// Space: the time-of-day animation on or off; on the stage, the show played.
    Animate,
    /// S: the stage's scene, edited, saved to its file.
    Save,
    /// W: the wind in the clouds on or off.
    Wind,
    /// P: a screenshot (PNG) and its still command.
    Screenshot,
    /// E: the same as linear radiance (EXR).
    ScreenshotExr,
    /// Tab: the panel shown or hidden.
    Panel,
}

impl Key {
    /// Every key by the name scripts use.
    pub const NAMES: &'static [(&'static str, Key)] = &[
        ("r", Key::Climb),
        ("f", Key::Descend),
        ("plus", Key::Faster),
        ("minus", Key::Slower),
        ("left", Key::SunLeft),
        ("right", Key::SunRight),
        ("up", Key::SunUp),
        ("down", Key::SunDown),
        ("space", Key::Animate),
        ("s", Key::Save),
        ("w", Key::Wind),
        ("p", Key::Screenshot),
        ("e", Key::ScreenshotExr),
        ("tab", Key::Panel),
    ];

    fn named(name: &str) -> Option<Key> {
        Key::NAMES
            .iter()
            .find(|(n, _)| n.eq_ignore_ascii_case(name))
            .map(|(_, k)| *k)
    }
}

/// Input events replayed at given frames: one a line, `FRAME key NAME`,
/// `FRAME drag DX DY`, `FRAME aim LIGHT X Y` or `FRAME set PARAMETER VALUE` (the value
/// the rest of the line); `#` starts a comment.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Script {
    /// (frame, input), in the file's order.
    events: Vec<(u64, Input)>,
}

/// Largest script file, bytes: 100,000 lines of a key or an edit (a 10 MB `set` line
/// took 2.3 GB in the panel's text layout).
pub const SCRIPT_LIMIT_BYTES: u64 = 4 << 20;

/// Longest line of a script, bytes: a key, a drag or an edit's value as a person types it.
pub const SCRIPT_LINE_BYTES: usize = 4096;

impl Script {
    /// Reads and parses a script file; errors name the file and line.
    pub fn read(path: &Path) -> crate::Result<Script> {
        let text = crate::files::read_text(path, "script", SCRIPT_LIMIT_BYTES)?;
        Script::parse(&text, &path.display().to_string())
    }

    /// Parses a script's text; `origin` names it in errors (`origin:line`).
    pub fn parse(text: &str, origin: &str) -> crate::Result<Script> {
        let mut events = Vec::new();
        for (i, line) in text.lines().enumerate() {
            let bad = |message: String| Error::Parse {
                path: format!("{origin}:{}", i + 1),
                message,
            };
            if line.len() > SCRIPT_LINE_BYTES {
                return Err(bad(format!(
                    "the line is {} bytes; a script's line is at most {SCRIPT_LINE_BYTES}",
                    line.len()
                )));
            }
            let line = line.split('#').next().unwrap_or("").trim();
            if line.is_empty() {
                continue;
            }
            let words: Vec<&str> = line.split_whitespace().collect();
            let frame: u64 = words[0]
                .parse()
                .map_err(|_| bad(format!("'{}' is not a frame number", words[0])))?;
            let number = |word: &str| -> crate::Result<f32> {
                word.parse::<f32>()
                    .ok()
                    .filter(|v| v.is_finite())
                    .ok_or_else(|| bad(format!("'{word}' is not a finite number")))
            };
            let input = match words[1..] {
                ["key", name] => Input::Key(Key::named(name).ok_or_else(|| {
                    let names: Vec<&str> = Key::NAMES.iter().map(|(n, _)| *n).collect();
                    bad(format!("no key '{name}'; keys: {}", names.join(", ")))
                })?),
                ["drag", dx, dy] => Input::Drag(number(dx)?, number(dy)?),
                ["aim", light, x, y] => Input::Aim(
                    light
                        .parse()
                        .map_err(|_| bad(format!("'{light}' is not a light's index")))?,
                    number(x)?,
                    number(y)?,
                ),
                ["set", name, ref value @ ..] if !value.is_empty() => {
                    Input::Set(name.to_string(), value.join(" "))
                }
                _ => {
                    return Err(bad(format!(
                        "'{line}' is not 'FRAME key NAME', 'FRAME drag DX DY', \
                         'FRAME aim LIGHT X Y' or 'FRAME set PARAMETER VALUE'"
                    )))
                }
            };
            events.push((frame, input));
        }
        Ok(Script { events })
    }

    /// The inputs of `frame`, in order.
    pub fn at(&self, frame: u64) -> impl Iterator<Item = &Input> {
        self.events
            .iter()
            .filter(move |(f, _)| *f == frame)
            .map(|(_, input)| input)
    }

    /// Refuses a panel edit of a parameter not among `names`, the parameters of `mode`
    /// ("the sky"), before the window opens.
    pub fn check_parameters(&self, mode: &str, names: &[&str]) -> crate::Result<()> {
        match self.parameters().find(|n| !names.contains(n)) {
            Some(name) => Err(unknown_parameter(name, mode, names)),
            None => Ok(()),
        }
    }

    /// Every panel edit's parameter name, to check against a mode's before the window
    /// opens.
    pub fn parameters(&self) -> impl Iterator<Item = &str> {
        self.events.iter().filter_map(|(_, input)| match input {
            Input::Set(name, _) => Some(name.as_str()),
            _ => None,
        })
    }
}

/// The error for a parameter `mode` does not have, listing those it has (`names`).
pub fn unknown_parameter(name: &str, mode: &str, names: &[&str]) -> Error {
    Error::Invalid(format!(
        "no parameter '{name}' in {mode}; parameters: {}",
        names.join(", ")
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_script_reads_keys_drags_and_edits_by_frame() {
        let script = Script::parse(
            "# a climb\n0 key r\n0 drag 10 -4.5\n\n3 set sun-elevation 12.5 # dusk\n\
             4 aim 2 10.5 20\n4 set camera.position [1, 2, 3]\n",
            "s",
        )
        .unwrap();
        let first: Vec<&Input> = script.at(0).collect();
        assert_eq!(first, [&Input::Key(Key::Climb), &Input::Drag(10.0, -4.5)]);
        assert_eq!(script.at(1).count(), 0);
        assert_eq!(
            script.at(3).next(),
            Some(&Input::Set("sun-elevation".into(), "12.5".into()))
        );
        let fourth: Vec<&Input> = script.at(4).collect();
        assert_eq!(
            fourth,
            [
                &Input::Aim(2, 10.5, 20.0),
                &Input::Set("camera.position".into(), "[1, 2, 3]".into())
            ]
        );
        assert_eq!(
            script.parameters().collect::<Vec<_>>(),
            ["sun-elevation", "camera.position"]
        );
    }

    #[test]
    fn a_bad_line_is_refused_with_its_file_and_line() {
        for (text, says) in [
            ("x key r", "not a frame number"),
            ("1 key q", "no key 'q'"),
            ("1 drag 1 nan", "not a finite number"),
            ("1 jump", "is not 'FRAME key NAME'"),
            ("1 set time", "is not 'FRAME key NAME'"),
            ("1 aim x 1 2", "not a light's index"),
            (
                &format!("1 set camera.position [{}]", "1, ".repeat(5000)),
                "a script's line is at most 4096",
            ),
        ] {
            let e = Script::parse(&format!("# ok\n{text}"), "run.txt")
                .unwrap_err()
                .to_string();
            assert!(e.contains("run.txt:2") && e.contains(says), "{text}: {e}");
        }
    }
}
