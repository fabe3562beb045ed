//! `atmo precompute sky`, `atmo sky --table` and `atmo inspect`: a table made, drawn,
//! animated and inspected; bad tables refused.

mod common;

use std::process::Command;

use common::{atmo, files_in, scratch, tiny_table, SMALL};

#[test]
fn a_table_is_precomputed_drawn_animated_and_inspected() {
    let dir = scratch("table");
    let table = tiny_table(&dir);
    let t = table.to_str().unwrap();
    // Drawn anywhere inside its ranges, not only at grid points.
    let out = dir.join("sky.png");
    let mut args = vec![
        "sky",
        "--table",
        t,
        "--sun-elevation",
        "12.5",
        "--altitude",
        "3100",
    ];
    args.extend(["-o", out.to_str().unwrap()]);
    args.extend(SMALL);
    let o = atmo(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let png = image::open(&out).unwrap().to_rgb8();
    assert_eq!(png.dimensions(), (48, 32));
    assert!(png.get_pixel(24, 0).0[2] > 50, "{:?}", png.get_pixel(24, 0));
    // A sunset in three frames, and its animated PNG.
    let frames = dir.join("frames");
    let mut args = vec![
        "sky",
        "--table",
        t,
        "--animate",
        "sun",
        "--frame-count",
        "3",
    ];
    args.extend(["-o", frames.to_str().unwrap()]);
    args.extend(SMALL);
    let o = atmo(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for name in ["frame_000000.png", "frame_000002.png", "animation.png"] {
        let img = image::open(frames.join(name)).unwrap();
        assert_eq!((img.width(), img.height()), (48, 32), "{name}");
    }
    let first = image::open(frames.join("frame_000000.png"))
        .unwrap()
        .to_rgb8();
    let last = image::open(frames.join("frame_000002.png"))
        .unwrap()
        .to_rgb8();
    let brightness = |img: &image::RgbImage| img.pixels().map(|p| p.0[2] as u32).sum::<u32>();
    assert!(
        brightness(&last) < brightness(&first) / 2,
        "the sun has set"
    );
    // inspect prints the parameters and writes its pictures.
    let plots = dir.join("plots");
    let o = atmo(&["inspect", t, "--plots", plots.to_str().unwrap()]);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for needle in [
        "8 x 8 directions",
        "6 sun elevations",
        "3 altitudes",
        "epsilon",
        "terms",
    ] {
        assert!(stdout.contains(needle), "`{needle}` not in {stdout}");
    }
    for (name, size) in [
        ("singular-values.png", (640, 360)),
        ("terms.png", (64, 64)),
        ("direct.png", (64, 64)),
        ("table.png", (64, 64)),
        ("error.png", (64, 64)),
    ] {
        let img = image::open(plots.join(name)).unwrap();
        assert_eq!((img.width(), img.height()), size, "{name}");
    }
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn bad_tables_and_ranges_exit_2_and_write_nothing() {
    let dir = scratch("table-bad");
    let table = tiny_table(&dir);
    let t = table.to_str().unwrap();
    let out = dir.join("out");
    std::fs::create_dir_all(&out).unwrap();
    let expect_2 = |args: &[&str], needle: &str| {
        let o = atmo(args);
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(stderr.contains(needle), "`{needle}` not in {stderr}");
        assert_eq!(files_in(&out), 0, "{args:?} wrote something");
    };
    let png = out.join("sky.png");
    let png = png.to_str().unwrap();
    expect_2(
        &["sky", "--table", t, "--sun-elevation", "-12", "-o", png],
        "--sun-elevation: sun.elevation_deg",
    );
    expect_2(
        &["sky", "--table", t, "--altitude", "14000", "-o", png],
        "altitude",
    );
    let frames = out.join("frames");
    let frames = frames.to_str().unwrap();
    expect_2(
        &[
            "sky",
            "--table",
            t,
            "--animate",
            "altitude",
            "--altitude",
            "-5",
            "-o",
            frames,
        ],
        "altitude",
    );
    let sky = out.join("x.atmo-sky");
    let sky = sky.to_str().unwrap();
    expect_2(
        &["precompute", "sky", "-o", sky, "--epsilon", "0"],
        "epsilon",
    );
    expect_2(
        &["precompute", "sky", "-o", sky, "--epsilon", "-1/255"],
        "epsilon",
    );
    expect_2(
        &["precompute", "sky", "-o", sky, "--sun-steps", "1"],
        "sun_steps",
    );
    expect_2(
        &["precompute", "sky", "-o", sky, "--max-altitude", "90000"],
        "max_altitude",
    );
    expect_2(
        &[
            "precompute",
            "sky",
            "-o",
            sky,
            "--directions",
            "1024",
            "--sun-steps",
            "1024",
        ],
        "budget",
    );
    // A damaged and a foreign file.
    let mut bytes = std::fs::read(&table).unwrap();
    let middle = bytes.len() / 2;
    bytes[middle] ^= 0x10;
    let damaged = dir.join("damaged.atmo-sky");
    std::fs::write(&damaged, &bytes).unwrap();
    expect_2(&["inspect", damaged.to_str().unwrap()], "checksum");
    expect_2(
        &["sky", "--table", damaged.to_str().unwrap(), "-o", png],
        "checksum",
    );
    let foreign = dir.join("foreign.atmo-sky");
    std::fs::write(&foreign, b"\x89PNG\r\n\x1a\nnot a table").unwrap();
    expect_2(
        &["inspect", foreign.to_str().unwrap()],
        "not an atmo sky table",
    );
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn an_interrupted_precompute_leaves_no_table() {
    let dir = scratch("interrupted");
    let table = dir.join("big.atmo-sky");
    let mut child = Command::new(env!("CARGO_BIN_EXE_atmo"))
        .args(["precompute", "sky", "-o", table.to_str().unwrap()])
        .args(["--sun-steps", "64", "--altitude-steps", "16"])
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    std::thread::sleep(std::time::Duration::from_millis(1500));
    let finished = child.try_wait().unwrap().is_some();
    child.kill().unwrap();
    child.wait().unwrap();
    assert!(!finished, "the precompute should take longer than 1.5 s");
    assert!(
        !table.exists(),
        "a killed precompute left {}",
        table.display()
    );
    std::fs::remove_dir_all(dir).unwrap();
}

/// The temporaries in `dir` (`.atmo-PID-N.tmp`, files or folders).
fn temporaries(dir: &std::path::Path) -> Vec<String> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with(".atmo-") && n.ends_with(".tmp"))
        .collect()
}

/// An animation stopped by SIGTERM leaves whole frames and no temporary, and the same
/// command resumes it, keeping them; one stopped by SIGKILL may leave a frame's
/// temporary, which the next write into the folder removes and no run takes for a frame.
#[cfg(unix)]
#[test]
fn interrupted_animations_leave_whole_frames_and_resume() {
    let dir = scratch("interrupted-animation");
    let table = tiny_table(&dir);
    let frames = dir.join("sunset");
    let command = |range: &str| {
        let mut c = Command::new(env!("CARGO_BIN_EXE_atmo"));
        c.args([
            "sky",
            "--table",
            table.to_str().unwrap(),
            "--animate",
            "sun",
        ])
        .args(["--frame-count", "10000", "--frames", range])
        .args(["--width", "64", "--height", "32", "-o"])
        .arg(&frames)
        .stderr(std::process::Stdio::piped());
        c
    };
    let frame_files = || {
        std::fs::read_dir(&frames)
            .map(|d| {
                d.flatten()
                    .filter(|e| e.file_name().to_string_lossy().starts_with("frame_"))
                    .count()
            })
            .unwrap_or(0)
    };
    // Waits until the run has written a few frames.
    let writing = || {
        for _ in 0..600 {
            if frame_files() > 2 {
                return;
            }
            std::thread::sleep(std::time::Duration::from_millis(50));
        }
        panic!("no frames were written in 30 s");
    };
    let child = command("0..10000").spawn().unwrap();
    writing();
    // SAFETY: kill sends a signal to our own child, which is still running.
    assert_eq!(unsafe { libc::kill(child.id() as i32, libc::SIGTERM) }, 0);
    let o = child.wait_with_output().unwrap();
    assert_eq!(
        o.status.code(),
        Some(130),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(temporaries(&frames).is_empty() && temporaries(&dir).is_empty());
    let done = frame_files();
    assert!(done > 2 && done < 10_000, "{done} frames");
    for k in 0..done {
        let png = image::open(frames.join(format!("frame_{k:06}.png"))).unwrap();
        assert_eq!((png.width(), png.height()), (64, 32), "frame {k}");
    }
    // The same command over the first frames and one more keeps them all, draws one.
    let o = command(&format!("0..{}", done + 1)).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(
        stderr.contains(&format!("1 frame drawn, {done} kept")),
        "{stderr}"
    );
    // SIGKILL: no handler runs; a temporary may stay until the next write beside it.
    let mut child = command("0..10000").spawn().unwrap();
    let before = frame_files();
    for _ in 0..600 {
        if frame_files() > before + 2 {
            break;
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    let done = frame_files();
    let o = command(&format!("0..{}", done + 1)).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(
        temporaries(&frames).is_empty(),
        "{:?}",
        temporaries(&frames)
    );
    assert_eq!(frame_files(), done + 1);
    std::fs::remove_dir_all(dir).unwrap();
}

/// `--animate day`: a day at a place, sunrise to sunset past the table's lowest sun;
/// noon is brighter than the ends, and without a place the run is refused.
#[test]
fn a_day_is_animated_from_a_place_and_a_date() {
    let dir = scratch("day");
    let table = tiny_table(&dir);
    let folder = dir.join("day");
    let mut args = vec![
        "sky",
        "--table",
        table.to_str().unwrap(),
        "--animate",
        "day",
    ];
    args.extend([
        "--frame-count",
        "3",
        "--fisheye",
        "--width",
        "32",
        "--height",
        "32",
    ]);
    args.extend(["-o", folder.to_str().unwrap()]);
    let o = atmo(&args);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("needs --latitude, --longitude and --time"));
    assert!(!folder.exists());
    args.extend(["--latitude", "48.85", "--longitude", "2.35"]);
    args.extend(["--time", "2026-06-21T12:00:00+02:00"]);
    let o = atmo(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let mean = |k: usize| {
        let png = image::open(folder.join(format!("frame_{k:06}.png")))
            .unwrap()
            .to_rgb8();
        png.pixels().map(|p| p.0[2] as f64).sum::<f64>() / png.pixels().len() as f64
    };
    assert!(mean(1) > 4.0 * mean(0).max(1.0) && mean(1) > 4.0 * mean(2).max(1.0));
    assert!(folder.join("animation.png").exists());
    std::fs::remove_dir_all(dir).unwrap();
}

/// Drawing from a table is charged what drawing holds, not the table's precompute:
/// a table whose precompute needs more than 64 MiB is drawn under a 64 MiB budget
/// (it was refused for the precompute's memory, which drawing does not use).
#[test]
fn a_table_is_drawn_under_a_budget_its_precompute_would_not_fit() {
    let dir = scratch("table-budget");
    let table = dir.join("wide.atmo-sky");
    let settings = [
        "--order",
        "1",
        "--directions",
        "128",
        "--sun-steps",
        "32",
        "--altitude-steps",
        "4",
        "--shells",
        "12",
        "--scattering-directions",
        "16",
    ];
    let precompute = |extra: &[&str]| {
        atmo(
            &[
                &["precompute", "sky"],
                &settings[..],
                extra,
                &["-o", table.to_str().unwrap()],
            ]
            .concat(),
        )
    };
    let o = precompute(&["--memory-limit", "64M"]);
    assert_eq!(
        o.status.code(),
        Some(2),
        "the precompute fits 64 MiB: the test needs one that does not"
    );
    let o = precompute(&[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let out = dir.join("sky.png");
    let mut args = vec![
        "sky",
        "--table",
        table.to_str().unwrap(),
        "--memory-limit",
        "64M",
    ];
    args.extend(["-o", out.to_str().unwrap()]);
    args.extend(SMALL);
    let o = atmo(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(out.is_file());
    std::fs::remove_dir_all(dir).unwrap();
}
