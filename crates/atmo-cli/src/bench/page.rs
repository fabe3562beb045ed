//! `atmo bench page`: docs/benchmarks.md made from the `atmo bench ... --json` files
//! under docs/bench/, so the page never says what the data does not. A test holds the
//! checked-in page to what this makes of the checked-in files.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};
use serde_json::Value;

/// The file beside the JSON files naming the machine they were measured on (one line).
pub const MACHINE_FILE: &str = "machine.txt";

/// One bench family: the file's stem and its cases in the order they were printed.
struct Family {
    name: String,
    cases: Vec<Value>,
}

/// The page for the JSON files in `folder` (one object per line, as `--json` prints),
/// families in the order of their file names.
pub fn render(folder: &Path) -> Result<String> {
    let machine = atmo::files::read_text(
        &folder.join(MACHINE_FILE),
        "machine line",
        atmo::files::TEXT_LIMIT_BYTES,
    )?;
    let families = families(folder)?;
    if families.is_empty() {
        bail!(
            "{}: no .json files of `atmo bench --json` output",
            folder.display()
        );
    }
    let mut out = String::new();
    let _ = writeln!(out, "# Benchmarks\n");
    let _ = writeln!(
        out,
        "Made by `atmo bench page -o docs/benchmarks.md` from the `atmo bench AREA --json`\n\
         files in [docs/bench](bench/); do not edit it by hand. Each case is timed against\n\
         its baseline in the same run, and the ratio is the baseline's time over the case's\n\
         (above 1: the case is faster). Absolute times on a shared machine swing from run to\n\
         run; the ratio is the figure. How each bench is built: `atmo bench --help` and\n\
         the method pages in docs/.\n"
    );
    let _ = writeln!(out, "Machine: {}\n", machine.trim());
    for family in &families {
        let _ = writeln!(
            out,
            "## {}\n\n`{}` ([data](bench/{}.json))\n",
            family.name,
            command(family),
            family.name
        );
        let _ = writeln!(
            out,
            "| bench | device | median | baseline | baseline median | ratio | error and other figures | peak RSS |"
        );
        let _ = writeln!(out, "| --- | --- | --- | --- | --- | --- | --- | --- |");
        for (case, distinct) in family.cases.iter().zip(distinctions(&family.cases)) {
            let _ = writeln!(out, "{}", row(case, &distinct));
        }
        let _ = writeln!(out);
    }
    Ok(out)
}

/// The `.json` files of `folder`, sorted by name, each parsed line by line.
fn families(folder: &Path) -> Result<Vec<Family>> {
    let mut paths: Vec<PathBuf> = std::fs::read_dir(folder)
        .with_context(|| format!("{}: the bench folder", folder.display()))?
        .filter_map(|entry| entry.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e == "json"))
        .collect();
    paths.sort();
    paths
        .iter()
        .map(|path| {
            let text = atmo::files::read_text(path, "bench file", atmo::files::TEXT_LIMIT_BYTES)?;
            let cases = text
                .lines()
                .enumerate()
                .filter(|(_, line)| !line.trim().is_empty())
                .map(|(i, line)| {
                    case(line).with_context(|| format!("{}:{}", path.display(), i + 1))
                })
                .collect::<Result<Vec<_>>>()?;
            let name = path
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default();
            Ok(Family { name, cases })
        })
        .collect()
}

/// The command that writes the family's file: the `command` its cases name (a bench
/// that is not `atmo bench`'s, such as the Python package's), else `sky` is
/// `atmo bench sky --json`, `sky-gpu` the same area with `--backend gpu`.
fn command(family: &Family) -> String {
    if let Some(named) = family
        .cases
        .first()
        .and_then(|c| c.get("command"))
        .and_then(Value::as_str)
    {
        return named.to_string();
    }
    let name = &family.name;
    match name.strip_suffix("-gpu") {
        Some(area) => format!("atmo bench {area} --backend gpu --json"),
        None => format!("atmo bench {name} --json"),
    }
}

/// The fields every case may have, each in a column of its own; any other field of a
/// case (a sweep's rows, times by light count) goes into the figures column.
const COLUMNS: [&str; 10] = [
    "bench",
    "command",
    "params",
    "device",
    "median_ms",
    "gpu_ms",
    "baseline",
    "baseline_median_ms",
    "ratio",
    "peak_rss_mb",
];

/// One line of `--json` output: an object with at least a `bench` name.
fn case(line: &str) -> Result<Value> {
    let value: Value = serde_json::from_str(line).context("not a JSON object")?;
    if !value.get("bench").is_some_and(Value::is_string) {
        bail!("no \"bench\" name");
    }
    if value.get("median_ms").is_some_and(|m| !m.is_number()) {
        bail!("\"median_ms\" is not a number");
    }
    Ok(value)
}

