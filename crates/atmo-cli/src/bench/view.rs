//! `atmo bench view`: the window's frame times over scripted runs at 1280 x 720, beside
//! the still's draw of the same frame in the same run: the sky (a flight from the
//! table, the sun setting by the shell method), the stage (the camera orbiting, one
//! light re-aimed every frame) and the clouds (the sun going round). Each case runs `atmo view` as its own process (a
//! window per process), which prints its times as JSON.

use std::path::Path;
use std::process::Command;

use anyhow::{bail, Context, Result};
use atmo::shafts::edits::{self, Edit};
use atmo::shafts::SamplePlanes;
use atmo::sky::table::SkylightTable;
use atmo::sky::{SkyModel, SkyPicture, SkySettings, View};
use atmo::view::{Camera, Fov, Sun};
use atmo::Atmosphere;
use glam::Vec3;
use serde_json::{json, Value};

use super::sky_table::table_settings;
use super::{emit, median, time_ms};
use crate::commands::clouds::{Cloud, CloudStill, WindowClouds};
use atmo_view::clouds::CloudPictures;
use clap::Parser;

const SIZE: (u32, u32) = (1280, 720);

/// The preview the window draws by default while a CPU picture changes (`--preview`).
const PREVIEW: u32 = 4;

/// A flight: the time of day running (the sun sets a quarter degree a frame) while the
/// viewpoint climbs 250 m a frame from the ground.
fn flight(frames: u64) -> String {
    let mut script = String::from("0 key space\n");
    for f in 1..frames {
        script.push_str(&format!("{f} key r\n"));
    }
    script
}

/// An orbit: the camera 2.4 deg around the stage a frame (a drag of 8 pixels).
fn orbit(frames: u64) -> String {
    (1..frames).map(|f| format!("{f} drag 8 0\n")).collect()
}

/// A light edit: spotlight 1's aim walked across the stage, 10 cm a frame.
fn light_walk(frames: u64) -> String {
    (1..frames)
        .map(|f| {
            format!(
                "{f} set spotlight[1].aim [{},0,-1.5]\n",
                -2.2 + 0.1 * f as f32
            )
        })
        .collect()
}

/// Runs `atmo view` with `args` (the mode first) for `frames` frames under the current
/// display and returns its times.
fn window(dir: &Path, args: &[&str], frames: u64, script: &str) -> Result<Value> {
    let script_path = dir.join("script.txt");
    std::fs::write(&script_path, script)?;
    let shot = dir.join("last.png");
    let exe = std::env::current_exe()?;
    let (w, h) = (SIZE.0.to_string(), SIZE.1.to_string());
    let output = Command::new(exe)
        .arg("view")
        .args(args)
        .args(["--width", &w, "--height", &h, "--timings"])
        .args(["--frames", &frames.to_string()])
        .args(["--screenshot", shot.to_str().context("a UTF-8 path")?])
        .args(["--script", script_path.to_str().context("a UTF-8 path")?])
        .output()?;
    let stdout = String::from_utf8_lossy(&output.stdout);
    if !output.status.success() {
        bail!(
            "atmo view failed: {}",
            String::from_utf8_lossy(&output.stderr)
        );
    }
    let line = stdout
        .lines()
        .last()
        .context("atmo view printed no times")?;
    Ok(serde_json::from_str(line)?)
}

/// The still's draw of one frame (CPU, the picture only), median of `runs`.
fn still_ms(runs: usize, mut draw: impl FnMut(&View)) -> Result<f64> {
    let camera = Camera::yaw_pitch(Vec3::ZERO, 180.0, 15.0, Fov::Vertical(70.0), SIZE)?;
    let view = View {
        camera,
        sun_disc: true,
    };
    draw(&view);
    Ok(median((0..runs).map(|_| time_ms(|| draw(&view))).collect()))
}

/// The still's draw of the stage's frame (`atmo shafts` on the CPU: shadow maps and
/// picture) at the bench's size, median of `runs`.
fn stage_still_ms(scene: &Path, runs: usize) -> Result<f64> {
    let size = [
        Edit::set("camera.width", SIZE.0.to_string()),
        Edit::set("camera.height", SIZE.1.to_string()),
    ];
    let scene = edits::load(scene, &size)?;
    let draw = || std::hint::black_box(SamplePlanes::new(&scene).render());
    draw();
    Ok(median(
        (0..runs).map(|_| time_ms(|| drop(draw()))).collect(),
    ))
}

