//! `atmo bench clouds`: the light pass of the 3-D intensity buffer (clouds 3) against
//! the Harris baseline (clouds 2.1) on the paper's three particle counts and three
//! buffer sizes, in the same run; the buffer's error against the exact transmittance;
//! the time to draw a 1280 x 720 frame with every order (by the transfer table, the
//! octaves and the transfer solve) against the paper's own billboards in the same run,
//! and to make the particles' depths the table reads; and a small picture
//! of every order against the path tracer, its error and the two times.

use anyhow::Result;
use atmo::atmosphere::PhaseFunction;
use atmo::clouds::buffer::{IntensityBuffer, Splat};
use atmo::clouds::generator::{Cumulus, SplitMix64};
use atmo::clouds::harris::light_per_particle;
use atmo::clouds::render::{
    paper_billboards, render_with_depths, solve_for, AerialHaze, CloudLight,
};
use atmo::clouds::{
    CloudDepths, CloudShadow, DiffuseLight, Diffusion, Octaves, Scattering, SkyLight,
};
use atmo::image::{Display, Frame, ToneMap};
use atmo::reference::clouds::{
    transmittance, Agreement, PathSettings, ReferenceCloud, ReferenceLight,
};
use atmo::view::{Camera, Fov, Sun};
use atmo_gpu::clouds::GpuClouds;
use atmo_gpu::{Gpu, Rendered};
use glam::Vec3;
use rayon::prelude::*;
use serde_json::json;

use super::{alternated, emit, levels, median, report, time_gpu, time_ms, Case};
use crate::backend::gpu_error;

/// Unit vector toward a sun at `elevation_deg` and `azimuth_deg` (valid values).
fn toward_sun(elevation_deg: f32, azimuth_deg: f32) -> Vec3 {
    Sun::from_degrees(elevation_deg as f64, azimuth_deg as f64)
        .expect("a bench's sun is valid")
        .toward()
}

