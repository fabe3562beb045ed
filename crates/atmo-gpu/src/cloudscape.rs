//! A cloud scene ([`atmo::cloudscape::Cloudscape`]) drawn frame after frame on the CPU
//! or the GPU, the backend a setting: [`CloudRenderer`] runs the light pass and the
//! drawing on either; [`CloudFrames`] keeps what does not change between frames (the
//! buffer lit for the last sun, the cloud's shadow, the sky around the cloud for the
//! camera's height, the particles where the wind took them) and redoes only what does.
//! `atmo clouds` and `atmo view clouds` both draw through it.

use atmo::clouds::render::{CloudLight, Scattering};
use atmo::clouds::shadow::CloudShadow;
use atmo::clouds::Diffusion;
use atmo::clouds::{Particle, Splat};
use atmo::cloudscape::{Cloudscape, CpuClouds, SkyAround};
use atmo::image::Frame;
use atmo::view::{Camera, Sun};
use glam::Vec3;

use crate::clouds::GpuClouds;
use crate::{Gpu, GpuError};

/// Texels a side of the cloud's shadow on the ground (some 10 m each across a cumulus).
pub const SHADOW_RESOLUTION: usize = 256;

/// How much coarser previews light the cloud than whole pictures: the intensity
/// buffer's and the shadow map's resolution divided by this (an eighth of the buffer's
/// cells, a quarter of the map's texels), while the picture itself is drawn at a
/// fraction of its size anyway.
pub const PREVIEW_COARSENING: usize = 2;

/// The coarsest intensity buffer a preview lights, voxels a side.
pub const PREVIEW_MIN_RESOLUTION: usize = 32;

/// The light pass and the drawing, on the CPU or on a GPU (one a run: the sizes of the
/// variants do not matter).
#[allow(clippy::large_enum_variant)]
pub enum CloudRenderer {
    Cpu(CpuClouds),
    /// The device and the cloud on it.
    Gpu(Box<(Gpu, GpuClouds)>),
}

impl CloudRenderer {
    /// The renderer of `particles` through a buffer of `resolution` voxels a side: on
    /// `gpu` where there is one, else on the CPU.
    pub fn new(
        gpu: Option<&Gpu>,
        particles: &[Particle],
        resolution: usize,
    ) -> Result<CloudRenderer, GpuError> {
        Ok(match gpu {
            Some(gpu) => CloudRenderer::Gpu(Box::new((
                gpu.clone(),
                GpuClouds::new(gpu, particles, resolution)?,
            ))),
            None => CloudRenderer::Cpu(CpuClouds::new(resolution)),
        })
    }

    /// The intensity buffer of `particles` (which may have moved) lit from `to_sun`.
    pub fn light(
        &mut self,
        particles: &[Particle],
        to_sun: Vec3,
        forward: f32,
        splat: Splat,
    ) -> Result<(), GpuError> {
        match self {
            CloudRenderer::Cpu(cpu) => cpu.light(particles, to_sun, forward, splat)?,
            CloudRenderer::Gpu(on) => {
                let (gpu, clouds) = &mut **on;
                clouds.move_particles(gpu, particles)?;
                clouds.light(gpu, to_sun, forward, splat)?;
            }
        }
        Ok(())
    }

    /// The picture of `particles` through `camera` lit by `light` over `background`
    /// (read back from the GPU where it runs there).
    pub fn draw(
        &self,
        particles: &[Particle],
        camera: &Camera,
        light: &CloudLight,
        background: Option<&Frame>,
    ) -> Result<Frame, GpuError> {
        Ok(match self {
            CloudRenderer::Cpu(cpu) => cpu.draw(particles, camera, light, background)?,
            CloudRenderer::Gpu(on) => {
                let (gpu, clouds) = &**on;
                clouds.render(gpu, camera, light, background)?.frame
            }
        })
    }
}

/// A renderer, the sun its intensity buffer was last lit by (none before its first
/// light pass, or after the wind moved the particles) and the cloud's shadow then.
struct Lit {
    renderer: CloudRenderer,
    sun: Option<Sun>,
    shadow: Option<CloudShadow>,
    /// Texels a side of the shadow map.
    shadow_resolution: usize,
}

