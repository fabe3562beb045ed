//! Clouds in the window: the sun moved and the camera orbited around a particle cloud
//! (`atmo clouds`), the picture drawn by whoever made the cloud ([`CloudPictures`]: the
//! command line, which owns the cloud's flags) on the CPU or on the GPU.
//!
//! The window changes the sun, the camera and the display, each by the `atmo clouds`
//! flag that sets it; a screenshot prints the cloud's own flags with these.

use anyhow::Result;
use atmo::image::{Display, Frame, ToneMap};
use atmo_gpu::Gpu;
use glam::Vec3;

use crate::input::{unknown_parameter, Input, Key, Script};
use crate::panel::{edits, not, number, tone_name, tone_named};
use crate::{Mode, Picture};

/// The sun's azimuth per frame while the sun goes round, degrees.
const SUN_STEP_DEG: f64 = 1.0;

/// The wind's time per frame while the wind blows, s (`atmo clouds --animate wind`'s).
const WIND_STEP_S: f32 = 4.0;

/// What the window changes, each the value of one of `atmo clouds`'s flags.
#[derive(Debug, Clone, PartialEq)]
pub struct CloudParams {
    /// `--sun-elevation`, degrees.
    pub sun_elevation_deg: f32,
    /// `--sun-azimuth`, degrees clockwise from north.
    pub sun_azimuth_deg: f32,
    /// `--camera`, m.
    pub camera: Vec3,
    /// `--look-at`, m.
    pub look_at: Vec3,
    /// `--fov`, degrees.
    pub fov_deg: f32,
    /// `--wind-s`: how long the breeze has carried the particles, s.
    pub wind_s: f32,
    /// `--exposure`.
    pub exposure: f32,
    /// `--tone-map`.
    pub tone: ToneMap,
}

impl CloudParams {
    /// Each parameter by its flag's name, with its value as the flag reads it (floats
    /// printed exactly, so that the still command gives the same picture).
    pub fn fields(&self) -> Vec<(&'static str, String)> {
        let v = |v: Vec3| format!("{},{},{}", v.x, v.y, v.z);
        vec![
            ("sun-elevation", self.sun_elevation_deg.to_string()),
            ("sun-azimuth", self.sun_azimuth_deg.to_string()),
            ("camera", v(self.camera)),
            ("look-at", v(self.look_at)),
            ("fov", self.fov_deg.to_string()),
            ("wind-s", self.wind_s.to_string()),
            ("exposure", self.exposure.to_string()),
            ("tone-map", tone_name(self.tone).to_string()),
        ]
    }

    /// The parameters' names.
    fn names(&self) -> Vec<&'static str> {
        self.fields().iter().map(|(n, _)| *n).collect()
    }

    /// The flags of `atmo clouds` that give these parameters.
    pub fn flags(&self) -> String {
        let flags: Vec<String> = self
            .fields()
            .into_iter()
            .map(|(name, value)| format!("--{name} {value}"))
            .collect();
        flags.join(" ")
    }

    /// Sets the parameter `name` (a flag's name) from `value`; an unknown name or a
    /// value that does not parse is an error naming it.
    pub fn set(&mut self, name: &str, value: &str) -> atmo::Result<()> {
        let number = || number(name, value).map(|v| v as f32);
        let vector = || {
            let v: Vec<f32> = value
                .split(',')
                .filter_map(|c| c.trim().parse().ok())
                .collect();
            match v[..] {
                [x, y, z] if v.iter().all(|c| c.is_finite()) => Ok(Vec3::new(x, y, z)),
                _ => Err(not(name, value, "X,Y,Z (three finite numbers)")),
            }
        };
        match name {
            "sun-elevation" => self.sun_elevation_deg = number()?,
            "sun-azimuth" => self.sun_azimuth_deg = number()?,
            "camera" => self.camera = vector()?,
            "look-at" => self.look_at = vector()?,
            "fov" => self.fov_deg = number()?,
            "wind-s" => self.wind_s = number()?,
            "exposure" => self.exposure = number()?,
            "tone-map" => self.tone = tone_named(name, value)?,
            _ => return Err(unknown_parameter(name, "the clouds", &self.names())),
        }
        Ok(())
    }
}

/// Draws the cloud's pictures: made by the command line from `atmo clouds`'s flags.
/// The light pass is run again only where the sun or the wind changed; parameters the
/// cloud cannot be drawn at (a sun below the horizon, a camera inside a particle) are
/// refused, naming the flag.
pub trait CloudPictures {
    /// The picture at `params` and `size` on the CPU (linear radiance); a `preview`
    /// ([`Picture::preview`]) may be drawn more coarsely than the still would be.
    fn draw(&mut self, params: &CloudParams, size: (u32, u32), preview: bool) -> Result<Frame>;
    /// The picture at `params` drawn into `picture` on the GPU: what is behind the
    /// cloud uploaded, the billboards recorded into `encoder` and put over it, with no
    /// read-back.
    fn draw_on(
        &mut self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        picture: &mut Picture,
        params: &CloudParams,
    ) -> Result<()>;
    /// `atmo clouds`'s flags for the cloud and its light: all but [`CloudParams`].
    fn flags(&self) -> String;
}

