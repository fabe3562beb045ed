//! `atmo bench`: each method timed against its baseline in the same run: medians after
//! a warm-up, ratios, and the error between them, one JSON object a case with
//! `--json`. The files under docs/bench/ are its output, and `atmo bench page` makes
//! docs/benchmarks.md from them ([`page`]).

mod child;
mod clouds;
mod farm;
mod memory;
pub mod page;
mod shafts;
mod sky;
mod sky_table;
mod view;

use std::io::Write as _;
use std::time::Instant;

use anyhow::Result;
use atmo_gpu::{Gpu, GpuError};
use clap::{Args, ValueEnum};
use serde_json::{json, Value};

use crate::backend::{backend_parser, gpu_error, Backend, BackendArgs};

#[derive(Args)]
pub struct BenchArgs {
    /// What to time.
    #[arg(value_enum)]
    area: Area,
    /// Fewer repetitions and reference directions: a minute instead of several.
    #[arg(long)]
    quick: bool,
    /// One JSON object per case on its own line, instead of a table.
    #[arg(long)]
    json: bool,
    /// shafts, view and farm: the folder holding spotlight-sphere.toml, stage.toml and
    /// show.toml.
    #[arg(long, default_value = "scenes")]
    scenes: std::path::PathBuf,
    /// shafts: a folder to write the plane sweep into as shafts-sweep.csv and .svg
    /// (without it the sweep is only printed).
    #[arg(long, value_name = "FOLDER")]
    sweep_dir: Option<std::path::PathBuf>,
    /// cpu: each method against its baseline; gpu: each GPU pipeline beside the same
    /// method on the CPU.
    #[arg(long, value_parser = backend_parser(), default_value_t = Backend::Cpu)]
    backend: Backend,
    /// With --backend gpu: the adapter (part of its name, or a backend).
    #[arg(long, value_name = "NAME")]
    adapter: Option<String>,
    /// page: the folder of `atmo bench AREA --json` files and machine.txt.
    #[arg(long, value_name = "FOLDER", default_value = "docs/bench")]
    from: std::path::PathBuf,
    /// page: the Markdown file to write (docs/benchmarks.md); without it, standard output.
    #[arg(short, long, value_name = "FILE.md")]
    output: Option<std::path::PathBuf>,
}

#[derive(Clone, Copy, ValueEnum)]
enum Area {
    /// The skylight map by sampling shells against the reference integrator.
    Sky,
    /// The SVD skylight table: precompute, size, error against the shell method, and
    /// drawing a map and a 1920 x 1080 frame from it.
    SkyTable,
    /// Shafts of light: sample planes against ray marching on the paper's Fig. 6 scene,
    /// the five-light stage, and the sweep of plane and sub-plane counts.
    Shafts,
    /// Clouds: the intensity buffer's light pass against the Harris baseline, its error,
    /// and a frame.
    Clouds,
    /// The window of `atmo view`: frame times over scripted runs at 1280 x 720 (a
    /// climb with the sun setting from a table; the sun setting by the shell method;
    /// the stage orbited; one of its lights re-aimed; the sun round a cloud) beside the
    /// still's draw of the same frame; needs a display (xvfb-run).
    View,
    /// Render farms: a show in chunks and a sky table in parts, each piece a process,
    /// against one process of the whole (wall and CPU time, bytes compared), and the
    /// per-frame and per-map costs a farm is projected from (docs/farm.md).
    Farm,
    /// Whether --memory-limit holds: for each input a knob sizes (a picture, shadow
    /// maps, a cloud's particles and buffer, compare's pictures), the largest value
    /// accepted under 64 MiB found by bisection, each run a process measured from
    /// outside, its peak beyond the command's fixed footprint against the budget.
    Memory,
    /// Times nothing: makes docs/benchmarks.md from the JSON files under --from.
    Page,
}

