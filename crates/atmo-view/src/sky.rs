//! The sky in the window: the parameters of `atmo sky`'s pictures, changed by the
//! panel, the keys, the mouse and scripts, drawn each frame from a skylight table or by
//! the shell method, on the CPU or on the GPU.

use std::sync::Arc;

use anyhow::Result;
use atmo::image::{Display, ToneMap};
use atmo::sky::table::SkylightTable;
use atmo::sky::{SkyModel, SkyPicture, SkySettings, View};
use atmo::view::{Camera, Fov, Sun};
use atmo::{Atmosphere, Error};
use atmo_gpu::sky::{Prepared, SkyRenderer, SkySource as RenderedFrom};
use atmo_gpu::Gpu;
use glam::Vec3;

use crate::input::{Input, Key, Script};
use crate::panel::{edits, not, number, tone_name, tone_named};
use crate::{Mode, Picture};

/// What `atmo sky` draws from.
pub enum SkySource {
    /// A skylight table (`atmo precompute sky`): any sun and altitude in its ranges.
    Table(Arc<SkylightTable>),
    /// The shell method: the model is rebuilt when the altitude changes.
    Shells {
        atmosphere: Box<Atmosphere>,
        settings: SkySettings,
    },
}

/// The picture's parameters, each the value of one of `atmo sky`'s flags.
#[derive(Debug, Clone, PartialEq)]
pub struct SkyParams {
    /// `--sun-elevation`, degrees.
    pub sun_elevation_deg: f64,
    /// `--sun-azimuth`, degrees clockwise from north, in [0, 360).
    pub sun_azimuth_deg: f64,
    /// `--altitude`, metres.
    pub altitude_m: f64,
    /// `--yaw`, degrees clockwise from north.
    pub yaw_deg: f64,
    /// `--pitch`, degrees.
    pub pitch_deg: f64,
    /// `--fov`, vertical, degrees.
    pub fov_deg: f64,
    /// `--fisheye`.
    pub fisheye: bool,
    /// Not `--no-sun-disc`.
    pub sun_disc: bool,
    /// `--exposure`.
    pub exposure: f32,
    /// `--tone-map`.
    pub tone: ToneMap,
}

impl SkyParams {
    /// The sun.
    pub fn sun(&self) -> atmo::Result<Sun> {
        Sun::from_degrees(self.sun_elevation_deg, self.sun_azimuth_deg)
    }

    /// Refuses a sun out of range, an altitude below the ground or not a number, or an
    /// exposure that is not positive, naming the field (the model refuses an altitude
    /// above its atmosphere's top).
    pub fn validate(&self) -> atmo::Result<()> {
        self.sun()?;
        if !(self.altitude_m.is_finite() && self.altitude_m >= 0.0) {
            return Err(Error::out_of_range(
                "altitude_m",
                self.altitude_m,
                "[0, the atmosphere's top) m",
            ));
        }
        if !(self.exposure.is_finite() && self.exposure > 0.0) {
            return Err(Error::out_of_range(
                "exposure",
                self.exposure as f64,
                "(0, inf)",
            ));
        }
        Ok(())
    }

    /// The view of a `width` x `height` picture, as `atmo sky` makes it.
    pub fn view(&self, (width, height): (u32, u32)) -> atmo::Result<View> {
        let eye = Vec3::new(0.0, self.altitude_m as f32, 0.0);
        let camera = if self.fisheye {
            Camera::dome(eye, (width, height))?
        } else {
            let fov = Fov::Vertical(self.fov_deg as f32);
            Camera::yaw_pitch(eye, self.yaw_deg, self.pitch_deg, fov, (width, height))?
        };
        Ok(View {
            camera,
            sun_disc: self.sun_disc,
        })
    }

    /// Each parameter by its flag's name, with its value as the flag reads it (floats
    /// printed exactly: the still command gives the same picture).
    pub fn fields(&self) -> Vec<(&'static str, String)> {
        vec![
            ("sun-elevation", self.sun_elevation_deg.to_string()),
            ("sun-azimuth", self.sun_azimuth_deg.to_string()),
            ("altitude", self.altitude_m.to_string()),
            ("yaw", self.yaw_deg.to_string()),
            ("pitch", self.pitch_deg.to_string()),
            ("fov", self.fov_deg.to_string()),
            ("fisheye", self.fisheye.to_string()),
            ("sun-disc", self.sun_disc.to_string()),
            ("exposure", self.exposure.to_string()),
            ("tone-map", tone_name(self.tone).to_string()),
        ]
    }