/// The clouds mode: the parameters, the sun's animation and the drawer.
pub struct CloudsMode {
    pub params: CloudParams,
    pictures: Box<dyn CloudPictures>,
    /// The sun going round, a degree a frame.
    pub animate: bool,
    /// The wind blowing, 4 s of it a frame.
    pub wind: bool,
    /// The orbit's step for keys, degrees.
    pub step_deg: f32,
    on_gpu: bool,
    /// What the picture shows now: its parameters, size and backend.
    drawn: Option<(CloudParams, (u32, u32), bool)>,
    /// The picture is a preview ([`Picture::preview`]), to be drawn whole.
    coarse: bool,
}

impl CloudsMode {
    /// The mode at `params`, drawn by `pictures`.
    pub fn new(mut params: CloudParams, pictures: Box<dyn CloudPictures>) -> CloudsMode {
        // The panel's azimuth runs over [0, 360).
        params.sun_azimuth_deg = params.sun_azimuth_deg.rem_euclid(360.0);
        CloudsMode {
            params,
            pictures,
            animate: false,
            wind: false,
            step_deg: 5.0,
            on_gpu: false,
            drawn: None,
            coarse: false,
        }
    }
}

/// The camera of `p` moved about the point it looks at (see [`crate::orbit`]).
fn orbit_camera(p: &mut CloudParams, yaw_deg: f32, pitch_deg: f32, scale: f32) {
    p.camera = crate::orbit(p.camera, p.look_at, yaw_deg, pitch_deg, scale);
}