impl Lit {
    fn new(renderer: CloudRenderer, shadow_resolution: usize) -> Lit {
        Lit {
            renderer,
            sun: None,
            shadow: None,
            shadow_resolution,
        }
    }
}

/// A cloud scene drawn frame after frame as its sun, wind and camera change: the light
/// pass run again only when the sun, the wind or the device changed, the sky around the
/// cloud made again only when the camera's height changed (the sky in front of it is
/// drawn from there). Previews, drawn on the CPU while a picture changes, are lit
/// [`PREVIEW_COARSENING`] times more coarsely and apart from the whole pictures (a
/// preview does not spoil the buffer the next whole picture reuses).
pub struct CloudFrames {
    scene: Cloudscape,
    /// The particles where the wind has carried them, and its seconds.
    particles: Vec<Particle>,
    wind_s: f32,
    /// The renderer of whole pictures, and whether it is the GPU's.
    whole: Option<(bool, Lit)>,
    /// The CPU's renderer of previews.
    preview: Option<Lit>,
    /// The sky around the cloud, and the camera height it was made for.
    sky: Option<(f32, Option<SkyAround>)>,
}

impl CloudFrames {
    /// The frames of `scene`, its particles carried `wind_s` seconds by the wind.
    pub fn new(scene: Cloudscape, wind_s: f32) -> CloudFrames {
        CloudFrames {
            particles: scene.blown(wind_s),
            wind_s,
            scene,
            whole: None,
            preview: None,
            sky: None,
        }
    }

    /// The scene drawn.
    pub fn scene(&self) -> &Cloudscape {
        &self.scene
    }

    /// The particles where the wind has carried them.
    pub fn particles(&self) -> &[Particle] {
        &self.particles
    }

    /// Makes the intensity buffer and the cloud's shadow right for `sun` and the
    /// particles `wind_s` seconds of wind on, on `gpu` where given (else the CPU; a
    /// `preview` on the CPU more coarsely lit): nothing where they already are.
    pub fn light(
        &mut self,
        gpu: Option<&Gpu>,
        sun: Sun,
        wind_s: f32,
        preview: bool,
    ) -> Result<(), GpuError> {
        if wind_s != self.wind_s {
            self.particles = self.scene.blown(wind_s);
            self.wind_s = wind_s;
            let lit = self
                .whole
                .iter_mut()
                .map(|(_, lit)| lit)
                .chain(&mut self.preview);
            lit.for_each(|lit| lit.sun = None);
            if let Some((_, Some(sky))) = &mut self.sky {
                sky.moved(&self.particles);
            }
        }
        let coarse = preview && gpu.is_none();
        let resolution = self.scene.resolution;
        if coarse && self.preview.is_none() {
            let coarser = (resolution / PREVIEW_COARSENING).max(PREVIEW_MIN_RESOLUTION);
            let renderer = CloudRenderer::Cpu(CpuClouds::new(coarser.min(resolution)));
            self.preview = Some(Lit::new(renderer, SHADOW_RESOLUTION / PREVIEW_COARSENING));
        }
        let on_gpu = gpu.is_some();
        if !coarse && !matches!(self.whole, Some((on, _)) if on == on_gpu) {
            let renderer = CloudRenderer::new(gpu, &self.particles, resolution)?;
            self.whole = Some((on_gpu, Lit::new(renderer, SHADOW_RESOLUTION)));
        }
        let (scene, particles) = (&self.scene, &self.particles);
        let lit = chosen(&mut self.whole, &mut self.preview, coarse).expect("made above");
        if lit.sun != Some(sun) {
            let (forward, splat) = (scene.forward, scene.splat);
            lit.renderer
                .light(particles, sun.toward(), forward, splat)?;
            lit.shadow = scene.shadow(particles, sun, lit.shadow_resolution)?;
            lit.sun = Some(sun);
        }
        Ok(())
    }

    /// Makes the sky around the cloud for `camera`'s height where the scene has a sky
    /// and it is not made yet (the sky models of the cloud's and the camera's heights:
    /// seconds with every order), or was made for another height.
    pub fn sky(&mut self, camera: &Camera) -> Result<(), GpuError> {
        let height = camera.position.y;
        if !matches!(self.sky, Some((h, _)) if h == height) {
            let sky = self.scene.sky_around(&self.particles, camera)?;
            self.sky = Some((height, sky));
        }
        Ok(())
    }

