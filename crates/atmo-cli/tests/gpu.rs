//! `--backend gpu`: every method gives the CPU's picture on the GPU.

mod common;

use common::{atmo, files_in, has_gpu, scene, scratch, tiny_table, SMALL};

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
    let mut envmap_args = shell_args.to_vec();
    envmap_args.extend(["--envmap", "equirect", "--envmap-size", "16"]);
    // Every pixel on the CPU too: the GPU has no adaptive sampling.
    let shafts_args = [
        "shafts",
        &fig6,
        "--planes",
        "8",
        "--supersampling",
        "1",
        "--every-pixel",
    ];
    // The GPU draws every order by the octaves (the CPU's default is the transfer
    // table): the same model on both.
    let clouds_args = [
        "clouds",
        "--generate",
        "cumulus",
        "--particles",
        "800",
        "--resolution",
        "32",
        "--scattering",
        "octaves",
    ];
    for (name, args) in [
        ("sky-table", &table_args[..]),
        ("sky-shells", &shell_args[..]),
        ("sky-envmap", &envmap_args[..]),
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