/// The table row of one case; `distinct` tells it from others of the same name.
fn row(case: &Value, distinct: &str) -> String {
    let text = |key: &str| case.get(key).and_then(Value::as_str).unwrap_or("");
    let ms = |key: &str| case.get(key).and_then(Value::as_f64).map(milliseconds);
    let device = match case.get("device") {
        Some(device) => device
            .get("adapter")
            .and_then(Value::as_str)
            .unwrap_or("GPU")
            .to_string(),
        None => "CPU".into(),
    };
    let peak = case
        .get("peak_rss_mb")
        .and_then(Value::as_f64)
        .map_or(String::new(), |mb| format!("{mb:.0} MiB"));
    let name = match distinct {
        "" => format!("`{}`", text("bench")),
        _ => format!("`{}` ({distinct})", text("bench")),
    };
    format!(
        "| {} | {} | {} | {} | {} | {} | {} | {} |",
        cell(&name),
        cell(&device),
        ms("median_ms").unwrap_or_default(),
        cell(text("baseline")),
        ms("baseline_median_ms").unwrap_or_default(),
        case.get("ratio")
            .and_then(Value::as_f64)
            .map_or(String::new(), significant),
        cell(&figures(case)),
        peak,
    )
}

/// The case's error and every field without a column of its own, flattened.
fn figures(case: &Value) -> String {
    let Value::Object(fields) = case else {
        return String::new();
    };
    let error = fields.get("error").map(flat).unwrap_or_default();
    let others = fields
        .iter()
        .filter(|(key, _)| *key != "error" && !COLUMNS.contains(&key.as_str()))
        .map(|(key, value)| match value {
            Value::Array(items) if items.iter().all(Value::is_object) => {
                format!("{key}: {} rows", items.len())
            }
            Value::Array(items) => format!(
                "{key} {}",
                items
                    .iter()
                    .map(|v| match v {
                        Value::Number(n) => number(n),
                        other => other.to_string(),
                    })
                    .collect::<Vec<_>>()
                    .join(" / ")
            ),
            other => flat(&serde_json::json!({ key.as_str(): other })),
        })
        .filter(|text| !text.is_empty());
    std::iter::once(error)
        .filter(|e| !e.is_empty())
        .chain(others)
        .collect::<Vec<_>>()
        .join("; ")
}

/// A time in ms to three significant digits ([`significant`]).
fn milliseconds(ms: f64) -> String {
    format!("{} ms", significant(ms))
}

/// `x` to three significant digits (whole numbers from 100 up).
fn significant(x: f64) -> String {
    let a = x.abs();
    if a >= 100.0 || a == 0.0 {
        format!("{x:.0}")
    } else if a >= 10.0 {
        format!("{x:.1}")
    } else if a >= 1.0 {
        format!("{x:.2}")
    } else if a >= 1e-3 {
        // Three significant digits below 1: as many decimals as the leading zeros need.
        let decimals = (2.0 - a.log10().floor()) as usize;
        format!("{x:.decimals$}")
    } else {
        format!("{x:.2e}")
    }
}

/// An error object's fields as `name value` pairs (in the order of their names, as
/// serde_json keeps them); nested objects by their path.
fn flat(value: &Value) -> String {
    fn walk(prefix: &str, value: &Value, out: &mut Vec<String>) {
        match value {
            Value::Object(fields) => {
                for (key, v) in fields {
                    let name = if prefix.is_empty() {
                        key.clone()
                    } else {
                        format!("{prefix}.{key}")
                    };
                    walk(&name, v, out);
                }
            }
            Value::Number(n) => out.push(format!("{prefix} {}", number(n))),
            Value::Null => {}
            other => out.push(format!("{prefix} {}", other.to_string().trim_matches('"'))),
        }
    }
    let mut out = Vec::new();
    walk("", value, &mut out);
    out.join(", ")
}

/// A whole number as it is, any other to three significant digits.
fn number(n: &serde_json::Number) -> String {
    match n.as_f64() {
        Some(x) if n.is_f64() => significant(x),
        _ => n.to_string(),
    }
}

