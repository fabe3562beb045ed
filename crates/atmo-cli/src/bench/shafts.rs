//! `atmo bench shafts`: the sample-plane method (shafts 4) against the paper's
//! conventional ray marcher (shafts 5.1) in the same run, its error against the
//! converged reference in 8-bit levels, the five-light stage, and the sweep of plane and
//! sub-plane counts (the paper's Figs. 4 and 5) as CSV and SVG.

use std::fmt::Write as _;
use std::path::Path;

use anyhow::Result;
use atmo::files::write_atomically;
use atmo::image::Frame;
use atmo::reference::shafts::RayMarcher;
use atmo::shafts::{SamplePlanes, Scene};
use atmo_gpu::shafts::{GpuShafts, ShaftsMethod};
use atmo_gpu::{Gpu, Rendered};
use serde_json::json;

use super::{alternated, emit, levels, median, report, time_gpu, time_ms, Alternated, Case};
use crate::backend::gpu_error;

/// Median time of `runs` renders by the plane method after one warm-up, and the last
/// frame.
fn time_planes(scene: &Scene, runs: usize) -> (f64, Frame) {
    let (ms, frame, _) = time_planes_counted(scene, runs);
    (ms, frame)
}

/// [`time_planes`], and what became of the last frame's pixels (the share of them
/// whose scattered light was computed).
fn time_planes_counted(scene: &Scene, runs: usize) -> (f64, Frame, f64) {
    let mut last = SamplePlanes::new(scene).render_counted();
    let ms = median(
        (0..runs)
            .map(|_| time_ms(|| last = SamplePlanes::new(scene).render_counted()))
            .collect(),
    );
    (ms, last.0, last.1.computed_share())
}

/// [`time_planes_counted`] with each render timed in turn with `baseline` (after one
/// warm-up): the timings, the last frame and its share of computed pixels.
fn time_planes_against(
    scene: &Scene,
    runs: usize,
    baseline: impl FnMut(),
) -> (Alternated, Frame, f64) {
    let mut last = SamplePlanes::new(scene).render_counted();
    let timing = alternated(
        runs,
        || last = SamplePlanes::new(scene).render_counted(),
        baseline,
    );
    (timing, last.0, last.1.computed_share())
}

