//! Memory held by a run, measured from outside: each child's own peak resident size,
//! as `wait4` gives it for that child alone (tests run side by side).

mod common;

use std::os::unix::process::ExitStatusExt as _;

use common::{probe_file, scratch, COARSE_SHELLS};

/// What a run of `atmo` with `args` gave: its exit status, standard output and error,
/// and its peak resident size, bytes.
#[cfg(target_os = "linux")]
#[allow(clippy::zombie_processes)] // reaped by wait4, which gives its own rusage
fn atmo_measured(args: &[&str]) -> (std::process::Output, u64) {
    let dir = scratch(&format!("measured-{:?}", std::thread::current().id()));
    let (out, err) = (dir.join("stdout"), dir.join("stderr"));
    let child = std::process::Command::new(env!("CARGO_BIN_EXE_atmo"))
        .args(args)
        .stdout(std::fs::File::create(&out).unwrap())
        .stderr(std::fs::File::create(&err).unwrap())
        .spawn()
        .expect("atmo runs");
    let mut status = 0;
    // SAFETY: wait4 reaps our own child and writes into the structs it is given.
    let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
    let pid = unsafe { libc::wait4(child.id() as i32, &mut status, 0, &mut usage) };
    assert_eq!(pid, child.id() as i32);
    let output = std::process::Output {
        status: std::process::ExitStatus::from_raw(status),
        stdout: std::fs::read(&out).unwrap(),
        stderr: std::fs::read(&err).unwrap(),
    };
    std::fs::remove_dir_all(dir).unwrap();
    (output, usage.ru_maxrss as u64 * 1024)
}

