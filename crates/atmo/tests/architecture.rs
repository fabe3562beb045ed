//! docs/architecture.md's first rule, held: no method imports another. The sky and
//! the shafts use only the floor (atmosphere, view, geometry, image, files, ...); the
//! clouds may use the sky's public lighting API (`sky::lighting`, `sky::aerial`) and
//! nothing else of it or of the shafts.

use std::path::Path;

/// Every `.rs` file under `dir`, with its text.
fn sources(dir: &Path) -> Vec<(String, String)> {
    let mut out = Vec::new();
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            out.extend(sources(&path));
        } else if path.extension().is_some_and(|e| e == "rs") {
            let text = std::fs::read_to_string(&path).unwrap();
            out.push((path.display().to_string(), text));
        }
    }
    out
}

/// The places in the method `method`'s files that name `other`'s paths (in code or in
/// doc links), less those `allowed` starts.
fn uses(method: &str, other: &str, allowed: &[&str]) -> Vec<String> {
    let src = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("src")
        .join(method);
    let needle = format!("crate::{other}");
    let mut found = Vec::new();
    for (path, text) in sources(&src) {
        for (n, line) in text.lines().enumerate() {
            let mut rest = line;
            while let Some(at) = rest.find(&needle) {
                let tail = &rest[at..];
                if !allowed.iter().any(|a| tail.starts_with(a)) {
                    found.push(format!("{path}:{}: {}", n + 1, line.trim()));
                }
                rest = &rest[at + needle.len()..];
            }
        }
    }
    found
}

#[test]
fn no_method_imports_another() {
    let mut found = Vec::new();
    found.extend(uses("sky", "clouds", &[]));
    found.extend(uses("sky", "shafts", &[]));
    found.extend(uses("shafts", "sky", &[]));
    found.extend(uses("shafts", "clouds", &[]));
    found.extend(uses("clouds", "shafts", &[]));
    found.extend(uses(
        "clouds",
        "sky",
        &["crate::sky::lighting", "crate::sky::aerial"],
    ));
    assert!(
        found.is_empty(),
        "a method names another:\n{}",
        found.join("\n")
    );
}

/// The check itself finds what it looks for.
#[test]
fn the_check_sees_a_cross_import() {
    assert!(
        !uses("clouds", "sky", &[]).is_empty(),
        "clouds use sky::lighting"
    );
}
