//! The stage in the window: a shafts scene file (`atmo shafts`) whose camera orbits and
//! whose lights are aimed and edited live, drawn by the sample planes on the CPU or on
//! the GPU.
//!
//! Every change is an edit of the scene file by key ([`atmo::shafts::edits`]), the one
//! `atmo shafts --set` takes, so a screenshot's still command is the file and the
//! window's edits, and "save scene" writes them into the file with its comments kept.
//! Only what changed is redone: the picture is drawn again only when the scene
//! changed, and on the CPU a light's shadow map is rebuilt only when that light moved
//! or its field changed ([`atmo::shafts::planes::ShadowMaps`]), so orbiting the camera
//! reuses every map. The file is watched: when it changes on disk it is read again with
//! the window's edits on top, and a bad file is shown as an error while the last good
//! scene stays.

use std::path::{Path, PathBuf};
use std::time::{Instant, SystemTime};

use anyhow::{Context, Result};
use atmo::geometry::Ray;
use atmo::image::Display;
use atmo::shafts::dmx::playback::Playback;
use atmo::shafts::dmx::receiver::{Receiver, Settings, Stats};
use atmo::shafts::edits::{merged, Document, Edit};
use atmo::shafts::Scene;
use atmo::Error;
use atmo_gpu::shafts::{ShaftsMethod, ShaftsPass, ShaftsRenderer};
use atmo_gpu::Gpu;
use glam::Vec3;

use crate::input::{Input, Key, Script};
use crate::panel::{tone_combo, tone_name};
use crate::{Figures, Mode, Picture};

/// Show time a frame advances while the show plays, s (the stills' 24 frames/s).
const SHOW_STEP_S: f32 = 1.0 / 24.0;

/// How often the scene file is looked at for changes.
const WATCH_INTERVAL_S: f64 = 0.25;

/// The stage mode: the scene file, the window's edits, the scene they give, and what
/// draws it.
pub struct StageMode {
    path: PathBuf,
    /// The file's text as last read or saved.
    text: String,
    /// When the file was last modified and its length, as last seen.
    stamp: Option<(SystemTime, u64)>,
    watched: Instant,
    /// The window's edits since the file was read or saved, one per key.
    edits: Vec<Edit>,
    /// The file with the edits: what the panel reads and "save scene" writes.
    edited: Document,
    /// The picture's size, pixels, once the window has one: the camera's.
    size: Option<(u32, u32)>,
    /// The scene the file, the edits and the size give, posed at `time_s`.
    scene: Scene,
    time_s: f32,
    playing: bool,
    /// The orbit's step for keys, degrees (and a dolly of `step / 50` of the distance).
    pub step_deg: f32,
    /// The light the panel shows and a right-button drag aims.
    selected: usize,
    /// The renderer on the mode's backend (made at the first frame drawn there; on the
    /// CPU it keeps the shadow maps of lights that did not move), and on the GPU the
    /// pass that draws into the window's picture.
    renderer: Option<ShaftsRenderer>,
    pass: Option<ShaftsPass>,
    on_gpu: bool,
    /// The scene changed since the picture was last drawn.
    dirty: bool,
    /// The picture is a preview ([`Picture::preview`]), to be drawn whole.
    coarse: bool,
    /// The last thing done to the file ("saved", "read again"), for the panel.
    status: Option<String>,
    /// A desk driving the patched fixtures, if the window listens to one.
    desk: Option<Desk>,
}

/// A lighting desk's DMX, live: the listening thread, the playback its frames drive,
/// and how long frames took to reach the picture.
struct Desk {
    receiver: Receiver,
    playback: Playback,
    /// When listening started: frames are stamped from it, and the heads posed at the
    /// time since.
    start: Instant,
    /// The states last posed, to draw again only when they change, and when, us.
    posed: Vec<(atmo::shafts::show::State, f32)>,
    posed_us: u64,
    /// Arrival times (us from `start`) of the frames applied since the last picture.
    waiting: Vec<u64>,
    /// From a frame's arrival to the end of the first picture drawn with it, ms.
    latency_ms: Vec<f64>,
    frames: u64,
    dropped: u64,
    /// The recording being written, if any.
    record: Option<PathBuf>,
}

impl StageMode {
    /// The scene file at `path` with `edits` (checked), posed at `time_s` into its show.
    pub fn new(path: &Path, edits: Vec<Edit>, time_s: f32) -> Result<StageMode> {
        atmo::error::check_range("time", time_s as f64, 0.0, 1e6)?;
        let text = Scene::read_text(path)?;
        let origin = path.display().to_string();
        let edited = Document::edited(&text, &origin, &edits)?;
        let scene = load(path, &edited, &[], time_s)?;
        Ok(StageMode {
            path: path.to_path_buf(),
            text,
            stamp: stamp(path),
            watched: Instant::now(),
            edits: merged(&edits),
            edited,
            size: None,
            scene,
            time_s,
            playing: false,
            step_deg: 5.0,
            selected: 0,
            renderer: None,
            pass: None,
            on_gpu: false,
            dirty: true,
            coarse: false,
            status: None,
            desk: None,
        })
    }