    /// The parameters' names.
    fn names() -> Vec<&'static str> {
        SkyParams::default()
            .fields()
            .iter()
            .map(|(n, _)| *n)
            .collect()
    }

    /// The flags of `atmo sky` that give these parameters.
    pub fn flags(&self) -> String {
        let mut out = Vec::new();
        for (name, value) in self.fields() {
            match (name, value.as_str()) {
                ("fisheye", "true") => out.push("--fisheye".to_string()),
                ("sun-disc", "false") => out.push("--no-sun-disc".to_string()),
                ("fisheye" | "sun-disc", _) => {}
                _ => out.push(format!("--{name} {value}")),
            }
        }
        out.join(" ")
    }

    /// Sets the parameter `name` (a flag's name) from `value`; an unknown name or a
    /// value that does not parse is an error naming it.
    pub fn set(&mut self, name: &str, value: &str) -> atmo::Result<()> {
        let number = || number(name, value);
        let flag = || {
            value
                .parse::<bool>()
                .map_err(|_| not(name, value, "true or false"))
        };
        match name {
            "sun-elevation" => self.sun_elevation_deg = number()?,
            "sun-azimuth" => self.sun_azimuth_deg = number()?,
            "altitude" => self.altitude_m = number()?,
            "yaw" => self.yaw_deg = number()?,
            "pitch" => self.pitch_deg = number()?,
            "fov" => self.fov_deg = number()?,
            "fisheye" => self.fisheye = flag()?,
            "sun-disc" => self.sun_disc = flag()?,
            "exposure" => self.exposure = number()? as f32,
            "tone-map" => self.tone = tone_named(name, value)?,
            _ => return Err(unknown_parameter(name)),
        }
        Ok(())
    }
}

/// The error for a parameter the sky does not have, listing those it has.
pub fn unknown_parameter(name: &str) -> Error {
    crate::input::unknown_parameter(name, "the sky", &SkyParams::names())
}

impl Default for SkyParams {
    /// `atmo sky`'s defaults (the camera toward the sun).
    fn default() -> Self {
        SkyParams {
            sun_elevation_deg: 30.0,
            sun_azimuth_deg: 180.0,
            altitude_m: 0.0,
            yaw_deg: 180.0,
            pitch_deg: 15.0,
            fov_deg: 70.0,
            fisheye: false,
            sun_disc: true,
            exposure: 0.15,
            tone: ToneMap::Exponential,
        }
    }
}

/// The sky mode: parameters, how they change, and the drawer.
pub struct SkyMode {
    pub params: SkyParams,
    source: SkySource,
    /// `atmo sky`'s flags for the source (`--table FILE`, or the atmosphere's and the
    /// method's), repeated in the still command.
    source_flags: String,
    /// The climb per key press, metres.
    pub step_m: f64,
    /// The time-of-day animation: the sun sets by `SUNSET_STEP_DEG` a frame.
    pub animate: bool,
    drawer: Option<SkyRenderer>,
    on_gpu: bool,
}

/// The sun's descent per frame while animated, degrees.
const SUNSET_STEP_DEG: f64 = 0.25;

impl SkyMode {
    /// The mode at `params` (checked) drawing from `source`, on the CPU until
    /// [`SkyMode::draw_on_gpu`] says otherwise.
    pub fn new(params: SkyParams, source: SkySource, source_flags: String) -> Result<SkyMode> {
        let mode = SkyMode {
            params: params.clone(),
            source,
            source_flags,
            step_m: 250.0,
            animate: false,
            drawer: None,
            on_gpu: false,
        };
        mode.check(&params)?;
        Ok(mode)
    }

    /// The sun's elevation range, degrees: the table's, or the whole sky's.
    pub fn sun_range(&self) -> (f64, f64) {
        match &self.source {
            SkySource::Table(t) => (
                t.sun_axis().min().to_degrees(),
                t.sun_axis().max().to_degrees(),
            ),
            SkySource::Shells { .. } => (-10.0, 90.0),
        }
    }

    /// The altitude range, metres: the table's, or up to the atmosphere's top.
    pub fn altitude_range(&self) -> (f64, f64) {
        match &self.source {
            SkySource::Table(t) => (t.altitude_axis().min(), t.altitude_axis().max()),
            SkySource::Shells { atmosphere, .. } => (
                0.0,
                atmosphere.top_radius_m - atmosphere.bottom_radius_m - 1.0,
            ),
        }
    }