impl Mode for CloudsMode {
    fn title(&self) -> &'static str {
        "atmo clouds"
    }

    fn check_script(&self, script: &Script) -> atmo::Result<()> {
        script.check_parameters("the clouds", &self.params.names())
    }

    fn draw_on_gpu(&mut self, on_gpu: bool) {
        self.on_gpu = on_gpu;
    }

    /// Applies `input` to a copy of the parameters; the copy is checked when it is
    /// drawn, and a refused one leaves the last good parameters.
    fn apply(&mut self, input: &Input) -> Result<()> {
        let p = &mut self.params;
        let step = self.step_deg;
        match input {
            Input::Key(key) => match key {
                Key::SunLeft => p.sun_azimuth_deg = (p.sun_azimuth_deg - 5.0).rem_euclid(360.0),
                Key::SunRight => p.sun_azimuth_deg = (p.sun_azimuth_deg + 5.0).rem_euclid(360.0),
                Key::SunUp => p.sun_elevation_deg += 1.0,
                Key::SunDown => p.sun_elevation_deg -= 1.0,
                Key::Climb => orbit_camera(p, 0.0, 0.0, 1.0 - step / 50.0),
                Key::Descend => orbit_camera(p, 0.0, 0.0, 1.0 / (1.0 - step / 50.0)),
                Key::Faster => self.step_deg = (step * 2.0).min(45.0),
                Key::Slower => self.step_deg = step / 2.0,
                Key::Animate => self.animate = !self.animate,
                Key::Wind => self.wind = !self.wind,
                Key::Screenshot | Key::ScreenshotExr | Key::Panel | Key::Save => {}
            },
            Input::Drag(dx, dy) => orbit_camera(p, -0.3 * dx, 0.3 * dy, 1.0),
            Input::Aim(..) => {}
            Input::Set(name, value) => p.set(name, value)?,
        }
        Ok(())
    }

    fn update(&mut self) -> Result<()> {
        let p = &mut self.params;
        if self.animate {
            p.sun_azimuth_deg = ((p.sun_azimuth_deg as f64 + SUN_STEP_DEG) % 360.0) as f32;
        }
        if self.wind {
            p.wind_s += WIND_STEP_S;
        }
        Ok(())
    }

    /// Draws where the parameters, the size or the backend changed; parameters the
    /// cloud refuses go back to the last drawn.
    fn draw(
        &mut self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        picture: &mut Picture,
    ) -> Result<bool> {
        let now = (self.params.clone(), picture.size, self.on_gpu);
        let changed = self.drawn.as_ref() != Some(&now);
        if !changed && !self.coarse {
            return Ok(false);
        }
        let drawn = if self.on_gpu {
            self.pictures.draw_on(gpu, encoder, picture, &self.params)
        } else {
            let (pictures, params, whole) = (&mut self.pictures, &self.params, picture.size);
            picture
                .draw_cpu(changed, |size| pictures.draw(params, size, size != whole))
                .map(|coarse| self.coarse = coarse)
        };
        match drawn {
            Ok(()) => {
                self.drawn = Some(now);
                Ok(true)
            }
            Err(e) => {
                if let Some((last, _, _)) = &self.drawn {
                    self.params = last.clone();
                }
                (self.animate, self.wind) = (false, false);
                Err(e)
            }
        }
    }

    fn display(&self) -> Display {
        Display {
            exposure: self.params.exposure,
            tone: self.params.tone,
        }
    }

    fn still_command(&self, output: &std::path::Path, (width, height): (u32, u32)) -> String {
        let backend = if self.on_gpu { "gpu" } else { "cpu" };
        format!(
            "atmo clouds {} {} --width {width} --height {height} --backend {backend} -o {}",
            self.pictures.flags(),
            self.params.flags(),
            output.display()
        )
    }

    fn panel(&mut self, ui: &mut egui::Ui) -> Vec<Input> {
        let mut p = self.params.clone();
        let mut animate = self.animate;
        ui.add(
            crate::panel::slider(&mut p.sun_elevation_deg, 0.5..=90.0).text("sun elevation, deg"),
        );
        ui.add(crate::panel::slider(&mut p.sun_azimuth_deg, 0.0..=359.9).text("sun azimuth, deg"));
        ui.checkbox(&mut animate, "the sun goes round (space)");
        let mut wind = self.wind;
        ui.checkbox(&mut wind, "the wind blows (W)");
        ui.add(crate::panel::slider(&mut p.wind_s, 0.0..=3600.0).text("wind, s"));
        ui.separator();
        ui.label(format!(
            "camera at {:.0}, {:.0}, {:.0} m (drag to orbit, R / F nearer / farther)",
            p.camera.x, p.camera.y, p.camera.z
        ));
        ui.add(crate::panel::slider(&mut p.fov_deg, 1.0..=170.0).text("field of view, deg"));
        crate::panel::display(ui, &mut p.exposure, &mut p.tone);
        let mut inputs = edits(p.fields(), self.params.fields());
        if animate != self.animate {
            inputs.push(Input::Key(Key::Animate));
        }
        if wind != self.wind {
            inputs.push(Input::Key(Key::Wind));
        }
        inputs
    }

    fn help(&self) -> &'static str {
        "drag: orbit; arrows: sun; R / F: nearer / farther; space: the sun goes round; W: \
         wind"
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn params() -> CloudParams {
        CloudParams {
            sun_elevation_deg: 20.0,
            sun_azimuth_deg: 40.0,
            camera: Vec3::new(-2200.0, 1900.0, 2200.0),
            look_at: Vec3::new(0.0, 1900.0, 0.0),
            fov_deg: 50.0,
            wind_s: 0.0,
            exposure: 0.05,
            tone: ToneMap::Aces,
        }
    }

    #[test]
    fn every_field_sets_back_to_itself_and_bad_edits_name_the_parameter() {
        let p = CloudParams {
            camera: Vec3::new(-2200.125, 1900.5, 2199.75),
            ..params()
        };
        let mut q = params();
        for (name, value) in p.fields() {
            q.set(name, &value).unwrap();
        }
        assert_eq!(p, q);
        assert!(p.flags().contains("--camera -2200.125,1900.5,2199.75 "));
        for (name, value, says) in [
            ("camera", "1,2", "X,Y,Z"),
            ("fov", "wide", "finite number"),
            ("colour", "red", "no parameter 'colour'"),
        ] {
            let e = q.set(name, value).unwrap_err().to_string();
            assert!(e.contains(name) && e.contains(says), "{e}");
        }
        assert_eq!(p, q, "a refused edit changes nothing");
    }

    #[test]
    fn an_orbit_keeps_the_distance_and_the_point_looked_at() {
        let mut p = params();
        let distance = (p.camera - p.look_at).length();
        orbit_camera(&mut p, 90.0, 0.0, 1.0);
        assert!(((p.camera - p.look_at).length() - distance).abs() < 1e-3 * distance);
        // A quarter turn about the vertical: from south-west to south-east (x east, z
        // south).
        assert!(
            (p.camera - Vec3::new(2200.0, 1900.0, 2200.0)).length() < 1.0,
            "{}",
            p.camera
        );
        orbit_camera(&mut p, 0.0, 0.0, 0.5);
        assert!(((p.camera - p.look_at).length() - 0.5 * distance).abs() < 1e-3 * distance);
    }
}