pub fn cpu(quick: bool, json: bool, scenes: &Path, sweep: Option<&Path>) -> Result<()> {
    let fig6 = Scene::from_file(&scenes.join("spotlight-sphere.toml"))?;
    let stage = Scene::from_file(&scenes.join("stage.toml"))?;
    let runs = if quick { 5 } else { 21 };
    let threads = rayon::current_num_threads();

    // The converged reference, and that doubling its samples changes it by < 0.1 % RMS.
    let reference = RayMarcher::CONVERGED.render(&fig6);
    let doubling = if quick {
        None
    } else {
        let doubled = RayMarcher {
            samples: 2 * RayMarcher::CONVERGED.samples,
            ..RayMarcher::CONVERGED
        }
        .render(&fig6);
        Some(relative_rms(&reference, &doubled))
    };

    // The scene as it loads: the scattered light computed where the picture needs it
    // (`render.adaptive`), timed in alternation with the paper's ray marcher (each after
    // a warm-up); and the paper's method, every pixel computed.
    // The ray marcher is deterministic: its warm-up's frame is the one it draws each
    // round.
    let baseline = RayMarcher::baseline(&fig6);
    let baseline_frame = baseline.render(&fig6);
    let ray_march = || drop(baseline.render(&fig6));
    let (fig6_timing, frame, computed) = time_planes_against(&fig6, runs, ray_march);
    let (ms, baseline_ms) = (fig6_timing.case_ms, fig6_timing.baseline_ms);
    let (every_ms, every_frame) = time_planes(&every_pixel(&fig6), runs);
    let against_every = frame.level_errors(&every_frame, fig6.display)?;
    let error = frame.level_errors(&reference, fig6.display)?;
    let baseline_error = baseline_frame.level_errors(&reference, fig6.display)?;
    // Surface pixels (shadow edges among them) and haze pixels (the lamp's own among
    // them) apart.
    let (surface, haze) = atmo::shafts::surface::pixel_kinds(&fig6);
    let [surface_error, haze_error] = [&surface, &haze]
        .map(|pixels| frame.level_errors_over(&reference, fig6.display, pixels.iter().copied()));
    let kind = |pixels: &[usize], e: &atmo::image::LevelErrors| json!({"pixels": pixels.len(), "rms_levels": e.rms, "max_levels": e.max});
    let equal = equal_error(&fig6, &reference, error.rms, if quick { 1 } else { 3 })?;
    let equal_error_ratio = equal.map(|(_, equal_ms, _)| equal_ms / ms);
    let params = |scene: &Scene| {
        json!({
            "width": scene.camera.width, "height": scene.camera.height,
            "lights": scene.light_count(), "planes": scene.planes.planes,
            "sub_planes": scene.planes.sub_planes, "shadow_map": scene.planes.shadow_map,
            "threads": threads,
        })
    };
    emit(
        json,
        json!({
            "bench": "shafts.fig6", "params": {"adaptive": fig6.planes.adaptive, "planes": params(&fig6)},
            "median_ms": ms, "computed_share": computed,
            "baseline": "shafts.ray-march", "baseline_median_ms": baseline_ms,
            "baseline_samples": baseline.samples, "ratio": fig6_timing.ratio,
            "error_vs_every_pixel": {"rms_levels": against_every.rms, "max_levels": against_every.max},
            "error": {"rms_levels": error.rms, "max_levels": error.max,
                      "surface": kind(&surface, &surface_error), "haze": kind(&haze, &haze_error)},
            "baseline_error": {"rms_levels": baseline_error.rms, "max_levels": baseline_error.max},
            "equal_error_ratio": equal_error_ratio,
            "equal_error": equal.map(|(samples, ms, rms)| json!({"samples": samples, "median_ms": ms, "rms_levels": rms})),
            "reference": {"samples": RayMarcher::CONVERGED.samples, "doubling_change_rms": doubling},
        }),
        format!(
            "shafts.fig6   {ms:>8.2} ms   baseline ({} samples) {baseline_ms:>8.0} ms   ratio {:>6.1}   \
             error rms {:.3} max {:.2} levels (baseline: rms {:.3} max {:.2})\n\
             scattered light computed at {:.1} % of the pixels; against every pixel computed: rms {:.3} max {:.2}\n\
             error on {} surface pixels rms {:.3} max {:.2}, on {} haze pixels rms {:.3} max {:.2}\n\
             equal error: {}\n\
             reference: {} samples per ray; doubling them changes it by {}",
            baseline.samples,
            fig6_timing.ratio,
            error.rms,
            error.max,
            baseline_error.rms,
            baseline_error.max,
            100.0 * computed,
            against_every.rms,
            against_every.max,
            surface.len(),
            surface_error.rms,
            surface_error.max,
            haze.len(),
            haze_error.rms,
            haze_error.max,
            match equal {
                Some((samples, equal_ms, rms)) => format!(
                    "the ray marcher needs {samples} samples a ray (rms {rms:.3} levels) and \
                     {equal_ms:.0} ms: ratio {:.1}",
                    equal_ms / ms
                ),
                None => format!(
                    "the ray marcher does not reach the planes' rms by {EQUAL_ERROR_MAX_SAMPLES} samples a ray"
                ),
            },
            RayMarcher::CONVERGED.samples,
            doubling.map_or("(not checked with --quick)".into(), |d| format!("{:.4} % RMS", 100.0 * d)),
        ),
    );

    // The camera moves, the lights and objects do not: shadow maps kept.
    let maps = atmo::shafts::planes::shadow_maps(&fig6);
    let camera_ms = median(
        (0..runs)
            .map(|_| time_ms(|| drop(SamplePlanes::with_shadow_maps(&fig6, &maps).render())))
            .collect(),
    );
    emit(
        json,
        json!({"bench": "shafts.fig6-camera", "params": params(&fig6), "median_ms": camera_ms,
               "baseline": "shafts.ray-march", "baseline_median_ms": baseline_ms,
               "ratio": baseline_ms / camera_ms}),
        format!(
            "shafts.fig6-camera {camera_ms:>8.2} ms   (shadow maps kept: only the camera moved)   ratio {:>6.1}",
            baseline_ms / camera_ms
        ),
    );

    // The paper's method: the scattered light computed at every pixel.
    let every_error = every_frame.level_errors(&reference, fig6.display)?;
    let [every_surface, every_haze] = [&surface, &haze].map(|pixels| {
        every_frame.level_errors_over(&reference, fig6.display, pixels.iter().copied())
    });
    emit(
        json,
        json!({"bench": "shafts.fig6-every-pixel", "params": {"adaptive": false, "planes": params(&fig6)},
               "median_ms": every_ms, "baseline": "shafts.ray-march", "baseline_median_ms": baseline_ms,
               "ratio": baseline_ms / every_ms, "adaptive_speedup": every_ms / ms,
               "error": {"rms_levels": every_error.rms, "max_levels": every_error.max,
                         "surface": kind(&surface, &every_surface), "haze": kind(&haze, &every_haze)}}),
        format!(
            "shafts.fig6-every-pixel {every_ms:>8.2} ms   ratio {:>6.1} (this / the adaptive frame's time: {:.2})\n\
             error rms {:.3} max {:.2} levels (surfaces rms {:.3} max {:.2}, haze rms {:.3} max {:.2})",
            baseline_ms / every_ms,
            every_ms / ms,
            every_error.rms,
            every_error.max,
            every_surface.rms,
            every_surface.max,
            every_haze.rms,
            every_haze.max,
        ),
    );

    // The stage, timed in alternation with Fig. 6's ray marcher: its speed target is a
    // share of that baseline's time.
    let (stage_timing, stage_frame, stage_computed) = time_planes_against(&stage, runs, ray_march);
    let stage_ms = stage_timing.case_ms;
    let (stage_every_ms, stage_every_frame) = time_planes(&every_pixel(&stage), runs);
    let stage_against = stage_frame.level_errors(&stage_every_frame, stage.display)?;
    emit(
        json,
        json!({"bench": "shafts.stage", "params": {"adaptive": stage.planes.adaptive, "planes": params(&stage)},
               "median_ms": stage_ms, "computed_share": stage_computed,
               "baseline": "shafts.ray-march", "baseline_median_ms": stage_timing.baseline_ms,
               "ratio": stage_timing.ratio,
               "error_vs_every_pixel": {"rms_levels": stage_against.rms, "max_levels": stage_against.max}}),
        format!(
            "shafts.stage  {stage_ms:>8.2} ms   ratio {:>6.2} to Fig. 6's baseline ({:.0} ms in the same rounds)   \
             ({} lights; scattered light computed at {:.1} % of the pixels; \
             against every pixel computed: rms {:.3} max {:.2} levels)",
            stage_timing.ratio,
            stage_timing.baseline_ms,
            stage.light_count(),
            100.0 * stage_computed,
            stage_against.rms,
            stage_against.max,
        ),
    );
    emit(
        json,
        json!({"bench": "shafts.stage-every-pixel", "params": {"adaptive": false, "planes": params(&stage)},
               "median_ms": stage_every_ms, "adaptive_speedup": stage_every_ms / stage_ms}),
        format!(
            "shafts.stage-every-pixel {stage_every_ms:>8.2} ms   (this / the adaptive frame's time: {:.2})",
            stage_every_ms / stage_ms,
        ),
    );

    // A show: the two seconds of scenes/show.toml in which all five heads move and one
    // gobo turns, frame after frame, shadow maps kept for lights that did not move; each
    // frame timed in alternation with Fig. 6's ray marcher.
    let mut show = Scene::from_file(&scenes.join("show.toml"))?;
    let fps = if quick { 12 } else { 24 };
    let frames = 2 * fps + 1;
    let (mut maps, mut rebuilt, mut k) = (atmo::shafts::planes::ShadowMaps::default(), 0, 0);
    let show_timing = alternated(
        frames,
        || {
            show.at_time(1.0 + k as f32 / fps as f32);
            drop(maps.render(&show));
            rebuilt += maps.rebuilt;
            k += 1;
        },
        ray_march,
    );
    let show_ms = show_timing.case_ms;
    emit(
        json,
        json!({"bench": "shafts.show", "params": params(&show), "median_ms": show_ms,
               "baseline": "shafts.ray-march", "baseline_median_ms": show_timing.baseline_ms,
               "ratio": show_timing.ratio, "frames": frames, "fps": fps,
               "shadow_maps_rebuilt_per_frame": rebuilt as f64 / frames as f64}),
        format!(
            "shafts.show   {show_ms:>8.2} ms   ratio {:>6.2} to Fig. 6's baseline ({:.0} ms in the same rounds)   \
             ({} heads moving, a gobo turning; {frames} frames at {fps}/s, {:.1} of {} shadow maps rebuilt a frame)",
            show_timing.ratio,
            show_timing.baseline_ms,
            show.show.fixtures.len(),
            rebuilt as f64 / frames as f64,
            show.light_count()
        ),
    );

    // Linearity: time against lights (the stage with its first k lights), each timed in
    // turn with the ray marcher so that a drifting host does not bend the line.
    let lines: Vec<Alternated> = (1..=stage.light_count())
        .map(|k| {
            let mut scene = stage.clone();
            scene.spotlights.truncate(k);
            time_planes_against(&scene, runs.min(7), ray_march).0
        })
        .collect();
    emit(
        json,
        json!({"bench": "shafts.stage-lights",
               "median_ms_by_lights": lines.iter().map(|l| l.case_ms).collect::<Vec<_>>(),
               "baseline": "shafts.ray-march",
               "share_of_baseline_by_lights": lines.iter().map(|l| 1.0 / l.ratio).collect::<Vec<_>>()}),
        lines
            .iter()
            .zip(1..)
            .map(|(l, k)| {
                format!(
                    "  stage, {k} light{}: {:.2} ms, {:.3} of Fig. 6's baseline's time in the same rounds",
                    if k == 1 { "" } else { "s" },
                    l.case_ms,
                    1.0 / l.ratio
                )
            })
            .collect::<Vec<_>>()
            .join("\n"),
    );

    // The paper's Figs. 4 and 5: its method, every pixel computed.
    sweep_planes(&every_pixel(&fig6), &reference, quick, json, sweep)
}

