//! `atmo view clouds`'s pictures: the window's sun, wind and camera over the cloud of
//! `atmo clouds`'s flags, drawn by the library's [`CloudFrames`].

use anyhow::Result;
use atmo::image::Frame;
use atmo::view::{Camera, Sun};
use atmo_gpu::clouds::CloudsPass;
use atmo_gpu::cloudscape::CloudFrames;
use atmo_gpu::display::write_frame;
use atmo_gpu::Gpu;
use atmo_view::clouds::{CloudParams, CloudPictures};
use atmo_view::Picture;

use super::{camera_at, check_sun, Cloud};
use crate::backend::gpu_error;

/// The cloud as `atmo view clouds` draws it, frame after frame ([`CloudFrames`] keeps
/// what did not change).
pub struct WindowClouds {
    cloud: Cloud,
    frames: CloudFrames,
    /// On the GPU: the pass that puts the cloud over what is behind it.
    pass: Option<CloudsPass>,
}

impl WindowClouds {
    pub fn new(cloud: Cloud) -> WindowClouds {
        WindowClouds {
            frames: CloudFrames::new(cloud.scene.clone(), cloud.wind_s),
            cloud,
            pass: None,
        }
    }

    /// The window's first parameters: the still's.
    pub fn params(&self) -> CloudParams {
        let c = &self.cloud;
        CloudParams {
            sun_elevation_deg: c.sun_elevation,
            sun_azimuth_deg: c.sun_azimuth,
            camera: c.camera.position,
            look_at: c.look_at,
            fov_deg: c.fov_deg,
            wind_s: c.wind_s,
            exposure: c.display.exposure,
            tone: c.display.tone,
        }
    }

    /// The sun at `p`, its parameters checked (exit 2 naming the flag), and the light
    /// pass made right for it and the wind, on `gpu` where given (a `preview` on the CPU
    /// more coarsely lit).
    fn lit(&mut self, gpu: Option<&Gpu>, p: &CloudParams, preview: bool) -> Result<Sun> {
        check_sun(p.sun_elevation_deg, p.sun_azimuth_deg)?;
        atmo::error::check_positive("--exposure", p.exposure as f64, 1e12)?;
        atmo::error::check_range("--wind-s", p.wind_s as f64, 0.0, 1e5)?;
        let sun = Sun::from_degrees(p.sun_elevation_deg as f64, p.sun_azimuth_deg as f64)?;
        self.frames
            .light(gpu, sun, p.wind_s, preview)
            .map_err(gpu_error)?;
        Ok(sun)
    }

    /// The camera of a `size` picture at `p`, checked against the particles where the
    /// wind has carried them.
    fn camera(&self, p: &CloudParams, size: (u32, u32)) -> Result<Camera> {
        let fov_axis = self.cloud.fov_axis;
        let particles = self.frames.particles();
        Ok(camera_at(
            particles, fov_axis, p.camera, p.look_at, p.fov_deg, size,
        )?)
    }
}

impl CloudPictures for WindowClouds {
    fn draw(&mut self, p: &CloudParams, size: (u32, u32), preview: bool) -> Result<Frame> {
        let sun = self.lit(None, p, preview)?;
        let camera = self.camera(p, size)?;
        self.frames
            .draw(None, sun, p.wind_s, &camera, preview)
            .map_err(gpu_error)
    }

    fn draw_on(
        &mut self,
        gpu: &Gpu,
        encoder: &mut atmo_gpu::wgpu::CommandEncoder,
        picture: &mut Picture,
        p: &CloudParams,
    ) -> Result<()> {
        let sun = self.lit(Some(gpu), p, false)?;
        let camera = self.camera(p, picture.size)?;
        let frames = &mut self.frames;
        let (light, background) = frames.lighting(sun, &camera, false).map_err(gpu_error)?;
        let clouds = frames.on_gpu().expect("lit on the GPU above");
        let behind = background.unwrap_or_else(|| Frame::new(picture.size.0, picture.size.1));
        write_frame(gpu, &picture.texture, &behind);
        let pass = match &mut self.pass {
            Some(pass) => pass,
            slot => {
                slot.insert(CloudsPass::new(gpu, picture.texture.format(), 1).map_err(gpu_error)?)
            }
        };
        clouds
            .prepare(gpu, encoder, pass, &camera, &light)
            .map_err(gpu_error)?;
        picture.draw_over(encoder, |render| pass.draw(render));
        Ok(())
    }

    fn flags(&self) -> String {
        self.cloud.fixed_flags().to_string()
    }
}
