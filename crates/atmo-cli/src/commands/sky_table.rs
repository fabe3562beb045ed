//! `atmo sky --table`: pictures and sequences drawn from a skylight table (sky 4.2).

use std::path::Path;
use std::time::Instant;

use anyhow::Result;
use atmo::error::check_range;
use atmo::image::{Display, Frame};
use atmo::sky::{SkyPicture, SkylightTable, View};
use atmo::view::Sun;
use atmo::Error;
use atmo_gpu::sky::{GpuSkyTable, SkyPass, SkyTarget};
use atmo_gpu::Gpu;
use clap::ValueEnum;
use std::cell::RefCell;

use crate::backend::gpu_error;
use crate::output::write_animation;

/// What `--animate` moves.
#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Animate {
    /// The sun sets: elevation from --sun-elevation down to the table's lowest.
    Sun,
    /// The viewpoint climbs: altitude from --altitude up to the table's highest.
    Altitude,
}

/// Draws pictures from a table, on the CPU or on the GPU.
pub enum TableDrawer<'a> {
    Cpu(&'a SkylightTable),
    /// The pass is the headless one, reused frame to frame.
    Gpu(
        &'a Gpu,
        Box<(GpuSkyTable<&'a SkylightTable>, RefCell<SkyPass>)>,
    ),
}

impl<'a> TableDrawer<'a> {
    /// On `gpu` when given (the table uploaded), else on the CPU.
    pub fn new(table: &'a SkylightTable, gpu: Option<&'a Gpu>) -> Result<Self> {
        Ok(match gpu {
            Some(gpu) => TableDrawer::Gpu(
                gpu,
                Box::new((
                    GpuSkyTable::new(gpu, table).map_err(gpu_error)?,
                    RefCell::new(SkyPass::new(gpu, SkyTarget::HEADLESS).map_err(gpu_error)?),
                )),
            ),
            None => TableDrawer::Cpu(table),
        })
    }

    /// The picture of `view` for `sun` seen from `altitude_m`.
    fn frame(&self, sun: Sun, altitude_m: f64, view: &View) -> Result<Frame> {
        Ok(match self {
            TableDrawer::Cpu(table) => SkyPicture::from_table(table, sun, altitude_m)?.render(view),
            TableDrawer::Gpu(gpu, drawer) => {
                let (sky, pass) = drawer.as_ref();
                sky.render(gpu, &mut pass.borrow_mut(), sun, altitude_m, view)
                    .map_err(gpu_error)?
                    .frame
            }
        })
    }
}

/// One picture of the table for `sun` at `altitude_m`, written to `path`.
pub fn draw(
    drawer: &TableDrawer,
    sun: Sun,
    altitude_m: f64,
    view: &View,
    display: Display,
    path: &Path,
) -> Result<()> {
    let start = Instant::now();
    let frame = drawer.frame(sun, altitude_m, view)?;
    let total_ms = start.elapsed().as_secs_f64() * 1e3;
    frame.write(path, display.exposure, display.tone)?;
    eprintln!(
        "atmo: {} ({}x{}) from the table in {total_ms:.1} ms",
        path.display(),
        view.camera.width,
        view.camera.height,
    );
    Ok(())
}

/// What a sequence moves, from where, over how many frames.
pub struct Animation {
    /// The sun or the altitude.
    pub what: Animate,
    /// Frames, at least 2.
    pub frames: usize,
    /// The sun of the first frame (and of all frames when the altitude moves).
    pub sun: Sun,
    /// The altitude of the first frame (and of all when the sun moves), m.
    pub altitude_m: f64,
}

impl Animation {
    /// (sun elevation rad, altitude m) of frame `k`; the last is exactly at the end.
    fn at(&self, table: &SkylightTable, k: usize) -> (f64, f64) {
        let u = k as f64 / (self.frames - 1) as f64;
        match self.what {
            Animate::Sun => {
                let end = table.sun_axis().min();
                (self.sun.elevation() * (1.0 - u) + end * u, self.altitude_m)
            }
            Animate::Altitude => {
                let end = table.altitude_axis().max();
                (self.sun.elevation(), self.altitude_m * (1.0 - u) + end * u)
            }
        }
    }
}

/// Writes `frame-0000.png` ... and `animation.png` (animated PNG, 30 frames/s) into the
/// folder `folder`, creating it. Everything is checked before the first file.
pub fn animate(
    drawer: &TableDrawer,
    table: &SkylightTable,
    animation: &Animation,
    view: &View,
    display: Display,
    folder: &Path,
) -> Result<()> {
    check_range("frames", animation.frames as f64, 2.0, 10_000.0)?;
    if folder.extension().is_some_and(|e| e == "png" || e == "exr") {
        return Err(Error::Invalid(format!(
            "{}: with --animate, -o names a folder for the frames",
            folder.display()
        ))
        .into());
    }
    for k in [0, animation.frames - 1] {
        let (sun, altitude) = animation.at(table, k);
        table.map(sun, altitude)?;
    }
    let start = Instant::now();
    let size = (view.camera.width, view.camera.height);
    let apng = write_animation(folder, animation.frames, size, display, |k, frame| {
        let (elevation, altitude) = animation.at(table, k);
        let sun = animation.sun.with_elevation(elevation);
        *frame = drawer.frame(sun, altitude, view)?;
        Ok(())
    })?;
    eprintln!(
        "atmo: {} frames and {} in {:.1} s",
        animation.frames,
        apng.display(),
        start.elapsed().as_secs_f64()
    );
    Ok(())
}
