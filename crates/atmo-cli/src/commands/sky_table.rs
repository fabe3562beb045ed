//! `atmo sky --table`: pictures and sequences drawn from a skylight table (sky 4.2).

use std::path::Path;
use std::time::Instant;

use anyhow::Result;
use atmo::error::check_range;
use atmo::image::Display;
use atmo::sky::{SkylightTable, View};
use atmo::view::place::Place;
use atmo::view::Sun;
use atmo::Error;
use atmo_gpu::sky::SkyRenderer;
use chrono::{DateTime, FixedOffset};
use clap::ValueEnum;

use crate::backend::gpu_error;
use crate::output::{self, write_animation, Chunk};

/// What `--animate` moves.
#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Animate {
    /// The sun sets: elevation from --sun-elevation down to the table's lowest.
    Sun,
    /// The viewpoint climbs: altitude from --altitude up to the table's highest.
    Altitude,
    /// A day at --latitude/--longitude on --time's date: from the sun rising past the
    /// table's lowest elevation to its setting below it, evenly in time.
    Day,
}

/// One picture of the table for `sun` at `altitude_m`, written to `path`.
pub fn draw(
    drawer: &mut SkyRenderer,
    sun: Sun,
    altitude_m: f64,
    view: &View,
    display: Display,
    path: &Path,
) -> Result<()> {
    let start = Instant::now();
    let frame = drawer.frame(sun, altitude_m, view).map_err(gpu_error)?;
    let total_ms = start.elapsed().as_secs_f64() * 1e3;
    frame.write(path, display.exposure, display.tone)?;
    note!(
        "atmo: {} ({}x{}) from the table in {total_ms:.1} ms",
        path.display(),
        view.camera.width,
        view.camera.height,
    );
    Ok(())
}

/// What a sequence moves, from where, over how many frames.
pub struct Animation {
    /// The sun, the altitude, or the day.
    pub what: Animate,
    /// Frames, at least 2.
    pub frames: usize,
    /// The sun of the first frame (and of all frames when the altitude moves).
    pub sun: Sun,
    /// The altitude of the first frame (and of all when the sun moves), m.
    pub altitude_m: f64,
    /// With [`Animate::Day`], the place and the time whose date is the day.
    pub day: Option<(Place, DateTime<FixedOffset>)>,
}

impl Animation {
    /// The sun of every frame and its altitude, m; the last frame is exactly at the end.
    fn frames(&self, table: &SkylightTable) -> atmo::Result<Vec<(Sun, f64)>> {
        let n = self.frames;
        let u = |k: usize| k as f64 / (n - 1) as f64;
        Ok(match self.what {
            Animate::Sun => {
                let end = table.sun_axis().min();
                (0..n)
                    .map(|k| {
                        let e = self.sun.elevation() * (1.0 - u(k)) + end * u(k);
                        (self.sun.with_elevation(e), self.altitude_m)
                    })
                    .collect()
            }
            Animate::Altitude => {
                let end = table.altitude_axis().max();
                (0..n)
                    .map(|k| (self.sun, self.altitude_m * (1.0 - u(k)) + end * u(k)))
                    .collect()
            }
            Animate::Day => {
                let (place, time) = self.day.ok_or_else(|| {
                    Error::Invalid("--animate day needs --latitude, --longitude and --time".into())
                })?;
                // Just inside the table's lowest sun, so the first frame can be drawn.
                let lowest = table.sun_axis().min().to_degrees() + 1e-3;
                let (rise, set) = place.daylight(time, lowest)?;
                let span = (set - rise).num_seconds() as f64;
                (0..n)
                    .map(|k| {
                        let at = rise + chrono::Duration::milliseconds((span * u(k) * 1e3) as i64);
                        Ok((place.sun_at(at)?.sun(), self.altitude_m))
                    })
                    .collect::<atmo::Result<_>>()?
            }
        })
    }
}

/// Writes the frames `chunk` selects (all by default, and then `animation.png`, 30
/// frames/s) into the folder `folder` (see [`crate::output`]). Everything is checked
/// before the first frame.
pub fn animate(
    drawer: &mut SkyRenderer,
    table: &SkylightTable,
    animation: &Animation,
    view: &View,
    display: Display,
    folder: &Path,
    chunk: &Chunk,
) -> Result<()> {
    check_range("--frame-count", animation.frames as f64, 2.0, 10_000.0)?;
    // Every frame inside the table's ranges (its coefficients, not its whole map).
    let frames = animation.frames(table)?;
    for (sun, altitude) in &frames {
        table.coefficients(sun.elevation(), *altitude)?;
    }
    let start = Instant::now();
    let written = write_animation(
        &output::Animation {
            command: "sky",
            folder,
            count: animation.frames,
            fps: 30,
            size: (view.camera.width, view.camera.height),
            display,
            chunk,
        },
        |k, frame| {
            let (sun, altitude) = frames[k];
            *frame = drawer.frame(sun, altitude, view).map_err(gpu_error)?;
            Ok(())
        },
    )?;
    output::report(folder, &written, start);
    Ok(())
}
