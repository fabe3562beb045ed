//! Moving heads and cues: the lights of a show over time, as a lighting desk runs them.
//!
//! A [`Fixture`] is a moving head: a base where it is hung, a yoke that pans about the
//! base's axis and a head that tilts, a zoom (the beam angle), an iris, a dimmer, a
//! colour (RGB, CMY or colour temperature), a gobo wheel whose gobo turns and a
//! prism that splits the beam into copies around it ([`Prism`]). Its
//! attributes change by [`Cue`]s: at a cue's time each attribute it sets starts a
//! linear fade, over the cue's fade time, from the value it has at that moment (even in
//! the middle of an earlier fade) to the cue's; a gobo change and the prism going in or
//! out snap at the cue's start.
//! [`Show::pose`] turns the fixtures' state at a time into the [`Spotlight`]s the
//! renderers draw, so every method (planes, reference, GPU) plays a show unchanged.
//!
//! Geometry: at pan 0 and tilt 0 the beam points along the base's `axis` (a hanging
//! head: down); tilt swings it toward `front`, then pan turns the yoke right-handedly
//! about `axis` (counterclockwise seen from below a hanging head, looking up). The head is a rigid body: its light frame's `y` (the
//! gobo's up) is `front` turned with it.

use glam::{Mat3, Quat, Vec3};

use super::dmx::Patch;
use super::objects::Object;
use super::spotlight::{light_frame, Falloff, Gobo, Profile, Spotlight};
use crate::geometry::{Mesh, Shape};

/// The attributes of a fixture that fade, in this order in a [`State`].
pub const CHANNELS: [&str; 10] = [
    "pan_deg",
    "tilt_deg",
    "zoom_deg",
    "iris",
    "dimmer",
    "red",
    "green",
    "blue",
    "gobo_speed_dps",
    "prism_deg",
];

/// Index of a channel in [`CHANNELS`].
const PAN: usize = 0;
const TILT: usize = 1;
const ZOOM: usize = 2;
const IRIS: usize = 3;
const DIMMER: usize = 4;
const RED: usize = 5;
const SPEED: usize = 8;
const PRISM: usize = 9;

/// A fixture's attributes at one moment.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct State {
    /// The fading attributes, as [`CHANNELS`] names them: pan and tilt (degrees), zoom
    /// (the beam's full angle, degrees), iris (0-1 of the aperture), dimmer (0-1),
    /// colour (linear RGB), the gobo's turning speed (degrees per second) and the
    /// prism's turn (degrees).
    pub channels: [f32; 10],
    /// The gobo wheel's slot: 0 open, `k` the wheel's `k`-th gobo.
    pub gobo: usize,
    /// Whether the head's prism (if it has one) is in the beam.
    pub prism_in: bool,
}

impl State {
    /// Pan and tilt, degrees.
    pub fn pan_tilt(&self) -> (f32, f32) {
        (self.channels[PAN], self.channels[TILT])
    }
}

/// What a cue sets on one fixture; `None` leaves an attribute as it is.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Change {
    /// New values of the fading attributes ([`CHANNELS`]).
    pub channels: [Option<f32>; 10],
    /// A new gobo slot.
    pub gobo: Option<usize>,
    /// The prism put in (`true`) or taken out of the beam.
    pub prism_in: Option<bool>,
}

/// A cue: at `time_s` the changes start, fading over `fade_s`.
#[derive(Debug, Clone, PartialEq)]
pub struct Cue {
    /// When it starts, s from the show's start.
    pub time_s: f32,
    /// How long its fades take, s (0: a snap).
    pub fade_s: f32,
    /// Per fixture (index into [`Show::fixtures`]) what it sets.
    pub changes: Vec<(usize, Change)>,
}

