//! `atmo bench memory`: whether `--memory-limit` holds. For each input whose size a
//! knob sets (a picture's width, a shadow map's side, a cloud's particles or buffer),
//! the largest value a run accepts under a 64 MiB budget is found by bisection, each
//! run a process of its own measured from outside (`wait4`): its peak resident size
//! beyond the same command's fixed footprint (the smallest value's run: the program,
//! its libraries, a GPU driver where one is probed, the sizes that do not depend on
//! the knob) must stay within 25 % over the budget. The first value refused shows the
//! refusal comes before the memory is taken.

use std::ffi::OsString;
use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};
use serde_json::json;

use super::child::{self, os, tempfile_in_temp, Cost};
use super::emit;

/// The budget every case runs under, MiB.
const BUDGET_MB: f64 = 64.0;

/// How far past the budget a run may reach beyond its footprint: the 25 %.
const TOLERANCE: f64 = 1.25;

/// An input whose size one whole-number knob sets.
struct Family<'a> {
    name: &'a str,
    /// What the knob is, for the reader.
    knob: &'a str,
    /// The smallest value (the footprint's run) and one surely over the budget.
    range: (u64, u64),
    /// The command line for a value of the knob (without `--memory-limit`).
    args: Box<dyn Fn(u64) -> Vec<OsString> + 'a>,
    /// Run before each value, with a generous budget: inputs the case reads.
    setup: Option<Box<dyn Fn(u64) -> Result<()> + 'a>>,
}

/// How a run under the budget ended.
enum Outcome {
    Accepted(Cost),
    Refused(Cost),
}

pub fn run(quick: bool, json_out: bool, scenes: &Path) -> Result<()> {
    let work = tempfile_in_temp("atmo-bench-memory");
    std::fs::create_dir_all(&work).context("the bench's folder")?;
    let result = families(scenes, &work)
        .iter()
        .filter(|f| !quick || !f.name.ends_with("compare"))
        .map(|f| family(f, quick, json_out))
        .collect::<Result<Vec<f64>>>();
    let _ = std::fs::remove_dir_all(&work);
    let worst = result?.into_iter().fold(0.0, f64::max);
    if worst > TOLERANCE {
        bail!("a run reached {worst:.2} times the budget beyond its footprint, past {TOLERANCE}");
    }
    Ok(())
}

/// The inputs measured: the sky on the CPU and the GPU, the stage's picture and shadow
/// maps, a cloud's particles and buffer, `compare`'s two pictures.
fn families<'a>(scenes: &'a Path, work: &'a Path) -> Vec<Family<'a>> {
    let stage = scenes.join("stage.toml");
    let sky = |backend: &'static str, out: PathBuf| {
        move |w: u64| {
            os(&[
                &"sky",
                &"--shells",
                &"8",
                &"--width",
                &w.to_string(),
                &"--height",
                &(w / 2).max(1).to_string(),
                &"--backend",
                &backend,
                &"-o",
                &out,
            ])
        }
    };
    let stage_at = move |width: u64, map: u64| {
        os(&[
            &"shafts",
            &stage,
            &"--backend",
            &"cpu",
            &"--set",
            &format!("camera.width={width}"),
            &"--set",
            &format!("camera.height={}", (width * 2 / 3).max(1)),
            &"--shadow-map",
            &map.to_string(),
            &"-o",
            &work.join("stage.png"),
        ])
    };
    let cloud = |particles: u64, resolution: u64| {
        os(&[
            &"clouds",
            &"--generate",
            &"cumulus",
            &"--particles",
            &particles.to_string(),
            &"--resolution",
            &resolution.to_string(),
            &"--width",
            &"320",
            &"--height",
            &"180",
            &"--backend",
            &"cpu",
            &"-o",
            &work.join("cloud.png"),
        ])
    };
    let (a, b) = (work.join("a.exr"), work.join("b.exr"));
    let pictures = move |w: u64| -> Result<()> {
        for (out, elevation) in [(&a, "20"), (&b, "21")] {
            let args = os(&[
                &"sky",
                &"--shells",
                &"8",
                &"--sun-elevation",
                &elevation,
                &"--width",
                &w.to_string(),
                &"--height",
                &(w / 2).max(1).to_string(),
                &"--backend",
                &"cpu",
                &"-o",
                out,
            ]);
            let run = child::run(&args)?;
            if run.code != Some(0) {
                bail!(
                    "making the pictures `compare` reads: {}",
                    run.messages.trim()
                );
            }
        }
        Ok(())
    };
    let compared = [work.join("a.exr"), work.join("b.exr")];
    vec![
        Family {
            name: "memory.sky",
            knob: "width (height half of it), --shells 8, on the CPU",
            range: (16, 16384),
            args: Box::new(sky("cpu", work.join("sky.exr"))),
            setup: None,
        },
        Family {
            name: "memory.sky_gpu",
            knob: "width (height half of it), --shells 8, on the GPU",
            range: (16, 16384),
            args: Box::new(sky("gpu", work.join("sky-gpu.exr"))),
            setup: None,
        },
        Family {
            name: "memory.shafts",
            knob: "stage.toml's camera.width (height two thirds of it)",
            range: (16, 16384),
            args: Box::new({
                let stage_at = stage_at.clone();
                move |w| stage_at(w, 512)
            }),
            setup: None,
        },
        Family {
            name: "memory.shadow_maps",
            knob: "stage.toml's --shadow-map (5 lights), at 64 x 42",
            range: (16, 8192),
            args: Box::new(move |m| stage_at(64, m)),
            setup: None,
        },
        Family {
            name: "memory.cloud_particles",
            knob: "--particles of a cumulus, 64^3 buffer, 320 x 180",
            range: (100, 5_000_000),
            args: Box::new(move |n| cloud(n, 64)),
            setup: None,
        },
        Family {
            name: "memory.cloud_buffer",
            knob: "--resolution of the intensity buffer, 2000 particles, 320 x 180",
            range: (8, 2048),
            args: Box::new(move |r| cloud(2000, r)),
            setup: None,
        },
        Family {
            name: "memory.compare",
            knob: "the width of the two EXR pictures compared (height half of it)",
            range: (16, 4096),
            args: Box::new(move |_| os(&[&"compare", &compared[0], &compared[1]])),
            setup: Some(Box::new(pictures)),
        },
    ]
}