    /// Listens to a desk (`settings`; the scene's patched universes where it names
    /// none), writing what arrives to `record` if given (in place when the window
    /// closes): the patched fixtures then move as the desk says, posed at the time
    /// since listening started (the time `atmo shafts --dmx-file` renders the
    /// recording at).
    pub fn listen(&mut self, settings: Settings, record: Option<PathBuf>) -> Result<()> {
        let start = Instant::now();
        let receiver = Receiver::start(settings, start, record.clone())?;
        self.desk = Some(Desk {
            receiver,
            playback: Playback::new(&self.scene.show),
            start,
            posed: Vec::new(),
            posed_us: 0,
            waiting: Vec::new(),
            latency_ms: Vec::new(),
            frames: 0,
            dropped: 0,
            record,
        });
        self.status = Some(format!(
            "listening for DMX at {}",
            self.desk
                .as_ref()
                .map(|d| d.receiver.local_addr())
                .expect("set")
        ));
        Ok(())
    }

    /// The frames from the desk since the last call applied, and the heads posed at
    /// now: the picture is drawn again where a state changed (a frame, a turning gobo,
    /// a strobe).
    fn follow_desk(&mut self) -> Result<()> {
        let Some(desk) = &mut self.desk else {
            return Ok(());
        };
        let (frames, dropped) = desk.receiver.take();
        desk.dropped += dropped;
        for frame in &frames {
            desk.playback.apply(&self.scene.show, frame);
            desk.waiting.push(frame.time_us);
        }
        desk.frames += frames.len() as u64;
        let now_us = (desk.start.elapsed().as_micros() as u64).max(desk.playback.time_us());
        let states = desk.playback.states(&self.scene.show, now_us);
        if states != desk.posed {
            self.scene.drive((now_us as f64 * 1e-6) as f32, &states);
            (desk.posed, desk.posed_us) = (states, now_us);
            self.dirty = true;
        }
        if let (_, Some(error)) = desk.receiver.stats() {
            return Err(anyhow::anyhow!("DMX: {error}"));
        }
        Ok(())
    }

    /// Listening's figures so far: frames taken and dropped, the latency from each
    /// frame's arrival to its first picture.
    pub fn desk_figures(&self) -> Option<DeskFigures> {
        let desk = self.desk.as_ref()?;
        Some(DeskFigures {
            posed_s: desk.posed_us as f64 * 1e-6,
            frames: desk.frames,
            dropped: desk.dropped,
            latency_ms: desk.latency_ms.clone(),
            stats: desk.receiver.stats().0,
        })
    }

    /// Stops listening, writing the recording in place.
    pub fn stop_listening(&mut self) -> Result<()> {
        match self.desk.take() {
            Some(desk) => Ok(desk.receiver.stop()?),
            None => Ok(()),
        }
    }

    /// The scene as it is drawn now.
    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    /// The window's edits, one per key, in the order keys were first changed.
    pub fn edits(&self) -> &[Edit] {
        &self.edits
    }

    /// The camera's size set to the picture's, where they differ.
    fn size_edits(&self) -> Vec<Edit> {
        let Some((width, height)) = self.size else {
            return Vec::new();
        };
        [("camera.width", width), ("camera.height", height)]
            .into_iter()
            .filter(|(key, v)| self.edited.number(key) != Some(*v as f64))
            .map(|(key, v)| Edit::set(key, v.to_string()))
            .collect()
    }

    /// Makes the scene from `text` with `edits`: on success the mode's, and the
    /// picture to be drawn again; on failure the error, and nothing changed. Shadow
    /// maps are dropped where the objects may have changed (a map is kept by its
    /// light's pose and its size, [`ShadowMaps::update`], so other edits need not).
    ///
    /// Where only the camera's keys changed (an orbit, a new picture size), only the
    /// camera is read again ([`Scene::camera_from_toml_str`]): the objects' meshes,
    /// the gobos and the photometric files are not, which took some 5 ms a frame of
    /// a stage orbit.
    fn rebuild(&mut self, text: String, edits: Vec<Edit>) -> Result<()> {
        let origin = self.path.display().to_string();
        let edits = merged(&edits);
        let edited = Document::edited(&text, &origin, &edits)?;
        // The edits of keys that `keep` takes, before and after.
        let kept = |keep: fn(&str) -> bool| {
            let of = |edits: &[Edit]| -> Vec<Edit> {
                edits.iter().filter(|e| keep(&e.key)).cloned().collect()
            };
            (of(&self.edits), of(&edits))
        };
        let (besides_camera, solid) = (
            kept(|key| !key.starts_with("camera.")),
            kept(|key| key.starts_with("object")),
        );
        let same_file = text == self.text;
        if same_file && besides_camera.0 == besides_camera.1 {
            let text = sized(&edited, &self.size_edits())?;
            self.scene.camera = Scene::camera_from_toml_str(&text, &origin)?;
        } else {
            let scene = load(&self.path, &edited, &self.size_edits(), self.time_s)?;
            if !same_file || solid.0 != solid.1 {
                self.renderer
                    .iter_mut()
                    .for_each(ShaftsRenderer::objects_changed);
            }
            self.scene = scene;
        }
        (self.text, self.edits, self.edited) = (text, edits, edited);
        if let Some(desk) = &mut self.desk {
            desk.playback = desk.playback.for_show(&self.scene.show);
            desk.posed.clear();
        }
        self.dirty = true;
        Ok(())
    }