/// A moving head, validated.
#[derive(Debug, Clone)]
pub struct Fixture {
    /// Its name in the scene file, for cues and messages.
    pub name: String,
    /// The head's centre (where the beam starts), m.
    pub position: Vec3,
    /// The pan axis (unit): the beam's direction at pan 0 and tilt 0.
    pub axis: Vec3,
    /// Unit, perpendicular to `axis`: where a positive tilt swings the beam at pan 0,
    /// and the gobo's up.
    pub front: Vec3,
    /// On-axis intensity at the widest zoom, cd (or W/sr); a narrower zoom gathers the
    /// same flux into a smaller cone.
    pub intensity: f32,
    /// The zoom's range, degrees (narrowest, widest).
    pub zoom_range_deg: [f32; 2],
    /// atmo's beam angle (full intensity) per degree of zoom: 1, or for a GDTF
    /// fixture, whose zoom is its half-intensity angle, the ratio of the smooth edge's
    /// beam to it ([`super::gdtf::to_smooth_edge`]).
    pub zoom_scale: f32,
    /// Field angle over beam angle (> 1: the soft edge's width).
    pub field_ratio: f32,
    /// Edge between beam and field.
    pub falloff: Falloff,
    /// The gobo wheel's gobos (slot 1 is the first).
    pub wheel: Vec<Gobo>,
    /// The gobo's turn at the show's start, degrees.
    pub gobo_rotation_deg: f32,
    /// How far the yoke pans and the head tilts, degrees (low, high).
    pub pan_range_deg: [f32; 2],
    pub tilt_range_deg: [f32; 2],
    /// The attributes before any cue.
    pub start: State,
    /// A prism in the beam, if the head has one.
    pub prism: Option<Prism>,
    /// The lamp's white (linear RGB, the colour with no filter in), which DMX colour
    /// channels filter ([`super::dmx::Reading::state`]).
    pub white: Vec3,
    /// Where a desk drives it, if it is patched.
    pub patch: Option<Patch>,
    /// Whether its body is drawn ([`Fixture::body`]).
    pub body: bool,
    /// The body its GDTF file draws, if it has models; else atmo's generic head.
    #[cfg(feature = "gdtf")]
    pub model: Option<std::sync::Arc<super::gdtf_body::GdtfBody>>,
}

/// A prism in a head's beam: `facets` copies of the beam, each turned `angle_deg` off
/// the head's axis toward its own side, the sides `360 / facets` degrees apart from the
/// head's `prism_deg` channel (measured from the gobo's up, toward its right; cues fade
/// it, so the prism turns), each carrying an equal share of the light. A circular
/// prism of a moving head, as a desk runs it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Prism {
    pub facets: u32,
    pub angle_deg: f32,
}

impl Prism {
    /// The facets a prism may have, fewest and most.
    pub const FACETS: [u32; 2] = [2, 16];
    /// The most a facet's beam may be turned off the head's, degrees.
    pub const MAX_ANGLE_DEG: f32 = 60.0;
}

/// Fixtures and their cues, and the spotlights they make at one time of the show: the
/// moving heads of a [`super::Scene`], beside its fixed spotlights.
#[derive(Debug, Clone, Default)]
pub struct Show {
    /// The moving heads.
    pub fixtures: Vec<Fixture>,
    /// The cues, in time order.
    pub cues: Vec<Cue>,
    /// The time the heads are posed at, s.
    time_s: f32,
    /// The heads' spotlights at `time_s`, in fixture order ([`Show::pose`]).
    lights: Vec<Spotlight>,
    /// Each fixture's pan and tilt at `time_s`, degrees.
    pan_tilt: Vec<(f32, f32)>,
}

/// One attribute's course through the cues: the fade running at the latest cue that
/// set it.
#[derive(Debug, Clone, Copy)]
struct Fade {
    from: f32,
    to: f32,
    start: f32,
    length: f32,
}

impl Fade {
    fn at(&self, t: f32) -> f32 {
        if self.length <= 0.0 || t >= self.start + self.length {
            self.to
        } else {
            let w = ((t - self.start) / self.length).max(0.0);
            self.from + (self.to - self.from) * w
        }
    }
}

impl Show {
    /// The show of these fixtures and cues (in time order), its heads posed at its
    /// start.
    pub fn new(fixtures: Vec<Fixture>, cues: Vec<Cue>) -> Show {
        let mut show = Show {
            fixtures,
            cues,
            ..Show::default()
        };
        show.at_time(0.0);
        show
    }

    /// Poses the heads as the cues have them at `time_s`, s; again after a caller
    /// changes [`Show::fixtures`] or [`Show::cues`].
    pub fn at_time(&mut self, time_s: f32) {
        self.lights = self.pose(time_s);
        self.pan_tilt = (0..self.fixtures.len())
            .map(|f| self.state(f, time_s).pan_tilt())
            .collect();
        self.time_s = time_s;
    }

    /// Poses the heads in `states` (one per fixture, each with its gobo's turn,
    /// degrees), as a desk drives them ([`super::dmx::playback`]), at `time_s`.
    pub fn drive(&mut self, time_s: f32, states: &[(State, f32)]) {
        self.lights = self
            .fixtures
            .iter()
            .zip(states)
            .flat_map(|(f, (state, gobo_deg))| f.lights(state, *gobo_deg))
            .collect();
        self.pan_tilt = states.iter().map(|(s, _)| s.pan_tilt()).collect();
        self.time_s = time_s;
    }