pub fn run(args: BenchArgs) -> Result<()> {
    if let Area::Page = args.area {
        let page = page::render(&args.from)?;
        return match &args.output {
            Some(path) => Ok(atmo::files::write_atomically(path, |w| {
                w.write_all(page.as_bytes())
                    .map_err(atmo::Error::io_at(path))
            })?),
            None => {
                crate::streams::out(format_args!("{page}"));
                Ok(())
            }
        };
    }
    if let Area::View = args.area {
        let backends: &[&str] = match args.backend {
            Backend::Cpu => &["cpu"],
            Backend::Gpu => &["gpu"],
            Backend::Auto => &["cpu", "gpu"],
        };
        return view::run(args.quick, args.json, backends, &args.scenes);
    }
    if let Area::Memory = args.area {
        return memory::run(args.quick, args.json, &args.scenes);
    }
    if let Area::Farm = args.area {
        if args.backend != Backend::Cpu {
            anyhow::bail!("--backend: `atmo bench farm` times pieces on the CPU; allowed: cpu");
        }
        return farm::cpu(args.quick, args.json, &args.scenes);
    }
    if args.backend != Backend::Cpu {
        let device = BackendArgs {
            backend: Backend::Gpu,
            adapter: args.adapter.clone(),
        };
        let gpu = device
            .open()?
            .expect("--backend gpu opens a device or fails");
        return match args.area {
            Area::Sky => sky::gpu(&gpu, args.quick, args.json),
            Area::SkyTable => sky_table::gpu(&gpu, args.quick, args.json),
            Area::Shafts => shafts::gpu(&gpu, args.quick, args.json, &args.scenes),
            Area::Clouds => clouds::gpu(&gpu, args.quick, args.json),
            Area::View | Area::Farm | Area::Memory | Area::Page => unreachable!("handled above"),
        };
    }
    match args.area {
        Area::Sky => sky::cpu(args.quick, args.json),
        Area::SkyTable => sky_table::cpu(args.quick, args.json),
        Area::Clouds => clouds::cpu(args.quick, args.json),
        Area::View | Area::Farm | Area::Memory | Area::Page => unreachable!("handled above"),
        Area::Shafts => {
            if let Some(dir) = &args.sweep_dir {
                atmo::files::check_folder(&dir.join("shafts-sweep.csv"))?;
            }
            shafts::cpu(
                args.quick,
                args.json,
                &args.scenes,
                args.sweep_dir.as_deref(),
            )
        }
    }
}

/// The median of `v` (the upper one of an even count).
pub fn median(v: Vec<f64>) -> f64 {
    percentile(v, 0.5)
}

/// The value of `v` at fraction `q` of its sorted order (the nearest rank, halves up).
pub fn percentile(mut v: Vec<f64>, q: f64) -> f64 {
    v.sort_by(|a, b| a.total_cmp(b));
    v[((v.len() - 1) as f64 * q).round() as usize]
}

/// Milliseconds taken by `f`.
pub fn time_ms(f: impl FnOnce()) -> f64 {
    let start = Instant::now();
    f();
    start.elapsed().as_secs_f64() * 1e3
}

/// A case and its baseline timed in alternation ([`alternated`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Alternated {
    /// The medians of the case's and the baseline's times, ms.
    pub case_ms: f64,
    pub baseline_ms: f64,
    /// The median of the rounds' `baseline / case`.
    pub ratio: f64,
}

/// Times `case` and `baseline` one after the other, `rounds` times: their medians and
/// the median of each round's ratio. A round's two times see the same host, so on a
/// shared one whose speed drifts within a run the ratio holds where two medians taken
/// minutes apart do not (the stage against the ray marcher timed a minute apart gave
/// 0.28 and 0.37 of its time in two runs seven minutes apart).
pub fn alternated(rounds: usize, case: impl FnMut(), baseline: impl FnMut()) -> Alternated {
    alternated_by(rounds, case, baseline, |f| time_ms(f))
}

/// [`alternated`] with the clock `time` (ms taken by the function it is given).
fn alternated_by(
    rounds: usize,
    mut case: impl FnMut(),
    mut baseline: impl FnMut(),
    mut time: impl FnMut(&mut dyn FnMut()) -> f64,
) -> Alternated {
    let (mut cases, mut baselines, mut ratios) = (Vec::new(), Vec::new(), Vec::new());
    for _ in 0..rounds.max(1) {
        let (c, b) = (time(&mut case), time(&mut baseline));
        cases.push(c);
        baselines.push(b);
        ratios.push(b / c);
    }
    Alternated {
        case_ms: median(cases),
        baseline_ms: median(baselines),
        ratio: median(ratios),
    }
}