/// Runs `family` at its smallest value, then bisects for the largest value accepted
/// under the budget; prints the case and gives its ratio, (peak - footprint) / budget.
fn family(family: &Family, quick: bool, json_out: bool) -> Result<f64> {
    let (mut lo, mut hi) = family.range;
    let footprint = match measure(family, lo) {
        Ok(Outcome::Accepted(cost)) => cost,
        Ok(Outcome::Refused(_)) => bail!("{}: the smallest value {lo} is refused", family.name),
        Err(why) => {
            emit(
                json_out,
                json!({"bench": family.name, "skipped": format!("{why:#}")}),
                format!("{:<24} skipped: {why:#}", family.name),
            );
            return Ok(0.0);
        }
    };
    let (mut accepted, mut refused) = match measure(family, hi)? {
        Outcome::Refused(cost) => (footprint, cost),
        Outcome::Accepted(_) => bail!("{}: {hi} is accepted under {BUDGET_MB} MiB", family.name),
    };
    let step = if quick { 1.25 } else { 1.05 };
    let mut runs = 2;
    while hi as f64 > lo as f64 * step && hi > lo + 1 {
        let mid = ((lo as f64 * hi as f64).sqrt().round() as u64).clamp(lo + 1, hi - 1);
        runs += 1;
        match measure(family, mid)? {
            Outcome::Accepted(cost) => (lo, accepted) = (mid, cost),
            Outcome::Refused(cost) => (hi, refused) = (mid, cost),
        }
    }
    let beyond = accepted.peak_mb - footprint.peak_mb;
    let ratio = beyond / BUDGET_MB;
    emit(
        json_out,
        json!({
            "bench": family.name,
            "params": {"knob": family.knob, "memory_limit_mb": BUDGET_MB,
                       "smallest": family.range.0, "largest_accepted": lo, "refused_at": hi},
            "peak_rss_mb": accepted.peak_mb, "footprint_mb": footprint.peak_mb,
            "beyond_footprint_mb": beyond, "ratio_to_budget": ratio,
            "refused_peak_rss_mb": refused.peak_mb, "median_ms": accepted.wall_ms,
            "runs": runs,
        }),
        format!(
            "{:<24} largest accepted {lo:>8} (refused at {hi:>8}): peak {:>7.1} MiB, footprint {:>6.1}, beyond it {:>6.1} = {ratio:.2} x the budget; refused run's peak {:.1} MiB",
            family.name, accepted.peak_mb, footprint.peak_mb, beyond, refused.peak_mb
        ),
    );
    Ok(ratio)
}

/// One run of `family` at `value` under the budget: accepted or refused for the
/// budget; an error, with the run's messages, when it failed otherwise.
fn measure(family: &Family, value: u64) -> Result<Outcome> {
    if let Some(setup) = &family.setup {
        setup(value)?;
    }
    let mut args = (family.args)(value);
    args.extend(os(&[&"--memory-limit", &format!("{BUDGET_MB}M")]));
    let run = child::run(&args)?;
    match run.code {
        Some(0) => Ok(Outcome::Accepted(run.cost)),
        Some(2) if run.messages.contains("memory budget") => Ok(Outcome::Refused(run.cost)),
        _ => bail!("{} at {value}: {}", family.name, run.messages.trim()),
    }
}
