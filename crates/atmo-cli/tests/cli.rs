//! The `atmo` binary as a user runs it: pictures of the requested size, numbers for
//! probes, and every bad input refused with exit code 2, a message naming the field,
//! and no output file.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn atmo(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_atmo"))
        .args(args)
        .output()
        .expect("atmo runs")
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("atmo-cli-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn files_in(dir: &Path) -> usize {
    std::fs::read_dir(dir).unwrap().count()
}

const SMALL: [&str; 4] = ["--width", "48", "--height", "32"];

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
    refused("sun", &["--sun-elevation", "95"], "sun elevation");
    refused("sun-nan", &["--sun-elevation", "NaN"], "sun elevation");
    refused("below", &["--altitude", "-5"], "altitude");
    refused("above", &["--altitude", "70000"], "altitude");
    refused("width", &["--width", "0"], "width");
    refused(
        "budget",
        &["--width", "16384", "--height", "16384"],
        "budget",
    );
    refused("order", &["--order", "4"], "order");
    refused("shells", &["--shells", "1"], "shells");
    refused("fov", &["--fov", "0"], "fov");
    refused("exposure", &["--exposure", "-1"], "exposure");
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

/// A tiny table (8 x 8 directions, 6 suns, 3 altitudes) in `dir`, made with the CLI.
fn tiny_table(dir: &Path) -> PathBuf {
    let table = dir.join("tiny.atmo-sky");
    let o = atmo(&[
        "precompute",
        "sky",
        "-o",
        table.to_str().unwrap(),
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
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    table
}

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
    let mut args = vec!["sky", "--table", t, "--animate", "sun", "--frames", "3"];
    args.extend(["-o", frames.to_str().unwrap()]);
    args.extend(SMALL);
    let o = atmo(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for name in ["frame-0000.png", "frame-0002.png", "animation.png"] {
        let img = image::open(frames.join(name)).unwrap();
        assert_eq!((img.width(), img.height()), (48, 32), "{name}");
    }
    let first = image::open(frames.join("frame-0000.png"))
        .unwrap()
        .to_rgb8();
    let last = image::open(frames.join("frame-0002.png"))
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
        "sun elevation",
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
        &["precompute", "sky", "-o", sky, "--epsilon=-1/255"],
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

fn scene(name: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenes")
        .join(name)
        .to_string_lossy()
        .into_owned()
}

#[test]
fn shafts_render_a_scene_and_compare_measures_two_renders() {
    let dir = scratch("shafts");
    let (png, fast, slow, diff) = (
        dir.join("stage.png"),
        dir.join("fast.exr"),
        dir.join("slow.exr"),
        dir.join("diff.png"),
    );
    let o = atmo(&["shafts", &scene("stage.toml"), "-o", png.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let img = image::open(&png).unwrap().to_rgb8();
    assert_eq!((img.width(), img.height()), (720, 480));
    assert!(img.pixels().any(|p| p.0[0] > 100), "the beams show");

    let fig6 = scene("spotlight-sphere.toml");
    let small = ["--planes", "10", "--sub-planes", "2"];
    let o = atmo(&[&["shafts", &fig6, "-o", fast.to_str().unwrap()][..], &small].concat());
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let o = atmo(&[
        "shafts",
        &fig6,
        "-o",
        slow.to_str().unwrap(),
        "--reference",
        "--samples",
        "256",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let o = atmo(&[
        "compare",
        fast.to_str().unwrap(),
        slow.to_str().unwrap(),
        "-o",
        diff.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = String::from_utf8_lossy(&o.stdout);
    let rms: f64 = text
        .split("rms ")
        .nth(1)
        .and_then(|s| s.split_whitespace().next())
        .and_then(|s| s.parse().ok())
        .unwrap_or_else(|| panic!("{text}"));
    assert!(rms > 0.0 && rms < 10.0, "{text}");
    assert!(image::open(&diff).is_ok());
    // A picture against itself: zero.
    let o = atmo(&[
        "compare",
        fast.to_str().unwrap(),
        fast.to_str().unwrap(),
        "-o",
        diff.to_str().unwrap(),
    ]);
    assert!(String::from_utf8_lossy(&o.stdout).contains("rms 0.000"));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn bad_shafts_input_exits_2_and_writes_nothing() {
    let dir = scratch("shafts-bad");
    let good = std::fs::read_to_string(scene("spotlight-sphere.toml")).unwrap();
    let bad = [
        (
            "syntax.toml",
            good.replacen("width = 720", "width = = 720", 1),
            "line",
        ),
        (
            "unknown.toml",
            good.replacen("albedo = 0.9", "albedo = 0.9\nfog = 1", 1),
            "fog",
        ),
        (
            "beam.toml",
            good.replacen("field_deg = 34.0", "field_deg = 10.0", 1),
            "beam_deg",
        ),
        (
            "gobo.toml",
            good.replacen("kelvin = 3200", "kelvin = 3200\ngobo = \"nope.png\"", 1),
            "nope.png",
        ),
        (
            "fov.toml",
            good.replacen("fov_deg = 50.0", "fov_deg = 0.0", 1),
            "fov_deg",
        ),
    ];
    let out = dir.join("out.png");
    for (name, text, wanted) in bad {
        assert_ne!(text, good, "{name}");
        let path = dir.join(name);
        std::fs::write(&path, text).unwrap();
        let o = atmo(&[
            "shafts",
            path.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
        ]);
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{name}: {stderr}");
        assert!(stderr.contains(wanted), "{name}: {stderr}");
        assert!(!out.exists(), "{name}");
    }
    // compare: pictures of different sizes, and PNG input.
    let (a, b) = (dir.join("a.exr"), dir.join("b.exr"));
    atmo::image::Frame::new(4, 3)
        .write(&a, 1.0, atmo::image::ToneMap::Clamp)
        .unwrap();
    atmo::image::Frame::new(3, 3)
        .write(&b, 1.0, atmo::image::ToneMap::Clamp)
        .unwrap();
    let o = atmo(&[
        "compare",
        a.to_str().unwrap(),
        b.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("differ in size"));
    let o = atmo(&[
        "compare",
        a.to_str().unwrap(),
        out.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(!out.exists());
    std::fs::remove_dir_all(&dir).unwrap();
}

const SMALL_CLOUD: [&str; 10] = [
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

#[test]
fn clouds_render_from_the_generator_or_a_file_and_animate() {
    let dir = scratch("clouds");
    let (png, saved, again, frames) = (
        dir.join("cloud.png"),
        dir.join("cloud.csv"),
        dir.join("again.png"),
        dir.join("frames"),
    );
    let mut args = vec![
        "clouds",
        "--generate",
        "cumulus",
        "-o",
        png.to_str().unwrap(),
    ];
    args.extend(["--save-particles", saved.to_str().unwrap()]);
    args.extend(SMALL_CLOUD);
    let o = atmo(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let img = image::open(&png).unwrap().to_rgb8();
    assert_eq!((img.width(), img.height()), (160, 90));
    assert!(img.pixels().any(|p| p.0[2] > 60), "the cloud shows");
    // The same particles from the file: the same picture.
    let mut args = vec![
        "clouds",
        "--particles-file",
        saved.to_str().unwrap(),
        "-o",
        again.to_str().unwrap(),
    ];
    args.extend(&SMALL_CLOUD[2..]);
    let o = atmo(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(image::open(&again).unwrap().to_rgb8(), img);
    let mut args = vec![
        "clouds",
        "--generate",
        "cumulus",
        "--animate",
        "sun",
        "--frames",
        "3",
        "-o",
        frames.to_str().unwrap(),
    ];
    args.extend(SMALL_CLOUD);
    let o = atmo(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for name in ["frame-0000.png", "frame-0002.png", "animation.png"] {
        assert!(frames.join(name).exists(), "{name}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn bad_cloud_input_exits_2_and_writes_nothing() {
    let dir = scratch("clouds-bad");
    let out = dir.join("out.png");
    let bad_file = dir.join("bad.csv");
    std::fs::write(
        &bad_file,
        "x,y,z,radius,density\n0,0,0,10,0.1\n0,0,0,-3,0.1\n",
    )
    .unwrap();
    let empty = dir.join("empty.csv");
    std::fs::write(&empty, "x,y,z,radius,density\n").unwrap();
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (
            vec!["--particles-file", bad_file.to_str().unwrap()],
            "bad.csv:3: radius",
        ),
        (
            vec!["--particles-file", empty.to_str().unwrap()],
            "no particles",
        ),
        (
            vec!["--generate", "cumulus", "--sun-elevation", "-5"],
            "sun-elevation",
        ),
        (
            vec!["--generate", "cumulus", "--resolution", "1024"],
            "budget",
        ),
        (vec!["--generate", "cumulus", "--forward", "2"], "forward"),
    ];
    for (extra, wanted) in cases {
        let mut args = vec![
            "clouds",
            "-o",
            out.to_str().unwrap(),
            "--width",
            "32",
            "--height",
            "18",
        ];
        args.extend(extra);
        let o = atmo(&args);
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(stderr.contains(wanted), "{args:?}: {stderr}");
        assert!(!out.exists());
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn clouds_in_front_of_the_sky() {
    let dir = scratch("clouds-sky");
    let out = dir.join("sky.png");
    let mut args = vec![
        "clouds",
        "--generate",
        "cumulus",
        "--sky",
        "--view-height",
        "300",
        "-o",
        out.to_str().unwrap(),
    ];
    args.extend(SMALL_CLOUD);
    let o = atmo(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let img = image::open(&out).unwrap().to_rgb8();
    // The sky behind: the top corner is blue, not black.
    let corner = img.get_pixel(2, 2).0;
    assert!(corner[2] > 80 && corner[2] > corner[0], "{corner:?}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Whether this machine has a GPU adapter (in CI, where the driver is installed, it
/// must: a missing one fails here rather than skipping the GPU checks).
fn has_gpu() -> bool {
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

#[test]
fn every_method_gives_the_same_picture_on_the_gpu_and_the_cpu() {
    if !has_gpu() {
        return;
    }
    let dir = scratch("backends");
    let table = tiny_table(&dir);
    let fig6 = scene("spotlight-sphere.toml");
    let table_args = [
        "sky",
        "--table",
        table.to_str().unwrap(),
        "--sun-elevation",
        "5",
    ];
    let shell_args = [
        "sky",
        "--sun-elevation",
        "5",
        "--directions",
        "16",
        "--shells",
        "16",
    ];
    let shafts_args = ["shafts", &fig6, "--planes", "8", "--supersampling", "1"];
    let clouds_args = [
        "clouds",
        "--generate",
        "cumulus",
        "--particles",
        "800",
        "--resolution",
        "32",
    ];
    for (name, args) in [
        ("sky-table", &table_args[..]),
        ("sky-shells", &shell_args[..]),
        ("shafts", &shafts_args[..]),
        ("clouds", &clouds_args[..]),
    ] {
        let mut frames = Vec::new();
        for backend in ["gpu", "cpu"] {
            let out = dir.join(format!("{name}-{backend}.exr"));
            let mut all = args.to_vec();
            all.extend(["--backend", backend, "-o", out.to_str().unwrap()]);
            if name != "shafts" {
                all.extend(SMALL);
            }
            let o = atmo(&all);
            let stderr = String::from_utf8_lossy(&o.stderr);
            assert!(o.status.success(), "{name} {backend}: {stderr}");
            // The GPU run says which device ran it.
            assert_eq!(
                backend == "gpu",
                stderr.contains("running on the GPU"),
                "{stderr}"
            );
            frames.push(atmo::image::Frame::read_exr(&out).unwrap());
        }
        let display = atmo::image::Display {
            exposure: 1.0,
            tone: atmo::image::ToneMap::Exponential,
        };
        let e = frames[0].level_errors(&frames[1], display).unwrap();
        assert!(e.rms <= 0.5 && e.max <= 2.0, "{name}: GPU vs CPU {e:?}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn an_adapter_that_does_not_exist_exits_2() {
    let dir = scratch("adapter");
    let out = dir.join("x.png");
    let o = atmo(&[
        "shafts",
        &scene("spotlight-sphere.toml"),
        "--adapter",
        "no-such-gpu-anywhere",
        "-o",
        out.to_str().unwrap(),
    ]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("no GPU adapter") && stderr.contains("--backend cpu")
            || stderr.contains("no-such-gpu-anywhere"),
        "{stderr}"
    );
    assert_eq!(files_in(&dir), 0);
    std::fs::remove_dir_all(&dir).unwrap();
}