    /// Refuses parameters the sky cannot draw, with a message naming the field.
    fn check(&self, p: &SkyParams) -> Result<()> {
        p.validate()?;
        p.view((2, 2))?;
        let sun = p.sun()?;
        match &self.source {
            SkySource::Table(t) => drop(t.coefficients(sun.elevation(), p.altitude_m)?),
            SkySource::Shells { .. } => {
                let (low, high) = self.altitude_range();
                if !(low..=high).contains(&p.altitude_m) {
                    let range = format!("[{low}, {high}]");
                    return Err(Error::out_of_range("altitude_m", p.altitude_m, &range).into());
                }
            }
        }
        Ok(())
    }

    /// The renderer of the mode's source on its backend: a model built at the
    /// parameters' altitude (the shell method).
    fn make_drawer(&self, gpu: &Gpu) -> Result<SkyRenderer> {
        let source = match &self.source {
            SkySource::Table(t) => RenderedFrom::Table(t.clone()),
            SkySource::Shells {
                atmosphere,
                settings,
            } => RenderedFrom::Model(SkyModel::new(atmosphere, settings, self.params.altitude_m)?),
        };
        Ok(SkyRenderer::new(self.on_gpu.then_some(gpu), source)?)
    }
}

impl Mode for SkyMode {
    fn title(&self) -> &'static str {
        "atmo sky"
    }

    fn check_script(&self, script: &Script) -> atmo::Result<()> {
        script.check_parameters("the sky", &SkyParams::names())
    }

    fn draw_on_gpu(&mut self, on_gpu: bool) {
        if on_gpu != self.on_gpu {
            self.on_gpu = on_gpu;
            self.drawer = None;
        }
    }

    fn apply(&mut self, input: &Input) -> Result<()> {
        let mut p = self.params.clone();
        match input {
            Input::Key(key) => match key {
                Key::Climb => p.altitude_m += self.step_m,
                Key::Descend => p.altitude_m -= self.step_m,
                Key::Faster => self.step_m *= 2.0,
                Key::Slower => self.step_m /= 2.0,
                Key::SunLeft => p.sun_azimuth_deg = (p.sun_azimuth_deg - 5.0).rem_euclid(360.0),
                Key::SunRight => p.sun_azimuth_deg = (p.sun_azimuth_deg + 5.0).rem_euclid(360.0),
                Key::SunUp => p.sun_elevation_deg += 1.0,
                Key::SunDown => p.sun_elevation_deg -= 1.0,
                Key::Animate => self.animate = !self.animate,
                // The window's own keys, and the stage's.
                Key::Screenshot | Key::ScreenshotExr | Key::Panel | Key::Save | Key::Wind => {}
            },
            Input::Drag(dx, dy) if !p.fisheye => {
                p.yaw_deg = (p.yaw_deg + 0.2 * *dx as f64).rem_euclid(360.0);
                p.pitch_deg = (p.pitch_deg - 0.2 * *dy as f64).clamp(-89.0, 89.0);
            }
            Input::Drag(..) | Input::Aim(..) => {}
            Input::Set(name, value) => p.set(name, value)?,
        }
        if p != self.params {
            self.check(&p)?;
            self.params = p;
        }
        Ok(())
    }

    /// Advances the animation by a frame: the sun sets to the lowest elevation drawn,
    /// then rises again at 60 deg (or the highest).
    fn update(&mut self) -> Result<()> {
        if self.animate {
            let (low, high) = self.sun_range();
            let next = self.params.sun_elevation_deg - SUNSET_STEP_DEG;
            self.params.sun_elevation_deg = if next < low { high.min(60.0) } else { next };
        }
        Ok(())
    }

    /// Draws the picture into `picture` (cleared), on the mode's backend. The model of
    /// the shell method is rebuilt first where the altitude changed.
    fn draw(
        &mut self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        picture: &mut Picture,
    ) -> Result<bool> {
        let p = &self.params;
        let (sun, view) = (p.sun()?, p.view(picture.size)?);
        let stale = match &self.drawer {
            Some(drawer) => drawer
                .model_altitude()
                .is_some_and(|altitude| altitude != p.altitude_m),
            None => true,
        };
        if stale {
            self.drawer = Some(self.make_drawer(gpu)?);
        }
        let display = self.display();
        let drawer = self.drawer.as_mut().expect("made above");
        match drawer.prepare(encoder, sun, p.altitude_m, &view)? {
            Prepared::Cpu(sky) => draw_cpu(&sky, &view, display, picture),
            Prepared::Gpu(pass) => picture.draw(encoder, |render| pass.draw(render)),
        }
        Ok(true)
    }

    fn still_command(&self, output: &std::path::Path, (width, height): (u32, u32)) -> String {
        let backend = if self.on_gpu { "gpu" } else { "cpu" };
        format!(
            "atmo sky {} {} --width {width} --height {height} --backend {backend} -o {}",
            self.source_flags,
            self.params.flags(),
            output.display()
        )
    }

    fn panel(&mut self, ui: &mut egui::Ui) -> Vec<Input> {
        let mut p = self.params.clone();
        let (sun_low, sun_high) = self.sun_range();
        let (low, high) = self.altitude_range();
        let mut animate = self.animate;
        ui.add(
            crate::panel::slider(&mut p.sun_elevation_deg, sun_low..=sun_high)
                .text("sun elevation, deg"),
        );
        ui.add(crate::panel::slider(&mut p.sun_azimuth_deg, 0.0..=359.9).text("sun azimuth, deg"));
        ui.checkbox(&mut animate, "time of day (space)");
        ui.add(crate::panel::slider(&mut p.altitude_m, low..=high).text("altitude, m"));
        ui.label(format!("R / F: climb / descend {} m (+ / -)", self.step_m));
        ui.separator();
        ui.checkbox(&mut p.fisheye, "fisheye (the whole dome)");
        ui.add_enabled_ui(!p.fisheye, |ui| {
            ui.add(crate::panel::slider(&mut p.yaw_deg, 0.0..=359.9).text("yaw, deg (drag)"));
            ui.add(crate::panel::slider(&mut p.pitch_deg, -89.0..=89.0).text("pitch, deg"));
            ui.add(crate::panel::slider(&mut p.fov_deg, 10.0..=150.0).text("vertical fov, deg"));
        });
        ui.checkbox(&mut p.sun_disc, "sun disc");
        ui.separator();
        crate::panel::display(ui, &mut p.exposure, &mut p.tone);
        let mut inputs = edits(p.fields(), self.params.fields());
        if animate != self.animate {
            inputs.push(Input::Key(Key::Animate));
        }
        inputs
    }

    fn display(&self) -> Display {
        Display {
            exposure: self.params.exposure,
            tone: self.params.tone,
        }
    }

    fn help(&self) -> &'static str {
        "drag: look; arrows: sun; R / F: climb; space: time of day"
    }
}

