//! `atmo bench farm`: what splitting work for a render farm costs (docs/farm.md). A
//! show drawn in chunks and assembled, and a sky table computed in parts and merged,
//! each piece a process of its own (this executable), run one after the other, against
//! one process of the whole in the same run: wall time, CPU time of every thread, the
//! largest process's memory, and whether the outputs are the same bytes. Then the
//! per-frame and per-map costs a farm's time is projected from.

use std::ffi::OsString;
use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};
use serde_json::json;

use super::child::{self, os, tempfile_in_temp, Cost};
use super::emit;

/// Runs this executable with `args`, which must succeed (its messages are the error
/// if not), and what it took.
fn atmo(args: &[OsString]) -> Result<Cost> {
    let run = child::run(args)?;
    if run.code != Some(0) {
        let shown: Vec<_> = args.iter().map(|a| a.to_string_lossy()).collect();
        bail!("atmo {} failed: {}", shown.join(" "), run.messages.trim());
    }
    Ok(run.cost)
}

/// Whether the two files hold the same bytes.
fn same_bytes(a: &Path, b: &Path) -> Result<bool> {
    let read = |p: &Path| std::fs::read(p).with_context(|| p.display().to_string());
    Ok(read(a)? == read(b)?)
}

/// The frames of a folder of `atmo --animate` output, sorted.
fn frames(folder: &Path) -> Result<Vec<PathBuf>> {
    let mut frames: Vec<PathBuf> = std::fs::read_dir(folder)?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            p.file_name()
                .is_some_and(|n| n.to_string_lossy().starts_with("frame_"))
        })
        .collect();
    frames.sort();
    Ok(frames)
}

/// The JSON fields of a split against one process.
fn split_fields(pieces: Cost, whole: Cost) -> serde_json::Value {
    json!({
        "median_ms": pieces.wall_ms, "baseline_median_ms": whole.wall_ms,
        "ratio": whole.wall_ms / pieces.wall_ms,
        "cpu_ms": pieces.cpu_ms, "baseline_cpu_ms": whole.cpu_ms,
        "cpu_ratio": whole.cpu_ms / pieces.cpu_ms,
        "peak_rss_mb": pieces.peak_mb, "baseline_peak_rss_mb": whole.peak_mb,
        "runs": 1,
    })
}

fn merge(mut a: serde_json::Value, b: serde_json::Value) -> serde_json::Value {
    if let (Some(a), serde_json::Value::Object(b)) = (a.as_object_mut(), b) {
        a.extend(b);
    }
    a
}

pub fn cpu(quick: bool, json_out: bool, scenes: &Path) -> Result<()> {
    let work = tempfile_in_temp("atmo-bench-farm");
    std::fs::create_dir_all(&work).context("the bench's folder")?;
    let result = run(quick, json_out, scenes, &work);
    let _ = std::fs::remove_dir_all(&work);
    result
}

fn run(quick: bool, json_out: bool, scenes: &Path, work: &Path) -> Result<()> {
    let scene = scenes.join("show.toml");
    let scene = scene.as_path();
    // The show at its own 720 x 480, 24 frames a second (169 frames); --quick: a
    // quarter as wide and high, at 7 (50 frames).
    let (size, fps) = if quick {
        ((180, 120), "7")
    } else {
        ((720, 480), "24")
    };
    let show = |extra: &[&str], out: &Path| draw_show(scene, size, fps, extra, out);
    let whole_dir = work.join("whole");
    let whole = show(&[], &whole_dir)?;
    let frame_count = frames(&whole_dir)?.len();
    for chunks in [4, 16] {
        let dir = work.join(format!("chunks-{chunks}"));
        let mut pieces = Cost::default();
        for k in 1..=chunks {
            pieces = pieces.then(show(&["--chunk", &format!("{k}/{chunks}")], &dir)?);
        }
        let output = work.join(format!("chunks-{chunks}.png"));
        let assemble = atmo(&os(&[&"assemble", &dir, &"-o", &output]))?;
        let identical = same_bytes(&whole_dir.join("animation.png"), &output)?;
        let all = pieces.then(assemble);
        emit(
            json_out,
            merge(
                json!({
                    "bench": "farm.show",
                    "params": {"scene": "show.toml", "width": size.0, "height": size.1,
                               "fps": fps, "frames": frame_count, "chunks": chunks,
                               "threads": rayon::current_num_threads()},
                    "baseline": "one process: the frames and animation.png",
                    "assemble_ms": assemble.wall_ms, "identical": identical,
                }),
                split_fields(all, whole),
            ),
            format!(
                "farm.show        {chunks:>2} chunks + assemble {:>9.0} ms wall {:>9.0} ms CPU   one process {:>9.0} ms wall {:>9.0} ms CPU   ratio {:.3} (CPU {:.3})   assemble {:.0} ms   identical: {identical}",
                all.wall_ms, all.cpu_ms, whole.wall_ms, whole.cpu_ms,
                whole.wall_ms / all.wall_ms, whole.cpu_ms / all.cpu_ms, assemble.wall_ms
            ),
        );
        if !identical {
            bail!("farm.show: {chunks} chunks assembled differ from one process's animation");
        }
    }
    frame_cost(quick, json_out, scene, work)?;
    table(quick, json_out, work)
}

