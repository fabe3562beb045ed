//! `atmo inspect`: what a skylight table holds, and the pictures that explain it
//! (the singular-value decay, the term counts of the paper's Fig. 10c, and the error
//! map against the directly computed sky of Fig. 10a/b).

use std::path::{Path, PathBuf};

use anyhow::Result;
use atmo::image::{srgb_decode, Frame, ToneMap};
use atmo::sky::table::{SkylightTable, CHANNELS};
use atmo::Error;
use clap::Args;
use glam::Vec3;

#[derive(Args)]
pub struct InspectArgs {
    /// The table file (from `atmo precompute sky`).
    #[arg(value_name = "FILE.atmo-sky")]
    table: PathBuf,
    /// Write the pictures into this folder (created if needed): singular-values.png,
    /// terms.png, direct.png, table.png and error.png.
    #[arg(long, value_name = "DIR")]
    plots: Option<PathBuf>,
    /// Sun elevation of the direct, table and error maps, degrees.
    #[arg(long, default_value_t = 30.0)]
    sun_elevation: f64,
    /// Viewpoint altitude of those maps, metres.
    #[arg(long, default_value_t = 7000.0)]
    altitude: f64,
}

/// Pixels per grid point in the map pictures.
const CELL: u32 = 8;

pub fn run(args: InspectArgs) -> Result<()> {
    let table = SkylightTable::read(&args.table)?;
    let bytes = std::fs::metadata(&args.table)?.len();
    let sun = args.sun_elevation.to_radians();
    if args.plots.is_some() {
        // Checked before anything is written.
        table.map(sun, args.altitude)?;
    }
    print_summary(&table, &args.table, bytes);
    if let Some(folder) = &args.plots {
        std::fs::create_dir_all(folder).map_err(Error::io_at(folder))?;
        // The five plots, all of them or (after an error or a signal) none.
        let written =
            atmo::files::write_together(|| write_plots(&table, folder, sun, args.altitude))?;
        outln!("{written}");
    }
    Ok(())
}

fn print_summary(table: &SkylightTable, path: &Path, bytes: u64) {
    let s = table.settings();
    let (sun, altitude) = (table.sun_axis(), table.altitude_axis());
    let grid = table.grid(altitude.max());
    let raw = grid.azimuths * grid.elevations * sun.count() * altitude.count() * CHANNELS;
    let a = table.atmosphere();
    outln!(
        "{}: {bytes} bytes, {:.2} % of the {raw} bytes of the table in 8-bit RGB",
        path.display(),
        100.0 * bytes as f64 / raw as f64
    );
    outln!(
        "atmosphere: {} ({}), {} wavelengths",
        a.name,
        a.description,
        a.channels()
    );
    outln!(
        "shell method: {} shells, order {}, {} scattering directions{}",
        s.sky.shells,
        s.sky.order,
        s.sky.scattering_directions,
        if s.sky.multiple_mie {
            ", multiple Mie"
        } else {
            ""
        }
    );
    outln!(
        "grid: {} x {} directions (azimuth from the sun 0 to 180 deg, elevation from the \
         horizon, down to {:.2} deg at the highest altitude, to 90 deg), {} sun elevations \
         ({} to {} deg, {}x denser at the horizon), {} altitudes (0 to {} m, spacing power \
         {})",
        grid.azimuths,
        grid.elevations,
        grid.elevation_min.to_degrees(),
        sun.count(),
        sun.min().to_degrees(),
        sun.max().to_degrees(),
        s.sun_horizon_density,
        altitude.count(),
        altitude.max(),
        s.altitude_power
    );
    let b = s.bound;
    outln!(
        "bound: epsilon {:.6} (= 1/{:.1}) on {} values at exposure {} through the {:?} tone map",
        b.epsilon,
        1.0 / b.epsilon,
        if b.srgb { "sRGB-encoded" } else { "linear" },
        b.display.exposure,
        b.display.tone
    );
    let sigma = table.singular_values();
    outln!(
        "SVD: {} terms computed, {} stored (the most any direction uses); sigma_k / sigma_1 \
         at k = 2, 5, 10, 20, 50: {}",
        sigma.len(),
        table.max_terms(),
        [2, 5, 10, 20, 50]
            .iter()
            .filter(|&&k| k <= sigma.len())
            .map(|&k| format!("{:.2e}", sigma[k - 1] / sigma[0]))
            .collect::<Vec<_>>()
            .join(", ")
    );
    for (c, name) in ["red", "green", "blue"].iter().enumerate() {
        let t = table.terms(c);
        let mean = t.iter().map(|&x| x as f64).sum::<f64>() / t.len() as f64;
        let (min, max) = (t.iter().min().unwrap_or(&0), t.iter().max().unwrap_or(&0));
        outln!("terms T(theta, phi), {name}: {min} to {max}, mean {mean:.1}");
    }
    outln!(
        "largest error at the grid points: {:.3} epsilon",
        table.grid_error()
    );
}