/// `--probe` streams its directions in blocks: 50,000 of them held about 5 kB each
/// at once (a 2 M line file passed 5 GB), now a block's worth.
#[cfg(target_os = "linux")]
#[test]
fn probe_directions_stream_in_bounded_memory() {
    let dir = scratch("probe-memory");
    let file = probe_file(&dir, 50_000);
    let (o, peak) = atmo_measured(
        &[
            &["sky", "--probe", file.to_str().unwrap()][..],
            &COARSE_SHELLS,
        ]
        .concat(),
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(o.stdout.iter().filter(|&&b| b == b'\n').count(), 50_001);
    // Holding every direction's maps took 150 MB; one block of them is a tenth of it.
    assert!(peak < 80 << 20, "peak {} MB", peak >> 20);
    std::fs::remove_dir_all(dir).unwrap();
}

/// A `w` x `w` PNG gobo in `dir` named `name`: mostly dark, a stripe of light, the
/// pixel at `mark` lit so that files of one size differ.
fn gobo_png(dir: &std::path::Path, name: &str, w: u32, mark: u32) -> std::path::PathBuf {
    let image = image::GrayImage::from_fn(w, w, |x, y| {
        image::Luma([if y / 64 % 2 == 0 || (x, y) == (mark, 0) {
            255
        } else {
            0
        }])
    });
    let file = dir.join(name);
    image.save(&file).unwrap();
    file
}

/// The small show with `extra` added: its own lights, or a fixture.
fn show_with(dir: &std::path::Path, extra: &str) -> std::path::PathBuf {
    let show = common::small_show(dir);
    let text = std::fs::read_to_string(&show).unwrap() + extra;
    std::fs::write(&show, text).unwrap();
    show
}

/// A scene's files are read once however many lights and wheel slots name them (a
/// wheel listing one 4096^2 gobo 200 times held 200 copies, 10 GB; 100 spotlights
/// with it 5 GB), and files that differ are counted together against the budget
/// (40 different ones each within 1 GB took 2.1 GB under `--memory-limit 1G`).
#[cfg(target_os = "linux")]
#[test]
fn a_scenes_files_are_read_once_and_counted_together() {
    let dir = scratch("files-budget");
    let side = 2048; // 12 MB of texels a copy
    let one = gobo_png(&dir, "one.png", side, 0);
    let one = one.to_str().unwrap();
    let wheel = format!(
        "\n[[fixture]]\nname = \"wheel\"\nposition = [0.0, 6.5, 1.0]\nfront = [0.0, 0.0, -1.0]\n\
         intensity = 3000.0\ngobo_wheel = [{}]\nstart = {{ tilt_deg = 12.0, gobo = 3 }}\n",
        vec![format!("{one:?}"); 100].join(", ")
    );
    let spots: String = (0..40)
        .map(|i| {
            format!(
                "\n[[spotlight]]\nposition = [{}, 6.0, 2.0]\naim = [0.0, 0.0, -0.5]\n\
                 intensity = 100.0\nbeam_deg = 20.0\nfield_deg = 30.0\ngobo = {one:?}\n",
                i as f32 * 0.05
            )
        })
        .collect();
    let out = dir.join("out.png");
    let (o, peak) = atmo_measured(&[
        "shafts",
        show_with(&dir, &(wheel + &spots)).to_str().unwrap(),
        "--memory-limit",
        "256M",
        "--backend",
        "cpu",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    // 140 copies were 1.7 GB; one is 12 MB beside the 40 lights' shadow maps.
    assert!(peak < 300 << 20, "peak {} MB", peak >> 20);

    // Twenty different gobos of 12 MB each, under 128M: refused as the files add up,
    // naming them.
    let spots: String = (0..20)
        .map(|i| {
            let file = gobo_png(&dir, &format!("g{i}.png"), side, i + 1);
            format!(
                "\n[[spotlight]]\nposition = [{}, 6.0, 2.0]\naim = [0.0, 0.0, -0.5]\n\
                 intensity = 100.0\nbeam_deg = 20.0\nfield_deg = 30.0\ngobo = {:?}\n",
                i as f32 * 0.05,
                file.to_str().unwrap()
            )
        })
        .collect();
    let (o, _) = atmo_measured(&[
        "shafts",
        show_with(&dir, &spots).to_str().unwrap(),
        "--memory-limit",
        "128M",
        "-o",
        out.to_str().unwrap(),
    ]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("beside the scene's gobos, photometric files"),
        "{stderr}"
    );
    std::fs::remove_dir_all(dir).unwrap();
}

/// An OBJ file is charged by the triangles and vertices it gives, not its length: a
/// file of short face lines (3 M triangles over 1,000 vertices in 41 MB) held 446 MB
/// where four times its text, 164 MB, was charged.
#[cfg(target_os = "linux")]
#[test]
fn a_mesh_is_charged_by_its_triangles() {
    let dir = scratch("mesh-budget");
    // 600,000 triangles over 100 vertices in 8 MB: 77 MB as the mesh holds it, 33 MB
    // as four times its text.
    let mut obj = String::new();
    for i in 0..100 {
        obj += &format!("v {} {} {}\n", i % 10, (i / 10) % 10, i % 7);
    }
    for k in 0..600_000u64 {
        let [a, b, c] = [k % 97 + 1, (k * 7) % 89 + 2, (k * 13) % 83 + 3];
        obj += &format!("f {a} {b} {c}\n");
    }
    std::fs::write(dir.join("many.obj"), &obj).unwrap();
    let scene = show_with(
        &dir,
        "\n[[object]]\nkind = \"mesh\"\nfile = \"many.obj\"\nscale = 0.1\nalbedo = 0.5\n",
    );
    let (o, _) = atmo_measured(&[
        "shafts",
        scene.to_str().unwrap(),
        "--memory-limit",
        "64M",
        "-o",
        dir.join("out.png").to_str().unwrap(),
    ]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("600000 triangles") && stderr.contains("lower the mesh's size"),
        "{stderr}"
    );
    std::fs::remove_dir_all(dir).unwrap();
}

/// What a command holds together is counted together: the sky's maps beside its
/// picture (maps of 60 MiB and a 50 MiB frame each passed 64M alone, and took
/// 129 MB), a cloud's buffer beside its particles and picture, `compare`'s second
/// picture beside its first. Each is refused naming both, before the work.
#[cfg(target_os = "linux")]
#[test]
fn what_a_command_holds_together_is_counted_together() {
    let dir = scratch("held-together");
    let refused = |args: &[&str], beside: &str| {
        let (o, peak) = atmo_measured(&[args, &["--memory-limit", "64M"][..]].concat());
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{stderr}");
        assert!(stderr.contains(beside), "{stderr}");
        assert!(peak < 64 << 20, "peak {} MB", peak >> 20);
    };
    let sky = dir.join("sky.exr");
    let sky = sky.to_str().unwrap();
    refused(
        &[
            "sky", "--shells", "10", "--width", "2896", "--height", "1448", "-o", sky,
        ],
        "the sky maps of earth beside the picture",
    );
    let cloud = dir.join("cloud.png");
    refused(
        &[
            "clouds",
            "--generate",
            "cumulus",
            "--particles",
            "100000",
            "--resolution",
            "150",
            "--width",
            "1600",
            "--height",
            "900",
            "-o",
            cloud.to_str().unwrap(),
        ],
        "intensity buffer beside the particles and the picture",
    );
    // Two 1600 x 800 pictures: each decodes within the budget alone, not the second
    // beside the first (two of 1878 x 939 took 89 MB together).
    let (a, b) = (dir.join("a.exr"), dir.join("b.exr"));
    for (file, elevation) in [(&a, "20"), (&b, "21")] {
        let o = common::atmo(&[
            "sky",
            "--shells",
            "8",
            "--sun-elevation",
            elevation,
            "--width",
            "1600",
            "--height",
            "800",
            "--backend",
            "cpu",
            "-o",
            file.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    }
    refused(
        &["compare", a.to_str().unwrap(), b.to_str().unwrap()],
        "beside the first picture",
    );
    std::fs::remove_dir_all(dir).unwrap();
}

/// A picture drawn on the GPU is charged its texture, read-back and frame before they
/// are made (a 16384-wide sky under 1100M took 5.6-8.4 GB on the software driver).
#[cfg(target_os = "linux")]
#[test]
fn a_gpu_picture_is_charged_before_it_is_made() {
    if !common::has_gpu() {
        return;
    }
    let dir = scratch("gpu-picture");
    let (o, peak) = atmo_measured(&[
        "sky",
        "--shells",
        "8",
        "--backend",
        "gpu",
        "--width",
        "16384",
        "--height",
        "4096",
        "--memory-limit",
        "1100M",
        "-o",
        dir.join("sky.png").to_str().unwrap(),
    ]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("the sky frame (16384 x 4096) on the GPU"),
        "{stderr}"
    );
    assert!(peak < 1100 << 20, "peak {} MB", peak >> 20);
    std::fs::remove_dir_all(dir).unwrap();
}