    /// The camera's picture made `size`, pixels.
    fn resize(&mut self, size: (u32, u32)) -> Result<()> {
        if self.size != Some(size) {
            let old = self.size.replace(size);
            if let Err(e) = self.rebuild(self.text.clone(), self.edits.clone()) {
                self.size = old;
                return Err(e);
            }
        }
        Ok(())
    }

    /// One more edit.
    fn edit(&mut self, more: impl IntoIterator<Item = Edit>) -> Result<()> {
        let mut edits = self.edits.clone();
        edits.extend(more);
        self.rebuild(self.text.clone(), edits)
    }

    /// A point of the edited file, as a vector.
    fn point(&self, key: &str) -> Result<Vec3> {
        let v = self
            .edited
            .vector(key)
            .with_context(|| format!("{key} is not three numbers"))?;
        Ok(Vec3::new(v[0] as f32, v[1] as f32, v[2] as f32))
    }

    /// The camera moved about the point it looks at: `yaw_deg` around the vertical,
    /// `pitch_deg` up, its distance times `scale`.
    fn orbit(&mut self, yaw_deg: f32, pitch_deg: f32, scale: f32) -> Result<()> {
        let (position, look_at) = (
            self.point("camera.position")?,
            self.point("camera.look_at")?,
        );
        let position = crate::orbit(position, look_at, yaw_deg, pitch_deg, scale);
        self.edit([Edit::set("camera.position", vector(position))])
    }

    /// Light `light` aimed at what pixel (x, y) of the picture shows: a spotlight's
    /// `aim` set to the point; a moving head's pan and tilt at the show's start, the
    /// nearest within its ranges that point it there.
    fn aim(&mut self, light: usize, x: f32, y: f32) -> Result<()> {
        let (spotlights, lights) = (self.edited.count("spotlight"), self.light_count());
        if light >= lights {
            return Err(Error::Invalid(format!(
                "light {light}: the scene has {lights} lights ({spotlights} [[spotlight]]s, \
                 then the moving heads)"
            ))
            .into());
        }
        let camera = &self.scene.camera;
        let ray = Ray {
            origin: camera.position,
            dir: camera.ray(x, y).normalize(),
        };
        let hit = self
            .scene
            .objects
            .hit(&ray, camera.far)
            .context("nothing under the pointer to aim at")?;
        let point = ray.origin + hit.t * ray.dir;
        if let Some(k) = light.checked_sub(spotlights) {
            let head = &self.scene.show.fixtures[k];
            let (pan, tilt) = head.toward(point, head.start.pan_tilt()).with_context(|| {
                format!(
                    "{} cannot point at {point}: beyond its pan {:?} and tilt {:?} deg",
                    head.name, head.pan_range_deg, head.tilt_range_deg
                )
            })?;
            let at = |key: &str| format!("fixture[{k}].start.{key}");
            let edits = vec![
                Edit::set(&at("pan_deg"), pan.to_string()),
                Edit::set(&at("tilt_deg"), tilt.to_string()),
            ];
            return self.edit(edits);
        }
        let at = format!("spotlight[{light}]");
        let mut edits = vec![Edit::set(&format!("{at}.aim"), vector(point))];
        if self.edited.get(&format!("{at}.direction")).is_some() {
            edits.insert(0, Edit::remove(&format!("{at}.direction")));
        }
        self.edit(edits)
    }

    /// The show's time set, s.
    fn set_time(&mut self, time_s: f32) -> Result<()> {
        atmo::error::check_range("time", time_s as f64, 0.0, 1e6)?;
        self.time_s = time_s;
        self.scene.at_time(time_s);
        self.dirty = true;
        Ok(())
    }