    /// The bodies of the fixtures that show theirs, as posed ([`Fixture::body`]).
    pub fn bodies(&self) -> impl Iterator<Item = Object> + '_ {
        self.fixtures
            .iter()
            .zip(&self.pan_tilt)
            .filter(|(f, _)| f.body)
            .map(|(f, &(pan, tilt))| f.body(pan, tilt))
    }

    /// The time the heads are posed at, s ([`Show::at_time`]; 0 as made).
    pub fn time_s(&self) -> f32 {
        self.time_s
    }

    /// The heads' spotlights at [`Show::time_s`], in fixture order (a head with a prism
    /// in gives one per facet).
    pub fn lights(&self) -> &[Spotlight] {
        &self.lights
    }

    /// The time the last cue's fades end, s (0 without cues).
    pub fn duration(&self) -> f32 {
        self.cues
            .iter()
            .map(|c| c.time_s + c.fade_s)
            .fold(0.0, f32::max)
    }

    /// What the cues up to time `t` set on fixture `f`, in order, each with its cue.
    fn changes(&self, f: usize, t: f32) -> impl Iterator<Item = (&Cue, &Change)> {
        self.cues
            .iter()
            .take_while(move |c| c.time_s <= t)
            .flat_map(move |cue| {
                cue.changes
                    .iter()
                    .filter(move |(k, _)| *k == f)
                    .map(move |(_, change)| (cue, change))
            })
    }

    /// Fixture `f`'s fade of `channel` as it runs at time `t` (every cue up to `t`).
    fn fade(&self, f: usize, channel: usize, t: f32) -> Fade {
        let start = self.fixtures[f].start.channels[channel];
        let mut fade = Fade {
            from: start,
            to: start,
            start: 0.0,
            length: 0.0,
        };
        for (cue, change) in self.changes(f, t) {
            if let Some(to) = change.channels[channel] {
                fade = Fade {
                    from: fade.at(cue.time_s),
                    to,
                    start: cue.time_s,
                    length: cue.fade_s,
                };
            }
        }
        fade
    }

    /// Fixture `f`'s attributes at time `t`, s.
    pub fn state(&self, f: usize, t: f32) -> State {
        let start = &self.fixtures[f].start;
        let changes = || self.changes(f, t).map(|(_, change)| change);
        State {
            channels: std::array::from_fn(|c| self.fade(f, c, t).at(t)),
            gobo: changes()
                .filter_map(|c| c.gobo)
                .last()
                .unwrap_or(start.gobo),
            prism_in: changes()
                .filter_map(|c| c.prism_in)
                .last()
                .unwrap_or(start.prism_in),
        }
    }

    /// How far fixture `f`'s gobo has turned by time `t`, degrees: its start plus the
    /// integral of its speed, which is linear between cue starts and fade ends, so the
    /// midpoint rule over those times is exact (the trapezoid's ends would take a
    /// snapped speed's new value for the time before the snap).
    pub fn gobo_angle_deg(&self, f: usize, t: f32) -> f32 {
        let mut times: Vec<f32> = vec![0.0, t.max(0.0)];
        for (cue, _) in self
            .changes(f, t)
            .filter(|(_, change)| change.channels[SPEED].is_some())
        {
            times.push(cue.time_s);
            times.push((cue.time_s + cue.fade_s).min(t));
        }
        times.sort_by(f32::total_cmp);
        times.dedup();
        let speed = |at: f32| self.fade(f, SPEED, at).at(at);
        let turned: f32 = times
            .windows(2)
            .map(|w| speed(0.5 * (w[0] + w[1])) * (w[1] - w[0]))
            .sum();
        self.fixtures[f].gobo_rotation_deg + turned
    }

    /// The spotlights of the fixtures at time `t`, s, in fixture order (a head with a
    /// prism gives one per facet).
    pub fn pose(&self, t: f32) -> Vec<Spotlight> {
        (0..self.fixtures.len())
            .flat_map(|f| self.fixtures[f].lights(&self.state(f, t), self.gobo_angle_deg(f, t)))
            .collect()
    }

    /// How many spotlights [`Show::pose`] gives at time `t`, s.
    pub fn light_count(&self, t: f32) -> usize {
        (0..self.fixtures.len())
            .map(|f| {
                self.fixtures[f]
                    .prism_at(&self.state(f, t))
                    .map_or(1, |p| p.facets as usize)
            })
            .sum()
    }

    /// The most spotlights [`Show::pose`] gives at any time: every prism in.
    pub fn most_lights(&self) -> usize {
        self.fixtures
            .iter()
            .map(|f| f.prism.map_or(1, |p| p.facets as usize))
            .sum()
    }
}

