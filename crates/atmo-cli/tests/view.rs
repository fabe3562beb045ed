//! `atmo view sky` in a real window under Xvfb (`xvfb-run`, which CI installs) on the
//! software Vulkan driver: scripted runs save their last frame, and the still command
//! the viewer prints for it must draw the same picture.

mod common;

use std::path::Path;
use std::process::{Command, Output};

use atmo::image::{Display, Frame, ToneMap};
use common::{atmo, has_gpu, scratch, tiny_table, COARSE_SHELLS};

/// Runs `atmo` under a fresh Xvfb display; `None` (the test skipped) where xvfb-run is
/// missing, outside CI.
fn windowed(args: &[&str]) -> Option<Output> {
    if Command::new("xvfb-run").arg("--help").output().is_err() {
        assert!(
            std::env::var("CI").as_deref() != Ok("true"),
            "xvfb-run is missing: install xvfb"
        );
        eprintln!("skipped: no xvfb-run");
        return None;
    }
    let output = Command::new("xvfb-run")
        .args(["-a", "-s", "-screen 0 640x480x24"])
        .arg(env!("CARGO_BIN_EXE_atmo"))
        .args(args)
        .env_remove("WAYLAND_DISPLAY")
        .output()
        .expect("xvfb-run runs");
    Some(output)
}

/// Runs the still command a screenshot printed (its last line of stdout), writing to
/// `still` instead, and returns that command.
fn run_still(viewer: &Output, still: &Path) -> String {
    let stdout = String::from_utf8_lossy(&viewer.stdout);
    let command = stdout.lines().last().expect("a still command").to_string();
    let mut words: Vec<&str> = command.split_whitespace().collect();
    assert_eq!(words[..2], ["atmo", "sky"], "{command}");
    let o = words.iter().position(|w| *w == "-o").expect("-o");
    let still = still.to_str().unwrap();
    words[o + 1] = still;
    let out = atmo(&words[1..]);
    assert!(
        out.status.success(),
        "{command}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    command
}

/// Level errors (RMS, max) of two EXR files after the sky's display.
fn levels(a: &Path, b: &Path) -> (f64, f64) {
    let (a, b) = (Frame::read_exr(a).unwrap(), Frame::read_exr(b).unwrap());
    let display = Display {
        exposure: 0.15,
        tone: ToneMap::Exponential,
    };
    let e = a.level_errors(&b, display).unwrap();
    (e.rms, e.max)
}

/// The viewer with `args` and `script`, then its still; returns the still command.
fn shot_and_still(dir: &Path, name: &str, args: &[&str], script: &str) -> Option<String> {
    let script_path = dir.join(format!("{name}.txt"));
    std::fs::write(&script_path, script).unwrap();
    let shot = dir.join(format!("{name}.exr"));
    let mut all = vec![
        "view", "sky", "--width", "96", "--height", "64", "--frames", "4",
    ];
    all.extend(["--screenshot", shot.to_str().unwrap()]);
    all.extend(["--script", script_path.to_str().unwrap()]);
    all.extend(args);
    let o = windowed(&all)?;
    assert!(
        o.status.success(),
        "{name}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    let still = dir.join(format!("{name}-still.exr"));
    let command = run_still(&o, &still);
    let (rms, max) = levels(&shot, &still);
    eprintln!("{name}: window vs still RMS {rms:.3}, max {max:.3} levels");
    assert!(
        rms <= 0.5,
        "{name}: window vs still RMS {rms} levels ({command})"
    );
    Some(command)
}

#[test]
fn scripted_windows_give_the_pictures_of_their_still_commands() {
    let dir = scratch("view");
    let table = tiny_table(&dir);
    let table = table.to_str().unwrap();
    let mut backends = vec!["cpu"];
    if has_gpu() {
        backends.push("gpu");
    }
    for backend in backends {
        // From the table: the sun moved by a panel edit and a key, the camera dragged.
        let name = format!("table-{backend}");
        let script = "1 set sun-elevation 6\n1 drag 30 -10\n2 key right\n";
        let args = [
            "--table",
            table,
            "--sun-elevation",
            "20",
            "--backend",
            backend,
        ];
        let Some(still) = shot_and_still(&dir, &name, &args, script) else {
            return;
        };
        for flag in [
            "--sun-elevation 6 ",
            "--sun-azimuth 185 ",
            "--yaw 186 ",
            "--pitch 17 ",
        ] {
            assert!(still.contains(flag), "{name}: {flag} missing from {still}");
        }
        // By the shell method: a climb rebuilds the model at the new altitude.
        let name = format!("shells-{backend}");
        let coarse = COARSE_SHELLS;
        let mut args = vec!["--backend", backend, "--sun-elevation", "8"];
        args.extend(coarse);
        let still = shot_and_still(&dir, &name, &args, "1 key r\n2 key r\n").unwrap();
        assert!(still.contains("--altitude 500 "), "{name}: {still}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_refused_edit_keeps_the_last_good_picture_and_says_why() {
    let dir = scratch("view-refused");
    let table = tiny_table(&dir);
    let args = ["--table", table.to_str().unwrap(), "--backend", "cpu"];
    let script = "1 set sun-elevation 95\n2 set exposure 0\n";
    let Some(still) = shot_and_still(&dir, "refused", &args, script) else {
        return;
    };
    assert!(
        still.contains("--sun-elevation 30 ") && still.contains("--exposure 0.15 "),
        "{still}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn bad_input_before_the_window_exits_2_with_a_message() {
    let dir = scratch("view-bad");
    let bad_line = dir.join("bad-line.txt");
    std::fs::write(&bad_line, "0 key r\n3 jump\n").unwrap();
    let unknown = dir.join("unknown.txt");
    std::fs::write(&unknown, "0 set colour red\n").unwrap();
    let (bad_line, unknown) = (bad_line.to_str().unwrap(), unknown.to_str().unwrap());
    let missing = dir.join("missing.atmo-sky");
    let shot = dir.join("x.png");
    let frames = ["--frames", "1", "--screenshot", shot.to_str().unwrap()];
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (vec!["--script", bad_line], "bad-line.txt:2"),
        (vec!["--script", unknown], "no parameter 'colour'"),
        (
            vec!["--table", missing.to_str().unwrap()],
            "missing.atmo-sky",
        ),
        (vec!["--sun-elevation", "91"], "--sun-elevation"),
        (vec!["--frames", "0", "--screenshot", "x.png"], "frames"),
    ];
    for (args, says) in cases {
        let mut all = vec!["view", "sky"];
        all.extend(&args);
        if !args.contains(&"--frames") {
            all.extend(frames);
        }
        let o = atmo(&all);
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(stderr.contains(says), "{args:?}: {stderr}");
    }
    // No display at all.
    let o = Command::new(env!("CARGO_BIN_EXE_atmo"))
        .args(["view", "sky"])
        .args(frames)
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("needs a display"), "{stderr}");
    // A display but no such adapter.
    let mut all = vec!["view", "sky", "--adapter", "no-such-gpu"];
    all.extend(frames);
    if let Some(o) = windowed(&all) {
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{stderr}");
        assert!(stderr.contains("no-such-gpu"), "{stderr}");
    }
    assert!(!shot.exists(), "a failed run wrote {}", shot.display());
    std::fs::remove_dir_all(&dir).unwrap();
}