/// `scene` drawn by the paper's method: the scattered light computed at every pixel.
fn every_pixel(scene: &Scene) -> Scene {
    let mut scene = scene.clone();
    scene.planes.adaptive = false;
    scene
}

/// The most samples a ray [`equal_error`] tries (about 30 times the baseline's time).
const EQUAL_ERROR_MAX_SAMPLES: u32 = 8192;

/// The fair comparison: the ray marcher with the baseline's sampling (evenly along the
/// whole ray), its samples doubled from 16 until its RMS error against `reference` is
/// at most `rms`, then the last doubling halved three times (a count within 1/8 of the
/// doubling's step of the least that reaches it); that count, its median time over
/// `runs` renders (ms) and its error, or `None` if [`EQUAL_ERROR_MAX_SAMPLES`] do not
/// reach it.
fn equal_error(
    scene: &Scene,
    reference: &Frame,
    rms: f64,
    runs: usize,
) -> Result<Option<(u32, f64, f64)>> {
    let marcher = |samples| RayMarcher {
        samples,
        ..RayMarcher::baseline(scene)
    };
    let error = |samples| -> Result<f64> {
        Ok(marcher(samples)
            .render(scene)
            .level_errors(reference, scene.display)?
            .rms)
    };
    let mut samples = 16;
    let mut reached = error(samples)?;
    while reached > rms {
        if samples >= EQUAL_ERROR_MAX_SAMPLES {
            return Ok(None);
        }
        samples *= 2;
        reached = error(samples)?;
    }
    // Between the last count that missed and the first that reached.
    let mut missed = samples / 2;
    for _ in 0..3 {
        if samples - missed < 2 {
            break;
        }
        let middle = (missed + samples) / 2;
        let e = error(middle)?;
        if e <= rms {
            (samples, reached) = (middle, e);
        } else {
            missed = middle;
        }
    }
    let ms = median(
        (0..runs)
            .map(|_| time_ms(|| drop(marcher(samples).render(scene))))
            .collect(),
    );
    Ok(Some((samples, ms, reached)))
}

