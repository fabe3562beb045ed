//! `atmo view sky` in a real window under Xvfb (`xvfb-run`, which CI installs) on the
//! software Vulkan driver: scripted runs save their last frame, and the still command
//! the viewer prints for it must draw the same picture.

mod common;

use std::path::Path;
use std::process::{Command, Output};

use atmo::image::{Display, Frame, ToneMap};
use common::{atmo, has_gpu, scratch, tiny_table, COARSE_SHELLS};

/// Runs `atmo` under a fresh Xvfb display in the folder `dir` (where the P and E keys
/// save); `None` (the test skipped) where xvfb-run is missing, outside CI.
fn windowed(dir: &Path, args: &[&str]) -> Option<Output> {
    if Command::new("xvfb-run").arg("--help").output().is_err() {
        assert!(
            std::env::var("CI").as_deref() != Ok("true"),
            "xvfb-run is missing: install xvfb"
        );
        common::skip("no xvfb-run (install xvfb)");
        return None;
    }
    let output = Command::new("xvfb-run")
        .args(["-a", "-s", "-screen 0 640x480x24"])
        .arg(env!("CARGO_BIN_EXE_atmo"))
        .args(args)
        .current_dir(dir)
        .env_remove("WAYLAND_DISPLAY")
        .output()
        .expect("xvfb-run runs");
    Some(output)
}

