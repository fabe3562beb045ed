//! `atmo sky` as a user runs it: pictures of the requested size, numbers for probes,
//! and every bad input refused with exit code 2, a message naming the field, and no
//! output file.

mod common;

use common::{atmo, files_in, probe_file, scratch, COARSE_SHELLS, SMALL};

#[test]
fn renders_png_and_exr_of_the_requested_size() {
    let dir = scratch("ok");
    for name in ["sky.png", "sky.exr"] {
        let out = dir.join(name);
        let mut args = vec![
            "sky",
            "--sun-elevation",
            "10",
            "--altitude",
            "7000",
            "-o",
            out.to_str().unwrap(),
        ];
        args.extend(SMALL);
        let o = atmo(&args);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let img = image::open(&out).unwrap();
        assert_eq!((img.width(), img.height()), (48, 32));
    }
    // A sunlit sky is not black: the top row of the PNG has blue in it.
    let png = image::open(dir.join("sky.png")).unwrap().to_rgb8();
    assert!(png.get_pixel(24, 0).0[2] > 50, "{:?}", png.get_pixel(24, 0));
    let fisheye = dir.join("dome.png");
    let o = atmo(&[
        "sky",
        "--fisheye",
        "--width",
        "40",
        "--height",
        "40",
        "-o",
        fisheye.to_str().unwrap(),
    ]);
    assert!(o.status.success());
    let dome = image::open(&fisheye).unwrap().to_rgb8();
    assert_eq!(
        dome.get_pixel(0, 0).0,
        [0, 0, 0],
        "outside the dome is black"
    );
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn probe_prints_radiance_per_wavelength() {
    let dir = scratch("probe");
    let dirs = dir.join("dirs.csv");
    std::fs::write(&dirs, "azimuth_deg,elevation_deg\n0,90\n180,5\n-180,5\n").unwrap();
    let o = atmo(&[
        "sky",
        "--sun-elevation",
        "30",
        "--probe",
        dirs.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = String::from_utf8(o.stdout).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert!(lines[0].starts_with("azimuth_deg,elevation_deg,radiance_420nm"));
    assert_eq!(lines.len(), 4);
    let values = |l: &str| {
        l.split(',')
            .skip(2)
            .map(|v| v.parse::<f64>().unwrap())
            .collect::<Vec<_>>()
    };
    // Symmetric about the sun's vertical plane; positive; blue zenith.
    assert_eq!(values(lines[2]), values(lines[3]));
    let zenith = values(lines[1]);
    assert!(zenith.iter().all(|&v| v > 0.0) && zenith[0] > zenith[5]);
    std::fs::remove_dir_all(dir).unwrap();
}

/// Runs `atmo sky` with `extra` arguments and expects exit code 2, a message containing
/// `needle`, and no file in the output folder.
fn refused(name: &str, extra: &[&str], needle: &str) {
    let dir = scratch(name);
    let out = dir.join("out.png");
    let mut args = vec!["sky", "-o", out.to_str().unwrap()];
    if !extra.contains(&"--width") {
        args.extend(SMALL);
    }
    args.extend(extra);
    let o = atmo(&args);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{name}: {stderr}");
    assert!(
        stderr.contains(needle),
        "{name}: `{needle}` not in {stderr}"
    );
    assert_eq!(files_in(&dir), 0, "{name}: something was written");
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn bad_input_exits_2_with_a_message_and_no_file() {
    refused(
        "sun",
        &["--sun-elevation", "95"],
        "--sun-elevation: sun.elevation_deg = 95",
    );
    refused(
        "sun-nan",
        &["--sun-elevation", "NaN"],
        "--sun-elevation: sun.elevation_deg",
    );
    refused("below", &["--altitude", "-5"], "altitude");
    refused(
        "altitude-nan",
        &["--altitude", "NaN"],
        "--altitude: altitude_m = NaN",
    );
    // A cubemap's six faces over the budget name --envmap-size, not the height of one
    // tall frame; an equirectangular map's name it too.
    refused(
        "cubemap-budget",
        &[
            "--envmap",
            "cubemap",
            "--envmap-size",
            "8192",
            "--memory-limit",
            "64M",
        ],
        "--envmap-size: six 8192 x 8192 cube faces",
    );
    refused(
        "equirect-budget",
        &[
            "--envmap",
            "equirect",
            "--envmap-size",
            "8192",
            "--memory-limit",
            "64M",
        ],
        "--envmap-size: a 16384 x 8192 map",
    );
    refused("above", &["--altitude", "70000"], "altitude");
    refused("width", &["--width", "0"], "width");
    refused(
        "budget",
        &["--width", "16384", "--height", "16384"],
        "budget",
    );
    refused("envmap-kind", &["--envmap", "sphere"], "envmap");
    refused(
        "albedo",
        &["--ground-albedo", "1.5"],
        "--ground-albedo = 1.5 is out of range: allowed [0, 1]",
    );
    refused(
        "envmap-size",
        &["--envmap", "equirect", "--envmap-size", "2"],
        "envmap size",
    );
    refused("order", &["--order", "61"], "order");
    refused("order-word", &["--order", "most"], "order");
    refused("shells", &["--shells", "1"], "shells");
    refused("fov", &["--fov", "0"], "fov");
    refused(
        "exposure",
        &["--exposure", "-1"],
        "--exposure: exposure = -1",
    );
    // Negative values are numbers refused by range, not clap's "unexpected argument".
    refused(
        "width-negative",
        &["--width", "-1"],
        "--width = -1 is out of range",
    );
    refused(
        "sun-minus-inf",
        &["--sun-elevation", "-inf"],
        "sun.elevation_deg = -inf is out of range",
    );
    refused("preset", &["--preset", "mars"], "preset");
    refused(
        "missing",
        &["--atmosphere", "/nonexistent/atmosphere.toml"],
        "nonexistent",
    );
    let dir = scratch("toml");
    let earth = include_str!("../../atmo/presets/earth.toml");
    for (name, text, needle) in [
        (
            "unknown",
            earth.replacen("ground_albedo", "ground_albdo", 1),
            "ground_albdo",
        ),
        (
            "nan",
            earth.replacen(
                "single_scattering_albedo = 0.9",
                "single_scattering_albedo = nan",
                1,
            ),
            "mie.single_scattering_albedo",
        ),
        (
            "negative",
            earth.replacen("scale_height_m = 8000.0", "scale_height_m = -8000.0", 1),
            "rayleigh.scale_height_m",
        ),
        ("syntax", earth.replacen("name = ", "name == ", 1), "line"),
        // In the documented range before, and NaN pixels with exit 0.
        (
            "tiny-sun",
            earth.replacen(
                "sun_angular_radius_deg = 0.2678",
                "sun_angular_radius_deg = 1e-20",
                1,
            ),
            "sun_angular_radius_deg = 0.00000000000000000001 is out of range: allowed [0.001, 10]",
        ),
    ] {
        let file = dir.join(format!("{name}.toml"));
        std::fs::write(&file, text).unwrap();
        refused(
            &format!("toml-{name}"),
            &["--atmosphere", file.to_str().unwrap()],
            needle,
        );
    }
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn bad_output_names_and_probe_files_are_refused() {
    let dir = scratch("ext");
    let o = atmo(&["sky", "-o", dir.join("sky.jpg").to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains(".png or .exr"));
    let probe = dir.join("dirs.csv");
    std::fs::write(&probe, "azimuth_deg,elevation_deg\n10,95\n").unwrap();
    let o = atmo(&["sky", "--probe", probe.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(
        stderr.contains("dirs.csv:2") && stderr.contains("elevation_deg"),
        "{stderr}"
    );
    std::fs::write(&probe, "az,el\n10,5\n").unwrap();
    assert_eq!(
        atmo(&["sky", "--probe", probe.to_str().unwrap()])
            .status
            .code(),
        Some(2)
    );
    std::fs::remove_dir_all(dir).unwrap();
}

/// `atmo sky --probe ... | head`: the reader closes the pipe, the run ends quietly as
/// other Unix tools do (it panicked on the closed pipe).
#[cfg(unix)]
#[test]
fn a_closed_pipe_ends_the_run_quietly() {
    use std::io::Read;
    use std::os::unix::process::ExitStatusExt;
    let dir = scratch("pipe");
    let file = probe_file(&dir, 20_000);
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_atmo"))
        .args(["sky", "--probe", file.to_str().unwrap(), "--shells", "8"])
        .args(["--directions", "8", "--scattering-directions", "8"])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let mut first = [0u8; 64];
    child.stdout.take().unwrap().read_exact(&mut first).unwrap();
    // The pipe's reader is gone now.
    let o = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert_eq!(
        o.status.signal(),
        Some(13),
        "ended by SIGPIPE: {:?}",
        o.status
    );
    std::fs::remove_dir_all(dir).unwrap();
}

/// `atmo sun` and `--latitude/--longitude/--time`: the sun of a place and a time (SPA),
/// the sunlight at that point, the same sky as the angles it prints, and bad input.
#[test]
fn the_sun_comes_from_a_place_and_a_time() {
    let place = [
        "--latitude",
        "48.85",
        "--longitude",
        "2.35",
        "--time",
        "2026-06-21T14:00:00+02:00",
    ];
    let o = atmo(&[&["sun"][..], &place].concat());
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    // Paris, midsummer, 12:00 UTC: high in the south (64.5 deg by SPA).
    let elevation = v["elevation_deg"].as_f64().unwrap();
    let azimuth = v["azimuth_deg"].as_f64().unwrap();
    assert!(
        (64.0..65.0).contains(&elevation) && (180.0..190.0).contains(&azimuth),
        "{v}"
    );
    let lux = v["sunlight"]["illuminance_lux"]["horizontal"]
        .as_f64()
        .unwrap();
    assert!((60e3..130e3).contains(&lux), "{v}");
    let colour = v["sunlight"]["linear_srgb_colour"].as_array().unwrap();
    assert!(
        colour[0].as_f64() > colour[2].as_f64(),
        "sunlight is warmer than white: {v}"
    );
    // The sky of the place and time is the sky of those angles.
    let dir = scratch("sun-place");
    let (a, b) = (dir.join("a.exr"), dir.join("b.exr"));
    let o = atmo(&[&["sky", "-o", a.to_str().unwrap()][..], &place, &SMALL].concat());
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (e, az) = (format!("{elevation}"), format!("{azimuth}"));
    let angles = ["--sun-elevation", &e, "--sun-azimuth", &az];
    let o = atmo(&[&["sky", "-o", b.to_str().unwrap()][..], &angles, &SMALL].concat());
    assert!(o.status.success());
    assert_eq!(std::fs::read(&a).unwrap(), std::fs::read(&b).unwrap());
    // Bad places and times name the flag and its range; nothing is written.
    let c = dir.join("c.png");
    for (flag, value, wanted) in [
        (
            "--latitude",
            "95",
            "--latitude: latitude = 95 is out of range: allowed [-90, 90]",
        ),
        (
            "--time",
            "2026-06-21T14:00:00",
            "--time: time = 2026-06-21T14:00:00 is out of range",
        ),
    ] {
        let mut args = vec!["sky", "-o", c.to_str().unwrap()];
        args.extend(place);
        let at = args.iter().position(|a| *a == flag).unwrap();
        args[at + 1] = value;
        let o = atmo(&args);
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{stderr}");
        assert!(stderr.contains(wanted), "{stderr}");
        assert!(!c.exists());
    }
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn envmaps_and_lighting_for_engines() {
    let dir = scratch("envmap");
    let (out, light) = (dir.join("env.exr"), dir.join("light.json"));
    let mut args = vec![
        "sky",
        "--sun-elevation",
        "30",
        "--sun-azimuth",
        "90",
        "--envmap",
        "cubemap",
        "--envmap-size",
        "16",
        "-o",
        out.to_str().unwrap(),
        "--lighting",
        light.to_str().unwrap(),
    ];
    args.extend(COARSE_SHELLS);
    let o = atmo(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    // Six faces and the lighting, nothing else.
    assert_eq!(files_in(&dir), 7);
    for face in ["px", "nx", "py", "ny", "pz", "nz"] {
        let img = image::open(dir.join(format!("env_{face}.exr"))).unwrap();
        assert_eq!((img.width(), img.height()), (16, 16), "{face}");
    }
    // The sun due east: the +X face is the brightest, the ground (-Y) the darkest.
    let mean = |face: &str| {
        let img = image::open(dir.join(format!("env_{face}.exr")))
            .unwrap()
            .to_rgb32f();
        img.pixels().map(|p| p.0[2] as f64).sum::<f64>() / 256.0
    };
    assert!(mean("px") > mean("nx") && mean("py") > mean("ny"));
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&light).unwrap()).unwrap();
    let direction: Vec<f64> = serde_json::from_value(json["sun"]["direction"].clone()).unwrap();
    // Toward the sun: east (x) and up (y), 30 deg elevation.
    assert!(
        (direction[0] - 30f64.to_radians().cos()).abs() < 1e-4,
        "{direction:?}"
    );
    assert!((direction[1] - 0.5).abs() < 1e-4 && direction[2].abs() < 1e-4);
    let sh: Vec<Vec<f64>> =
        serde_json::from_value(json["sky"]["sh9_radiance_linear_srgb"].clone()).unwrap();
    assert_eq!((sh.len(), sh[0].len()), (9, 3));
    // A blue sky: more blue than red in the first coefficient; the east brighter (x).
    assert!(sh[0][2] > sh[0][0] && sh[3][2] > 0.0, "{sh:?}");
    let lux = json["sky"]["illuminance_up_lux"].as_f64().unwrap();
    assert!((1000.0..100_000.0).contains(&lux), "{lux}");
    std::fs::remove_dir_all(dir).unwrap();
}

/// The default is the truest sky (every order, ozone on); `--preset paper` takes the
/// paper's two orders, `--no-ozone` takes the ozone out, and asking for ozone both on
/// and off is refused.
#[test]
fn the_default_sky_is_every_order_with_ozone() {
    let dir = scratch("defaults");
    let sky = |name: &str, extra: &[&str]| {
        let out = dir.join(name);
        let mut args = vec!["sky", "--sun-elevation", "2", "-o", out.to_str().unwrap()];
        args.extend(SMALL);
        args.extend(COARSE_SHELLS);
        args.extend(extra);
        let o = atmo(&args);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        (
            String::from_utf8_lossy(&o.stderr).into_owned(),
            std::fs::read(&out).unwrap(),
        )
    };
    let (default_log, default_png) = sky("default.png", &[]);
    assert!(default_log.contains("order all"), "{default_log}");
    let (paper_log, _) = sky("paper.png", &["--preset", "paper"]);
    assert!(paper_log.contains("order 2"), "{paper_log}");
    let (_, no_ozone_png) = sky("no-ozone.png", &["--no-ozone"]);
    assert_ne!(default_png, no_ozone_png, "ozone changes the sunset");
    let (_, ozone_png) = sky("ozone.png", &["--ozone"]);
    assert_eq!(default_png, ozone_png, "the default has ozone on");
    let o = atmo(&["sky", "--ozone", "--no-ozone", "-o", "x.png"]);
    assert_eq!(o.status.code(), Some(2));
    std::fs::remove_dir_all(dir).unwrap();
}

/// An output that is there and not a regular file (a device, a FIFO, a folder) exits 2
/// naming what it is, and is left as it was: never opened, never replaced.
#[test]
#[cfg(unix)]
fn outputs_that_are_not_regular_files_exit_2_and_stay() {
    use std::os::unix::fs::FileTypeExt as _;
    let dir = scratch("not-files");
    let fifo = dir.join("fifo.png");
    let made = std::process::Command::new("mkfifo").arg(&fifo).status();
    assert!(made.unwrap().success(), "mkfifo");
    let folder = dir.join("folder.png");
    std::fs::create_dir(&folder).unwrap();
    // A device through a link (as /proc/self/fd/N are), named as a picture.
    let device = dir.join("null.png");
    std::os::unix::fs::symlink("/dev/null", &device).unwrap();
    for (out, kind) in [
        (device.as_path(), "a device"),
        (fifo.as_path(), "a FIFO"),
        (folder.as_path(), "a folder"),
    ] {
        let mut args = vec!["sky", "-o", out.to_str().unwrap()];
        args.extend(SMALL);
        let o = atmo(&args);
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{}: {stderr}", out.display());
        assert!(stderr.contains(&format!("is {kind}")), "{stderr}");
    }
    let t = |p: &std::path::Path| std::fs::metadata(p).unwrap().file_type();
    assert!(t(&device).is_char_device() && t("/dev/null".as_ref()).is_char_device());
    assert!(t(&fifo).is_fifo() && t(&folder).is_dir());
    assert_eq!(files_in(&folder), 0);
    std::fs::remove_dir_all(dir).unwrap();
}

/// A full standard output (`> /dev/full`) ends the run with exit 1 and a message, not
/// a panic (exit 101); a full standard error loses the messages and the run still
/// writes its picture.
#[test]
#[cfg(target_os = "linux")]
fn full_standard_streams_never_panic() {
    use std::process::{Command, Stdio};
    let full = || {
        std::fs::OpenOptions::new()
            .write(true)
            .open("/dev/full")
            .unwrap()
    };
    let dir = scratch("full-streams");
    let table = common::tiny_table(&dir);
    for args in [
        vec![
            "sun",
            "--latitude",
            "48.2",
            "--longitude",
            "16.4",
            "--time",
            "2026-06-21T12:00:00Z",
        ],
        vec!["inspect", table.to_str().unwrap()],
    ] {
        let o = Command::new(env!("CARGO_BIN_EXE_atmo"))
            .args(&args)
            .stdout(full())
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {stderr}");
        assert!(
            stderr.contains("standard output") && !stderr.contains("panicked"),
            "{args:?}: {stderr}"
        );
    }
    let out = dir.join("sky.png");
    let mut args = vec!["sky", "-o", out.to_str().unwrap()];
    args.extend(SMALL);
    let o = Command::new(env!("CARGO_BIN_EXE_atmo"))
        .args(&args)
        .stdout(Stdio::null())
        .stderr(full())
        .status()
        .unwrap();
    assert_eq!(o.code(), Some(0));
    assert!(out.is_file());
    std::fs::remove_dir_all(dir).unwrap();
}

/// `--lighting` with `-o` and no `--envmap` writes both: the JSON and the picture, the
/// same picture as without `--lighting`.
#[test]
fn lighting_with_a_picture_writes_both() {
    let dir = scratch("lighting-picture");
    let (with, without, light) = (
        dir.join("with.png"),
        dir.join("without.png"),
        dir.join("light.json"),
    );
    let mut base = vec!["sky", "--backend", "cpu"];
    base.extend(SMALL);
    base.extend(COARSE_SHELLS);
    let run = |extra: &[&str]| {
        let o = atmo(&[base.as_slice(), extra].concat());
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    };
    run(&[
        "-o",
        with.to_str().unwrap(),
        "--lighting",
        light.to_str().unwrap(),
    ]);
    run(&["-o", without.to_str().unwrap()]);
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&light).unwrap()).unwrap();
    assert!(json["sun"]["illuminance_lux"]["normal"].as_f64().unwrap() > 0.0);
    assert_eq!(
        std::fs::read(&with).unwrap(),
        std::fs::read(&without).unwrap()
    );
    std::fs::remove_dir_all(dir).unwrap();
}

/// A cubemap's faces and the lighting are written together: when the last of them
/// cannot be written (here a folder where the JSON goes), no face appears either.
#[test]
fn cube_faces_and_lighting_appear_together_or_not_at_all() {
    let dir = scratch("together");
    let (env, light) = (dir.join("env.exr"), dir.join("light.json"));
    std::fs::create_dir(&light).unwrap();
    let mut args = vec!["sky", "--backend", "cpu", "--envmap", "cubemap"];
    args.extend(["--envmap-size", "8", "-o", env.to_str().unwrap()]);
    args.extend(["--lighting", light.to_str().unwrap()]);
    args.extend(COARSE_SHELLS);
    let o = atmo(&args);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("is a folder"), "{stderr}");
    // Only the folder that was there: no face, no temporary.
    assert_eq!(files_in(&dir), 1, "{stderr}");
    std::fs::remove_dir(&light).unwrap();
    let o = atmo(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(files_in(&dir), 7);
    std::fs::remove_dir_all(dir).unwrap();
}
