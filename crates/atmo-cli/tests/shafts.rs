//! `atmo shafts` and `atmo compare`: a scene rendered and measured; bad input refused.

mod common;

use common::{atmo, scene, scratch};

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
    // A picture against itself: zero; without -o, the figures and no image (run in
    // the scratch folder, which holds nothing else to write over).
    std::fs::remove_file(&diff).unwrap();
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_atmo"))
        .args(["compare", fast.to_str().unwrap(), fast.to_str().unwrap()])
        .current_dir(&dir)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(
        text.contains("rms 0.000") && !text.contains("difference image"),
        "{text}"
    );
    let written: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .flatten()
        .map(|e| e.file_name())
        .collect();
    assert_eq!(written.len(), 3, "only the three renders: {written:?}");
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
        // A mesh that never ends stops at the bounded reader's limit (it aborted).
        #[cfg(target_os = "linux")]
        (
            "endless.toml",
            format!("{good}\n[[object]]\nkind = \"mesh\"\nfile = \"/dev/zero\"\nalbedo = 0.5\n"),
            "OBJ file is longer than the limit of 64 MiB",
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
            "--memory-limit",
            "64M",
        ]);
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{name}: {stderr}");
        assert!(stderr.contains(wanted), "{name}: {stderr}");
        assert!(!out.exists(), "{name}");
    }
    // Edits by --set are validated as the file is.
    let fig6 = scene("spotlight-sphere.toml");
    for (edit, wanted) in [
        (
            "spotlight[3].dimmer=1",
            "has 1 [[spotlight]], not one at index 3",
        ),
        ("spotlight[0].dimmer=2", "spotlight[0].dimmer"),
        ("camera.lens=7", "lens"),
        ("dimmer", "give KEY=VALUE"),
    ] {
        let args = [fig6.as_str(), "--set", edit];
        let o = atmo(&[&["shafts"][..], &args, &["-o", out.to_str().unwrap()]].concat());
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{edit}: {stderr}");
        assert!(stderr.contains(wanted), "{edit}: {stderr}");
        assert!(!out.exists(), "{edit}");
    }
    // An output over the scene's own gobo is refused before anything is written.
    let scenes = dir.join("scenes");
    std::fs::create_dir_all(scenes.join("gobos")).unwrap();
    let gobo = scenes.join("gobos/dots.png");
    std::fs::copy(scene("gobos/dots.png"), &gobo).unwrap();
    let with_gobo = scenes.join("gobo.toml");
    std::fs::write(
        &with_gobo,
        good.replacen(
            "kelvin = 3200",
            "kelvin = 3200\ngobo = \"gobos/dots.png\"",
            1,
        ),
    )
    .unwrap();
    let before = std::fs::read(&gobo).unwrap();
    let o = atmo(&[
        "shafts",
        with_gobo.to_str().unwrap(),
        "-o",
        gobo.to_str().unwrap(),
    ]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("also an input (a file the scene names)"),
        "{stderr}"
    );
    assert_eq!(std::fs::read(&gobo).unwrap(), before);
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