    /// Sunlight and sky light at the cloud for `sun`, and what `camera` sees behind it
    /// (the sky around the cloud made again where the camera's height changed), under
    /// the shadow of the previews' light pass where `coarse`, else the whole pictures'.
    pub fn lighting(
        &mut self,
        sun: Sun,
        camera: &Camera,
        coarse: bool,
    ) -> Result<(CloudLight, Option<Frame>), GpuError> {
        self.sky(camera)?;
        let scene = &self.scene;
        let sky = self.sky.as_ref().and_then(|(_, sky)| sky.as_ref());
        let lit = chosen(&mut self.whole, &mut self.preview, coarse).ok_or_else(|| {
            atmo::Error::Invalid("the clouds were drawn before their light pass".into())
        })?;
        Ok(scene.lighting(sky, lit.shadow.as_ref(), sun, camera)?)
    }

    /// The picture for `sun`, `wind_s` seconds of wind and `camera`: on `gpu` where
    /// given (read back), else on the CPU (a `preview` more coarsely lit).
    pub fn draw(
        &mut self,
        gpu: Option<&Gpu>,
        sun: Sun,
        wind_s: f32,
        camera: &Camera,
        preview: bool,
    ) -> Result<Frame, GpuError> {
        self.light(gpu, sun, wind_s, preview)?;
        let coarse = preview && gpu.is_none();
        let (mut light, background) = self.lighting(sun, camera, coarse)?;
        // Previews solve the orders past the first on a grid as much coarser as their
        // light pass (a sun move's preview at 1280 x 720 took 198 ms on the full grid).
        if let (true, Scattering::Solve(d)) = (coarse, light.scattering) {
            let cells = (d.cells / PREVIEW_COARSENING).max(8);
            light.scattering = Scattering::Solve(Diffusion { cells });
        }
        let lit = chosen(&mut self.whole, &mut self.preview, coarse).expect("lit above");
        lit.renderer
            .draw(&self.particles, camera, &light, background.as_ref())
    }

    /// The cloud on the GPU, once [`CloudFrames::light`] ran there: to record its
    /// passes into a caller's encoder (`GpuClouds::prepare`).
    pub fn on_gpu(&self) -> Option<&GpuClouds> {
        match &self.whole {
            Some((true, Lit { renderer, .. })) => match renderer {
                CloudRenderer::Gpu(on) => Some(&on.1),
                CloudRenderer::Cpu(_) => None,
            },
            _ => None,
        }
    }

    /// The CPU renderer's buffer resolution and shadow map resolution, of the previews'
    /// where `coarse`, else of the whole pictures' (once lit on the CPU).
    pub fn resolutions(&self, coarse: bool) -> Option<(usize, usize)> {
        let lit = if coarse {
            self.preview.as_ref()
        } else {
            self.whole.as_ref().map(|(_, lit)| lit)
        }?;
        match &lit.renderer {
            CloudRenderer::Cpu(cpu) => Some((
                cpu.buffer()?.resolution,
                lit.shadow.as_ref().map_or(0, |s| s.resolution),
            )),
            CloudRenderer::Gpu(_) => None,
        }
    }

    /// How many times the whole pictures' CPU renderer made the particles' depths.
    pub fn depths_made(&self) -> usize {
        match &self.whole {
            Some((
                _,
                Lit {
                    renderer: CloudRenderer::Cpu(cpu),
                    ..
                },
            )) => cpu.depths_made(),
            _ => 0,
        }
    }

    /// The sun the renderer of previews (`coarse`) or of whole pictures was last lit by.
    pub fn lit_by(&self, coarse: bool) -> Option<Sun> {
        if coarse {
            self.preview.as_ref()?.sun
        } else {
            self.whole.as_ref()?.1.sun
        }
    }
}