pub fn cpu(quick: bool, json: bool) -> Result<()> {
    let counts: &[usize] = if quick {
        &[9_382]
    } else {
        &[9_382, 32_914, 60_134]
    };
    let sizes: &[usize] = if quick { &[128] } else { &[128, 256, 384] };
    let runs = if quick { 3 } else { 7 };
    let to_sun = toward_sun(20.0, 40.0);
    // The buffer holds the sun's transmittance (what every order needs).
    let forward = 0.0;
    for &count in counts {
        let particles = Cumulus {
            particles: count,
            ..Cumulus::default()
        }
        .generate();
        for &n in sizes {
            // The buffer updated in place for a sun a little moved each round, timed in
            // alternation with the baseline at the same lateral resolution.
            let mut buffer = IntensityBuffer::new(&particles, to_sun, n, forward, Splat::Pieces)?;
            let mut k = 0;
            let timing = alternated(
                runs,
                || {
                    k += 1;
                    let sun = toward_sun(20.0 + 0.01 * k as f32, 40.0);
                    buffer
                        .update(&particles, sun, forward, Splat::Pieces)
                        .expect("validated")
                },
                || drop(light_per_particle(&particles, to_sun, n, forward)),
            );
            let (ms, harris_ms) = (timing.case_ms, timing.baseline_ms);
            buffer.update(&particles, to_sun, 0.0, Splat::Pieces)?;
            let (pieces_err, whole_err) = if n == 128 || !quick {
                let whole = IntensityBuffer::new(&particles, to_sun, n, 0.0, Splat::Whole)?;
                (
                    mean_error(&buffer, &particles, to_sun),
                    mean_error(&whole, &particles, to_sun),
                )
            } else {
                (f64::NAN, f64::NAN)
            };
            emit(
                json,
                json!({"bench": "clouds.light-pass", "params": {"particles": count, "resolution": n, "splat": "pieces", "forward": forward},
                       "median_ms": ms, "baseline": "clouds.harris", "baseline_median_ms": harris_ms, "ratio": timing.ratio,
                       "error": {"mean_rel": pieces_err, "mean_rel_whole_particles": whole_err}}),
                format!(
                    "clouds.light-pass {count:>6} particles {n:>3}^3: {ms:>8.1} ms   harris {harris_ms:>8.1} ms   ratio {:>5.2}   mean error {:.2e} (paper's whole particles: {:.3})",
                    timing.ratio,
                    pieces_err,
                    whole_err
                ),
            );
        }
    }
    // A frame of the largest cloud.
    let particles = Cumulus {
        particles: *counts.last().expect("one count"),
        ..Cumulus::default()
    }
    .generate();
    let buffer = IntensityBuffer::new(&particles, to_sun, 256, forward, Splat::Pieces)?;
    let camera = bench_camera(&particles, (1280, 720));
    // The particles' depths, made once for frames of the same particles.
    let mut depths = CloudDepths::default();
    let depths_ms = median(
        (0..runs.min(5))
            .map(|_| time_ms(|| depths = CloudDepths::of(&particles).expect("validated")))
            .collect(),
    );
    emit(
        json,
        json!({"bench": "clouds.depths", "params": {"particles": particles.len(), "resolution": atmo::clouds::sky_light::VERTICAL_RESOLUTION}, "median_ms": depths_ms}),
        format!(
            "clouds.depths     {:>6} particles: {depths_ms:.1} ms (once per particle set)",
            particles.len()
        ),
    );
    // Each frame in alternation with the paper's own billboards (the same drawing, its
    // pixel a thin blob lit by one read).
    for (name, scattering) in EVERY_ORDER {
        let light = lighting(to_sun, scattering);
        let diffuse = solve_for(&particles, &buffer, &light, None)?;
        let timing = alternated(
            runs.min(5),
            || {
                let drawn = render_with_depths(
                    &particles,
                    &depths,
                    &buffer,
                    diffuse.as_ref(),
                    &camera,
                    &light,
                    None,
                );
                drop(drawn.expect("a pinhole"))
            },
            || {
                drop(
                    paper_billboards(&particles, &buffer, &camera, &light, None)
                        .expect("a pinhole"),
                )
            },
        );
        emit(
            json,
            json!({"bench": "clouds.frame", "params": {"particles": particles.len(), "width": 1280, "height": 720, "scattering": name},
                   "median_ms": timing.case_ms, "baseline": "clouds.paper-billboards", "baseline_median_ms": timing.baseline_ms, "ratio": timing.ratio}),
            format!(
                "clouds.frame      {:>6} particles 1280 x 720: {:.1} ms (every order, {name})   the paper's billboards {:.1} ms   ratio {:.2}",
                particles.len(),
                timing.case_ms,
                timing.baseline_ms,
                timing.ratio
            ),
        );
    }
    // The cloud's shadow on the ground, made with each light pass where a picture shows
    // the ground: its time beside the light pass's, and its transmittance on a grid of
    // ground points 125 m apart around the shadow against the exact one.
    let mut lit = buffer.clone();
    let light_ms = median(
        (0..runs.min(5))
            .map(|_| {
                time_ms(|| {
                    lit.update(&particles, to_sun, forward, Splat::Pieces)
                        .expect("validated")
                })
            })
            .collect(),
    );
    let shadow_ms = median(
        (0..runs.min(5))
            .map(|_| {
                time_ms(|| drop(CloudShadow::new(&particles, to_sun, 256).expect("validated")))
            })
            .collect(),
    );
    let shadow = CloudShadow::new(&particles, to_sun, 256)?;
    let centre = particles.iter().map(|p| p.position).sum::<Vec3>() / particles.len() as f32;
    let hit = centre - centre.y / to_sun.y * to_sun;
    let errors: Vec<f64> = (0..24 * 24)
        .into_par_iter()
        .map(|k| {
            let p = hit + Vec3::new((k % 24) as f32 - 11.5, 0.0, (k / 24) as f32 - 11.5) * 125.0;
            let exact = transmittance(&particles, to_sun, p);
            ((-shadow.depth_at(p)).exp() as f64 - exact).abs()
        })
        .collect();
    let (mean_err, max_err) = (
        errors.iter().sum::<f64>() / errors.len() as f64,
        errors.iter().copied().fold(0.0, f64::max),
    );
    emit(
        json,
        json!({"bench": "clouds.shadow", "params": {"particles": particles.len(), "resolution": 256},
               "median_ms": shadow_ms, "baseline": "clouds.light-pass", "baseline_median_ms": light_ms,
               "ratio": light_ms / shadow_ms, "error": {"transmittance_mean_abs": mean_err, "transmittance_max_abs": max_err}}),
        format!(
            "clouds.shadow     {:>6} particles 256^2: {shadow_ms:.1} ms   light pass 256^3 {light_ms:.1} ms   ratio {:.1}   transmittance error mean {mean_err:.1e} max {max_err:.1e}",
            particles.len(),
            light_ms / shadow_ms
        ),
    );
    // The transfer solve when the sun moves (by half a degree each round, back and
    // forth, each sun's buffer lit beforehand: started from the last solve, as a moving
    // sun's frames are) and from scratch, alternated with the light pass it follows.
    let suns = [to_sun, toward_sun(20.5, 40.0)];
    let other = IntensityBuffer::new(&particles, suns[1], 256, forward, Splat::Pieces)?;
    let lit_for = [&buffer, &other];
    // Without a sky and with one (its light through the same solve: the transmittance
    // from the grid's faces swept too, a diffusion per channel).
    for (sky_name, sky) in [("none", SkyLight::NONE), ("daylight", bench_sky())] {
        let solve = |buffer: &IntensityBuffer, sun: Vec3, previous: Option<&DiffuseLight>| {
            DiffuseLight::solve(
                &particles,
                buffer,
                sun,
                PhaseFunction::CloudMie,
                &sky,
                &Diffusion::DEFAULT,
                previous,
            )
            .expect("validated")
        };
        let mut last = solve(&buffer, to_sun, None);
        let cold_iterations = last.iterations;
        let cold_ms = median(
            (0..runs.min(5))
                .map(|_| time_ms(|| drop(solve(&buffer, to_sun, None))))
                .collect(),
        );
        let mut k = 0;
        let timing = alternated(
            runs.min(5),
            || {
                k += 1;
                last = solve(lit_for[k % 2], suns[k % 2], Some(&last));
            },
            || {
                lit.update(&particles, to_sun, forward, Splat::Pieces)
                    .expect("validated")
            },
        );
        let dims = last.dims();
        emit(
            json,
            json!({"bench": "clouds.solve", "params": {"particles": particles.len(), "cells": Diffusion::DEFAULT.cells,
                       "grid": dims, "sun_step_deg": 0.5, "sky": sky_name},
                   "median_ms": timing.case_ms, "baseline": "clouds.light-pass-256", "baseline_median_ms": timing.baseline_ms,
                   "ratio": timing.ratio, "cold_ms": cold_ms, "cold_iterations": cold_iterations,
                   "warm_iterations": last.iterations}),
            format!(
                "clouds.solve      {:>6} particles {} x {} x {} (sky: {sky_name}): {:.1} ms when the sun moves ({} iterations; from scratch {cold_ms:.1} ms, {cold_iterations})   light pass 256^3 {:.1} ms   ratio {:.2}",
                particles.len(),
                dims[0],
                dims[1],
                dims[2],
                timing.case_ms,
                last.iterations,
                timing.baseline_ms,
                timing.ratio
            ),
        );
    }
    // Every order against the path tracer, on a small picture of the same view: by the
    // table, the octaves and the solve, against the same path-traced picture.
    let size = if quick { (32, 18) } else { (64, 36) };
    let paths = if quick { 8 } else { 16 };
    let small = bench_camera(&particles, size);
    let reference = ReferenceCloud::new(
        &particles,
        ReferenceLight {
            to_sun: to_sun.as_dvec3(),
            phase: PhaseFunction::CloudMie,
            sky: 0.0,
        },
    );
    let settings = PathSettings {
        paths,
        orders: usize::MAX,
        seed: 5,
    };
    let mut traced = Vec::new();
    let traced_ms = time_ms(|| traced = reference.path_traced_picture(&small, &settings));
    let traced: Vec<f64> = traced.iter().map(|t| t.0).collect();
    // Over the cloud's pixels (those its particles cover, optical depth over 0.1): the
    // mean, and the share of 8 x 8 blocks within 15 %.
    let covered = reference.covered(&small);
    for (name, scattering) in EVERY_ORDER {
        let light = lighting(to_sun, scattering);
        let (fast_ms, fast) = timed_render(&particles, &depths, &buffer, &small, &light, runs);
        let agreement = Agreement::of(
            &fast.pixels.iter().map(|p| p.x as f64).collect::<Vec<_>>(),
            &traced,
            &covered,
            small.width as usize,
        );
        let error = agreement.mean_ratio - 1.0;
        let share = |within: usize| within as f64 / agreement.blocks.max(1) as f64;
        let (blocks, medians) = (
            share(agreement.blocks_within_15),
            share(agreement.medians_within_15),
        );
        emit(
            json,
            json!({"bench": "clouds.multiple", "params": {"particles": particles.len(), "width": size.0, "height": size.1,
                       "scattering": name, "paths_per_pixel": paths,
                       "cloud_pixels": covered.iter().filter(|c| **c).count()},
                   "median_ms": fast_ms, "baseline": "clouds.path-traced", "baseline_median_ms": traced_ms,
                   "ratio": traced_ms / fast_ms,
                   "error": {"vs_path_traced": error, "blocks_within_15": blocks, "blocks": agreement.blocks,
                             "block_medians_within_15": medians}}),
            format!(
                "clouds.multiple   {:>6} particles {} x {} ({name}): {fast_ms:.1} ms   path tracer ({paths} paths) {traced_ms:.0} ms   ratio {:.0}   mean error {:+.1} %   8 x 8 blocks within 15 %: {} of {} by their means, {} by their medians",
                particles.len(),
                size.0,
                size.1,
                traced_ms / fast_ms,
                100.0 * error,
                agreement.blocks_within_15,
                agreement.blocks,
                agreement.medians_within_15
            ),
        );
    }
    Ok(())
}