    /// Writes the edited scene into its file (atomically) and starts again from it.
    fn save(&mut self) -> Result<()> {
        if self
            .path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("mvr"))
        {
            return Err(Error::Invalid(format!(
                "{} is an MVR rig, not a scene file: copy the scene atmo made around it \
                 into a .toml file (its [mvr] names the rig) to save edits",
                self.path.display()
            ))
            .into());
        }
        let text = self.edited.to_string();
        atmo::files::write_atomically(&self.path, |w| {
            use std::io::Write;
            w.write_all(text.as_bytes())
                .map_err(atmo::Error::io_at(&self.path))
        })?;
        self.stamp = stamp(&self.path);
        self.rebuild(text, Vec::new())?;
        self.status = Some(format!("saved {}", self.path.display()));
        Ok(())
    }

    /// Reads the file again if it changed on disk since it was last seen.
    fn watch(&mut self) -> Result<()> {
        if self.watched.elapsed().as_secs_f64() < WATCH_INTERVAL_S {
            return Ok(());
        }
        self.watched = Instant::now();
        let now = stamp(&self.path);
        if now == self.stamp {
            return Ok(());
        }
        self.stamp = now;
        let text = Scene::read_text(&self.path)?;
        if text == self.text {
            return Ok(());
        }
        self.rebuild(text, self.edits.clone()).with_context(|| {
            format!(
                "{} changed on disk and is refused; the last good scene stays",
                self.path.display()
            )
        })?;
        self.status = Some(format!("read {} again", self.path.display()));
        Ok(())
    }

    /// How many lights the scene has: its spotlights and its moving heads.
    fn light_count(&self) -> usize {
        self.edited.count("spotlight") + self.scene.show.fixtures.len()
    }

    /// The lights by name, in scene order: the spotlights, then the moving heads.
    fn light_names(&self) -> Vec<String> {
        let spotlights = self.edited.count("spotlight");
        (0..spotlights)
            .map(|i| format!("spotlight {i}"))
            .chain(self.scene.show.fixtures.iter().map(|f| f.name.clone()))
            .collect()
    }

    /// The panel's widgets for spotlight `i`.
    fn spotlight_panel(&self, ui: &mut egui::Ui, i: usize, edits: &mut Vec<Edit>) {
        let at = |key: &str| format!("spotlight[{i}].{key}");
        vector_row(ui, &self.edited, &at("position"), "position, m", edits);
        if self.edited.get(&at("aim")).is_some() {
            vector_row(ui, &self.edited, &at("aim"), "aim, m (right drag)", edits);
        }
        let list = vec![
            Slider::new(at("intensity"), "intensity, cd", 1.0..=1e6).logarithmic(),
            Slider::new(at("dimmer"), "dimmer", 0.0..=1.0).or(1.0),
            Slider::new(at("beam_deg"), "beam, deg", 0.1..=170.0),
            Slider::new(at("field_deg"), "field, deg", 0.1..=170.0),
            Slider::new(at("kelvin"), "colour temperature, K", 1000.0..=40000.0).logarithmic(),
        ];
        sliders(ui, &self.edited, list, edits);
        if let Some(c) = self.edited.vector(&at("color")) {
            let mut rgb = c.map(|v| v as f32);
            ui.horizontal(|ui| {
                ui.label("colour (linear RGB)");
                egui::color_picker::color_edit_button_rgb(ui, &mut rgb);
            });
            if rgb != c.map(|v| v as f32) {
                edits.push(Edit::set(&at("color"), vector(Vec3::from(rgb))));
            }
        }
    }

    /// The panel's widgets for moving head `k`: its attributes at the show's start.
    fn fixture_panel(&self, ui: &mut egui::Ui, k: usize, edits: &mut Vec<Edit>) {
        ui.label("at the show's start (the cues change them); right drag: pan and tilt");
        let at = |key: &str| format!("fixture[{k}].start.{key}");
        // Where the start does not set them: along the axis, full (zoom: the widest,
        // which only the fixture's range knows).
        let mut list = vec![
            Slider::new(at("pan_deg"), "pan, deg", -540.0..=540.0).or(0.0),
            Slider::new(at("tilt_deg"), "tilt, deg", -270.0..=270.0).or(0.0),
            Slider::new(at("zoom_deg"), "zoom, deg", 1.0..=90.0),
            Slider::new(at("dimmer"), "dimmer", 0.0..=1.0).or(1.0),
        ];
        let prism = self.scene.show.fixtures[k].prism.is_some();
        if prism {
            list.push(Slider::new(at("prism_deg"), "prism turn, deg", -360.0..=360.0).or(0.0));
        }
        sliders(ui, &self.edited, list, edits);
        if prism {
            // In unless the start takes it out.
            let was = self
                .edited
                .get(&at("prism_in"))
                .and_then(|v| v.as_bool())
                .unwrap_or(true);
            let mut prism_in = was;
            ui.checkbox(&mut prism_in, "prism in the beam");
            if prism_in != was {
                edits.push(Edit::set(&at("prism_in"), prism_in.to_string()));
            }
        }
    }
}

/// What listening to a desk came to ([`StageMode::desk_figures`]).
#[derive(Debug, Clone)]
pub struct DeskFigures {
    /// The time the heads were last posed at, s from listening's start: the picture
    /// shows them then.
    pub posed_s: f64,
    /// Frames (changed universes) applied, and dropped because the window fell behind.
    pub frames: u64,
    pub dropped: u64,
    /// From each frame's arrival to the end of the first picture drawn with it, ms.
    pub latency_ms: Vec<f64>,
    /// The listener's counts.
    pub stats: Stats,
}