#[test]
fn compare_refuses_pictures_with_nan_or_infinity() {
    let dir = scratch("compare-nan");
    let exr = |name: &str, value: f32| {
        let path = dir.join(name);
        image::Rgb32FImage::from_pixel(4, 3, image::Rgb([value; 3]))
            .save(&path)
            .unwrap();
        path.to_string_lossy().into_owned()
    };
    let (black, nan, inf) = (
        exr("black.exr", 0.0),
        exr("nan.exr", f32::NAN),
        exr("inf.exr", f32::NEG_INFINITY),
    );
    let diff = dir.join("difference.png");
    for (a, b, which) in [(&nan, &black, "first"), (&black, &inf, "second")] {
        let o = atmo(&["compare", a, b, "-o", diff.to_str().unwrap()]);
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{stderr}");
        assert!(
            stderr.contains(&format!(
                "the {which} picture has 36 of 36 values that are not finite"
            )),
            "{stderr}"
        );
        assert!(!diff.exists());
    }
    let o = atmo(&["compare", &black, &black, "-o", diff.to_str().unwrap()]);
    assert!(o.status.success() && diff.exists());
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn a_show_plays_into_frames_and_an_animated_png() {
    let dir = scratch("shafts-show");
    let file = common::small_show(&dir);
    let out = dir.join("frames");
    let o = atmo(&[
        "shafts",
        file.to_str().unwrap(),
        "--animate",
        "--fps",
        "2",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    // 7 s of cues at 2 frames/s: 0, 0.5, ..., 7.
    // And animation.png and the manifest.
    assert_eq!(common::files_in(&out), 15 + 2);
    let first = image::open(out.join("frame_000000.png")).unwrap().to_rgb8();
    let last = image::open(out.join("frame_000014.png")).unwrap().to_rgb8();
    assert_eq!(first.dimensions(), (72, 48));
    assert_ne!(first, last, "the heads moved");
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(
        stderr.contains("15 frames") && stderr.contains("shadow maps rebuilt"),
        "{stderr}"
    );
    // The still at 7 s is the last frame.
    let still = dir.join("end.png");
    let o = atmo(&[
        "shafts",
        file.to_str().unwrap(),
        "--time",
        "7",
        "-o",
        still.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(image::open(&still).unwrap().to_rgb8(), last);

    // A scene without cues has no show to play; a file name is not a folder.
    let fig6 = scene("spotlight-sphere.toml");
    let o = atmo(&[
        "shafts",
        &fig6,
        "--animate",
        "-o",
        dir.join("none").to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("it has none"));
    let o = atmo(&[
        "shafts",
        file.to_str().unwrap(),
        "--animate",
        "-o",
        dir.join("a.png").to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(!dir.join("none").exists() && !dir.join("a.png").exists());
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A scene whose shadow maps are over the memory budget is refused naming
/// `--shadow-map`, and that flag then makes it fit: the flag is applied before the
/// scene is built and charged.
#[test]
fn the_shadow_map_flag_answers_the_budget_message() {
    let dir = scratch("shafts-shadow-budget");
    let out = dir.join("out.png");
    let stage = scene("spotlight-sphere.toml");
    let base = [
        stage.as_str(),
        "--set",
        "render.shadow_map=8192",
        "--memory-limit",
        "64M",
        "-o",
        out.to_str().unwrap(),
    ];
    let o = atmo(&[&["shafts"], &base[..]].concat());
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("--shadow-map") && !out.exists(), "{stderr}");
    let o = atmo(&[&["shafts"], &base[..], &["--shadow-map", "256"]].concat());
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{stderr}");
    assert!(
        stderr.contains("256^2 shadow maps") && out.is_file(),
        "{stderr}"
    );
    std::fs::remove_dir_all(dir).unwrap();
}

/// A scene file is charged to the memory budget before it is parsed (its TOML tree
/// takes about 47 bytes a byte): one too large for the budget is refused naming it,
/// and the same file parses under the default budget.
#[test]
fn a_scene_too_large_for_the_budget_is_refused_before_it_is_parsed() {
    let dir = scratch("shafts-big-scene");
    let show = common::small_show(&dir);
    let mut text = std::fs::read_to_string(&show).unwrap();
    for i in 0..25_000 {
        text += &format!(
            "\n[[cue]]\ntime_s = {}\nfade_s = 0.5\nset.left = {{ pan_deg = {}.0 }}\n",
            7.0 + i as f64 * 0.01,
            i % 90
        );
    }
    assert!(text.len() > 1 << 20);
    std::fs::write(&show, text).unwrap();
    let out = dir.join("out.png");
    let args = [show.to_str().unwrap(), "-o", out.to_str().unwrap()];
    let o = atmo(&[&["shafts", "--memory-limit", "64M"], &args[..]].concat());
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("parsed would need") && stderr.contains("lower the file's size"),
        "{stderr}"
    );
    let o = atmo(&[&["shafts"], &args[..]].concat());
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    std::fs::remove_dir_all(dir).unwrap();
}

/// The plane method's buffers are charged at what they hold a pixel (a frame's 12
/// bytes were a third of it): a picture whose buffers are past the budget is refused
/// naming the camera's size; the scene's own size fits.
#[test]
fn the_pictures_buffers_are_charged_to_the_budget() {
    let dir = scratch("shafts-picture-budget");
    let out = dir.join("out.png");
    let sphere = scene("spotlight-sphere.toml");
    let run = |size: &[&str]| {
        let mut args = vec!["shafts", sphere.as_str(), "--memory-limit", "64M"];
        args.extend(size);
        args.extend(["--backend", "cpu", "-o", out.to_str().unwrap()]);
        atmo(&args)
    };
    // 2560 x 1440: 44 MB as frames were charged, 141 MB as the method holds them.
    let o = run(&["--set", "camera.width=2560", "--set", "camera.height=1440"]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("lower camera.width and camera.height"),
        "{stderr}"
    );
    assert!(!out.exists());
    let o = run(&[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    std::fs::remove_dir_all(dir).unwrap();
}
