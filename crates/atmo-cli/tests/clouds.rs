//! `atmo clouds`: from the generator or a file, animated, in front of the sky; bad
//! input refused.

mod common;

use common::{atmo, files_in, has_gpu, scratch, SMALL_CLOUD};

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
        "--frame-count",
        "3",
        // The sun goes round from 300 deg: past 360 on the way.
        "--sun-azimuth",
        "300",
        "-o",
        frames.to_str().unwrap(),
    ];
    args.extend(SMALL_CLOUD);
    let o = atmo(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for name in ["frame_000000.png", "frame_000002.png", "animation.png"] {
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
    // Finite, and inside the ranges before: NaN pixels with exit 0, CPU and GPU.
    let good = dir.join("good.csv");
    std::fs::write(&good, "x,y,z,radius,density\n0,0,0,100,0.05\n").unwrap();
    let dense = dir.join("dense.csv");
    std::fs::write(&dense, "x,y,z,radius,density\n0,0,0,100,3e38\n").unwrap();
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (
            vec!["--particles-file", bad_file.to_str().unwrap()],
            "bad.csv:3: radius",
        ),
        (
            vec!["--particles-file", empty.to_str().unwrap()],
            "no particles",
        ),
        // The output is the input: refused before it is overwritten.
        (
            vec![
                "--particles-file",
                good.to_str().unwrap(),
                "--save-particles",
                good.to_str().unwrap(),
            ],
            "the output is also an input (--particles-file)",
        ),
        (
            vec!["--particles-file", dense.to_str().unwrap()],
            "dense.csv:2: density = 300000000000000000000000000000000000000 is out of range: \
             allowed [0, 1] 1/m at radius 100 m",
        ),
        (
            vec!["--generate", "cumulus", "--sun-elevation", "-5"],
            "sun-elevation",
        ),
        (
            vec!["--generate", "cumulus", "--resolution", "1024"],
            "budget",
        ),
        (
            vec![
                "--generate",
                "cumulus",
                "--scattering",
                "single",
                "--forward",
                "2",
            ],
            "forward",
        ),
        (
            vec!["--generate", "cumulus", "--forward", "0.5"],
            "applies to --scattering single only",
        ),
        (
            vec!["--generate", "cumulus", "--solve-cells", "3"],
            "--solve-cells = 3 is out of range: allowed [4, 256]",
        ),
        (
            vec![
                "--generate",
                "cumulus",
                "--scattering",
                "octaves",
                "--solve-cells",
                "64",
            ],
            "--solve-cells = 64 applies to --scattering solve only",
        ),
        (
            vec!["--generate", "cumulus", "--ambient", "sky"],
            "the sky's light needs --sky",
        ),
        (
            vec!["--generate", "cumulus", "--ambient", "1,2"],
            "--ambient = \"1,2\": not three finite numbers >= 0",
        ),
        (
            vec!["--generate", "cumulus", "--ambient", "0.1,-1,0"],
            "--ambient",
        ),
        (
            vec!["--generate", "cumulus", "--ground-albedo", "1.5"],
            "--ground-albedo",
        ),
        (
            vec!["--generate", "cumulus", "--camera", "0,1900,0"],
            "--camera = [0, 1900, 0] is inside particle",
        ),
        (
            vec![
                "--generate",
                "cumulus",
                "--camera",
                "0,1000,-5000",
                "--look-at",
                "0,1000,-5000",
            ],
            "--look-at",
        ),
        (
            vec![
                "--generate",
                "cumulus",
                "--camera",
                "0,9000,0",
                "--look-at",
                "0,0,0",
            ],
            "parallel",
        ),
        (
            vec!["--generate", "cumulus", "--sun-direction", "0,0,0"],
            "--sun-direction",
        ),
        (
            vec!["--generate", "cumulus", "--sun-direction", "1,NaN,0"],
            "--sun-direction",
        ),
        (
            vec!["--generate", "cumulus", "--view-azimuth", "NaN"],
            "--view-azimuth = NaN is out of range: allowed [-360, 360]",
        ),
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

/// Seen from straight above with the sun 45 degrees high in the east, the cloud's
/// shadow lies its height (some 1.9 km) west of it on the ground: dark there, the open
/// ground lit, on the painted ground and on the sky module's.
#[test]
fn the_cloud_casts_its_shadow_on_the_ground() {
    let dir = scratch("clouds-ground");
    for ground in [&["--ground-albedo", "0.3"][..], &["--sky"][..]] {
        let out = dir.join("ground.png");
        let mut args = vec!["clouds", "--generate", "cumulus", "--particles", "2000"];
        args.extend(["--camera", "0,9000,1", "--look-at", "0,0,0", "--fov", "60"]);
        args.extend([
            "--sun-elevation",
            "45",
            "--sun-azimuth",
            "90",
            "--resolution",
            "48",
        ]);
        args.extend([
            "--width",
            "120",
            "--height",
            "120",
            "-o",
            out.to_str().unwrap(),
        ]);
        args.extend(ground);
        let o = atmo(&args);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let img = image::open(&out).unwrap().to_luma8();
        // 60 degrees over 120 pixels at 9 km: 87 m a pixel; the shadow's middle some
        // 22 pixels left of the picture's centre, the cloud at the centre.
        let at = |x: u32, y: u32| img.get_pixel(x, y).0[0] as f64;
        let (shadow, open) = (at(38, 60), at(60, 100));
        assert!(open > 30.0, "{ground:?}: the open ground is lit: {open}");
        // In 8-bit sRGB levels: the painted ground's shadow is black (no ambient light);
        // the sky's keeps the sky's light and the haze of 9 km of air (134 vs 193).
        assert!(
            shadow < 0.8 * open,
            "{ground:?}: shadow {shadow} vs open {open}"
        );
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn saved_particles_are_written_only_once_everything_is_valid() {
    let dir = scratch("clouds-save");
    let (saved, out) = (dir.join("cloud.csv"), dir.join("cloud.png"));
    for bad in [["--fov", "0"], ["--forward", "2"], ["--resolution", "1"]] {
        let mut args = vec!["clouds", "--generate", "cumulus", "--particles", "50"];
        args.extend([
            "--save-particles",
            saved.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
        ]);
        args.extend(bad);
        let o = atmo(&args);
        assert_eq!(
            o.status.code(),
            Some(2),
            "{bad:?}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        assert_eq!(files_in(&dir), 0, "{bad:?} left a file");
    }
    std::fs::remove_dir_all(dir).unwrap();
}

/// A camera south-west of the cloud at its middle height and the sun behind it, by
/// flags (the scene test writes the same as a file).
const EXPLICIT_VIEW: [&str; 12] = [
    "--generate",
    "cumulus",
    "--camera",
    "-1800,1900,1800",
    "--look-at",
    "0,1900,0",
    "--fov",
    "50",
    "--fov-axis",
    "horizontal",
    "--sun-direction",
    "-1,1,1",
];

#[test]
fn an_explicit_camera_and_sun_and_every_order_brighter_than_one() {
    let dir = scratch("clouds-camera");
    let mean = |path: &std::path::Path| {
        let img = image::open(path).unwrap().to_luma8();
        img.pixels().map(|p| p.0[0] as f64).sum::<f64>() / img.pixels().len() as f64
    };
    let mut means = Vec::new();
    for scattering in ["single", "multiple", "solve"] {
        let out = dir.join(format!("{scattering}.png"));
        let mut args = vec!["clouds"];
        args.extend(EXPLICIT_VIEW);
        args.extend(["--scattering", scattering, "-o", out.to_str().unwrap()]);
        // SMALL_CLOUD without its camera distance.
        args.extend(&SMALL_CLOUD[..8]);
        let o = atmo(&args);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        means.push(mean(&out));
    }
    // The cloud shows, and the light of every order makes it brighter, by the table
    // and by the transfer solve alike (within a fifth of each other).
    assert!(means[0] > 5.0, "{means:?}");
    assert!(means[1] > 1.3 * means[0], "{means:?}");
    assert!((means[2] / means[1] - 1.0).abs() < 0.2, "{means:?}");
    // The solve on a coarser grid is the same light, drawn from other cells.
    let coarse = dir.join("coarse.png");
    let mut args = vec!["clouds"];
    args.extend(EXPLICIT_VIEW);
    args.extend(["--solve-cells", "8", "-o", coarse.to_str().unwrap()]);
    args.extend(&SMALL_CLOUD[..8]);
    let o = atmo(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (a, b) = (
        image::open(&coarse).unwrap(),
        image::open(dir.join("solve.png")).unwrap(),
    );
    assert_ne!(a.as_bytes(), b.as_bytes(), "--solve-cells changed nothing");
    assert!((mean(&coarse) / means[2] - 1.0).abs() < 0.2, "{means:?}");
    // The GPU draws the solve too, the picture as the CPU's (the library's tests hold
    // the two to each other closely; here the command line's path through it).
    if has_gpu() {
        let out = dir.join("gpu.png");
        let mut args = vec!["clouds"];
        args.extend(EXPLICIT_VIEW);
        args.extend(["--scattering", "solve", "--backend", "gpu"]);
        args.extend(["-o", out.to_str().unwrap()]);
        args.extend(&SMALL_CLOUD[..8]);
        let o = atmo(&args);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let gpu = mean(&out);
        assert!((gpu / means[2] - 1.0).abs() < 0.03, "{gpu} {means:?}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_scene_file_stands_for_its_flags_and_the_command_line_overrides_it() {
    let dir = scratch("clouds-scene");
    let scene = dir.join("cloud.toml");
    std::fs::write(
        &scene,
        "# from the south-west\ngenerate = \"cumulus\"\nparticles = 2000\ncamera = [-1800, 1900, 1800]\n\
         look-at = [0, 1900, 0]\nfov = 50\nfov-axis = \"horizontal\"\nsun-direction = [-1, 1, 1]\n\
         width = 160\nheight = 90\nresolution = 48\n",
    )
    .unwrap();
    let (from_scene, from_flags, overridden) = (
        dir.join("scene.png"),
        dir.join("flags.png"),
        dir.join("single.png"),
    );
    let run = |args: &[&str]| {
        let o = atmo(args);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    };
    run(&[
        "clouds",
        "--scene",
        scene.to_str().unwrap(),
        "-o",
        from_scene.to_str().unwrap(),
    ]);
    let mut flags = vec!["clouds"];
    flags.extend(EXPLICIT_VIEW);
    flags.extend(["-o", from_flags.to_str().unwrap()]);
    flags.extend(&SMALL_CLOUD[..8]);
    run(&flags);
    let picture = |p: &std::path::Path| image::open(p).unwrap().to_rgb8();
    assert_eq!(picture(&from_scene), picture(&from_flags));
    // A flag on the command line wins over the scene's value.
    run(&[
        "clouds",
        "--scene",
        scene.to_str().unwrap(),
        "--scattering",
        "single",
        "-o",
        overridden.to_str().unwrap(),
    ]);
    assert_ne!(picture(&overridden), picture(&from_scene));
    // The scene in scenes/, smaller.
    let shipped = concat!(env!("CARGO_MANIFEST_DIR"), "/../../scenes/cumulus.toml");
    let small = dir.join("shipped.png");
    let mut args = vec!["clouds", "--scene", shipped, "-o", small.to_str().unwrap()];
    args.extend(&SMALL_CLOUD[..8]);
    run(&args);
    assert_eq!(picture(&small).dimensions(), (160, 90));
    // A key that is no flag, and a line that is no TOML: exit 2, named, nothing written.
    let out = dir.join("bad.png");
    for (text, wanted) in [
        (
            "generate = \"cumulus\"\ncolour = 3\n",
            "`colour` is not a flag",
        ),
        ("generate = \"cumulus\"\nfov = \n", "line 2"),
        (
            "generate = \"cumulus\"\ncamera = [1, \"a\", 2]\n",
            "`camera` must hold numbers",
        ),
    ] {
        std::fs::write(&scene, text).unwrap();
        let o = atmo(&[
            "clouds",
            "--scene",
            scene.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
        ]);
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{text}: {stderr}");
        assert!(stderr.contains(wanted), "{text}: {stderr}");
        assert!(!out.exists());
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Particles are charged to the memory budget (about 400 bytes each once drawn) before
/// they are read or generated: a file or a count past it is refused, naming it.
#[test]
fn particles_past_the_budget_are_refused_before_they_are_read() {
    let dir = scratch("clouds-particle-budget");
    let count: u32 = 200_000;
    let file = dir.join("many.atmo-particles");
    let mut bytes = b"ATMOPART".to_vec();
    for word in [1, count, 0] {
        bytes.extend(word.to_le_bytes());
    }
    bytes.resize(bytes.len() + count as usize * 20, 0);
    std::fs::write(&file, bytes).unwrap();
    let out = dir.join("out.png");
    let base = [
        "clouds",
        "--memory-limit",
        "64M",
        "--resolution",
        "64",
        "-o",
    ];
    for (source, named) in [
        (
            vec!["--particles-file", file.to_str().unwrap()],
            "200000 particles (".to_string(),
        ),
        (
            vec!["--generate", "cumulus", "--particles", "200000"],
            "200000 particles (--particles)".to_string(),
        ),
    ] {
        let o = atmo(&[&base[..], &[out.to_str().unwrap()], &source[..]].concat());
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{stderr}");
        assert!(
            stderr.contains(&named) && stderr.contains("lower the particle count"),
            "{stderr}"
        );
        assert!(!out.exists());
    }
    std::fs::remove_dir_all(dir).unwrap();
}