/// The models of every order the benches time and score, by their names in the JSON's
/// params: the transfer table (the CPU's default), the octaves (the GPU's) and the
/// transfer solve (made once per picture, not timed with the frame: `clouds.solve`).
const EVERY_ORDER: [(&str, Scattering); 3] = [
    ("multiple", Scattering::MULTIPLE),
    ("octaves", Scattering::Octaves(Octaves::MULTIPLE)),
    ("solve", Scattering::SOLVE),
];

/// The median time of drawing `particles` (their `depths` given, and the transfer
/// solve where `light` draws with one, made before), and the last frame.
fn timed_render(
    particles: &[atmo::clouds::particles::Particle],
    depths: &CloudDepths,
    buffer: &IntensityBuffer,
    camera: &Camera,
    light: &CloudLight,
    runs: usize,
) -> (f64, Frame) {
    let diffuse = solve_for(particles, buffer, light, None).expect("validated");
    let mut frame = Frame::new(1, 1);
    let ms = median(
        (0..runs)
            .map(|_| {
                time_ms(|| {
                    frame = render_with_depths(
                        particles,
                        depths,
                        buffer,
                        diffuse.as_ref(),
                        camera,
                        light,
                        None,
                    )
                    .expect("a pinhole")
                })
            })
            .collect(),
    );
    (ms, frame)
}