/// Of the renderers, the previews' where `coarse`, else the whole pictures'.
fn chosen<'a>(
    whole: &'a mut Option<(bool, Lit)>,
    preview: &'a mut Option<Lit>,
    coarse: bool,
) -> Option<&'a mut Lit> {
    if coarse {
        preview.as_mut()
    } else {
        whole.as_mut().map(|(_, lit)| lit)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use atmo::atmosphere::PhaseFunction;
    use atmo::clouds::{Cumulus, Scattering};
    use atmo::cloudscape::Ambient;
    use atmo::view::Fov;

    /// 300 particles through a `resolution` buffer, over a painted ground (so that it
    /// has a shadow map) or in front of the sky.
    fn scene(resolution: usize, sky: bool) -> Cloudscape {
        Cloudscape {
            calm: Cumulus {
                particles: 300,
                ..Cumulus::default()
            }
            .generate(),
            resolution,
            forward: 0.0,
            splat: Splat::Pieces,
            phase: PhaseFunction::CloudMie,
            scattering: Scattering::MULTIPLE,
            ambient: if sky {
                atmo::cloudscape::Ambient::Sky
            } else {
                Ambient::Rgb(Vec3::ZERO)
            },
            sky,
            ground_albedo: (!sky).then_some(0.3),
        }
    }

    fn camera(frames: &CloudFrames, size: (u32, u32)) -> Camera {
        let centre = Cloudscape::centre_of(frames.particles());
        let eye = centre + Vec3::new(-1500.0, -300.0, 2500.0);
        Camera::look_at(eye, centre, Vec3::Y, Fov::Vertical(40.0), size).unwrap()
    }

    #[test]
    fn previews_are_lit_coarsely_apart_from_the_whole_pictures() {
        let whole_size = (64, 36);
        let mut frames = CloudFrames::new(scene(64, false), 0.0);
        let mut sun = Sun::from_degrees(20.0, 40.0).unwrap();
        let mut wind_s = 0.0;
        let cam = camera(&frames, whole_size);
        frames.draw(None, sun, wind_s, &cam, false).unwrap();
        // The sun and then the wind move while previews are drawn; each whole picture
        // after them is the one fresh frames draw, bit for bit (its own light pass
        // redone for the new sun and particles, not the preview's reused).
        for change in [0, 1] {
            if change == 0 {
                sun = Sun::from_degrees(20.0, 50.0).unwrap();
            } else {
                wind_s = 120.0;
            }
            let small = camera(&frames, (16, 9));
            let preview = frames.draw(None, sun, wind_s, &small, true).unwrap();
            assert_eq!((preview.width, preview.height), (16, 9));
            assert_eq!(frames.lit_by(true), Some(sun));
            // Half the whole pictures' resolution (at least 32 voxels), half the map's.
            assert_eq!(frames.resolutions(true), Some((32, SHADOW_RESOLUTION / 2)));
            let whole = frames.draw(None, sun, wind_s, &cam, false).unwrap();
            assert_eq!(frames.resolutions(false), Some((64, SHADOW_RESOLUTION)));
            let fresh = CloudFrames::new(scene(64, false), 0.0)
                .draw(None, sun, wind_s, &cam, false)
                .unwrap();
            assert!(whole.pixels == fresh.pixels, "change {change}");
        }
    }

    /// With the sky's light dimmed inside the cloud, frames on the CPU keep the
    /// particles' depths in the cloud while only the sun moves and make them again once
    /// the wind has moved the particles: each picture is fresh frames', bit for bit.
    #[test]
    fn the_sky_depths_are_kept_while_the_particles_stay() {
        let size = (48, 27);
        let mut frames = CloudFrames::new(scene(32, true), 0.0);
        let cam = camera(&frames, size);
        let fresh = |sun: Sun, wind_s: f32| {
            CloudFrames::new(scene(32, true), 0.0)
                .draw(None, sun, wind_s, &cam, false)
                .unwrap()
        };
        let sun = Sun::from_degrees(20.0, 40.0).unwrap();
        frames.draw(None, sun, 0.0, &cam, false).unwrap();
        assert_eq!(frames.depths_made(), 1);
        let turned = Sun::from_degrees(20.0, 70.0).unwrap();
        let lit = frames.draw(None, turned, 0.0, &cam, false).unwrap();
        assert_eq!(
            frames.depths_made(),
            1,
            "the same depths for the same particles"
        );
        assert!(lit.pixels == fresh(turned, 0.0).pixels);
        let blown = frames.draw(None, turned, 120.0, &cam, false).unwrap();
        assert_eq!(frames.depths_made(), 2, "made again for moved particles");
        assert!(blown.pixels == fresh(turned, 120.0).pixels);
    }
}