/// Medians of `runs` GPU runs after a warm-up: (wall ms, GPU ms if timed) and the last
/// result.
pub(crate) fn time_gpu<T>(
    runs: usize,
    mut run: impl FnMut() -> Result<(T, Option<f64>), GpuError>,
) -> Result<(f64, Option<f64>, T)> {
    let (mut last, _) = run().map_err(gpu_error)?;
    let (mut walls, mut gpus) = (Vec::new(), Vec::new());
    for _ in 0..runs {
        let mut result = Ok(());
        walls.push(time_ms(|| match run() {
            Ok((value, gpu_ms)) => {
                last = value;
                gpus.extend(gpu_ms);
            }
            Err(e) => result = Err(e),
        }));
        result.map_err(gpu_error)?;
    }
    let gpu_ms = (!gpus.is_empty()).then(|| median(gpus));
    Ok((median(walls), gpu_ms, last))
}

/// One case: the GPU's times beside the CPU's, and how far the pictures are apart.
pub(crate) struct Case<'a> {
    name: &'a str,
    params: Value,
    wall_ms: f64,
    gpu_ms: Option<f64>,
    cpu_ms: f64,
    /// How far the case's result is from the baseline's: [`levels`] for pictures.
    error: Option<Value>,
}

/// Two pictures' difference in display levels, as a case's error.
pub(crate) fn levels(e: atmo::image::LevelErrors) -> Value {
    json!({"rms_levels": e.rms, "max_levels": e.max})
}

pub(crate) fn report(json: bool, gpu: &Gpu, case: Case) {
    let device = json!({"adapter": gpu.describe(), "software": gpu.is_software()});
    let error = case.error;
    let said = error
        .as_ref()
        .and_then(Value::as_object)
        .map_or(String::new(), |e| {
            let pairs: Vec<String> = e.iter().map(|(k, v)| format!("{k} {v:.4}")).collect();
            format!("   error {}", pairs.join(" "))
        });
    emit(
        json,
        json!({
            "bench": case.name, "params": case.params, "device": device,
            "median_ms": case.wall_ms, "gpu_ms": case.gpu_ms,
            "baseline": "the same method on the CPU", "baseline_median_ms": case.cpu_ms,
            "ratio": case.cpu_ms / case.wall_ms, "error": error,
        }),
        format!(
            "{:<24} GPU {:>9.2} ms (GPU time {})   CPU {:>8.2} ms   ratio {:>6.3}{}",
            case.name,
            case.wall_ms,
            case.gpu_ms
                .map_or("not measured".into(), |ms| format!("{ms:.2} ms")),
            case.cpu_ms,
            case.cpu_ms / case.wall_ms,
            said
        ),
    );
}

/// Prints `line` as JSON with --json, else `text`. The JSON line gets `peak_rss_mb`
/// unless it has its own (a case measured in other processes): the process's peak
/// resident memory since the previous line (the peak starts again after each), MiB, or
/// null where the system does not say.
pub fn emit(json: bool, mut line: Value, text: String) {
    if json {
        let peak = atmo::budget::peak_rss_bytes()
            .map(|b| (b as f64 / (1u64 << 20) as f64 * 10.0).round() / 10.0);
        if let Value::Object(fields) = &mut line {
            fields.entry("peak_rss_mb").or_insert(json!(peak));
        }
        outln!("{line}");
    } else {
        outln!("{text}");
    }
    atmo::budget::reset_peak_rss();
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn alternated_rounds_pair_the_case_with_its_baseline() {
        // A clock that reads out given times: the host slows down in the second round
        // and is in between in the third. Each round's ratio is 3, 3 and 4 (median 3),
        // where the two medians, 20 and 80 ms, would say 4.
        let times = [10.0, 30.0, 40.0, 120.0, 20.0, 80.0];
        let order = std::cell::RefCell::new(Vec::new());
        let mut next = 0;
        let timing = alternated_by(
            3,
            || order.borrow_mut().push("case"),
            || order.borrow_mut().push("baseline"),
            |f| {
                f();
                next += 1;
                times[next - 1]
            },
        );
        assert_eq!(timing.ratio, 3.0);
        assert_eq!((timing.case_ms, timing.baseline_ms), (20.0, 80.0));
        assert_eq!(order.into_inner(), ["case", "baseline"].repeat(3));
    }
}
