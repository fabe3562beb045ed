//! The shafts drawn on the CPU or a GPU, the backend a setting: one renderer for
//! `atmo shafts` (stills and animations).

use std::sync::Arc;
use std::time::Instant;

use atmo::image::Frame;
use atmo::shafts::adaptive::Counts;
use atmo::shafts::planes::ShadowMaps;
use atmo::shafts::{SamplePlanes, Scene};

use super::{GpuShafts, ShaftsMethod, ShaftsPass, ShaftsPipelines};
use crate::{Gpu, GpuError};

/// Where the shafts are drawn, and what is kept from frame to frame there (one a
/// renderer: the sizes of the variants do not matter).
#[allow(clippy::large_enum_variant)]
enum On {
    /// The sample planes on the CPU, each light's shadow map kept while it stands.
    Cpu(ShadowMaps),
    /// The passes compiled once; each frame uploads its scene.
    Gpu(Gpu, Arc<ShaftsPipelines>, ShaftsMethod),
}

/// The sample planes of any scene, frame after frame, on the CPU or a GPU.
pub struct ShaftsRenderer {
    on: On,
}

/// A frame of the shafts and what it took.
pub struct Drawn {
    pub frame: Frame,
    /// The GPU's own time for the frame, where it runs there and times its passes, ms.
    pub gpu_ms: Option<f64>,
    /// On the CPU: how many pixels' scattered light was computed and how many
    /// interpolated ([`atmo::shafts::PlaneSettings::adaptive`]).
    pub counts: Option<Counts>,
    /// On the CPU: shadow maps rebuilt for this frame (the lights that moved), and the
    /// time the maps and the planes' set-up took, ms.
    pub maps_rebuilt: usize,
    pub prepared_ms: f64,
}

impl ShaftsRenderer {
    /// The renderer on `gpu` where given (by `method`), else on the CPU.
    pub fn new(gpu: Option<&Gpu>, method: ShaftsMethod) -> Result<ShaftsRenderer, GpuError> {
        let on = match gpu {
            Some(gpu) => On::Gpu(gpu.clone(), ShaftsPipelines::new(gpu)?, method),
            None => On::Cpu(ShadowMaps::default()),
        };
        Ok(ShaftsRenderer { on })
    }

    /// Whether it draws on a GPU.
    pub fn on_gpu(&self) -> bool {
        matches!(self.on, On::Gpu(..))
    }

    /// Forgets the kept shadow maps: the objects changed (a map is kept by its light's
    /// pose alone).
    pub fn objects_changed(&mut self) {
        if let On::Cpu(maps) = &mut self.on {
            *maps = ShadowMaps::default();
        }
    }

    /// On the GPU: records `scene`'s passes into `encoder` and sets `pass` (made for
    /// the caller's target) to draw the picture, with no read-back. On the CPU: an
    /// error, as there is nothing to record ([`ShaftsRenderer::draw`] draws there).
    pub fn prepare(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        pass: &mut ShaftsPass,
        scene: &Scene,
    ) -> Result<(), GpuError> {
        match &self.on {
            On::Gpu(gpu, pipelines, method) => {
                let shafts = GpuShafts::with_pipelines(gpu, scene, pipelines.clone())?;
                shafts.prepare(gpu, encoder, pass, *method)
            }
            On::Cpu(_) => Err(atmo::Error::Invalid(
                "the shafts' passes were asked of the CPU's renderer".into(),
            )
            .into()),
        }
    }

    /// `scene`'s picture (read back from the GPU where it runs there).
    pub fn draw(&mut self, scene: &Scene) -> Result<Drawn, GpuError> {
        let start = Instant::now();
        Ok(match &mut self.on {
            On::Cpu(maps) => {
                let planes = SamplePlanes::with_shadow_maps(scene, maps.update(scene));
                let prepared_ms = start.elapsed().as_secs_f64() * 1e3;
                let (frame, counts) = planes.render_counted();
                Drawn {
                    frame,
                    gpu_ms: None,
                    counts: Some(counts),
                    maps_rebuilt: maps.rebuilt,
                    prepared_ms,
                }
            }
            On::Gpu(gpu, pipelines, method) => {
                let shafts = GpuShafts::with_pipelines(gpu, scene, pipelines.clone())?;
                let rendered = shafts.render(gpu, *method)?;
                Drawn {
                    frame: rendered.frame,
                    gpu_ms: rendered.gpu_ms,
                    counts: None,
                    maps_rebuilt: 0,
                    prepared_ms: 0.0,
                }
            }
        })
    }
}
