//! The sky drawn from a table or a model, on the CPU or the GPU, the backend a setting:
//! one renderer for `atmo sky` (stills and animations) and the window's sky mode.

use std::borrow::Borrow;
use std::sync::Arc;

use atmo::image::Frame;
use atmo::sky::frame::{SkyPicture, View};
use atmo::sky::table::SkylightTable;
use atmo::sky::SkyModel;
use atmo::view::Sun;

use super::{GpuSkyModel, GpuSkyTable, SkyPass, SkyTarget};
use crate::{Gpu, GpuError, Rendered};

/// What a sky is drawn from (given once to [`SkyRenderer::new`], which keeps it: the
/// sizes of the variants do not matter).
#[allow(clippy::large_enum_variant)]
pub enum SkySource {
    /// The skylight table (sky 4): any sun and altitude within its ranges.
    Table(Arc<SkylightTable>),
    /// The shell method's model (sky 3): any sun, seen from the model's altitude.
    Model(SkyModel),
}

/// A sky on the GPU, from a model or a table (`M` and `T` borrowed or owned): what
/// a renderer that draws either keeps (the sizes of the variants do not matter).
#[allow(clippy::large_enum_variant)]
pub enum GpuSky<M: Borrow<SkyModel>, T: Borrow<SkylightTable>> {
    Model(GpuSkyModel<M>),
    Table(GpuSkyTable<T>),
}

impl<M: Borrow<SkyModel>, T: Borrow<SkylightTable>> GpuSky<M, T> {
    /// The one altitude a model draws from, m; `None` for a table (any of its range).
    pub fn model_altitude(&self) -> Option<f64> {
        match self {
            GpuSky::Model(sky) => Some(sky.model().altitude_m()),
            GpuSky::Table(_) => None,
        }
    }

    /// Records this frame's maps for `sun` seen from `altitude_m` (a model: from its
    /// own) into `encoder` and sets `pass` to draw them in `view`, as the model's and
    /// the table's `prepare`.
    pub fn prepare(
        &self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        pass: &mut SkyPass,
        sun: Sun,
        altitude_m: f64,
        view: &View,
    ) -> Result<(), GpuError> {
        match self {
            GpuSky::Model(sky) => sky.prepare(gpu, encoder, pass, sun, view),
            GpuSky::Table(sky) => sky.prepare(gpu, encoder, pass, sun, altitude_m, view),
        }
    }

    /// The picture of `view` for `sun` seen from `altitude_m` (a model: from its own),
    /// read back.
    pub fn render(
        &self,
        gpu: &Gpu,
        pass: &mut SkyPass,
        sun: Sun,
        altitude_m: f64,
        view: &View,
    ) -> Result<Rendered, GpuError> {
        match self {
            GpuSky::Model(sky) => sky.render(gpu, pass, sun, view),
            GpuSky::Table(sky) => sky.render(gpu, pass, sun, altitude_m, view),
        }
    }
}

/// The sky on the CPU or on a GPU, from a table or a model (one a run: the sizes of the
/// variants do not matter).
#[allow(clippy::large_enum_variant)]
enum Drawer {
    CpuTable(Arc<SkylightTable>),
    CpuModel(SkyModel),
    /// The device, the sky on it and the headless pass drawn through, reused frame to
    /// frame.
    Gpu(Gpu, GpuSky<SkyModel, Arc<SkylightTable>>, SkyPass),
}

/// One renderer of the sky whatever it is drawn from and wherever it runs.
pub struct SkyRenderer {
    drawer: Drawer,
}

/// A frame's sky as the backend has it: a picture to draw on the CPU, or the GPU's pass
/// set up to be drawn into a render pass.
pub enum Prepared<'a> {
    Cpu(SkyPicture),
    Gpu(&'a SkyPass),
}

impl SkyRenderer {
    /// The sky of `source`, on `gpu` where given (uploaded there), else on the CPU.
    pub fn new(gpu: Option<&Gpu>, source: SkySource) -> Result<SkyRenderer, GpuError> {
        let pass = |gpu: &Gpu| SkyPass::new(gpu, SkyTarget::HEADLESS);
        let drawer = match (gpu, source) {
            (None, SkySource::Table(table)) => Drawer::CpuTable(table),
            (None, SkySource::Model(model)) => Drawer::CpuModel(model),
            (Some(gpu), SkySource::Table(table)) => {
                let sky = GpuSky::Table(GpuSkyTable::new(gpu, table)?);
                Drawer::Gpu(gpu.clone(), sky, pass(gpu)?)
            }
            (Some(gpu), SkySource::Model(model)) => {
                let sky = GpuSky::Model(GpuSkyModel::new(gpu, model)?);
                Drawer::Gpu(gpu.clone(), sky, pass(gpu)?)
            }
        };
        Ok(SkyRenderer { drawer })
    }

    /// The one altitude a model draws from, m; `None` for a table (any of its range).
    pub fn model_altitude(&self) -> Option<f64> {
        match &self.drawer {
            Drawer::CpuModel(model) => Some(model.altitude_m()),
            Drawer::CpuTable(_) => None,
            Drawer::Gpu(_, sky, _) => sky.model_altitude(),
        }
    }

    /// This frame's sky for `sun` seen from `altitude_m` in `view`: on the CPU the
    /// picture (for a caller that draws it its own way), on the GPU the maps recorded
    /// into `encoder` and the pass set to draw them. A model draws from its own altitude.
    pub fn prepare(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        sun: Sun,
        altitude_m: f64,
        view: &View,
    ) -> Result<Prepared<'_>, GpuError> {
        Ok(match &mut self.drawer {
            Drawer::CpuTable(table) => {
                Prepared::Cpu(SkyPicture::from_table(table, sun, altitude_m)?)
            }
            Drawer::CpuModel(model) => Prepared::Cpu(SkyPicture::new(model, sun)),
            Drawer::Gpu(gpu, sky, pass) => {
                sky.prepare(gpu, encoder, pass, sun, altitude_m, view)?;
                Prepared::Gpu(pass)
            }
        })
    }

    /// The picture of `view` for `sun` seen from `altitude_m` (a model: from its own),
    /// read back from the GPU where it runs there.
    pub fn frame(&mut self, sun: Sun, altitude_m: f64, view: &View) -> Result<Frame, GpuError> {
        Ok(match &mut self.drawer {
            Drawer::CpuTable(table) => SkyPicture::from_table(table, sun, altitude_m)?.render(view),
            Drawer::CpuModel(model) => SkyPicture::new(model, sun).render(view),
            Drawer::Gpu(gpu, sky, pass) => sky.render(gpu, pass, sun, altitude_m, view)?.frame,
        })
    }
}