/// Draws the show `scene` (an animation) at `size` and `fps` on the CPU, with `extra`
/// flags, into `out`.
fn draw_show(
    scene: &Path,
    size: (u32, u32),
    fps: &str,
    extra: &[&str],
    out: &Path,
) -> Result<Cost> {
    let (width, height) = (
        format!("camera.width={}", size.0),
        format!("camera.height={}", size.1),
    );
    let mut args = os(&[
        &"shafts",
        &scene,
        &"--animate",
        &"--fps",
        &fps,
        &"--backend",
        &"cpu",
        &"--set",
        &width,
        &"--set",
        &height,
    ]);
    args.extend(extra.iter().map(OsString::from));
    args.extend(os(&[&"-o", &out]));
    atmo(&args)
}

/// The cost of a frame of the show at 4K (--quick: 640 x 360), from a run of frames in
/// its busiest second, as a chunk of a farm draws them: what a long show is projected
/// from.
fn frame_cost(quick: bool, json_out: bool, scene: &Path, work: &Path) -> Result<()> {
    let size = if quick { (640, 360) } else { (3840, 2160) };
    let count = 6;
    let frames = format!("60..{}", 60 + count);
    let cost = draw_show(
        scene,
        size,
        "30",
        &["--frames", &frames],
        &work.join("frame-cost"),
    )?;
    let per_frame = |ms: f64| ms / count as f64;
    emit(
        json_out,
        json!({
            "bench": "farm.frame",
            "params": {"scene": "show.toml", "width": size.0, "height": size.1, "fps": 30,
                       "frames": frames, "threads": rayon::current_num_threads()},
            "median_ms": per_frame(cost.wall_ms), "cpu_ms": per_frame(cost.cpu_ms),
            "unit": "a frame, its process's start and files included",
            "peak_rss_mb": cost.peak_mb, "runs": 1,
        }),
        format!(
            "farm.frame       {} x {}: {:.0} ms wall, {:.0} ms CPU a frame",
            size.0,
            size.1,
            per_frame(cost.wall_ms),
            per_frame(cost.cpu_ms)
        ),
    );
    Ok(())
}

/// The sky table (the default every-order one; --quick: a small one) computed in 8
/// parts and merged against one precompute, and a part of one map: the light at the
/// shells each part computes again.
fn table(quick: bool, json_out: bool, work: &Path) -> Result<()> {
    let settings: &[&str] = if quick {
        &[
            "--directions",
            "16",
            "--sun-steps",
            "16",
            "--altitude-steps",
            "4",
            "--shells",
            "16",
        ]
    } else {
        &[]
    };
    let maps = if quick { 16 * 4 } else { 128 * 32 };
    let precompute = |extra: &[&str], out: &Path| {
        let mut args = os(&[&"precompute", &"sky"]);
        args.extend(settings.iter().chain(extra).map(OsString::from));
        args.extend(os(&[&"-o", &out]));
        atmo(&args)
    };
    let whole_file = work.join("whole.atmo-sky");
    let whole = precompute(&[], &whole_file)?;
    let parts = 8;
    let dir = work.join("parts");
    let mut pieces = Cost::default();
    for k in 1..=parts {
        pieces = pieces.then(precompute(&["--part", &format!("{k}/{parts}")], &dir)?);
    }
    let merged_file = work.join("merged.atmo-sky");
    let merged = precompute(&["--merge", &dir.to_string_lossy()], &merged_file)?;
    let one_map = precompute(&["--part", &format!("1/{maps}")], &work.join("one-map"))?;
    let identical = same_bytes(&whole_file, &merged_file)?;
    let all = pieces.then(merged);
    emit(
        json_out,
        merge(
            json!({
                "bench": "farm.table",
                "params": {"settings": if quick { settings.join(" ") } else { "the defaults".into() },
                           "maps": maps, "parts": parts, "threads": rayon::current_num_threads()},
                "baseline": "one precompute",
                "merge_ms": merged.wall_ms, "merge_cpu_ms": merged.cpu_ms,
                "merge_peak_rss_mb": merged.peak_mb,
                "one_map_part_ms": one_map.wall_ms, "identical": identical,
            }),
            split_fields(all, whole),
        ),
        format!(
            "farm.table        {parts} parts + merge {:>9.0} ms wall {:>9.0} ms CPU   one process {:>9.0} ms wall {:>9.0} ms CPU   ratio {:.3} (CPU {:.3})   merge {:.0} ms   a part of one map {:.0} ms   identical: {identical}",
            all.wall_ms, all.cpu_ms, whole.wall_ms, whole.cpu_ms,
            whole.wall_ms / all.wall_ms, whole.cpu_ms / all.cpu_ms, merged.wall_ms, one_map.wall_ms
        ),
    );
    if !identical {
        bail!("farm.table: the merged parts differ from one precompute's table");
    }
    Ok(())
}
