//! Changes to a scene file by key, `spotlight[0].intensity = 5000`, made to its TOML
//! text with its comments and layout kept: what `atmo shafts --set` applies, what the
//! viewer's panel and mouse change, and what the viewer's "save scene" writes. The
//! edited text is then loaded as any scene file ([`Scene::from_toml_str`]), so an edit
//! is validated exactly as the file is, with the same messages.
//!
//! A key is a dotted path of the file's tables, with `[i]` picking one of an array of
//! tables (`fixture[1].start.pan_deg`, `haze.box.min`, `camera.position`); a value is
//! a TOML value (`5000`, `[0, 1.5, -2]`, `"linear"`; a bare word is read as a string).
//! An empty value removes the key (to give `kelvin` where `color` was).

use std::path::Path;

use toml_edit::{DocumentMut, Item, TableLike, Value};

use super::scene::Scene;
use crate::error::{Error, Result};

/// One change: the value of `key`, or (`None`) the key removed.
#[derive(Debug, Clone, PartialEq)]
pub struct Edit {
    pub key: String,
    pub value: Option<String>,
}

impl Edit {
    /// `key` set to `value` (a TOML value's text).
    pub fn set(key: &str, value: impl Into<String>) -> Edit {
        Edit {
            key: key.to_string(),
            value: Some(value.into()),
        }
    }

    /// `key` removed.
    pub fn remove(key: &str) -> Edit {
        Edit {
            key: key.to_string(),
            value: None,
        }
    }

    /// Reads `KEY=VALUE` (as `--set` takes it); `KEY=` removes the key.
    pub fn parse(text: &str) -> Result<Edit> {
        let (key, value) = text.split_once('=').ok_or_else(|| {
            Error::Invalid(format!(
                "--set '{text}': give KEY=VALUE, e.g. spotlight[0].intensity=5000"
            ))
        })?;
        let (key, value) = (key.trim(), value.trim());
        Ok(match value {
            "" => Edit::remove(key),
            _ => Edit::set(key, value),
        })
    }

    /// The edit as `--set` reads it back, quoted for a shell where it must be.
    pub fn flag(&self) -> String {
        let text = format!("{}={}", self.key, self.value.as_deref().unwrap_or(""));
        let plain = text
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || "_-.=[],+".contains(c));
        if plain {
            format!("--set {text}")
        } else {
            format!("--set '{}'", text.replace('\'', r"'\''"))
        }
    }
}

/// `edits` applied in order to a list of them where each key keeps its last change,
/// in the order keys were first changed: the shortest list that gives the same file.
pub fn merged(edits: &[Edit]) -> Vec<Edit> {
    let mut out: Vec<Edit> = Vec::new();
    for edit in edits {
        match out.iter_mut().find(|e| e.key == edit.key) {
            Some(e) => e.value = edit.value.clone(),
            None => out.push(edit.clone()),
        }
    }
    out
}

/// A scene file's text, parsed as TOML (not yet as a scene): what edits change and
/// what a panel reads its values from.
#[derive(Debug, Clone)]
pub struct Document(DocumentMut);

impl Document {
    /// Parses `text`; `origin` names it in messages.
    pub fn parse(text: &str, origin: &str) -> Result<Document> {
        text.parse()
            .map(Document)
            .map_err(|e: toml_edit::TomlError| Error::Parse {
                path: origin.to_string(),
                message: e.to_string(),
            })
    }

    /// `text` parsed, with `edits` made in order.
    pub fn edited(text: &str, origin: &str, edits: &[Edit]) -> Result<Document> {
        let mut doc = Document::parse(text, origin)?;
        doc.apply_all(edits)?;
        Ok(doc)
    }

    /// Makes `edit`; a key that cannot be reached is an error naming it.
    pub fn apply(&mut self, edit: &Edit) -> Result<()> {
        apply_one(self.0.as_table_mut(), edit)
    }

    /// Makes `edits` in order; the first that cannot be made is the error.
    pub fn apply_all(&mut self, edits: &[Edit]) -> Result<()> {
        edits.iter().try_for_each(|edit| self.apply(edit))
    }

    /// The value at `key`, if there is one.
    pub fn get(&self, key: &str) -> Option<&Value> {
        let parts = path(key).ok()?;
        let ((name, None), tables) = parts.split_last()? else {
            return None;
        };
        let mut table: &dyn TableLike = self.0.as_table();
        for &(name, index) in tables {
            let item = table.get(name)?;
            table = match index {
                None => item.as_table_like()?,
                Some(i) => item.as_array_of_tables()?.get(i)?,
            };
        }
        table.get(name)?.as_value()
    }

    /// The number at `key` (an integer or a float).
    pub fn number(&self, key: &str) -> Option<f64> {
        number(self.get(key)?)
    }