/// The benches' light: unit sunlight from `to_sun`, `scattering`, no ambient light.
fn lighting(to_sun: Vec3, scattering: Scattering) -> CloudLight {
    CloudLight {
        to_sun,
        sun: Vec3::ONE,
        ambient: SkyLight::NONE,
        phase: PhaseFunction::CloudMie,
        haze: AerialHaze::CLEAR,
        scattering,
    }
}

/// A daylight sky for the solve's bench, brighter above than below: its cost is any
/// sky's (the field is solved per channel whatever the sky's shape).
fn bench_sky() -> SkyLight {
    let mut harmonics = [[0.0; 3]; 9];
    harmonics[0] = [0.2, 0.3, 0.5];
    harmonics[1] = [0.05, 0.08, 0.15];
    SkyLight::from_harmonics(&harmonics)
}

/// Mean |Gamma - exact| / exact at 400 voxel centres where the exact value is above 1e-3
/// (no forward scattering: Gamma is then a transmittance).
fn mean_error(
    buffer: &IntensityBuffer,
    particles: &[atmo::clouds::particles::Particle],
    to_sun: Vec3,
) -> f64 {
    let n = buffer.resolution;
    let mut rng = SplitMix64::new(11);
    let (mut sum, mut count) = (0.0, 0);
    while count < 400 {
        let pick = |rng: &mut SplitMix64| (rng.next_u64() % n as u64) as usize;
        let (ix, iy, iz) = (pick(&mut rng), pick(&mut rng), pick(&mut rng));
        let exact = transmittance(particles, to_sun, buffer.voxel_centre(ix, iy, iz));
        if exact > 1e-3 && exact < 0.999 {
            sum += (buffer.at(ix, iy, iz) as f64 - exact).abs() / exact;
            count += 1;
        }
    }
    sum / count as f64
}