/// The albedo of a fixture's body: a black-painted head, as stage fixtures are.
pub const BODY_ALBEDO: f32 = 0.08;

/// Adds the twelve triangles of a cuboid at `centre` whose half-extents run along
/// three perpendicular unit vectors (also a GDTF model's box primitive).
pub(crate) fn cuboid(out: &mut Vec<[Vec3; 3]>, centre: Vec3, half: [(Vec3, f32); 3]) {
    let corner = |i: usize| {
        half.iter().enumerate().fold(centre, |p, (k, &(dir, h))| {
            p + dir * if i >> k & 1 == 1 { h } else { -h }
        })
    };
    // Each face's corners in order around it (bit k: the k-th extent's + side).
    for face in [
        [0, 2, 6, 4],
        [1, 5, 7, 3],
        [0, 4, 5, 1],
        [2, 3, 7, 6],
        [0, 1, 3, 2],
        [4, 6, 7, 5],
    ] {
        let [a, b, c, d] = face.map(corner);
        out.extend([[a, b, c], [a, c, d]]);
    }
}

/// A moving head's body hung at `position` (the lamp, m) with its pan `axis` and
/// `front` (unit, as [`Fixture`]'s), at `pan` and `tilt`, degrees: a base where it
/// hangs, a yoke that pans with two arms holding the head at its tilt pivot (the lamp),
/// and the head, its lens 2 cm ahead of the lamp so that the beam leaves through it: a
/// generic moving head about 0.3 m across, its parts cuboids. It is seen and lit but
/// casts no shadow, since it holds its own lamp.
pub fn body_object(position: Vec3, axis: Vec3, front: Vec3, pan_deg: f32, tilt_deg: f32) -> Object {
    let tilt_axis = axis.cross(front);
    let pan = Quat::from_axis_angle(axis, pan_deg.to_radians());
    let turn = pan * Quat::from_axis_angle(tilt_axis, tilt_deg.to_radians());
    let (beam, up) = (turn * axis, turn * front);
    let right = beam.cross(up);
    let (side, yoke_front) = (pan * tilt_axis, pan * front);
    let (p, a) = (position, axis);
    let mut triangles = Vec::with_capacity(5 * 12);
    cuboid(
        &mut triangles,
        p - 0.14 * beam,
        [(beam, 0.16), (up, 0.12), (right, 0.12)],
    );
    for sign in [-1.0, 1.0] {
        cuboid(
            &mut triangles,
            p + side * (0.19 * sign) - a * 0.17,
            [(side, 0.025), (a, 0.19), (yoke_front, 0.05)],
        );
    }
    cuboid(
        &mut triangles,
        p - a * 0.36,
        [(side, 0.215), (a, 0.025), (yoke_front, 0.05)],
    );
    cuboid(
        &mut triangles,
        p - a * 0.45,
        [(tilt_axis, 0.2), (a, 0.06), (front, 0.17)],
    );
    Object {
        shape: Shape::Mesh(Mesh::new(triangles)),
        albedo: Vec3::splat(BODY_ALBEDO),
        casts_shadow: false,
    }
}

impl Fixture {
    /// The fixture's body at `pan` and `tilt`, degrees: its GDTF file's models
    /// ([`Fixture::model_at`]) or atmo's generic head ([`body_object`]).
    pub fn body(&self, pan_deg: f32, tilt_deg: f32) -> Object {
        #[cfg(feature = "gdtf")]
        if let Some(model) = &self.model {
            return self.model_at(model, pan_deg, tilt_deg);
        }
        body_object(self.position, self.axis, self.front, pan_deg, tilt_deg)
    }