/// The scene of the edited file with `more` edits (the picture's size), posed.
fn load(path: &Path, edited: &Document, more: &[Edit], time_s: f32) -> atmo::Result<Scene> {
    let mut scene = Scene::from_text_at(&sized(edited, more)?, path)?;
    scene.at_time(time_s);
    Ok(scene)
}

/// The text of the edited file with `more` edits (the picture's size).
fn sized(edited: &Document, more: &[Edit]) -> atmo::Result<String> {
    let mut doc = edited.clone();
    doc.apply_all(more)?;
    Ok(doc.to_string())
}

/// When the file was last modified, and its length.
fn stamp(path: &Path) -> Option<(SystemTime, u64)> {
    let m = std::fs::metadata(path).ok()?;
    Some((m.modified().ok()?, m.len()))
}

/// A vector as a TOML array, each float printed exactly (the value read back is it).
fn vector(v: Vec3) -> String {
    format!("[{},{},{}]", v.x, v.y, v.z)
}

/// What a slider edits: the key, its label and range, whether the scale is
/// logarithmic, and the value the scene takes where the file has none (the slider is
/// left out where it has neither).
struct Slider {
    key: String,
    label: &'static str,
    range: std::ops::RangeInclusive<f64>,
    logarithmic: bool,
    default: Option<f64>,
}

impl Slider {
    fn new(key: String, label: &'static str, range: std::ops::RangeInclusive<f64>) -> Slider {
        Slider {
            key,
            label,
            range,
            logarithmic: false,
            default: None,
        }
    }

    fn logarithmic(self) -> Slider {
        Slider {
            logarithmic: true,
            ..self
        }
    }

    fn or(self, default: f64) -> Slider {
        Slider {
            default: Some(default),
            ..self
        }
    }
}

/// A slider for each of `list`; a change becomes an edit.
fn sliders(ui: &mut egui::Ui, doc: &Document, list: Vec<Slider>, edits: &mut Vec<Edit>) {
    for s in list {
        let Some(old) = doc.number(&s.key).or(s.default) else {
            continue;
        };
        let mut value = old;
        ui.add(
            crate::panel::slider(&mut value, s.range)
                .logarithmic(s.logarithmic)
                .text(s.label),
        );
        if value != old {
            edits.push(Edit::set(&s.key, (value as f32).to_string()));
        }
    }
}

/// Three drag values for the point at `key`; a change becomes an edit.
fn vector_row(ui: &mut egui::Ui, doc: &Document, key: &str, label: &str, edits: &mut Vec<Edit>) {
    let Some(old) = doc.vector(key) else { return };
    let mut v = old.map(|c| c as f32);
    ui.horizontal(|ui| {
        for c in &mut v {
            ui.add(egui::DragValue::new(c).speed(0.05));
        }
        ui.label(label);
    });
    if v != old.map(|c| c as f32) {
        edits.push(Edit::set(key, vector(Vec3::from(v))));
    }
}