    /// The three numbers at `key` (a point or a colour).
    pub fn vector(&self, key: &str) -> Option<[f64; 3]> {
        let array = self.get(key)?.as_array()?;
        let v: Vec<f64> = array.iter().filter_map(number).collect();
        (v.len() == 3 && array.len() == 3).then(|| [v[0], v[1], v[2]])
    }

    /// The string at `key`.
    pub fn text(&self, key: &str) -> Option<&str> {
        self.get(key)?.as_str()
    }

    /// How many tables the array of tables `name` at the top holds (`spotlight`).
    pub fn count(&self, name: &str) -> usize {
        self.0
            .get(name)
            .and_then(Item::as_array_of_tables)
            .map_or(0, |a| a.len())
    }
}

impl std::fmt::Display for Document {
    /// The text, comments and layout kept.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        self.0.fmt(f)
    }
}

fn number(value: &Value) -> Option<f64> {
    value
        .as_float()
        .or_else(|| value.as_integer().map(|i| i as f64))
}

/// `text` (a scene file, named `origin` in messages) with `edits` made in order.
pub fn apply(text: &str, origin: &str, edits: &[Edit]) -> Result<String> {
    Ok(Document::edited(text, origin, edits)?.to_string())
}

/// Loads the scene of the file at `path` with `edits` made to it first: the scene
/// that `atmo shafts FILE --set ...` draws.
pub fn load(path: &Path, edits: &[Edit]) -> Result<Scene> {
    let text = Scene::read_text(path)?;
    let text = apply(&text, &path.display().to_string(), edits)?;
    Scene::from_text_at(&text, path)
}

/// The most parts a key may have (`cue[0].set.left.pan_deg` has 4), and its longest,
/// bytes: beyond what a person writes, a key only makes nested tables that the TOML
/// reader then recurses into (a 10,000-part key took 7.9 GB before it aborted).
pub const MAX_KEY_PARTS: usize = 16;
pub const MAX_KEY_BYTES: usize = 256;

/// The longest value an edit sets, bytes: a long list of numbers, not a file.
pub const MAX_VALUE_BYTES: usize = 64 << 10;

/// The most quote characters of one kind in a row a value's strings may hold: the
/// TOML writer counts such runs in a byte and overflowed past 255 (found by the
/// `set_edits` fuzz target); no scene's string has more than two.
pub const MAX_QUOTE_RUN: usize = 64;

/// The longest run of `"` or of `'` in the strings (and inline tables' keys) of `value`.
fn quote_run(value: &Value) -> usize {
    let in_text = |text: &str| {
        ['"', '\'']
            .iter()
            .map(|&q| text.split(|c| c != q).map(str::len).max().unwrap_or(0))
            .max()
            .unwrap_or(0)
    };
    match value {
        Value::String(s) => in_text(s.value()),
        Value::Array(a) => a.iter().map(quote_run).max().unwrap_or(0),
        Value::InlineTable(t) => t
            .iter()
            .map(|(k, v)| in_text(k).max(quote_run(v)))
            .max()
            .unwrap_or(0),
        _ => 0,
    }
}

/// A key's parts: each table's name, and the index where it is an array of tables.
fn path(key: &str) -> Result<Vec<(&str, Option<usize>)>> {
    let parts = key.split('.').count();
    if key.len() > MAX_KEY_BYTES || parts > MAX_KEY_PARTS {
        let shown: String = key.chars().take(48).collect();
        return Err(Error::Invalid(format!(
            "--set {shown}...: a key is at most {MAX_KEY_PARTS} parts and {MAX_KEY_BYTES} \
             bytes (this one: {parts} parts, {} bytes); a scene's deepest is 5",
            key.len()
        )));
    }
    let bad = || {
        Error::Invalid(format!(
            "--set {key}: a key is NAME or NAME[INDEX] parts joined by '.', e.g. \
             spotlight[0].intensity"
        ))
    };
    key.split('.')
        .map(|part| {
            let (name, index) = match part.split_once('[') {
                None => (part, None),
                Some((name, rest)) => {
                    let i = rest.strip_suffix(']').and_then(|i| i.parse().ok());
                    (name, Some(i.ok_or_else(bad)?))
                }
            };
            let good = !name.is_empty()
                && name
                    .chars()
                    .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-');
            if good {
                Ok((name, index))
            } else {
                Err(bad())
            }
        })
        .collect()
}