/// For each case, the parameters that tell it from the family's other cases of the
/// same name (`clouds.frame` by its scattering), as `key value` pairs.
fn distinctions(cases: &[Value]) -> Vec<String> {
    cases
        .iter()
        .map(|case| {
            let same: Vec<&Value> = cases
                .iter()
                .filter(|c| c["bench"] == case["bench"])
                .collect();
            let Some(Value::Object(params)) = case.get("params") else {
                return String::new();
            };
            params
                .iter()
                .filter(|(key, value)| {
                    same.iter()
                        .any(|other| other["params"].get(key.as_str()) != Some(value))
                })
                .map(|(key, value)| flat(&serde_json::json!({ key.as_str(): value })))
                .collect::<Vec<_>>()
                .join(", ")
        })
        .collect()
}

/// `text` safe inside a Markdown table cell.
fn cell(text: &str) -> String {
    text.replace('|', "\\|").replace('\n', " ")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_keep_three_significant_digits() {
        assert_eq!(significant(1234.5), "1234");
        assert_eq!(significant(39.24), "39.2");
        assert_eq!(significant(3.192), "3.19");
        assert_eq!(significant(0.0599), "0.0599");
        assert_eq!(significant(0.3126), "0.313");
        assert_eq!(significant(2.5e-4), "2.50e-4");
    }

    #[test]
    fn a_case_becomes_one_row_with_its_error_flattened() {
        let line = r#"{"bench":"shafts.fig6","median_ms":39.21,"baseline":"ray marching","baseline_median_ms":429.0,"ratio":11.23,"error":{"rms":0.06,"max":3.0,"x":null},"peak_rss_mb":212.4}"#;
        let row = row(&case(line).unwrap(), "");
        assert_eq!(
            row,
            "| `shafts.fig6` | CPU | 39.2 ms | ray marching | 429 ms | 11.2 | max 3.00, rms 0.0600 | 212 MiB |"
        );
    }

    #[test]
    fn a_gpu_case_names_its_adapter() {
        let line = r#"{"bench":"sky.frame.gpu","median_ms":219.0,"device":{"adapter":"llvmpipe (Vulkan)","software":true},"baseline":"the same method on the CPU","baseline_median_ms":48.0,"ratio":0.219,"error":{"rms_levels":0.001,"max_levels":0.0}}"#;
        let row = row(&case(line).unwrap(), "");
        assert!(
            row.starts_with("| `sky.frame.gpu` | llvmpipe (Vulkan) | 219 ms |"),
            "{row}"
        );
        assert!(row.contains("| 0.219 |"), "{row}");
    }

    #[test]
    fn a_gpu_family_is_the_area_with_the_gpu_backend() {
        let family = |name: &str, cases: Vec<Value>| Family {
            name: name.into(),
            cases,
        };
        let plain = serde_json::json!({"bench": "x", "median_ms": 1.0});
        assert_eq!(
            command(&family("sky-table", vec![plain.clone()])),
            "atmo bench sky-table --json"
        );
        assert_eq!(
            command(&family("clouds-gpu", vec![plain])),
            "atmo bench clouds --backend gpu --json"
        );
        // A bench of its own names its command, which is not a figure.
        let named = serde_json::json!({"bench": "python.radiance", "command": "python bench.py", "median_ms": 2.0});
        assert_eq!(
            command(&family("python", vec![named.clone()])),
            "python bench.py"
        );
        assert!(!figures(&named).contains("bench.py"));
    }

    #[test]
    fn a_line_without_a_bench_name_or_with_a_wrong_time_is_refused() {
        assert!(case(r#"{"median_ms":1.0}"#).is_err());
        assert!(case(r#"{"bench":"sky.map","median_ms":"4 ms"}"#).is_err());
        assert!(case("sky.map 4.1 ms").is_err());
    }

    #[test]
    fn cases_of_one_name_are_told_apart_by_their_parameters() {
        let cases: Vec<Value> = [
            r#"{"bench":"clouds.frame","median_ms":149.1,"params":{"width":1280,"scattering":"multiple"}}"#,
            r#"{"bench":"clouds.frame","median_ms":136.7,"params":{"width":1280,"scattering":"octaves"}}"#,
            r#"{"bench":"clouds.depths","median_ms":9.5,"params":{"width":1280}}"#,
        ]
        .iter()
        .map(|l| case(l).unwrap())
        .collect();
        assert_eq!(
            distinctions(&cases),
            ["scattering multiple", "scattering octaves", ""]
        );
    }

    #[test]
    fn fields_without_a_column_are_figures() {
        let line = r#"{"bench":"shafts.stage-lights","median_ms_by_lights":[34.97,48.46],"rows":[{"a":1},{"a":2}],"csv":null}"#;
        let row = row(&case(line).unwrap(), "");
        assert!(
            row.contains("| median_ms_by_lights 35.0 / 48.5; rows: 2 rows |"),
            "{row}"
        );
    }
}