/// RMS of the difference relative to the RMS of `b`, linear radiance.
fn relative_rms(a: &Frame, b: &Frame) -> f64 {
    let (mut d, mut n) = (0.0f64, 0.0f64);
    for (p, q) in a.pixels.iter().zip(&b.pixels) {
        d += (*p - *q).length_squared() as f64;
        n += q.length_squared() as f64;
    }
    (d / n.max(1e-300)).sqrt()
}

/// One row of the sweep.
struct SweepRow {
    planes: u32,
    sub_planes: u32,
    ms: f64,
    rms_levels: f64,
    max_levels: f64,
}

/// Planes with 6 sub-planes, then sub-planes with 30 planes: time and error against the
/// converged reference, to `shafts-sweep.csv` and `shafts-sweep.svg` in `folder` if given.
fn sweep_planes(
    fig6: &Scene,
    reference: &Frame,
    quick: bool,
    json: bool,
    folder: Option<&Path>,
) -> Result<()> {
    let plane_counts: &[u32] = if quick {
        &[10, 30, 60]
    } else {
        &[5, 10, 15, 20, 30, 40, 60, 80, 120, 160, 200]
    };
    let sub_counts: &[u32] = if quick {
        &[1, 6, 12]
    } else {
        &[1, 2, 3, 4, 6, 8, 12, 16, 25]
    };
    let runs = if quick { 3 } else { 7 };
    let settings = plane_counts
        .iter()
        .map(|&p| (p, 6))
        .chain(sub_counts.iter().map(|&m| (30, m)));
    let mut rows = Vec::new();
    for (planes, sub_planes) in settings {
        let mut scene = fig6.clone();
        scene.planes.planes = planes;
        scene.planes.sub_planes = sub_planes;
        let (ms, frame) = time_planes(&scene, runs);
        let e = frame.level_errors(reference, scene.display)?;
        rows.push(SweepRow {
            planes,
            sub_planes,
            ms,
            rms_levels: e.rms,
            max_levels: e.max,
        });
    }
    let mut csv = String::from("planes,sub_planes,median_ms,rms_levels,max_levels\n");
    for r in &rows {
        writeln!(
            csv,
            "{},{},{:.3},{:.4},{:.3}",
            r.planes, r.sub_planes, r.ms, r.rms_levels, r.max_levels
        )?;
    }
    // Files only where asked for (--sweep-dir); the sweep is printed either way.
    let paths = folder.map(|f| (f.join("shafts-sweep.csv"), f.join("shafts-sweep.svg")));
    if let Some((csv_path, svg_path)) = &paths {
        write_atomically(csv_path, |w| write_all(w, csv_path, csv.as_bytes()))?;
        let svg = plot(&rows, plane_counts.len());
        write_atomically(svg_path, |w| write_all(w, svg_path, svg.as_bytes()))?;
    }
    let title = match &paths {
        Some((c, s)) => format!("sweep ({} and {}):", c.display(), s.display()),
        None => "sweep (--sweep-dir to write it as CSV and SVG):".into(),
    };
    emit(
        json,
        json!({"bench": "shafts.sweep", "csv": paths.as_ref().map(|p| &p.0),
               "plot": paths.as_ref().map(|p| &p.1),
               "rows": rows.iter().map(|r| json!({"planes": r.planes, "sub_planes": r.sub_planes,
               "median_ms": r.ms, "rms_levels": r.rms_levels, "max_levels": r.max_levels})).collect::<Vec<_>>()}),
        format!("{title}\n{}", csv.trim_end()),
    );
    Ok(())
}