impl Mode for StageMode {
    fn title(&self) -> &'static str {
        "atmo stage"
    }

    fn check_script(&self, _: &Script) -> atmo::Result<()> {
        // An edit's key is checked when it is made, against the scene as it is then.
        Ok(())
    }

    fn draw_on_gpu(&mut self, on_gpu: bool) {
        if on_gpu != self.on_gpu {
            self.on_gpu = on_gpu;
            self.renderer = None;
            self.dirty = true;
        }
    }

    fn apply(&mut self, input: &Input) -> Result<()> {
        let step = self.step_deg;
        match input {
            Input::Key(key) => match key {
                Key::Climb => self.orbit(0.0, 0.0, 1.0 - step / 50.0)?,
                Key::Descend => self.orbit(0.0, 0.0, 1.0 / (1.0 - step / 50.0))?,
                Key::Faster => self.step_deg = (step * 2.0).min(45.0),
                Key::Slower => self.step_deg = step / 2.0,
                Key::SunLeft => self.orbit(-step, 0.0, 1.0)?,
                Key::SunRight => self.orbit(step, 0.0, 1.0)?,
                Key::SunUp => self.orbit(0.0, step, 1.0)?,
                Key::SunDown => self.orbit(0.0, -step, 1.0)?,
                Key::Animate => self.playing = !self.playing,
                Key::Save => self.save()?,
                Key::Screenshot | Key::ScreenshotExr | Key::Panel | Key::Wind => {}
            },
            Input::Drag(dx, dy) => self.orbit(-0.3 * dx, 0.3 * dy, 1.0)?,
            Input::Aim(light, x, y) => self.aim(*light, *x, *y)?,
            Input::Set(name, value) if name == "time" => {
                let t = value
                    .parse::<f32>()
                    .map_err(|_| Error::Invalid(format!("time: '{value}' is not a number")))?;
                self.set_time(t)?;
            }
            Input::Set(key, value) => self.edit([Edit::parse(&format!("{key}={value}"))?])?,
        }
        Ok(())
    }

    fn update(&mut self) -> Result<()> {
        if self.desk.is_some() {
            self.follow_desk()?;
        } else if self.playing {
            let duration = self.scene.show.duration();
            let next = self.time_s + SHOW_STEP_S;
            self.set_time(if next > duration { 0.0 } else { next })?;
        }
        self.watch()
    }

    /// Draws the picture where the scene changed (else the picture keeps the last):
    /// on the GPU recorded into the frame's encoder and drawn into the picture with no
    /// read-back, on the CPU with the shadow maps of unchanged lights kept.
    fn draw(
        &mut self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        picture: &mut Picture,
    ) -> Result<bool> {
        self.resize(picture.size)?;
        if !self.dirty && !self.coarse {
            return Ok(false);
        }
        let renderer = match &mut self.renderer {
            Some(renderer) => renderer,
            slot => slot.insert(ShaftsRenderer::new(
                self.on_gpu.then_some(gpu),
                ShaftsMethod::Planes,
            )?),
        };
        if self.on_gpu {
            let pass = match &mut self.pass {
                Some(pass) => pass,
                slot => slot.insert(ShaftsPass::new(gpu, picture.texture.format())?),
            };
            renderer.prepare(encoder, pass, &self.scene)?;
            picture.draw(encoder, |render| pass.draw(render));
        } else {
            // A preview is the same scene through a camera of fewer pixels (the lens
            // keeps its angles); the shadow maps do not depend on the camera.
            let scene = &mut self.scene;
            self.coarse = picture.draw_cpu(self.dirty, |(width, height)| {
                let whole = (scene.camera.width, scene.camera.height);
                (scene.camera.width, scene.camera.height) = (width, height);
                let drawn = renderer.draw(scene);
                (scene.camera.width, scene.camera.height) = whole;
                Ok(drawn?.frame)
            })?;
        }
        self.dirty = false;
        if let Some(desk) = &mut self.desk {
            let now_us = desk.start.elapsed().as_micros() as u64;
            desk.latency_ms.extend(
                desk.waiting
                    .drain(..)
                    .map(|t| now_us.saturating_sub(t) as f64 * 1e-3),
            );
        }
        Ok(true)
    }

    fn display(&self) -> Display {
        self.scene.display
    }

    fn still_command(&self, output: &Path, _: (u32, u32)) -> String {
        let backend = if self.on_gpu { "gpu" } else { "cpu" };
        let mut words = vec![format!("atmo shafts {}", self.path.display())];
        let size = self.size_edits();
        words.extend(self.edits.iter().chain(&size).map(Edit::flag));
        match &self.desk {
            // The recording renders the heads as the desk had them when last posed.
            Some(Desk {
                record: Some(record),
                posed_us,
                ..
            }) => words.push(format!(
                "--dmx-file {} --time {:.6}",
                record.display(),
                *posed_us as f64 * 1e-6
            )),
            _ if self.time_s > 0.0 => words.push(format!("--time {}", self.time_s)),
            _ => {}
        }
        words.push(format!("--backend {backend} -o {}", output.display()));
        words.join(" ")
    }

    fn panel(&mut self, ui: &mut egui::Ui) -> Vec<Input> {
        let mut edits = Vec::new();
        let mut inputs = Vec::new();
        ui.label(format!(
            "{}{}",
            self.path.display(),
            if self.edits.is_empty() {
                ""
            } else {
                " (edited)"
            }
        ));
        if let Some(status) = &self.status {
            ui.label(status);
        }
        if let Some(desk) = &self.desk {
            let stats = desk.receiver.stats().0;
            ui.label(format!(
                "DMX: {} frames ({} datagrams, {} ignored){}",
                desk.frames,
                stats.datagrams,
                stats.ignored,
                desk.latency_ms.last().map_or(String::new(), |ms| format!(
                    "; the last {ms:.0} ms to the picture"
                ))
            ));
        }
        let duration = self.scene.show.duration();
        if duration > 0.0 {
            let mut t = self.time_s;
            ui.add(crate::panel::slider(&mut t, 0.0..=duration).text("show time, s"));
            if t != self.time_s {
                inputs.push(Input::Set("time".into(), t.to_string()));
            }
            let mut playing = self.playing;
            ui.checkbox(&mut playing, "play the show (space)");
            if playing != self.playing {
                inputs.push(Input::Key(Key::Animate));
            }
        }
        ui.separator();
        let list = vec![
            Slider::new("camera.fov_deg".into(), "field of view, deg", 5.0..=150.0),
            Slider::new("haze.extinction".into(), "haze extinction, 1/m", 1e-4..=1.0).logarithmic(),
            Slider::new("display.exposure".into(), "exposure", 1e-3..=1e3)
                .logarithmic()
                .or(1.0),
        ];
        sliders(ui, &self.edited, list, &mut edits);
        let mut tone = self.scene.display.tone;
        tone_combo(ui, &mut tone);
        if tone != self.scene.display.tone {
            let name = tone_name(tone);
            edits.push(Edit::set("display.tone_map", format!("\"{name}\"")));
        }
        let mut adaptive = self.scene.planes.adaptive;
        ui.checkbox(&mut adaptive, "adaptive sampling (the CPU)")
            .on_hover_text(
                "the scattered light computed where the picture changes, interpolated between",
            );
        if adaptive != self.scene.planes.adaptive {
            edits.push(Edit::set("render.adaptive", adaptive.to_string()));
        }
        ui.separator();
        let names = self.light_names();
        self.selected = self.selected.min(names.len().saturating_sub(1));
        egui::ComboBox::from_label("light")
            .selected_text(names.get(self.selected).map_or("none", |n| n.as_str()))
            .show_ui(ui, |ui| {
                for (i, name) in names.iter().enumerate() {
                    ui.selectable_value(&mut self.selected, i, name);
                }
            });
        let spotlights = self.edited.count("spotlight");
        if self.selected < spotlights {
            self.spotlight_panel(ui, self.selected, &mut edits);
        } else if self.selected < names.len() {
            self.fixture_panel(ui, self.selected - spotlights, &mut edits);
        }
        ui.separator();
        if ui.button("save scene (S)").clicked() {
            inputs.push(Input::Key(Key::Save));
        }
        inputs.extend(edits.into_iter().map(|e| match e.value {
            Some(v) => Input::Set(e.key, v),
            None => Input::Set(e.key, String::new()),
        }));
        inputs
    }

    fn help(&self) -> &'static str {
        "drag: orbit; right drag: aim the light; arrows: orbit; R / F: nearer / farther; \
         space: play; S: save scene"
    }

    fn aimed_light(&self) -> Option<usize> {
        (self.selected < self.light_count()).then_some(self.selected)
    }

    /// Stops listening to the desk (its recording written in place) and gives the
    /// DMX figures: frames taken and dropped, latency to the picture.
    fn close(&mut self) -> Result<Figures> {
        let Some(f) = self.desk_figures() else {
            return Ok(Figures::default());
        };
        self.stop_listening()?;
        Ok(Figures {
            values: vec![
                ("dmx_frames", f.frames as f64),
                ("dmx_dropped", f.dropped as f64),
                ("dmx_datagrams", f.stats.datagrams as f64),
                ("dmx_ignored", f.stats.ignored as f64),
                ("dmx_posed_s", f.posed_s),
            ],
            series: vec![("dmx_latency", f.latency_ms)],
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A copy of scenes/stage.toml in a fresh folder (with its gobo and mesh), for a
    /// test that writes the file.
    fn stage_copy(name: &str) -> PathBuf {
        let scenes = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes");
        let dir = std::env::temp_dir().join(format!("atmo-view-{}-{name}", std::process::id()));
        std::fs::create_dir_all(dir.join("gobos")).unwrap();
        std::fs::create_dir_all(dir.join("meshes")).unwrap();
        for file in ["stage.toml", "gobos/dots.png", "meshes/knot.obj"] {
            if scenes.join(file).exists() {
                std::fs::copy(scenes.join(file), dir.join(file)).unwrap();
            }
        }
        dir.join("stage.toml")
    }

    /// The stage at a small size, the camera toward the floor.
    fn small(path: &Path) -> StageMode {
        let mut mode = StageMode::new(path, vec![Edit::set("render.shadow_map", "64")], 0.0)
            .expect("the stage loads");
        mode.resize((48, 32)).unwrap();
        mode
    }

    #[test]
    fn orbiting_keeps_every_shadow_map_and_editing_a_light_rebuilds_only_its_own() {
        let path = stage_copy("maps");
        let mut mode = small(&path);
        let lights = mode.scene.light_count();
        // The CPU's renderer draws the scene: how many shadow maps it rebuilt.
        let rebuilt = |mode: &mut StageMode| {
            let renderer = mode.renderer.get_or_insert_with(|| {
                ShaftsRenderer::new(None, ShaftsMethod::Planes).expect("the CPU's")
            });
            renderer.draw(&mode.scene).unwrap().maps_rebuilt
        };
        assert_eq!(rebuilt(&mut mode), lights);
        let look_at = mode.point("camera.look_at").unwrap();
        let distance = |m: &StageMode| (m.point("camera.position").unwrap() - look_at).length();
        let before = distance(&mode);
        mode.apply(&Input::Drag(150.0, -20.0)).unwrap();
        mode.apply(&Input::Key(Key::Climb)).unwrap();
        assert!((distance(&mode) - 0.9 * before).abs() < 1e-4 * before);
        // Only the camera was read again: as the whole file with the edits reads.
        let fresh = load(&path, &mode.edited, &mode.size_edits(), 0.0).unwrap();
        assert_eq!(mode.scene.camera, fresh.camera);
        assert_ne!(mode.scene.camera, small(&path).scene.camera);
        assert_eq!(rebuilt(&mut mode), 0, "the camera moved: no map rebuilt");
        mode.apply(&Input::Set("spotlight[2].aim".into(), "[1, 0, 1]".into()))
            .unwrap();
        assert_eq!(rebuilt(&mut mode), 1, "one light moved");
        mode.apply(&Input::Set("object[0].albedo".into(), "0.5".into()))
            .unwrap();
        assert_eq!(rebuilt(&mut mode), lights, "the objects changed");
        std::fs::remove_dir_all(path.parent().unwrap()).unwrap();
    }

    #[test]
    fn the_mouse_aims_a_light_at_the_point_under_it() {
        let path = stage_copy("aim");
        let mut mode = small(&path);
        // The pixel's ray meets the floor (y = 0) where the light is now aimed.
        mode.apply(&Input::Aim(1, 20.0, 30.0)).unwrap();
        let aim = mode.point("spotlight[1].aim").unwrap();
        let camera = &mode.scene.camera;
        let ray = camera.ray(20.0, 30.0).normalize();
        let toward = (aim - camera.position).normalize();
        assert!(aim.y.abs() < 1e-4 && toward.dot(ray) > 1.0 - 1e-6, "{aim}");
        let light = &mode.scene.spotlights[1];
        let axis = (aim - light.position).normalize();
        assert!((light.light_from_world * axis - Vec3::Z).length() < 1e-5);
        // Over the sky there is nothing to aim at; a moving head is not aimed so.
        let e = mode.apply(&Input::Aim(1, 24.0, 0.0)).unwrap_err();
        assert!(e.to_string().contains("nothing under the pointer"), "{e}");
        let e = mode.apply(&Input::Aim(9, 20.0, 30.0)).unwrap_err();
        assert!(e.to_string().contains("5 [[spotlight]]s"), "{e}");
        std::fs::remove_dir_all(path.parent().unwrap()).unwrap();
    }

    #[test]
    fn the_mouse_aims_a_moving_head_by_its_pan_and_tilt() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/show.toml");
        let mut mode = StageMode::new(&path, vec![Edit::set("render.shadow_map", "64")], 0.0)
            .expect("the show loads");
        mode.resize((48, 32)).unwrap();
        // Light 2 is the third head, "centre" (the show has no [[spotlight]]).
        mode.apply(&Input::Aim(2, 12.0, 26.0)).unwrap();
        let head = &mode.scene.show.fixtures[2];
        let camera = &mode.scene.camera;
        let ray = Ray {
            origin: camera.position,
            dir: camera.ray(12.0, 26.0).normalize(),
        };
        let point = ray.origin + mode.scene.objects.hit(&ray, camera.far).unwrap().t * ray.dir;
        let (pan, tilt) = head.start.pan_tilt();
        let edited = mode.edited.number("fixture[2].start.pan_deg");
        assert_eq!(edited.map(|p| p as f32), Some(pan));
        let beam = head.aim(pan, tilt).0;
        assert!(
            beam.dot((point - head.position).normalize()) > 1.0 - 1e-6,
            "{pan} {tilt}"
        );
        // The light drawn at the show's start is that head so aimed.
        assert!((mode.scene.show.lights()[2].light_from_world * beam - Vec3::Z).length() < 1e-4);
        // Beyond the head's tilt: refused, the aim kept.
        let reach = tilt.abs() + 1.0;
        let narrow = Input::Set(
            "fixture[2].tilt_range_deg".into(),
            format!("[-{reach}, {reach}]"),
        );
        mode.apply(&narrow).unwrap();
        // The back wall, near the heads' height: some 80 deg from straight down.
        let e = mode.apply(&Input::Aim(2, 24.0, 8.0)).unwrap_err();
        assert!(e.to_string().contains("centre cannot point at"), "{e}");
        assert_eq!(mode.scene.show.fixtures[2].start.pan_tilt(), (pan, tilt));
    }

    #[test]
    fn a_changed_file_is_read_again_under_the_edits_and_a_bad_one_refused() {
        let path = stage_copy("watch");
        let mut mode = small(&path);
        mode.apply(&Input::Set("spotlight[0].dimmer".into(), "0.5".into()))
            .unwrap();
        let before = mode.scene.spotlights[0].intensity;
        let text = std::fs::read_to_string(&path).unwrap();
        let brighter = text.replace("intensity = 3000.0", "intensity = 6000.0");
        std::fs::write(&path, &brighter).unwrap();
        mode.watched -= std::time::Duration::from_secs(1);
        mode.update().unwrap();
        // Twice the intensity, still at the window's half dimmer.
        let after = mode.scene.spotlights[0].intensity;
        assert!(
            (after - 2.0 * before).length() < 1e-3 * after.length(),
            "{after}"
        );
        assert_eq!(mode.edits()[1], Edit::set("spotlight[0].dimmer", "0.5"));
        std::fs::write(&path, brighter.replace("[haze]", "[haze")).unwrap();
        mode.watched -= std::time::Duration::from_secs(1);
        let e = mode.update().unwrap_err();
        assert!(format!("{e:#}").contains("refused"), "{e:#}");
        assert_eq!(
            mode.scene.spotlights[0].intensity, after,
            "the last good scene"
        );
        std::fs::remove_dir_all(path.parent().unwrap()).unwrap();
    }
}