/// The bench's camera: 40 degrees, looking at the cloud from 1.6 widths, `size` pixels.
fn bench_camera(particles: &[atmo::clouds::particles::Particle], size: (u32, u32)) -> Camera {
    let centre = particles.iter().map(|p| p.position).sum::<Vec3>() / particles.len() as f32;
    let position = centre + Vec3::new(-700.0, -600.0, 1900.0);
    Camera::look_at(position, centre, Vec3::Y, Fov::Vertical(40.0), size)
        .expect("the view is oblique: not along up")
}

pub fn gpu(gpu: &Gpu, quick: bool, json: bool) -> Result<()> {
    let runs = if quick { 3 } else { 7 };
    let particles = Cumulus::default().generate();
    let to_sun = toward_sun(20.0, 40.0);
    let forward = 0.0;
    let sizes: &[usize] = if quick { &[128] } else { &[128, 256] };
    for &n in sizes {
        let mut buffer = IntensityBuffer::new(&particles, to_sun, n, forward, Splat::Pieces)?;
        let cpu_ms = median(
            (0..runs)
                .map(|_| {
                    time_ms(|| {
                        buffer
                            .update(&particles, to_sun, forward, Splat::Pieces)
                            .expect("valid")
                    })
                })
                .collect(),
        );
        let mut clouds = GpuClouds::new(gpu, &particles, n).map_err(gpu_error)?;
        let (wall, gpu_ms, ()) = time_gpu(runs, || {
            let ms = clouds.light(gpu, to_sun, forward, Splat::Pieces)?;
            Ok(((), ms))
        })?;
        let log_gamma = clouds.log_gamma(gpu).map_err(gpu_error)?;
        let worst = log_gamma
            .iter()
            .zip(&buffer.log_gamma)
            .map(|(a, b)| (a - b).abs() * b.exp())
            .fold(0.0f32, f32::max);
        report(
            json,
            gpu,
            Case {
                name: "clouds.light-pass.gpu",
                params: json!({"particles": particles.len(), "resolution": n, "splat": "pieces",
                               "max_gamma_difference": worst}),
                wall_ms: wall,
                gpu_ms,
                cpu_ms,
                error: None,
            },
        );
    }
    solve_gpu(gpu, &particles, runs, json)?;
    let buffer = IntensityBuffer::new(&particles, to_sun, 256, forward, Splat::Pieces)?;
    let mut clouds = GpuClouds::new(gpu, &particles, 256).map_err(gpu_error)?;
    clouds
        .light(gpu, to_sun, forward, Splat::Pieces)
        .map_err(gpu_error)?;
    let camera = bench_camera(&particles, (1280, 720));
    let depths = CloudDepths::of(&particles)?;
    let display = Display {
        exposure: 10.0,
        tone: ToneMap::Exponential,
    };
    for (name, scattering) in EVERY_ORDER {
        let light = lighting(to_sun, scattering);
        let (cpu_ms, cpu) = timed_render(&particles, &depths, &buffer, &camera, &light, runs);
        let (wall, gpu_ms, frame) = time_gpu(runs, || {
            let Rendered { frame, gpu_ms } = clouds.render(gpu, &camera, &light, None)?;
            Ok((frame, gpu_ms))
        })?;
        report(
            json,
            gpu,
            Case {
                name: "clouds.frame.gpu",
                params: json!({"particles": particles.len(), "width": camera.width, "height": camera.height, "scattering": name}),
                wall_ms: wall,
                gpu_ms,
                cpu_ms,
                error: Some(levels(frame.level_errors(&cpu, display)?)),
            },
        );
    }
    Ok(())
}