fn write_all(w: &mut impl std::io::Write, path: &Path, bytes: &[u8]) -> atmo::Result<()> {
    w.write_all(bytes).map_err(atmo::Error::io_at(path))
}

/// Two panels side by side, as the paper's Figs. 4 and 5: error (levels, solid) and
/// time (ms, dashed) against the plane count, then against the sub-plane count.
fn plot(rows: &[SweepRow], split: usize) -> String {
    let (w, h, pad) = (900.0, 380.0, 60.0);
    let panel_w = (w - 3.0 * pad) / 2.0;
    let mut svg = format!(
        "<svg xmlns='http://www.w3.org/2000/svg' width='{w}' height='{h}' font-family='sans-serif' font-size='12'>\
         <rect width='100%' height='100%' fill='white'/>"
    );
    let panels = [
        (&rows[..split], "sample planes (6 sub-planes)", true),
        (&rows[split..], "sub-sample planes (30 planes)", false),
    ];
    for (k, (part, title, by_planes)) in panels.into_iter().enumerate() {
        let x0 = pad + k as f64 * (panel_w + pad);
        let (y0, y1) = (h - pad, pad);
        let xs: Vec<f64> = part
            .iter()
            .map(|r| if by_planes { r.planes } else { r.sub_planes } as f64)
            .collect();
        let x_max = xs.iter().cloned().fold(1.0, f64::max);
        let e_max = part.iter().map(|r| r.rms_levels).fold(0.1, f64::max) * 1.1;
        let t_max = part.iter().map(|r| r.ms).fold(0.1, f64::max) * 1.1;
        let px = |x: f64| x0 + x / x_max * panel_w;
        let line = |values: Vec<f64>, max: f64, colour: &str, dash: &str| {
            let points: Vec<String> = xs
                .iter()
                .zip(values)
                .map(|(x, v)| format!("{:.1},{:.1}", px(*x), y0 - v / max * (y0 - y1)))
                .collect();
            format!(
                "<polyline fill='none' stroke='{colour}' stroke-width='2' stroke-dasharray='{dash}' points='{}'/>",
                points.join(" ")
            )
        };
        let _ = write!(
            svg,
            "<rect x='{x0}' y='{y1}' width='{panel_w}' height='{}' fill='none' stroke='black'/>\
             <text x='{}' y='{}' text-anchor='middle'>{title}</text>\
             <text x='{}' y='{}' fill='#c0392b'>RMS error, levels (max {:.2})</text>\
             <text x='{}' y='{}' fill='#2471a3' text-anchor='end'>time, ms (max {:.1})</text>\
             <text x='{x0}' y='{}' text-anchor='middle'>0</text><text x='{}' y='{}' text-anchor='middle'>{x_max}</text>{}{}",
            y0 - y1,
            x0 + panel_w / 2.0,
            h - pad / 3.0,
            x0 + 4.0,
            y1 - 8.0,
            e_max,
            x0 + panel_w - 4.0,
            y1 - 8.0,
            t_max,
            y0 + 16.0,
            x0 + panel_w,
            y0 + 16.0,
            line(part.iter().map(|r| r.rms_levels).collect(), e_max, "#c0392b", "none"),
            line(part.iter().map(|r| r.ms).collect(), t_max, "#2471a3", "6,4"),
        );
    }
    svg.push_str("</svg>\n");
    svg
}