    /// The GDTF models of `model` posed: GDTF's frame (z up) turned into the fixture's
    /// (x along `axis x front`, y along `front`, z against `axis`), the tilt pivot (or,
    /// without one, the pan pivot) at the lamp's `position`; parts under the tilt axis
    /// tilt about its pivot, then everything under the pan axis pans about its pivot,
    /// as [`Fixture::aim`] turns the beam. Seen and lit; no shadow.
    #[cfg(feature = "gdtf")]
    pub fn model_at(
        &self,
        model: &super::gdtf_body::GdtfBody,
        pan_deg: f32,
        tilt_deg: f32,
    ) -> Object {
        use super::gdtf_body::Turns;
        let side = self.axis.cross(self.front);
        let turn = |p: Vec3| side * p.x + self.front * p.y - self.axis * p.z;
        let origin = self.position - turn(model.tilt_pivot);
        let (pan_pivot, tilt_pivot) = (origin + turn(model.pan_pivot), self.position);
        let pan = Quat::from_axis_angle(self.axis, pan_deg.to_radians());
        let tilt = Quat::from_axis_angle(side, tilt_deg.to_radians());
        let triangles = model
            .parts
            .iter()
            .flat_map(|part| {
                part.triangles.iter().map(move |t| {
                    t.map(|p| {
                        let w = origin + turn(p);
                        let w = match part.turns {
                            Turns::Not => return w,
                            Turns::Pan => w,
                            Turns::PanAndTilt => tilt_pivot + tilt * (w - tilt_pivot),
                        };
                        pan_pivot + pan * (w - pan_pivot)
                    })
                })
            })
            .collect();
        Object {
            shape: Shape::Mesh(Mesh::new(triangles)),
            albedo: Vec3::splat(BODY_ALBEDO),
            casts_shadow: false,
        }
    }

    /// The beam's direction and the head's up (unit) at `pan` and `tilt`, degrees.
    pub fn aim(&self, pan_deg: f32, tilt_deg: f32) -> (Vec3, Vec3) {
        let tilt_axis = self.axis.cross(self.front);
        let turn = Quat::from_axis_angle(self.axis, pan_deg.to_radians())
            * Quat::from_axis_angle(tilt_axis, tilt_deg.to_radians());
        (turn * self.axis, turn * self.front)
    }

    /// The pan and tilt, degrees, within the fixture's ranges, that aim the beam at
    /// `target` (m), nearest to `from` (pan, tilt) as a desk moves a head: the least
    /// total travel. `None` when no pan and tilt in the ranges reach it.
    ///
    /// [`Fixture::aim`] inverted: the beam at tilt `t` and pan `p` is
    /// `axis cos t + sin t (front cos p + side sin p)`, `side = axis x front`, so for a
    /// unit direction `d`: `t = +-acos(d . axis)`, `p = atan2(d . side, d . front)`
    /// (plus 180 deg for the negative tilt), each pan also 360 deg round.
    pub fn toward(&self, target: Vec3, from: (f32, f32)) -> Option<(f32, f32)> {
        let d = (target - self.position).try_normalize()?;
        let side = self.axis.cross(self.front);
        let (c, x, y) = (d.dot(self.axis), d.dot(self.front), d.dot(side));
        let sine = x.hypot(y);
        let tilt = sine.atan2(c).to_degrees();
        // Along the axis any pan will do: keep the one it has.
        let pan = if sine < 1e-6 {
            from.0
        } else {
            y.atan2(x).to_degrees()
        };
        let in_range = |v: f32, [lo, hi]: [f32; 2]| (lo..=hi).contains(&v);
        [(pan, tilt), (pan + 180.0, -tilt)]
            .into_iter()
            .flat_map(|(p, t)| (-3..=3).map(move |k| (p + 360.0 * k as f32, t)))
            .filter(|&(p, t)| in_range(p, self.pan_range_deg) && in_range(t, self.tilt_range_deg))
            .min_by(|a, b| {
                let travel = |(p, t): (f32, f32)| (p - from.0).abs() + (t - from.1).abs();
                travel(*a).total_cmp(&travel(*b))
            })
    }

    /// The spotlights this fixture is in `state`, its gobo turned `gobo_deg`: its beam,
    /// or through its prism one beam a facet, each with its share of the light.
    pub fn lights(&self, state: &State, gobo_deg: f32) -> Vec<Spotlight> {
        let c = &state.channels;
        let (beam, up) = self.aim(c[PAN], c[TILT]);
        let Some(prism) = self.prism_at(state) else {
            return vec![self.light_along(state, gobo_deg, beam, up, 1.0)];
        };
        let right = beam.cross(up);
        let share = 1.0 / prism.facets as f32;
        (0..prism.facets)
            .map(|k| {
                // The facet's side, and the turn that takes the beam toward it.
                let side = (c[PRISM] + 360.0 * k as f32 * share).to_radians();
                let toward = up * side.cos() + right * side.sin();
                let turn = Quat::from_axis_angle(beam.cross(toward), prism.angle_deg.to_radians());
                self.light_along(state, gobo_deg, turn * beam, turn * up, share)
            })
            .collect()
    }