/// The cloud of `atmo view clouds --generate cumulus --sky` at the bench's size.
#[derive(clap::Parser)]
struct CloudFlags {
    #[command(flatten)]
    still: CloudStill,
}

/// The flags of the clouds' case: the paper's largest cloud before the sky.
const CLOUD_FLAGS: [&str; 3] = ["--generate", "cumulus", "--sky"];

/// The still's draw of a frame of the clouds with the sun moved (`atmo clouds` on the
/// CPU: the light pass, the sky behind and the billboards), median of `runs`.
fn clouds_still_ms(runs: usize) -> Result<f64> {
    let (w, h) = (SIZE.0.to_string(), SIZE.1.to_string());
    let args = ["clouds", "--width", &w, "--height", &h];
    let flags = CloudFlags::try_parse_from(args.iter().chain(&CLOUD_FLAGS))?;
    let mut pictures = WindowClouds::new(Cloud::new(&flags.still)?);
    let mut params = pictures.params();
    let mut times = Vec::new();
    // The first frame also makes the sky around the cloud: not timed.
    for k in 0..=runs {
        params.sun_azimuth_deg += 1.0;
        let start = std::time::Instant::now();
        std::hint::black_box(pictures.draw(&params, SIZE, false)?);
        if k > 0 {
            times.push(start.elapsed().as_secs_f64() * 1e3);
        }
    }
    Ok(median(times))
}

/// Heads of the DMX case, and each one's channels: 16-bit pan and tilt, dimmer.
const HEADS: usize = 24;
const HEAD_CHANNELS: [&str; 5] = ["pan", "pan_fine", "tilt", "tilt_fine", "dimmer"];

/// A stage of [`HEADS`] moving heads patched on universe 1, hung in a 6 x 4 grid over a
/// floor with a ball, in the haze of scenes/dmx-rig.toml.
fn rig_scene(heads: usize) -> String {
    let mut toml = String::from(
        "[camera]\nposition = [0.0, 1.7, 11.0]\nlook_at = [0.0, 2.5, -1.0]\nfov_deg = 60.0\n\
         width = 1280\nheight = 720\nfar_m = 40.0\n\n[haze]\nextinction = 0.08\nalbedo = 0.9\n\
         phase = { kind = \"paper\", exponent = 16 }\n\
         box = { min = [-9.0, 0.0, -5.0], max = [9.0, 8.0, 6.0] }\n\n[display]\nexposure = 0.1\n\n\
         [[object]]\nkind = \"plane\"\npoint = [0.0, 0.0, 0.0]\nnormal = [0.0, 1.0, 0.0]\nalbedo = 0.35\n\n\
         [[object]]\nkind = \"sphere\"\ncenter = [0.0, 0.8, -1.0]\nradius = 0.8\nalbedo = 0.7\n",
    );
    let channels = HEAD_CHANNELS.map(|c| format!("\"{c}\"")).join(", ");
    for k in 0..heads {
        let (x, z) = (-7.5 + 3.0 * (k % 6) as f32, -3.0 + 2.0 * (k / 6) as f32);
        toml.push_str(&format!(
            "\n[[fixture]]\nname = \"head {k}\"\nposition = [{x}, 7.0, {z}]\nintensity = 20000.0\n\
             zoom_range_deg = [12.0, 12.0]\n\
             dmx = {{ universe = 1, address = {}, channels = [{channels}] }}\n",
            1 + HEAD_CHANNELS.len() * k
        ));
    }
    toml
}

/// Sends ArtDmx to `to` at 44 Hz until `stop`: every head's pan and tilt swept, each
/// a little behind the one before (a desk's fan), dimmers full.
fn send_sweep(
    to: std::net::SocketAddr,
    heads: usize,
    stop: &std::sync::atomic::AtomicBool,
) -> Result<u64> {
    let socket = std::net::UdpSocket::bind("127.0.0.1:0")?;
    let start = std::time::Instant::now();
    let mut sent = 0u64;
    while !stop.load(std::sync::atomic::Ordering::Relaxed) {
        let t = start.elapsed().as_secs_f64();
        let mut packet = b"Art-Net\0".to_vec();
        packet.extend_from_slice(&[0x00, 0x50, 0, 14, (sent % 255 + 1) as u8, 0, 0, 0, 2, 0]);
        let mut levels = [0u8; 512];
        for k in 0..heads {
            let phase = t * 0.8 + 0.15 * k as f64;
            let pan = (32768.0 + 3000.0 * phase.sin()) as u16;
            let tilt = (32768.0 + 2400.0 * (1.3 * phase).cos() + 2400.0) as u16;
            let at = HEAD_CHANNELS.len() * k;
            levels[at..at + 5].copy_from_slice(&[
                (pan >> 8) as u8,
                pan as u8,
                (tilt >> 8) as u8,
                tilt as u8,
                255,
            ]);
        }
        packet.extend_from_slice(&levels);
        socket.send_to(&packet, to)?;
        sent += 1;
        std::thread::sleep(std::time::Duration::from_micros(22_727));
    }
    Ok(sent)
}