/// A `width` x `height` picture of per-point values (`[row][column]`, row 0 the lowest
/// elevation), each point a `CELL`-pixel square, the zenith on top.
fn grid_picture(values: &[Vec3], width: usize, height: usize) -> Frame {
    let mut frame = Frame::new(width as u32 * CELL, height as u32 * CELL);
    let w = frame.width as usize;
    for (k, p) in frame.pixels.iter_mut().enumerate() {
        let (x, y) = (k % w / CELL as usize, k / w / CELL as usize);
        *p = values[(height - 1 - y) * width + x];
    }
    frame
}

/// Writes a picture whose pixel values are the displayed values wanted, in [0, 1].
fn write_display(frame: &mut Frame, path: &Path) -> atmo::Result<()> {
    for p in &mut frame.pixels {
        *p = Vec3::new(srgb_decode(p.x), srgb_decode(p.y), srgb_decode(p.z));
    }
    frame.write(path, 1.0, ToneMap::Clamp)
}

/// Writes the plots into `folder`, and says what they are.
fn write_plots(
    table: &SkylightTable,
    folder: &Path,
    sun: f64,
    altitude_m: f64,
) -> atmo::Result<String> {
    let grid = table.grid(altitude_m);
    let (w, h) = (grid.azimuths, grid.elevations);
    let bound = table.settings().bound;

    // Fig. 10c: (T_R, T_G, T_B) / max T as a colour.
    let most = table.max_terms().max(1) as f32;
    let terms: Vec<Vec3> = (0..w * h)
        .map(|d| Vec3::from_array(std::array::from_fn(|c| table.terms(c)[d] as f32 / most)))
        .collect();
    write_display(&mut grid_picture(&terms, w, h), &folder.join("terms.png"))?;

    // Fig. 10a/b and the error between them, in units of epsilon: black 0, white 1,
    // red beyond.
    let model = table.direct_model(altitude_m)?;
    let direct = table.direct_map(&model, sun);
    let drawn = table.map(sun, altitude_m)?;
    let display = bound.display;
    for (name, map) in [("direct.png", &direct), ("table.png", &drawn)] {
        grid_picture(map, w, h).write(&folder.join(name), display.exposure, display.tone)?;
    }
    let error: Vec<Vec3> = drawn
        .iter()
        .zip(&direct)
        .map(|(a, e)| {
            let worst = (0..CHANNELS)
                .map(|c| bound.error(a[c], e[c]))
                .fold(0.0, f32::max);
            if worst <= 1.0 {
                Vec3::splat(worst)
            } else {
                Vec3::new(1.0, 0.0, 0.0)
            }
        })
        .collect();
    write_display(&mut grid_picture(&error, w, h), &folder.join("error.png"))?;

    // Singular values: log10(sigma_k / sigma_1) against k, one line per decade, the
    // number of stored terms in red.
    let sigma = table.singular_values();
    let (pw, ph, margin) = (640usize, 360usize, 20usize);
    let floor = sigma
        .iter()
        .map(|s| (s / sigma[0]).max(1e-12).log10())
        .fold(0.0f32, f32::min)
        .floor()
        .min(-1.0);
    let mut plot = Frame::new(pw as u32, ph as u32);
    let to_px = |k: f32, v: f32| -> (usize, usize) {
        let x = margin as f32 + (pw - 2 * margin) as f32 * k / (sigma.len().max(2) - 1) as f32;
        let y = margin as f32 + (ph - 2 * margin) as f32 * (v / floor);
        (x.round() as usize, y.round() as usize)
    };
    let mut put = |x: usize, y: usize, c: Vec3| {
        if x < pw && y < ph {
            plot.pixels[y * pw + x] = c;
        }
    };
    for decade in (floor as i32)..=0 {
        let (_, y) = to_px(0.0, decade as f32);
        (margin..pw - margin).for_each(|x| put(x, y, Vec3::splat(0.25)));
    }
    let (stored, _) = to_px(table.max_terms().saturating_sub(1) as f32, 0.0);
    (margin..ph - margin).for_each(|y| put(stored, y, Vec3::new(0.8, 0.1, 0.1)));
    let points: Vec<(usize, usize)> = sigma
        .iter()
        .enumerate()
        .map(|(k, s)| to_px(k as f32, (s / sigma[0]).max(1e-12).log10()))
        .collect();
    for pair in points.windows(2) {
        let ((x0, y0), (x1, y1)) = (pair[0], pair[1]);
        let steps = x0.abs_diff(x1).max(y0.abs_diff(y1)).max(1);
        for s in 0..=steps {
            let f = s as f32 / steps as f32;
            let x = x0 as f32 + (x1 as f32 - x0 as f32) * f;
            let y = y0 as f32 + (y1 as f32 - y0 as f32) * f;
            put(x.round() as usize, y.round() as usize, Vec3::ONE);
        }
    }
    write_display(&mut plot, &folder.join("singular-values.png"))?;
    Ok(format!(
        "wrote {}: singular-values.png (log10 sigma_k/sigma_1 from 0 at the top to {floor} at \
         the bottom, one grey line a decade, k = 1 to {} left to right, red: terms stored), \
         terms.png (T_R, T_G, T_B / {most}: azimuth from the sun 0 to 180 deg left to right, \
         elevation up), direct.png and table.png (sun {:.1} deg, {altitude_m} m), error.png \
         (largest channel error: black 0, white epsilon, red above)",
        folder.display(),
        sigma.len(),
        sun.to_degrees()
    ))
}