    /// The prism in the beam in `state`, if the head has one and it is in.
    fn prism_at(&self, state: &State) -> Option<Prism> {
        self.prism.filter(|_| state.prism_in)
    }

    /// The spotlight of this fixture in `state` along `beam` with the gobo's `up`
    /// (unit, perpendicular), carrying `share` of its light.
    fn light_along(
        &self,
        state: &State,
        gobo_deg: f32,
        beam: Vec3,
        up: Vec3,
        share: f32,
    ) -> Spotlight {
        let c = &state.channels;
        let frame: Mat3 = light_frame(beam, up).expect("up is perpendicular to the beam");
        // The same flux in a narrower cone: the on-axis intensity grows as the profile's
        // solid angle shrinks. The iris cuts the cone, not the intensity on the axis.
        let gather = self.solid_angle(self.zoom_range_deg[1]) / self.solid_angle(c[ZOOM]);
        let colour = Vec3::new(c[RED], c[RED + 1], c[RED + 2]);
        let beam_half = 0.5 * (c[ZOOM] * self.zoom_scale * c[IRIS]).to_radians();
        let field_half = (beam_half * self.field_ratio).min(85f32.to_radians());
        let gobo = match state.gobo {
            0 => None,
            k => {
                let mut gobo = self.wheel[k - 1].clone();
                gobo.rotation = gobo_deg.to_radians();
                Some(gobo)
            }
        };
        Spotlight::new(
            self.position,
            frame,
            colour * (self.intensity * gather * c[DIMMER] * share),
            field_half,
            Profile::Beam {
                beam_half,
                falloff: self.falloff,
            },
            gobo,
        )
    }
}

impl Fixture {
    /// `integral profile dOmega` at zoom `zoom_deg` with the iris open, sr: the solid
    /// angle the on-axis intensity would fill, so flux = intensity times it.
    pub fn solid_angle(&self, zoom_deg: f32) -> f32 {
        let beam_half = 0.5 * (zoom_deg * self.zoom_scale).to_radians();
        let field_half = (beam_half * self.field_ratio).min(85f32.to_radians());
        profile_solid_angle(beam_half, field_half, self.falloff)
    }
}