/// The window listening to a desk (Art-Net on loopback) that moves [`HEADS`] heads at
/// 44 Hz, `frames` frames at `preview`: its times, the DMX figures, and the frames sent.
fn desk_window(
    dir: &Path,
    rig: &str,
    backend: &str,
    preview: u32,
    frames: u64,
) -> Result<(Value, u64)> {
    let port = std::net::UdpSocket::bind("127.0.0.1:0")?
        .local_addr()?
        .port();
    let to: std::net::SocketAddr = ([127, 0, 0, 1], port).into();
    let stop = std::sync::atomic::AtomicBool::new(false);
    let bind = to.to_string();
    let k = preview.to_string();
    let args = [
        "stage",
        rig,
        "--dmx",
        "artnet",
        "--bind",
        &bind,
        "--backend",
        backend,
        "--preview",
        &k,
    ];
    std::thread::scope(|scope| {
        let sender = scope.spawn(|| send_sweep(to, HEADS, &stop));
        let times = window(dir, &args, frames, "");
        stop.store(true, std::sync::atomic::Ordering::Relaxed);
        let sent = sender
            .join()
            .map_err(|_| anyhow::anyhow!("the sender panicked"))??;
        Ok((times?, sent))
    })
}

pub fn run(quick: bool, json: bool, backends: &[&str], scenes: &Path) -> Result<()> {
    if std::env::var_os("DISPLAY").is_none() && std::env::var_os("WAYLAND_DISPLAY").is_none() {
        return Err(atmo::Error::Invalid(
            "atmo bench view opens windows: it needs a display (run it under xvfb-run)".into(),
        )
        .into());
    }
    let dir = std::env::temp_dir().join(format!("atmo-bench-view-{}", std::process::id()));
    std::fs::create_dir_all(&dir)?;
    let atmosphere = Atmosphere::earth();
    note!("atmo: precomputing the table (a minute at the defaults, --quick: seconds)");
    let table = SkylightTable::precompute(&atmosphere, &table_settings(quick), &|_, _| {})?;
    let table_path = dir.join("bench.atmo-sky");
    table.write(&table_path)?;
    let frames = if quick { 20 } else { 49 };
    let sun = Sun::from_degrees(30.0, 180.0)?;
    let table_still = still_ms(5, |view| {
        let picture = SkyPicture::from_table(&table, sun, 3000.0).expect("inside the table");
        std::hint::black_box(picture.render(view));
    })?;
    let model = SkyModel::new(&atmosphere, &SkySettings::default(), 0.0)?;
    let shells_still = still_ms(5, |view| {
        std::hint::black_box(SkyPicture::new(&model, sun).render(view));
    })?;
    let table_arg = table_path.to_str().context("a UTF-8 path")?;
    let stage = scenes.join("stage.toml");
    let stage_arg = stage.to_str().context("a UTF-8 path")?;
    let stage_frames = if quick { 8 } else { 20 };
    let stage_still = stage_still_ms(&stage, if quick { 2 } else { 5 })?;
    let cloud_frames = if quick { 4 } else { 10 };
    let clouds_still = clouds_still_ms(if quick { 2 } else { 4 })?;
    let cloud_args = [&["clouds"][..], &CLOUD_FLAGS].concat();
    let picture_only = "the still's CPU draw of the same frame (picture only)";
    let whole_still = "the still's CPU draw of the same frame (shadow maps and picture)";
    for &backend in backends {
        // (name, mode and its flags, frames, script, what it does, the still, its time)
        let cases = [
            (
                "view.sky",
                vec!["sky", "--table", table_arg],
                frames,
                flight(frames),
                "climb 250 m a frame, sun setting",
                picture_only,
                table_still,
            ),
            (
                "view.sky-shells",
                vec!["sky"],
                frames,
                "0 key space\n".to_string(),
                "sun setting",
                picture_only,
                shells_still,
            ),
            (
                "view.stage.camera",
                vec!["stage", stage_arg],
                stage_frames,
                orbit(stage_frames),
                "orbit 2.4 deg a frame",
                whole_still,
                stage_still,
            ),
            (
                "view.stage.light-edit",
                vec!["stage", stage_arg],
                stage_frames,
                light_walk(stage_frames),
                "one light re-aimed a frame",
                whole_still,
                stage_still,
            ),
            (
                "view.clouds.sun",
                cloud_args.clone(),
                cloud_frames,
                "0 key space\n".to_string(),
                "the sun 1 deg round a frame",
                "the still's CPU draw of the same frame (light pass, sky, billboards)",
                clouds_still,
            ),
        ];
        // Every frame whole (the targets' measure), then for the stage and the clouds
        // drawn on the CPU the window as it runs by default: a quarter-size preview a
        // frame while the picture changes (the sky draws whole always).
        let runs = cases.into_iter().flat_map(|case| {
            let previews: &[u32] = if case.0.starts_with("view.sky") || backend != "cpu" {
                &[1]
            } else {
                &[1, PREVIEW]
            };
            previews.iter().map(move |&k| (case.clone(), k))
        });
        for ((name, mut args, frames, script, what, baseline, still), preview) in runs {
            let k = preview.to_string();
            args.extend(["--backend", backend, "--preview", &k]);
            let times = window(&dir, &args, frames, &script)?;
            let frame = &times["frame"];
            let median_ms = frame["median_ms"].as_f64().context("a frame time")?;
            emit(
                json,
                json!({
                    "bench": name,
                    "params": {"backend": backend, "width": SIZE.0, "height": SIZE.1,
                               "frames": frames, "script": what, "preview": preview},
                    "median_ms": median_ms, "p95_ms": frame["p95_ms"],
                    "method_median_ms": times["method"]["median_ms"],
                    "baseline": baseline,
                    "baseline_median_ms": still, "ratio": still / median_ms,
                }),
                format!(
                    "{name:<22} {backend} preview 1/{preview}: frame {median_ms:>7.1} ms (p95 {:.1}), method {:.1} ms; still draw {still:.1} ms",
                    frame["p95_ms"].as_f64().unwrap_or(f64::NAN),
                    times["method"]["median_ms"].as_f64().unwrap_or(f64::NAN),
                ),
            );
        }
    }
    // The desk's case: 24 heads moved from DMX, every picture a preview at the
    // window's default (CPU) while they move.
    let rig = dir.join("rig24.toml");
    std::fs::write(&rig, rig_scene(HEADS))?;
    let rig_arg = rig.to_str().context("a UTF-8 path")?;
    let rig_still = stage_still_ms(&rig, if quick { 1 } else { 3 })?;
    let desk_frames = if quick { 12 } else { 60 };
    for &backend in backends {
        let preview = if backend == "cpu" { PREVIEW } else { 1 };
        let (times, sent) = desk_window(&dir, rig_arg, backend, preview, desk_frames)?;
        let frame = &times["frame"];
        let median_ms = frame["median_ms"].as_f64().context("a frame time")?;
        let latency = times["dmx_latency"]["median_ms"].as_f64();
        emit(
            json,
            json!({
                "bench": "view.stage.desk",
                "params": {"backend": backend, "width": SIZE.0, "height": SIZE.1,
                           "frames": desk_frames, "heads": HEADS, "preview": preview,
                           "script": "24 heads' pan and tilt from Art-Net at 44 Hz"},
                "median_ms": median_ms, "p95_ms": frame["p95_ms"],
                "pictures_per_s": 1e3 / median_ms,
                "method_median_ms": times["method"]["median_ms"],
                "dmx_frames_sent": sent, "dmx_frames": times["dmx_frames"],
                "dmx_latency_median_ms": latency,
                "dmx_latency_p95_ms": times["dmx_latency"]["p95_ms"],
                "baseline": whole_still,
                "baseline_median_ms": rig_still, "ratio": rig_still / median_ms,
            }),
            format!(
                "{:<22} {backend} preview 1/{preview}: frame {median_ms:>7.1} ms ({:.1} pictures/s), DMX to picture {} ms; still draw {rig_still:.1} ms",
                "view.stage.desk",
                1e3 / median_ms,
                latency.map_or("-".into(), |ms| format!("{ms:.0}")),
            ),
        );
    }
    std::fs::remove_dir_all(&dir)?;
    Ok(())
}
