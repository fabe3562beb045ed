//! The heads over time as the desk's frames drive them: one [`Playback`] for the live
//! window ([`super::receiver`]) and for a recorded show ([`super::recording`]), so a
//! recording renders offline to the pictures the window showed at the same times.
//!
//! Frames ([`Event`]s, stamped in whole microseconds from the show's start) are applied
//! in order. Between two frames each head holds what the last said; a gobo or prism
//! set turning integrates its speed from the frame that set it (exactly: the speed is
//! constant until the next frame), one set to an index stands at it. A fixture without
//! a patch plays the scene's cues as before.

use super::{Levels, Reading, Turn};
use crate::shafts::show::{Show, State, CHANNELS};
use crate::shafts::Scene;

/// One universe's levels as they became at `time_us`, microseconds from the start.
#[derive(Debug, Clone, PartialEq)]
pub struct Event {
    pub time_us: u64,
    pub universe: u16,
    pub levels: Box<Levels>,
}

/// Of each strobe period, the share the shutter is open: a flash, first in the
/// period, periods counted from the show's start.
pub const STROBE_OPEN: f64 = 0.2;

/// A turning part's angle: where it was at the last frame, and how it moves.
#[derive(Debug, Clone, Copy)]
struct Angle {
    deg: f64,
    turn: Turn,
}

impl Angle {
    /// The angle `dt_s` seconds after the last frame, degrees.
    fn after(&self, dt_s: f64) -> f64 {
        match self.turn {
            Turn::Index(x) => x as f64,
            Turn::Spin(speed) => self.deg + speed as f64 * dt_s,
        }
    }
}

/// A patched head: what its channels said last, its gobo's and prism's angles.
#[derive(Debug, Clone, Copy)]
struct Head {
    reading: Reading,
    gobo: Angle,
    prism: Angle,
}

/// The index of a channel in a [`State`]'s.
fn channel(name: &str) -> usize {
    CHANNELS.iter().position(|c| *c == name).expect("a channel")
}

/// The desk's frames applied to a show's fixtures.
#[derive(Debug, Clone)]
pub struct Playback {
    /// Each universe's levels as last set.
    universes: std::collections::BTreeMap<u16, Box<Levels>>,
    /// The last frame's time, us.
    time_us: u64,
    /// One per fixture, `None` where it has no patch.
    heads: Vec<Option<Head>>,
}

impl Playback {
    /// The show's fixtures before any frame: each at its scene's start.
    pub fn new(show: &Show) -> Playback {
        let (speed, prism) = (channel("gobo_speed_dps"), channel("prism_deg"));
        let heads = show
            .fixtures
            .iter()
            .map(|f| {
                f.patch.as_ref().map(|_| Head {
                    reading: Reading::default(),
                    gobo: Angle {
                        deg: f.gobo_rotation_deg as f64,
                        turn: Turn::Spin(f.start.channels[speed]),
                    },
                    prism: Angle {
                        deg: f.start.channels[prism] as f64,
                        turn: Turn::Index(f.start.channels[prism]),
                    },
                })
            })
            .collect();
        Playback {
            universes: Default::default(),
            time_us: 0,
            heads,
        }
    }

    /// The playback for another show (the scene edited or read again): its fixtures
    /// as the universes' current levels drive them, turning parts from their starts.
    pub fn for_show(&self, show: &Show) -> Playback {
        let mut p = Playback::new(show);
        for (&universe, levels) in &self.universes {
            p.apply(
                show,
                &Event {
                    time_us: self.time_us,
                    universe,
                    levels: levels.clone(),
                },
            );
        }
        p
    }

    /// The last frame's time, us.
    pub fn time_us(&self) -> u64 {
        self.time_us
    }

    /// Applies a frame (one that is stamped before the last is taken at the last's
    /// time). Returns whether a patched fixture listens to its universe.
    pub fn apply(&mut self, show: &Show, event: &Event) -> bool {
        let t = event.time_us.max(self.time_us);
        let dt = (t - self.time_us) as f64 * 1e-6;
        for head in self.heads.iter_mut().flatten() {
            head.gobo.deg = head.gobo.after(dt);
            head.prism.deg = head.prism.after(dt);
        }
        self.time_us = t;
        let mut heard = false;
        for (f, head) in show.fixtures.iter().zip(&mut self.heads) {
            let (Some(patch), Some(head)) = (&f.patch, head) else {
                continue;
            };
            if patch.universe != event.universe {
                continue;
            }
            heard = true;
            let r = patch.read(&event.levels);
            head.gobo.turn = r.gobo_turn.unwrap_or(head.gobo.turn);
            head.prism.turn = r.prism_turn.unwrap_or(head.prism.turn);
            head.reading = r;
        }
        self.universes.insert(event.universe, event.levels.clone());
        heard
    }

    /// The universe's levels as the frames so far left them (all 0 before any).
    pub fn levels(&self, universe: u16) -> Option<&Levels> {
        self.universes.get(&universe).map(|l| &**l)
    }

    /// Each fixture's state at `time_us` (not before the last frame) with its gobo's
    /// angle, degrees: a patched head as its channels said last, turning parts moved
    /// on, the dimmer through the shutter; an unpatched one as the cues have it.
    pub fn states(&self, show: &Show, time_us: u64) -> Vec<(State, f32)> {
        let t_s = time_us as f64 * 1e-6;
        let dt = time_us.saturating_sub(self.time_us) as f64 * 1e-6;
        let (dimmer, speed, prism) = (
            channel("dimmer"),
            channel("gobo_speed_dps"),
            channel("prism_deg"),
        );
        show.fixtures
            .iter()
            .zip(&self.heads)
            .enumerate()
            .map(|(k, (f, head))| {
                let Some(head) = head else {
                    return (
                        show.state(k, t_s as f32),
                        show.gobo_angle_deg(k, t_s as f32),
                    );
                };
                let limits = [f.pan_range_deg, f.tilt_range_deg, f.zoom_range_deg];
                let mut s = head.reading.state(&f.start, f.white, limits);
                if s.gobo > f.wheel.len() {
                    s.gobo = 0;
                }
                s.channels[prism] = head.prism.after(dt) as f32;
                if let Turn::Spin(v) = head.gobo.turn {
                    s.channels[speed] = v;
                }
                let open = match head.reading.strobe_hz {
                    None => true,
                    Some(hz) => hz > 0.0 && (t_s * hz as f64).fract() < STROBE_OPEN,
                };
                if !open {
                    s.channels[dimmer] = 0.0;
                }
                (s, head.gobo.after(dt) as f32)
            })
            .collect()
    }

    /// Poses the scene's heads (and their bodies) at `time_us`.
    pub fn pose(&self, scene: &mut Scene, time_us: u64) {
        let states = self.states(&scene.show, time_us);
        scene.drive((time_us as f64 * 1e-6) as f32, &states);
    }

    /// Applies every frame of `frames` up to `time_us` (they are in time order), and
    /// poses the scene then: one step of an offline render of a recording.
    pub fn play_to<I>(
        &mut self,
        scene: &mut Scene,
        frames: &mut std::iter::Peekable<I>,
        time_us: u64,
    ) -> crate::error::Result<()>
    where
        I: Iterator<Item = crate::error::Result<Event>>,
    {
        while let Some(next) = frames.next_if(|e| e.as_ref().map_or(true, |e| e.time_us <= time_us))
        {
            self.apply(&scene.show, &next?);
        }
        self.pose(scene, time_us);
        Ok(())
    }
}