/// Runs the still command a screenshot printed (its last line of stdout) through the
/// shell, writing to `still` instead of the screenshot `shot`, and returns that command.
fn run_still(viewer: &Output, command_name: &str, shot: &Path, still: &Path) -> String {
    let stdout = String::from_utf8_lossy(&viewer.stdout);
    let command = stdout.lines().last().expect("a still command").to_string();
    let rest = command
        .strip_prefix(&format!("atmo {command_name} "))
        .unwrap_or_else(|| panic!("not atmo {command_name}: {command}"));
    let (shot, still) = (shot.to_str().unwrap(), still.to_str().unwrap());
    assert!(rest.ends_with(&format!(" -o {shot}")), "{command}");
    let rest = format!("{} -o {still}", &rest[..rest.len() - shot.len() - 4]);
    let out = Command::new("sh")
        .arg("-c")
        .arg(format!("\"$0\" {command_name} {rest}"))
        .arg(env!("CARGO_BIN_EXE_atmo"))
        .output()
        .expect("sh runs");
    assert!(
        out.status.success(),
        "{command}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    command
}

/// Level errors (RMS, max) of two EXR files after `display`.
fn levels(a: &Path, b: &Path, display: Display) -> (f64, f64) {
    let (a, b) = (Frame::read_exr(a).unwrap(), Frame::read_exr(b).unwrap());
    let e = a.level_errors(&b, display).unwrap();
    (e.rms, e.max)
}

/// The sky's display.
const SKY: Display = Display {
    exposure: 0.15,
    tone: ToneMap::Exponential,
};

/// `atmo view MODE...` (`args` from the mode on) for 5 frames at 96 x 64 with
/// `script`, the last frame saved as `name`.exr; `None` where there is no Xvfb.
fn viewer_run(dir: &Path, name: &str, args: &[&str], script: &str) -> Option<Output> {
    let script_path = dir.join(format!("{name}.txt"));
    std::fs::write(&script_path, script).unwrap();
    let shot = dir.join(format!("{name}.exr"));
    let mut all = vec!["view"];
    all.extend(args);
    all.extend(["--width", "96", "--height", "64", "--frames", "5"]);
    all.extend(["--screenshot", shot.to_str().unwrap()]);
    all.extend(["--script", script_path.to_str().unwrap()]);
    let o = windowed(dir, &all)?;
    assert!(
        o.status.success(),
        "{name}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    Some(o)
}

/// The screenshot of `name` against the picture of the still command (`atmo
/// COMMAND_NAME ...`) the viewer printed, after `display`; returns that command.
fn matches_its_still(
    dir: &Path,
    name: &str,
    o: &Output,
    command_name: &str,
    display: Display,
) -> String {
    let (shot, still) = (
        dir.join(format!("{name}.exr")),
        dir.join(format!("{name}-still.exr")),
    );
    let command = run_still(o, command_name, &shot, &still);
    let (rms, max) = levels(&shot, &still, display);
    eprintln!("{name}: window vs still RMS {rms:.3}, max {max:.3} levels");
    assert!(
        rms <= 0.5,
        "{name}: window vs still RMS {rms} levels ({command})"
    );
    command
}

/// Each of `cases` (the arguments after `atmo view`, and what stderr must say) exits 2
/// before a window opens; `--frames 1 --screenshot DIR/x.png` is added where a case
/// does not give --frames.
fn refused_before_the_window(dir: &Path, cases: Vec<(Vec<&str>, &str)>) {
    let shot = dir.join("x.png");
    for (args, says) in cases {
        let mut all = vec!["view"];
        all.extend(&args);
        if !args.contains(&"--frames") {
            all.extend(["--frames", "1", "--screenshot", shot.to_str().unwrap()]);
        }
        let o = atmo(&all);
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(stderr.contains(says), "{args:?}: {stderr}");
    }
}

/// The sky viewer with `args` and `script`, then its still; returns the still command.
fn shot_and_still(dir: &Path, name: &str, args: &[&str], script: &str) -> Option<String> {
    let mut all = vec!["sky"];
    all.extend(args);
    let o = viewer_run(dir, name, &all, script)?;
    Some(matches_its_still(dir, name, &o, "sky", SKY))
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
        // E at frame 2 saves that frame's picture, the sun's move in it (drawn and,
        // on the GPU, submitted before it is read back): the last frame's.
        let script = "1 set sun-elevation 6\n1 drag 30 -10\n2 key right\n2 key e\n";
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
        let key_shot = Frame::read_exr(&dir.join("atmo-view-0002.exr")).unwrap();
        let last = Frame::read_exr(&dir.join(format!("{name}.exr"))).unwrap();
        assert!(
            key_shot.pixels == last.pixels,
            "{name}: the E key's picture is not the last frame's"
        );
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
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (vec!["sky", "--script", bad_line], "bad-line.txt:2"),
        (vec!["sky", "--script", unknown], "no parameter 'colour'"),
        (
            vec!["sky", "--table", missing.to_str().unwrap()],
            "missing.atmo-sky",
        ),
        (vec!["sky", "--sun-elevation", "91"], "--sun-elevation"),
        (
            vec!["sky", "--frames", "0", "--screenshot", "x.png"],
            "frames",
        ),
        (vec!["sky", "--preview", "17"], "preview = 17"),
        // The clouds.
        (
            vec![CLOUD, CUMULUS, SMALL, "--sun-elevation", "0"],
            "--sun-elevation",
        ),
        (
            vec![CLOUD, CUMULUS, SMALL, "--script", unknown],
            "no parameter 'colour' in the clouds",
        ),
        (vec![CLOUD, CUMULUS, SMALL, "--fov", "200"], "--fov"),
        // The cloud's own flags, named as `atmo clouds` names them.
        (
            vec![CLOUD, CUMULUS, SMALL, "--resolution", "1"],
            "--resolution",
        ),
    ];
    refused_before_the_window(&dir, cases);
    let shot = dir.join("x.png");
    let frames = ["--frames", "1", "--screenshot", shot.to_str().unwrap()];
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
    if let Some(o) = windowed(&dir, &all) {
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{stderr}");
        assert!(stderr.contains("no-such-gpu"), "{stderr}");
    }
    assert!(!shot.exists(), "a failed run wrote {}", shot.display());
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A small cloud of the generator, for input refused before anything is drawn.
const CLOUD: &str = "clouds";
const CUMULUS: &str = "--generate=cumulus";
const SMALL: &str = "--particles=100";

/// The repository's scenes folder.
fn scenes() -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes")
}

/// `atmo view stage SCENE` with 128^2 shadow maps (see [`viewer_run`]).
fn stage_run(dir: &Path, name: &str, scene: &Path, args: &[&str], script: &str) -> Option<Output> {
    let mut all = vec![
        "stage",
        scene.to_str().unwrap(),
        "--set",
        "render.shadow_map=128",
    ];
    all.extend(args);
    viewer_run(dir, name, &all, script)
}

/// `atmo view MODE...` (`args`) with `script` on the CPU backend and, where there is a
/// GPU, on the GPU's: each last frame against the still command (`atmo COMMAND ...`)
/// it printed, which must hold each of `parts`. The viewers' outputs.
fn each_backend_matches_its_still(
    dir: &Path,
    args: &[&str],
    script: &str,
    command: &str,
    display: Display,
    parts: &[&str],
) -> Vec<Output> {
    let mut backends = vec!["cpu"];
    if has_gpu() {
        backends.push("gpu");
    }
    let mut outputs = Vec::new();
    for backend in backends {
        let name = format!("{}-{backend}", args[0]);
        let mut all = args.to_vec();
        all.extend(["--backend", backend]);
        let Some(o) = viewer_run(dir, &name, &all, script) else {
            break;
        };
        let still = matches_its_still(dir, &name, &o, command, display);
        for part in parts {
            assert!(still.contains(part), "{name}: {part} missing from {still}");
        }
        outputs.push(o);
    }
    outputs
}

#[test]
fn scripted_stage_windows_give_the_pictures_of_their_still_commands() {
    let dir = scratch("view-stage");
    // The camera orbited, a gel changed, a light aimed by the mouse, the exposure,
    // adaptive sampling off (the panel's checkbox; the GPU draws every pixel either way).
    let script = "1 drag 40 -10\n2 set spotlight[2].color [1, 0.2, 0.1]\n2 aim 1 40 52\n\
                  3 set display.exposure 1.5\n3 set render.adaptive false\n";
    let display = Display {
        exposure: 1.5,
        tone: ToneMap::Exponential,
    };
    let scene = scenes().join("stage.toml");
    let args = [
        "stage",
        scene.to_str().unwrap(),
        "--set",
        "render.shadow_map=128",
    ];
    let parts = [
        "--set camera.position=[",
        "--set 'spotlight[2].color=[1, 0.2, 0.1]'",
        "--set spotlight[1].aim=[",
        "--set display.exposure=1.5",
        "--set render.adaptive=false",
        "--set camera.width=96",
    ];
    each_backend_matches_its_still(&dir, &args, script, "shafts", display, &parts);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_refused_stage_edit_keeps_the_last_good_scene_and_save_writes_the_file() {
    let dir = scratch("view-stage-save");
    let scene = dir.join("lamp.toml");
    let text = std::fs::read_to_string(scenes().join("spotlight-sphere.toml")).unwrap();
    std::fs::write(&scene, &text).unwrap();
    let script = "1 set spotlight[0].intensity -5\n2 set spotlight[0].intensity 900\n2 key s\n\
                  3 drag 6 0\n3 key e\n";
    let Some(o) = stage_run(&dir, "save", &scene, &["--backend", "cpu"], script) else {
        return;
    };
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(stderr.contains("spotlight[0].intensity"), "{stderr}");
    // Saved: the new intensity, and the file's comments and the window's other edit.
    let saved = std::fs::read_to_string(&scene).unwrap();
    assert!(saved.contains("intensity = 900"), "{saved}");
    let comments = |t: &str| t.lines().filter(|l| l.contains('#')).count();
    assert_eq!(comments(&saved), comments(&text));
    assert!(saved.contains("shadow_map = 128"), "{saved}");
    // The still command is the saved file at the window's size with the camera's move
    // after it: the intensity is the file's.
    let display = atmo::shafts::Scene::from_file(&scene).unwrap().display;
    let still = matches_its_still(&dir, "save", &o, "shafts", display);
    // E saved the picture of frame 3 as linear radiance, whole though the camera moved
    // in that frame (a preview otherwise): the last frame's (nothing changed after it).
    let key_shot = Frame::read_exr(&dir.join("atmo-view-0003.exr")).unwrap();
    let last = Frame::read_exr(&dir.join("save.exr")).unwrap();
    assert_eq!(key_shot.pixels, last.pixels);
    assert!(
        !still.contains("intensity") && still.contains("camera.position"),
        "{still}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn bad_stage_input_before_the_window_exits_2_naming_it() {
    let dir = scratch("view-stage-bad");
    let stage = scenes().join("stage.toml");
    let stage = stage.to_str().unwrap();
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (vec!["stage", "no-such-scene.toml"], "no-such-scene.toml"),
        (
            vec!["stage", stage, "--set", "spotlight[9].dimmer=1"],
            "not one at index 9",
        ),
        (
            vec!["stage", stage, "--set", "haze.extinction=-1"],
            "haze.extinction",
        ),
        (vec!["stage", stage, "--time", "-1"], "time"),
        (vec!["stage", stage, "--width", "0"], "--width"),
    ];
    refused_before_the_window(&dir, cases);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn scripted_cloud_windows_give_the_pictures_of_their_still_commands() {
    let dir = scratch("view-clouds");
    // The sun moved by a key and the panel, the wind blowing, the camera orbited and
    // brought nearer, then a sun below the horizon refused (which stops the wind).
    let script = "1 key right\n1 set sun-elevation 35\n1 key w\n2 drag 40 -10\n2 key r\n\
                  3 set sun-elevation -5\n";
    let args = [
        "clouds",
        "--generate",
        "cumulus",
        "--particles",
        "3000",
        "--resolution",
        "48",
        "--sky",
    ];
    let display = Display {
        exposure: 0.15,
        tone: ToneMap::Exponential,
    };
    let parts = [
        "--sun-elevation 35 ",
        "--sun-azimuth 45 ",
        "--wind-s 8 ",
        "--sky ",
        "--particles 3000 ",
    ];
    for o in each_backend_matches_its_still(&dir, &args, script, "clouds", display, &parts) {
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert!(stderr.contains("--sun-elevation"), "{stderr}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