/// Draws `sky` through `view` into `picture` on the CPU, as the texels of `display`
/// alone where the window takes nothing else this frame (every frame is drawn anew).
fn draw_cpu(sky: &SkyPicture, view: &View, display: Display, picture: &mut Picture) {
    picture.draw_cpu_texels(
        display,
        |frame| sky.render_into(view, frame),
        |levels, order, texels| sky.render_texels_into(view, levels, order, texels),
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_field_sets_back_to_itself_and_reads_as_the_still_flags() {
        let p = SkyParams {
            sun_elevation_deg: 3.125,
            altitude_m: 1234.5,
            fisheye: true,
            sun_disc: false,
            tone: ToneMap::Aces,
            ..SkyParams::default()
        };
        let mut q = SkyParams::default();
        for (name, value) in p.fields() {
            q.set(name, &value).unwrap();
        }
        assert_eq!(p, q);
        let flags = p.flags();
        for part in [
            "--sun-elevation 3.125",
            "--altitude 1234.5",
            "--fisheye",
            "--no-sun-disc",
            "--tone-map aces",
        ] {
            assert!(flags.contains(part), "{part} missing from {flags}");
        }
    }

    #[test]
    fn bad_edits_name_the_parameter() {
        let mut p = SkyParams::default();
        let e = p.set("sun-elevation", "high").unwrap_err().to_string();
        assert!(
            e.contains("sun-elevation") && e.contains("finite number"),
            "{e}"
        );
        let e = p.set("colour", "red").unwrap_err().to_string();
        assert!(
            e.contains("no parameter 'colour'") && e.contains("sun-azimuth"),
            "{e}"
        );
        assert_eq!(p, SkyParams::default());
    }
}