pub fn gpu(gpu: &Gpu, quick: bool, json: bool, scenes: &Path) -> Result<()> {
    let runs = if quick { 3 } else { 7 };
    for (name, file) in [
        ("shafts.fig6", "spotlight-sphere.toml"),
        ("shafts.stage", "stage.toml"),
    ] {
        // The GPU draws every pixel: against the CPU doing the same.
        let scene = every_pixel(&Scene::from_file(&scenes.join(file))?);
        let (cpu_ms, cpu) = time_planes(&scene, runs);
        let shafts = GpuShafts::new(gpu, &scene).map_err(gpu_error)?;
        for method in [ShaftsMethod::Planes, ShaftsMethod::Compute] {
            let (wall, gpu_ms, frame) = time_gpu(runs, || {
                let Rendered { frame, gpu_ms } = shafts.render(gpu, method)?;
                Ok((frame, gpu_ms))
            })?;
            let suffix = match method {
                ShaftsMethod::Planes => "gpu-planes",
                ShaftsMethod::Compute => "gpu-compute",
            };
            report(
                json,
                gpu,
                Case {
                    name: &format!("{name}.{suffix}"),
                    params: json!({
                        "width": scene.camera.width, "height": scene.camera.height,
                        "lights": scene.light_count(), "planes": scene.planes.planes,
                        "sub_planes": scene.planes.sub_planes, "shadow_map": scene.planes.shadow_map,
                    }),
                    wall_ms: wall,
                    gpu_ms,
                    cpu_ms,
                    error: Some(levels(frame.level_errors(&cpu, scene.display)?)),
                },
            );
        }
    }
    Ok(())
}