/// `integral profile dOmega` of a beam full inside `beam_half`, falling by `falloff`
/// in angle to zero at `field_half` (radians), sr (midpoint rule, 2,000 steps: 1e-6).
pub fn profile_solid_angle(beam_half: f32, field_half: f32, falloff: Falloff) -> f32 {
    let steps = 2000;
    let d = field_half as f64 / steps as f64;
    let width = (field_half - beam_half).max(1e-9) as f64;
    let sum: f64 = (0..steps)
        .map(|k| {
            let theta = (k as f64 + 0.5) * d;
            let x = ((field_half as f64 - theta) / width).clamp(0.0, 1.0);
            falloff.shape(x as f32) as f64 * theta.sin()
        })
        .sum();
    (std::f64::consts::TAU * sum * d) as f32
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// A hanging head at 6 m, widest zoom 40 deg, gobo at 10 deg, no wheel or prism.
    pub(crate) fn head() -> Fixture {
        Fixture {
            name: "head".into(),
            position: Vec3::new(0.0, 6.0, 0.0),
            axis: Vec3::NEG_Y,
            front: Vec3::Z,
            intensity: 1000.0,
            zoom_range_deg: [10.0, 40.0],
            zoom_scale: 1.0,
            field_ratio: 1.25,
            falloff: Falloff::Smooth,
            wheel: Vec::new(),
            gobo_rotation_deg: 10.0,
            pan_range_deg: [-270.0, 270.0],
            tilt_range_deg: [-135.0, 135.0],
            start: State {
                channels: [0.0, 0.0, 40.0, 1.0, 1.0, 1.0, 1.0, 1.0, 0.0, 0.0],
                gobo: 0,
                prism_in: true,
            },
            prism: None,
            white: Vec3::ONE,
            patch: None,
            body: false,
            #[cfg(feature = "gdtf")]
            model: None,
        }
    }

    /// Three facets: each beam 10 deg off the head's, 120 deg apart around it, the
    /// first toward the gobo's up, the light shared equally.
    #[test]
    fn a_prism_splits_the_beam_into_facets_around_it() {
        let mut f = head();
        let mut state = f.start;
        (state.channels[PAN], state.channels[TILT]) = (30.0, 20.0);
        let whole = f.lights(&state, 0.0).remove(0);
        f.prism = Some(Prism {
            facets: 3,
            angle_deg: 10.0,
        });
        let facets = f.lights(&state, 0.0);
        assert_eq!(facets.len(), 3);
        let show = Show::new(vec![head(), f.clone()], Vec::new());
        assert_eq!((show.light_count(0.0), show.lights().len()), (4, 4));
        let total: Vec3 = facets.iter().map(|l| l.intensity).sum();
        assert!(
            (total - whole.intensity).abs().max_element() < 1e-3,
            "{total}"
        );
        let (beam, up) = (whole.light_from_world.row(2), whole.light_from_world.row(1));
        let around = |d: Vec3| (d - beam * d.dot(beam)).normalize();
        for (k, l) in facets.iter().enumerate() {
            let d = l.light_from_world.row(2);
            assert!(
                (d.dot(beam).acos().to_degrees() - 10.0).abs() < 1e-3,
                "{k}: {d}"
            );
            let next = facets[(k + 1) % 3].light_from_world.row(2);
            assert!((around(d).dot(around(next)) + 0.5).abs() < 1e-4);
            assert_eq!(l.position, whole.position);
        }
        assert!(around(facets[0].light_from_world.row(2)).dot(up) > 0.9999);
        // The prism turned a quarter: the first facet toward the gobo's right.
        state.channels[PRISM] = 90.0;
        let turned = f.lights(&state, 0.0);
        let right = beam.cross(up);
        assert!(around(turned[0].light_from_world.row(2)).dot(right) > 0.9999);
    }

    fn set(pairs: &[(usize, f32)]) -> Change {
        let mut change = Change::default();
        for (c, v) in pairs {
            change.channels[*c] = Some(*v);
        }
        change
    }

    #[test]
    fn pan_and_tilt_aim_a_hanging_head() {
        let f = head();
        let close = |a: Vec3, b: Vec3| (a - b).length() < 1e-5;
        assert!(close(f.aim(0.0, 0.0).0, Vec3::NEG_Y));
        // Tilt 90 at pan 0: toward front; then pan 90 about the (downward) axis.
        assert!(close(f.aim(0.0, 90.0).0, Vec3::Z));
        let panned = f.aim(90.0, 90.0).0;
        assert!(close(
            panned,
            Quat::from_axis_angle(Vec3::NEG_Y, 90f32.to_radians()) * Vec3::Z
        ));
        // Tilt 45: halfway between down and front; the head's up stays perpendicular.
        let (beam, up) = f.aim(30.0, 45.0);
        assert!((beam.y + 0.5f32.sqrt()).abs() < 1e-5);
        assert!(beam.dot(up).abs() < 1e-6);
    }

    #[test]
    fn toward_inverts_aim_within_the_ranges_and_nearest_to_where_the_head_is() {
        let mut f = head();
        f.position = Vec3::new(1.0, 6.0, -2.0);
        let hits = |(pan, tilt): (f32, f32), target: Vec3| {
            let beam = f.aim(pan, tilt).0;
            (beam - (target - f.position).normalize()).length() < 1e-4
        };
        for target in [
            Vec3::new(3.0, 0.0, 1.0),
            Vec3::new(-4.0, 0.0, -5.0),
            Vec3::new(1.0, 8.0, 4.0),
            Vec3::new(0.0, 6.0, -2.0),
        ] {
            for from in [(0.0, 0.0), (200.0, -100.0), (-250.0, 30.0)] {
                let (pan, tilt) = f.toward(target, from).expect("in reach");
                assert!(hits((pan, tilt), target), "{target} from {from:?}");
                assert!((-270.0..=270.0).contains(&pan) && (-135.0..=135.0).contains(&tilt));
            }
        }
        // Of the two ways to a point, the one nearer the head's pan: from 200 deg the
        // yoke does not swing back through 0.
        let target = Vec3::new(3.0, 0.0, 1.0);
        let near_zero = f.toward(target, (0.0, 0.0)).unwrap();
        let far = f.toward(target, (200.0, 0.0)).unwrap();
        assert!(
            near_zero.0.abs() < 180.0 && (far.0 - 200.0).abs() < 180.0,
            "{far:?}"
        );
        assert!((near_zero.0 - far.0).abs() > 90.0);
        // Straight down the axis keeps the pan; beyond the tilt's reach is none.
        assert_eq!(
            f.toward(Vec3::new(1.0, 0.0, -2.0), (42.0, 10.0)),
            Some((42.0, 0.0))
        );
        f.tilt_range_deg = [-60.0, 60.0];
        assert_eq!(f.toward(Vec3::new(1.0, 8.0, 4.0), (0.0, 0.0)), None);
    }

    #[test]
    fn cues_fade_from_where_the_attribute_is_and_gobos_turn_by_their_speed() {
        let mut show = Show::new(
            vec![head()],
            vec![
                Cue {
                    time_s: 1.0,
                    fade_s: 2.0,
                    changes: vec![(0, set(&[(PAN, 90.0), (DIMMER, 0.0), (SPEED, 30.0)]))],
                },
                Cue {
                    // Starts in the middle of the first cue's fade.
                    time_s: 2.0,
                    fade_s: 0.0,
                    changes: vec![(0, set(&[(PAN, -10.0)]))],
                },
            ],
        );
        assert_eq!(show.duration(), 3.0);
        assert_eq!(show.state(0, 0.5).channels[PAN], 0.0);
        assert!((show.state(0, 1.5).channels[PAN] - 22.5).abs() < 1e-4);
        // The second cue snaps pan; the first's dimmer fade runs on.
        assert_eq!(show.state(0, 2.0).channels[PAN], -10.0);
        assert!((show.state(0, 2.5).channels[DIMMER] - 0.25).abs() < 1e-5);
        assert_eq!(show.state(0, 9.0).channels[DIMMER], 0.0);
        // The speed ramps from 0 to 30 deg/s over 1-3 s: 30 degrees turned by 3 s, then
        // 30 a second.
        assert!((show.gobo_angle_deg(0, 1.0) - 10.0).abs() < 1e-4);
        assert!((show.gobo_angle_deg(0, 3.0) - 40.0).abs() < 1e-3);
        assert!((show.gobo_angle_deg(0, 5.0) - 100.0).abs() < 1e-3);
        // Posed: a dark head at the end, pointing where pan -10 puts it.
        assert!(show.lights()[0].intensity.max_element() > 0.0);
        show.at_time(3.0);
        assert_eq!(show.time_s(), 3.0);
        assert_eq!(show.lights()[0].intensity, Vec3::ZERO);
    }

    /// A snapped speed turns the gobo at the old speed up to the snap and the new one
    /// after it (the trapezoid rule over the snap's time averaged the two before it).
    #[test]
    fn a_snapped_gobo_speed_turns_at_the_old_speed_until_the_snap() {
        let show = Show::new(
            vec![head()],
            vec![
                Cue {
                    time_s: 1.0,
                    fade_s: 0.0,
                    changes: vec![(0, set(&[(SPEED, 90.0)]))],
                },
                Cue {
                    time_s: 3.0,
                    fade_s: 0.0,
                    changes: vec![(0, set(&[(SPEED, -30.0)]))],
                },
            ],
        );
        // Start 10 deg; still until 1 s, 90 deg/s to 3 s, then -30 deg/s.
        for (t, angle) in [
            (0.5, 10.0),
            (1.0, 10.0),
            (2.0, 100.0),
            (3.0, 190.0),
            (5.0, 130.0),
        ] {
            let got = show.gobo_angle_deg(0, t);
            assert!((got - angle).abs() < 1e-3, "at {t} s: {got}, not {angle}");
        }
    }

    #[test]
    fn a_narrower_zoom_gathers_the_flux_and_the_iris_cuts_the_cone() {
        let f = head();
        let mut state = f.start;
        let wide = f.lights(&state, 0.0).remove(0);
        state.channels[ZOOM] = 20.0;
        let narrow = f.lights(&state, 0.0).remove(0);
        // The same flux: the ratio of the profiles' solid angles, near the ratio of
        // the cones' cross-sections (7 % off it at these angles).
        let ratio = narrow.intensity.x / wide.intensity.x;
        let want = f.solid_angle(40.0) / f.solid_angle(20.0);
        assert!((ratio - want).abs() < 1e-4 * want, "{ratio} {want}");
        let small_angles = (20f32.to_radians().tan() / 10f32.to_radians().tan()).powi(2);
        assert!(
            (ratio - small_angles).abs() < 0.1 * small_angles,
            "{ratio} {small_angles}"
        );
        state.channels[IRIS] = 0.5;
        let irised = f.lights(&state, 0.0).remove(0);
        assert_eq!(irised.intensity, narrow.intensity);
        assert!((irised.field_half - 0.5 * narrow.field_half).abs() < 1e-6);
        assert!((narrow.field_half - 1.25 * 10f32.to_radians()).abs() < 1e-6);
    }
}