/// The transfer solve when the sun moves on the GPU against the CPU's, with a sky: the
/// same two suns half a degree apart alternated, each solve from the last and its light
/// pass made beforehand (untimed), as the CPU bench's; the GPU's light toward the eye
/// (the sun's and the sky's) against the CPU's for the last sun.
fn solve_gpu(
    gpu: &Gpu,
    particles: &[atmo::clouds::Particle],
    runs: usize,
    json: bool,
) -> Result<()> {
    let suns = [toward_sun(20.0, 40.0), toward_sun(20.5, 40.0)];
    let buffers = suns.map(|sun| IntensityBuffer::new(particles, sun, 256, 0.0, Splat::Pieces));
    let [a, b] = buffers;
    let buffers = [a?, b?];
    let camera = bench_camera(particles, (1280, 720));
    let sky = bench_sky();
    let solve = |k: usize, previous: Option<&DiffuseLight>| {
        DiffuseLight::solve(
            particles,
            &buffers[k % 2],
            suns[k % 2],
            PhaseFunction::CloudMie,
            &sky,
            &Diffusion::DEFAULT,
            previous,
        )
        .expect("validated")
    };
    let mut last = solve(0, None);
    let mut cpu_times = Vec::new();
    for k in 1..=runs {
        cpu_times.push(time_ms(|| last = solve(k, Some(&last))));
    }
    let mut clouds = GpuClouds::new(gpu, particles, 256).map_err(gpu_error)?;
    let (mut walls, mut gpu_times) = (Vec::new(), Vec::new());
    for k in 0..=runs {
        let sun = suns[k % 2];
        clouds
            .light(gpu, sun, 0.0, Splat::Pieces)
            .map_err(gpu_error)?;
        let light = CloudLight {
            ambient: sky,
            ..lighting(sun, Scattering::SOLVE)
        };
        let mut ms = Ok(None);
        let wall = time_ms(|| ms = clouds.solve(gpu, &light, camera.position));
        // The first from scratch, untimed.
        if k > 0 {
            walls.push(wall);
            gpu_times.extend(ms.map_err(gpu_error)?);
        }
    }
    // Every cell's sun's light and the sky's in each channel, side by side.
    let got: Vec<f32> = clouds
        .solved_toward(gpu)
        .map_err(gpu_error)?
        .into_iter()
        .flatten()
        .collect();
    let sky_toward = last.sky_toward(camera.position).unwrap_or_default();
    let want: Vec<f32> = last
        .toward(camera.position)
        .into_iter()
        .zip(sky_toward)
        .flat_map(|(sun, sky)| [sun, sky.x, sky.y, sky.z])
        .collect();
    let mean = |v: &[f32]| v.iter().map(|x| *x as f64).sum::<f64>() / v.len() as f64;
    let rms = (got
        .iter()
        .zip(&want)
        .map(|(g, w)| ((g - w) as f64).powi(2))
        .sum::<f64>()
        / want.len() as f64)
        .sqrt()
        / mean(&want);
    report(
        json,
        gpu,
        Case {
            name: "clouds.solve.gpu",
            params: json!({"particles": particles.len(), "cells": Diffusion::DEFAULT.cells,
                           "iterations": clouds.solve_iterations(gpu).map_err(gpu_error)?}),
            wall_ms: median(walls),
            gpu_ms: (!gpu_times.is_empty()).then(|| median(gpu_times)),
            cpu_ms: median(cpu_times),
            // The light toward the eye, every cell: the means' ratio and the RMS
            // difference over the mean.
            error: Some(json!({"mean_ratio": mean(&got) / mean(&want), "rms_of_mean": rms})),
        },
    );
    Ok(())
}