fn apply_one(root: &mut dyn TableLike, edit: &Edit) -> Result<()> {
    let parts = path(&edit.key)?;
    if let Some(value) = edit.value.as_ref().filter(|v| v.len() > MAX_VALUE_BYTES) {
        return Err(Error::Invalid(format!(
            "--set {}: the value is {} bytes; at most {} KiB",
            edit.key,
            value.len(),
            MAX_VALUE_BYTES >> 10
        )));
    }
    let (last, tables) = parts.split_last().expect("split gives one part at least");
    let mut table = root;
    let mut at = String::new();
    // Whether `table` is an inline table (`start = { ... }`), which holds values only:
    // a table made in it must be inline too, or it is kept but never written (found by
    // the `set_edits` fuzz target: `fixture[1].start.pan.deg` left the file as it was).
    let mut inline = false;
    for &(name, index) in tables {
        at = if at.is_empty() {
            name.to_string()
        } else {
            format!("{at}.{name}")
        };
        table = match index {
            // A missing table is made (`fixture[0].start` where the fixture had none).
            None => {
                let made = if inline {
                    Item::Value(Value::InlineTable(Default::default()))
                } else {
                    toml_edit::table()
                };
                let item = table.entry(name).or_insert(made);
                inline = item.is_value();
                let what = match item {
                    Item::ArrayOfTables(_) => "an array of tables: give it an [INDEX]",
                    _ => "a value, not a table",
                };
                item.as_table_like_mut()
                    .ok_or_else(|| Error::Invalid(format!("--set {}: {at} is {what}", edit.key)))?
            }
            // A missing array of tables is not: the index would point at nothing.
            Some(i) => {
                let tables = table.get_mut(name).and_then(|t| t.as_array_of_tables_mut());
                let count = tables.as_ref().map_or(0, |a| a.len());
                at = format!("{at}[{i}]");
                inline = false;
                match tables.and_then(|a| a.get_mut(i)) {
                    Some(t) => t,
                    None => {
                        return Err(Error::Invalid(format!(
                            "--set {}: the scene has {count} [[{name}]], not one at index {i}",
                            edit.key
                        )))
                    }
                }
            }
        };
    }
    let (name, index) = *last;
    if index.is_some() {
        return Err(Error::Invalid(format!(
            "--set {}: the last part names a value, without [INDEX]",
            edit.key
        )));
    }
    match &edit.value {
        None => drop(table.remove(name)),
        Some(text) => {
            let mut value = text
                .parse::<Value>()
                .unwrap_or_else(|_| Value::from(text.as_str()));
            let run = quote_run(&value);
            if run > MAX_QUOTE_RUN {
                return Err(Error::Invalid(format!(
                    "--set {}: the value holds {run} quotes in a row; at most {MAX_QUOTE_RUN}",
                    edit.key
                )));
            }
            // The old value's comment and spacing stay (`color = [...]  # a blue gel`).
            if let Some(old) = table.get(name).and_then(Item::as_value) {
                *value.decor_mut() = old.decor().clone();
            }
            table.insert(name, Item::Value(value));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    const STAGE: &str = include_str!("../../../../scenes/stage.toml");

    fn stage(edits: &[Edit]) -> Result<Scene> {
        let text = apply(STAGE, "stage.toml", edits)?;
        Scene::from_toml_str(&text, "stage.toml", Path::new("../../scenes"))
    }

    #[test]
    fn keys_and_values_past_what_a_person_writes_are_refused() {
        let refused =
            |key: &str, value: String| stage(&[Edit::set(key, value)]).unwrap_err().to_string();
        let e = refused(&vec!["a"; 10_000].join("."), "1".into());
        assert!(e.contains("at most 16 parts") && e.len() < 300, "{e}");
        let e = refused(&format!("camera.{}", "x".repeat(300)), "1".into());
        assert!(e.contains("256"), "{e}");
        let e = refused("camera.position", format!("[{}0]", "0, ".repeat(30_000)));
        assert!(e.contains("at most 64 KiB"), "{e}");
        // A run of quotes past what the TOML writer counts (it overflowed at 256).
        let e = refused("spotlight[0].name", format!("x{}", "\"".repeat(300)));
        assert!(e.contains("300 quotes in a row"), "{e}");
        let nested = format!("[{{ a = \"{}\" }}]", "\\\"".repeat(100));
        let e = refused("spotlight[0].name", nested);
        assert!(e.contains("100 quotes in a row"), "{e}");
        // The deepest a scene goes is well inside.
        let cue = Edit::set("cue[0].set.left.pan_deg", "10");
        assert!(
            apply(STAGE, "stage.toml", &[cue]).is_err_and(|e| e.to_string().contains("[[cue]]"))
        );
    }

    #[test]
    fn edits_change_only_their_keys_and_keep_the_comments() {
        let edits = [
            Edit::parse("spotlight[2].intensity=4000").unwrap(),
            Edit::parse("spotlight[2].color=[1, 0, 0]").unwrap(),
            Edit::parse("spotlight[1].kelvin=").unwrap(),
            Edit::parse("spotlight[1].color=[0,1,0]").unwrap(),
            Edit::parse("haze.box.min=[-7.0, 0.0, -4.0]").unwrap(),
        ];
        let text = apply(STAGE, "stage.toml", &edits).unwrap();
        assert!(
            text.contains("color = [1, 0, 0]           # a blue gel"),
            "{text}"
        );
        assert!(!text.contains("kelvin = 3200"));
        // Every other line as it was: four new lines, one gone.
        let new: Vec<&str> = text.lines().filter(|l| !STAGE.contains(l)).collect();
        assert_eq!(new.len(), 4, "{new:?}");
        assert_eq!(text.lines().count(), STAGE.lines().count());
        let (before, after) = (stage(&[]).unwrap(), stage(&edits).unwrap());
        // Light 2: 4000 cd of red where 2500 of blue gel were; light 1 green.
        assert_eq!(after.spotlights[2].intensity, Vec3::new(4000.0, 0.0, 0.0));
        assert_eq!(after.spotlights[1].intensity, Vec3::new(0.0, 2000.0, 0.0));
        assert_eq!(
            after.spotlights[0].intensity,
            before.spotlights[0].intensity
        );
        assert_eq!(after.haze.bounds.unwrap().min, Vec3::new(-7.0, 0.0, -4.0));
        let doc = Document::parse(&text, "stage.toml").unwrap();
        assert_eq!(doc.number("spotlight[2].intensity"), Some(4000.0));
        assert_eq!(doc.vector("spotlight[1].color"), Some([0.0, 1.0, 0.0]));
        assert_eq!(doc.number("spotlight[1].kelvin"), None);
        assert_eq!(doc.text("spotlight[3].falloff"), Some("linear"));
        assert_eq!(doc.count("spotlight"), 5);
    }

    /// A table made inside an inline table is inline: `start = { ... }` given
    /// `start.pan.deg` kept the new table out of the text it wrote (the `set_edits`
    /// fuzz target's input, as found, is `corpus/set_edits/inline-table.txt`).
    #[test]
    fn an_edit_inside_an_inline_table_is_written() {
        let text = "[[fixture]]\nname = \"a\"\nstart = { tilt_deg = 15.0 }\n";
        for key in [
            "fixture[0].start.pa.deg",
            "fixture[0].start.pa.b.c",
            "fixture[0].new.x",
        ] {
            let edit = Edit::set(key, "2.5");
            let edited = Document::edited(text, "t", std::slice::from_ref(&edit)).unwrap();
            let again = Document::parse(&edited.to_string(), "t").unwrap();
            assert_eq!(again.number(key), Some(2.5), "{key}: {edited}");
            assert_eq!(again.number("fixture[0].start.tilt_deg"), Some(15.0));
        }
    }

    #[test]
    fn a_bad_key_or_value_is_refused_naming_it() {
        for (edit, says) in [
            (
                "spotlight[7].intensity=1",
                "has 5 [[spotlight]], not one at index 7",
            ),
            (
                "spotlight.intensity=1",
                "array of tables: give it an [INDEX]",
            ),
            ("camera.position.x=1", "camera.position is a value"),
            ("camera..fov_deg=1", "a key is NAME or NAME[INDEX]"),
            ("spotlight[0].intensty=1", "intensty"),
            ("spotlight[0].intensity=-5", "spotlight[0].intensity"),
            ("spotlight[1].color=[1, 0, 0]", "at most one"),
        ] {
            let e = Edit::parse(edit)
                .and_then(|e| stage(&[e]))
                .unwrap_err()
                .to_string();
            assert!(e.contains(says), "{edit}: {e}");
        }
        assert!(Edit::parse("no equals sign").is_err());
    }

    #[test]
    fn edits_merge_to_the_last_value_of_each_key_and_read_back_from_their_flags() {
        let edits = [
            Edit::set("camera.position", "[1,2,3]"),
            Edit::set("spotlight[0].dimmer", "0.5"),
            Edit::set("camera.position", "[4,5,6]"),
            Edit::set("display.tone_map", "\"aces\""),
        ];
        let merged = merged(&edits);
        assert_eq!(merged.len(), 3);
        assert_eq!(merged[0], Edit::set("camera.position", "[4,5,6]"));
        for e in merged.iter().chain([&Edit::remove("spotlight[1].kelvin")]) {
            let flag = e.flag();
            let arg = flag.strip_prefix("--set ").unwrap();
            let arg = arg
                .strip_prefix('\'')
                .map_or(arg, |a| a.strip_suffix('\'').unwrap());
            assert_eq!(&Edit::parse(arg).unwrap(), e, "{flag}");
        }
        assert_eq!(
            Edit::set("display.tone_map", "\"aces\"").flag(),
            "--set 'display.tone_map=\"aces\"'"
        );
    }
}
