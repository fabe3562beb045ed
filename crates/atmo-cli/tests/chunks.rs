//! Work split as a render farm splits it: animations drawn in chunks (`--frames A..B`,
//! `--frame K`) and assembled, a table precomputed in parts and merged; each the same,
//! byte for byte, as one process. tools/farm-test.sh runs the same through Slurm.

mod common;

use std::path::Path;

use common::{atmo, scratch, small_show, tiny_table, SMALL_CLOUD, TINY_TABLE};

fn ok(args: &[&str]) -> String {
    let o = atmo(args);
    let stderr = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(o.status.success(), "{args:?}: {stderr}");
    stderr
}

fn refused(args: &[&str]) -> String {
    let o = atmo(args);
    let stderr = String::from_utf8_lossy(&o.stderr).into_owned();
    assert_eq!(o.status.code(), Some(2), "{args:?}: {stderr}");
    stderr
}

fn bytes(path: &Path) -> Vec<u8> {
    std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// `frame_000000.png` ... of `count` frames in `folder`, each the same as in `whole`.
fn same_frames(whole: &Path, folder: &Path, frames: std::ops::Range<usize>) {
    for k in frames {
        let name = format!("frame_{k:06}.png");
        assert!(
            bytes(&whole.join(&name)) == bytes(&folder.join(&name)),
            "{name} differs"
        );
    }
}

#[test]
fn a_show_in_chunks_is_the_whole_run_byte_for_byte() {
    let dir = scratch("chunks-show");
    let show = small_show(&dir);
    let show = show.to_str().unwrap();
    let whole = dir.join("whole");
    let chunks = dir.join("chunks");
    let base = ["shafts", show, "--animate", "--fps", "2"];
    fn with<'a>(base: &[&'a str], extra: &[&'a str]) -> Vec<&'a str> {
        [base, extra].concat()
    }
    ok(&with(&base, &["-o", whole.to_str().unwrap()]));
    // 15 frames in three uneven chunks, the last given inclusively, out of order.
    let c = chunks.to_str().unwrap();
    for range in ["9..=14", "0..4", "4..9"] {
        let stderr = ok(&with(&base, &["--frames", range, "-o", c]));
        assert!(stderr.contains("atmo assemble"), "{stderr}");
    }
    assert!(!chunks.join("animation.png").exists());
    same_frames(&whole, &chunks, 0..15);
    let apng = dir.join("show.apng");
    ok(&["assemble", c, "-o", apng.to_str().unwrap()]);
    assert!(bytes(&apng) == bytes(&whole.join("animation.png")));

    // A chunk run again keeps its frames; one frame lost is drawn again alone.
    std::fs::remove_file(chunks.join("frame_000005.png")).unwrap();
    let stderr = ok(&with(&base, &["--frames", "4..9", "-o", c]));
    assert!(stderr.contains("1 frame drawn, 4 kept"), "{stderr}");
    same_frames(&whole, &chunks, 4..9);
    // A damaged frame is no frame: drawn again, never assembled.
    std::fs::write(
        chunks.join("frame_000007.png"),
        b"\x89PNG\r\n\x1a\ntruncated",
    )
    .unwrap();
    let e = refused(&["assemble", c, "-o", apng.to_str().unwrap()]);
    assert!(e.contains("frame_000007.png"), "{e}");
    ok(&with(&base, &["--frame", "7", "-o", c]));
    same_frames(&whole, &chunks, 7..8);
    // A missing frame is named, and the animation already there stays.
    std::fs::remove_file(chunks.join("frame_000011.png")).unwrap();
    let e = refused(&["assemble", c, "-o", apng.to_str().unwrap()]);
    assert!(e.contains("frame 11 (frame_000011.png) is missing"), "{e}");
    assert!(bytes(&apng) == bytes(&whole.join("animation.png")));

    // Another animation into the folder is refused before anything is drawn.
    let e = refused(&[
        "shafts",
        show,
        "--animate",
        "--fps",
        "3",
        "--frames",
        "0..2",
        "-o",
        c,
    ]);
    assert!(e.contains("holds the frames of another animation"), "{e}");
    let e = refused(&with(&base, &["--frames", "10..16", "-o", c]));
    assert!(
        e.contains("--frames 10..16") && e.contains("0 to 14"),
        "{e}"
    );
    // Cue times the scene allows, at a rate --fps allows, past a million frames (the
    // names' six digits): refused before anything is drawn, naming the remedies.
    let late = dir.join("late");
    let e = refused(&[
        "shafts",
        show,
        "--animate",
        "--fps",
        "240",
        "--set",
        "cue[2].time_s=1000000",
        "-o",
        late.to_str().unwrap(),
    ]);
    assert!(
        e.contains("--fps 240") && e.contains("at most 1000000") && e.contains("time_s"),
        "{e}"
    );
    assert!(!late.exists());
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn clouds_and_skies_in_chunks_assemble_from_several_folders() {
    let dir = scratch("chunks-clouds");
    let folder = |name: &str| dir.join(name).to_str().unwrap().to_string();
    // The wind: particles carried a step a frame from the first.
    let clouds = |extra: &[&str], out: &str| {
        let mut args = vec!["clouds", "--generate", "cumulus", "--animate", "wind"];
        args.extend(["--frame-count", "4"]);
        args.extend(SMALL_CLOUD);
        args.extend(extra);
        args.extend(["-o", out]);
        ok(&args);
    };
    let (whole, a, b) = (folder("whole"), folder("a"), folder("b"));
    clouds(&[], &whole);
    clouds(&["--frames", "2..4"], &b);
    clouds(&["--frames", "0..2"], &a);
    same_frames(Path::new(&whole), Path::new(&a), 0..2);
    same_frames(Path::new(&whole), Path::new(&b), 2..4);
    let apng = dir.join("wind.png");
    ok(&["assemble", &a, &b, "-o", apng.to_str().unwrap()]);
    assert!(bytes(&apng) == bytes(&Path::new(&whole).join("animation.png")));
    let e = refused(&["assemble", &b, "-o", apng.to_str().unwrap()]);
    assert!(e.contains("frame 0 (frame_000000.png) is missing"), "{e}");

    // The sky from a table, as linear EXR frames: the animated PNG is the same.
    let table = tiny_table(&dir);
    let sky = |extra: &[&str], out: &str| {
        let mut args = vec!["sky", "--table", table.to_str().unwrap()];
        args.extend(["--animate", "sun", "--frame-count", "5"]);
        args.extend(["--width", "48", "--height", "32"]);
        args.extend(extra);
        args.extend(["-o", out]);
        ok(&args);
    };
    let (whole, exr) = (folder("sky"), folder("exr"));
    sky(&[], &whole);
    sky(&["--frames", "0..5", "--frame-format", "exr"], &exr);
    assert!(Path::new(&exr).join("frame_000004.exr").exists());
    let apng = dir.join("sky.png");
    ok(&["assemble", &exr, "-o", apng.to_str().unwrap()]);
    assert!(bytes(&apng) == bytes(&Path::new(&whole).join("animation.png")));
    // PNG frames into a folder of EXR frames: refused.
    let o = atmo(&[
        "sky",
        "--table",
        table.to_str().unwrap(),
        "--animate",
        "sun",
        "--frame-count",
        "5",
        "--width",
        "48",
        "--height",
        "32",
        "--frame",
        "1",
        "-o",
        &exr,
    ]);
    assert_eq!(o.status.code(), Some(2));
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn a_table_in_parts_merges_to_the_whole_run_byte_for_byte() {
    let dir = scratch("chunks-table");
    let whole = tiny_table(&dir);
    let parts = dir.join("parts");
    let p = parts.to_str().unwrap();
    // tiny_table's settings, in 4 parts of its 18 maps.
    let part = |k: &str| {
        let mut args = vec!["precompute", "sky", "--part", k, "-o", p];
        args.extend(TINY_TABLE);
        ok(&args)
    };
    for k in ["3/4", "1/4", "4/4"] {
        part(k);
    }
    let merged = dir.join("merged.atmo-sky");
    let m = merged.to_str().unwrap();
    let e = refused(&["precompute", "sky", "--merge", p, "-o", m]);
    assert!(e.contains("parts 2 of 4 are missing"), "{e}");
    assert!(!merged.exists());
    part("2/4");
    // A part that is there is kept (a requeued task resumes).
    assert!(part("2/4").contains("kept"));
    ok(&["precompute", "sky", "--merge", p, "-o", m]);
    assert!(bytes(&merged) == bytes(&whole), "the merged table differs");
    let e = refused(&["precompute", "sky", "--part", "5/4", "-o", p]);
    assert!(e.contains("K runs from 1 to N"), "{e}");
    std::fs::remove_dir_all(dir).unwrap();
}

/// A frame or manifest that claims pictures no animation has is refused naming it,
/// before the pixels are allocated: a 150-byte PNG claiming 100,000^2 pixels asked
/// for 30 GB and aborted (exit 134), and so did a manifest saying its frames are that
/// size.
#[test]
fn frames_and_manifests_past_the_pictures_limits_are_refused() {
    let dir = scratch("chunks-hostile");
    let show = small_show(&dir);
    let folder = dir.join("frames");
    let f = folder.to_str().unwrap();
    ok(&[
        "shafts",
        show.to_str().unwrap(),
        "--animate",
        "--fps",
        "2",
        "--frames",
        "0..2",
        "-o",
        f,
    ]);
    // Two frames of the 15: the manifest says 15; keep the two as the whole.
    let manifest = folder.join("atmo-frames.json");
    let text = std::fs::read_to_string(&manifest)
        .unwrap()
        .replace("\"frames\": 15", "\"frames\": 2");
    std::fs::write(&manifest, &text).unwrap();
    let out = dir.join("show.apng");
    ok(&["assemble", f, "-o", out.to_str().unwrap()]);
    // A frame whose header claims 100,000^2 pixels.
    let chunk = |t: &[u8], d: &[u8]| {
        let mut c = (d.len() as u32).to_be_bytes().to_vec();
        c.extend(t);
        c.extend(d);
        c.extend(crc32(&[t, d].concat()).to_be_bytes());
        c
    };
    let mut ihdr = 100_000u32.to_be_bytes().repeat(2);
    ihdr.extend([8, 2, 0, 0, 0]);
    // Its data one zero byte, stored (zlib without compression).
    let idat = [0x78, 1, 1, 1, 0, 0xfe, 0xff, 0, 0, 1, 0, 1];
    let png = [
        &b"\x89PNG\r\n\x1a\n"[..],
        &chunk(b"IHDR", &ihdr),
        &chunk(b"IDAT", &idat),
        &chunk(b"IEND", &[]),
    ]
    .concat();
    std::fs::write(folder.join("frame_000001.png"), &png).unwrap();
    let stderr = refused(&["assemble", f, "-o", out.to_str().unwrap()]);
    assert!(
        stderr.contains("frame_000001.png") && stderr.contains("100000 x 100000"),
        "{stderr}"
    );
    // A manifest whose frames are that size.
    let huge = text.replace("\"width\": 72", "\"width\": 100000");
    assert_ne!(huge, text);
    std::fs::write(&manifest, huge).unwrap();
    let stderr = refused(&["assemble", f, "-o", out.to_str().unwrap()]);
    assert!(
        stderr.contains("atmo-frames.json") && stderr.contains("width"),
        "{stderr}"
    );
    std::fs::remove_dir_all(dir).unwrap();
}

/// The CRC-32 of PNG chunks (ISO 3309), for the test's own PNG.
fn crc32(bytes: &[u8]) -> u32 {
    let mut crc = !0u32;
    for &b in bytes {
        crc ^= b as u32;
        for _ in 0..8 {
            crc = if crc & 1 == 1 {
                (crc >> 1) ^ 0xEDB8_8320
            } else {
                crc >> 1
            };
        }
    }
    !crc
}
