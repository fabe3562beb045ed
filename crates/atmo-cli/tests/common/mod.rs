//! What every CLI test uses: the binary, scratch folders, the example scenes, small
//! sizes. Each test file runs the `atmo` binary as a user does.

#![allow(dead_code)] // each test binary uses its own part

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// Runs `atmo` with `args`.
pub fn atmo(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_atmo"))
        .args(args)
        .output()
        .expect("atmo runs")
}

/// A fresh folder for one test.
pub fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("atmo-cli-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Entries in `dir`.
pub fn files_in(dir: &Path) -> usize {
    std::fs::read_dir(dir).unwrap().count()
}

/// Coarse shell-method settings: a model in a fraction of a second.
pub const COARSE_SHELLS: [&str; 6] = [
    "--shells",
    "12",
    "--directions",
    "16",
    "--scattering-directions",
    "16",
];

/// A probe file of `n` directions spread over the sphere, in `dir`.
pub fn probe_file(dir: &Path, n: usize) -> PathBuf {
    let file = dir.join("many.csv");
    let mut text = String::from("azimuth_deg,elevation_deg\n");
    for k in 0..n {
        text.push_str(&format!("{},{}\n", (k * 7) % 360, (k % 179) as f64 - 89.0));
    }
    std::fs::write(&file, text).unwrap();
    file
}

/// A small picture.
pub const SMALL: [&str; 4] = ["--width", "48", "--height", "32"];

/// The settings of [`tiny_table`]: 8 x 8 directions, 6 suns, 3 altitudes.
pub const TINY_TABLE: [&str; 10] = [
    "--directions",
    "8",
    "--sun-steps",
    "6",
    "--altitude-steps",
    "3",
    "--shells",
    "12",
    "--scattering-directions",
    "16",
];

/// A tiny table ([`TINY_TABLE`]) in `dir`, made with the CLI.
pub fn tiny_table(dir: &Path) -> PathBuf {
    let table = dir.join("tiny.atmo-sky");
    let mut args = vec!["precompute", "sky", "-o", table.to_str().unwrap()];
    args.extend(TINY_TABLE);
    let o = atmo(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    table
}

/// The example show (scenes/show.toml) at 72 x 48 in `dir`, its gobos where they are.
pub fn small_show(dir: &Path) -> PathBuf {
    let show = std::fs::read_to_string(scene("show.toml"))
        .unwrap()
        .replace("width = 720", "width = 72")
        .replace("height = 480", "height = 48")
        .replace("\"gobos/", &format!("\"{}/", scene("gobos")));
    let file = dir.join("show.toml");
    std::fs::write(&file, show).unwrap();
    file
}

/// The path of an example scene.
pub fn scene(name: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenes")
        .join(name)
        .to_string_lossy()
        .into_owned()
}

/// A small cloud.
pub const SMALL_CLOUD: [&str; 10] = [
    "--particles",
    "2000",
    "--width",
    "160",
    "--height",
    "90",
    "--resolution",
    "48",
    "--distance",
    "1.6",
];

/// Whether this machine has a GPU adapter (in CI, where the driver is installed, it
/// must: a missing one fails here rather than skipping the GPU checks); where it has
/// none the calling test's GPU part is reported skipped ([`skip`]). Probed once a
/// test binary: tests running side by side share the answer (and not the probe's
/// folder, which one of them would remove under the other).
pub fn has_gpu() -> bool {
    static FOUND: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    let found = *FOUND.get_or_init(probe_gpu);
    if !found {
        skip("its GPU part: no GPU adapter (install mesa-vulkan-drivers)");
    }
    found
}

/// Says on the terminal, past the test harness's capture (which takes only the print
/// macros), that the running test skipped `what`: a line `atmo-test: skipped TEST:
/// WHY` that the test run shows and `.ci/run` counts into its closing line.
pub fn skip(why: &str) {
    use std::io::Write as _;
    let test = std::thread::current()
        .name()
        .unwrap_or("a test")
        .to_string();
    let _ = writeln!(std::io::stderr(), "atmo-test: skipped {test}: {why}");
}

fn probe_gpu() -> bool {
    let dir = scratch("probe-gpu");
    let out = dir.join("x.png");
    let o = atmo(&[
        "clouds",
        "--generate",
        "cumulus",
        "--particles",
        "10",
        "--resolution",
        "4",
        "--backend",
        "gpu",
        "--width",
        "8",
        "--height",
        "8",
        "-o",
        out.to_str().unwrap(),
    ]);
    std::fs::remove_dir_all(&dir).unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    let found = !stderr.contains("no GPU adapter found");
    assert!(
        found || std::env::var("CI").as_deref() != Ok("true"),
        "{stderr}"
    );
    found
}
