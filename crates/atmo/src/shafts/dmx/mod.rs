//! DMX512 into moving heads: what a lighting desk sends, read as a fixture's attributes.
//!
//! A desk drives each fixture through a run of channels in one universe (512 bytes) from
//! its start address: the fixture's DMX mode ([`Mode`]) says which channel does what.
//! Its pieces are GDTF's (DIN SPEC 15800): a [`Channel`] takes one byte, or two or more
//! for coarse and fine (`Offset="1,2"`), and is split by DMX value into
//! [`Function`]s, each turning its span of values linearly into a physical one (degrees,
//! a 0-1 fraction, degrees per second, hertz) or, on a wheel, into a slot by its
//! [`ChannelSet`]s. A GDTF fixture's mode comes from its file ([`super::gdtf`]); a
//! fixture without one gives a personality in the scene file ([`Mode::personality`]).
//!
//! [`Patch::read`] gives what the channels say as a [`Reading`]; the [`playback`]
//! turns the readings over time into the heads' [`State`]s (turning gobos and prisms
//! integrate their speeds between frames), the same for a live desk
//! ([`receiver`]) and for a recorded show ([`recording`]).

#[cfg(feature = "gdtf")]
pub mod gdtf_mode;
pub mod playback;
#[cfg(feature = "dmx")]
pub mod receiver;
pub mod recording;
#[cfg(feature = "dmx")]
pub mod wire;

use glam::Vec3;

use super::show::State;
use crate::error::{Error, Result};

/// The channels of one universe.
pub const UNIVERSE_SIZE: usize = 512;

/// The highest universe number sACN allows (and the highest atmo patches).
pub const MAX_UNIVERSE: u16 = 63999;

/// One universe's levels, channel 1 first.
pub type Levels = [u8; UNIVERSE_SIZE];

/// What a channel function does to the fixture: the attributes atmo models (GDTF's
/// names in [`Attribute::from_gdtf`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Attribute {
    /// Pan and tilt, degrees.
    Pan,
    Tilt,
    /// The beam's angle, degrees (the fixture's zoom range).
    Zoom,
    /// The aperture, 0-1 of the open iris.
    Iris,
    /// The dimmer, 0-1.
    Dimmer,
    /// Additive colour, 0-1 per primary.
    Red,
    Green,
    Blue,
    /// Subtractive colour flags, 0-1 (1 takes its complement out).
    Cyan,
    Magenta,
    Yellow,
    /// The colour wheel's slot ([`ChannelSet::slot`] into [`Mode::colours`]).
    ColourWheel,
    /// The gobo wheel's slot ([`ChannelSet::slot`]: 0 open, `k` the `k`-th gobo).
    Gobo,
    /// The gobo's angle, degrees (index), or its turning speed, degrees per second.
    GoboIndex,
    GoboSpin,
    /// The prism in (a set whose slot is not 0) or out.
    Prism,
    /// The prism's angle, degrees, or its turning speed, degrees per second.
    PrismIndex,
    PrismSpin,
    /// The shutter: open or closed by the function's or set's name ("Closed").
    Shutter,
    /// A strobing shutter, flashes per second.
    Strobe,
}

impl Attribute {
    /// The attribute of a GDTF `Attribute` name, if atmo models it (focus, frost,
    /// colour temperature correction, animation wheels and the rest are not).
    pub fn from_gdtf(name: &str) -> Option<Attribute> {
        use Attribute::*;
        Some(match name {
            "Pan" => Pan,
            "Tilt" => Tilt,
            "Zoom" => Zoom,
            "Iris" => Iris,
            "Dimmer" => Dimmer,
            "ColorAdd_R" | "ColorRGB_Red" => Red,
            "ColorAdd_G" | "ColorRGB_Green" => Green,
            "ColorAdd_B" | "ColorRGB_Blue" => Blue,
            "ColorSub_C" => Cyan,
            "ColorSub_M" => Magenta,
            "ColorSub_Y" => Yellow,
            "Color1" => ColourWheel,
            "Gobo1" => Gobo,
            "Gobo1Pos" => GoboIndex,
            "Gobo1PosRotate" | "Gobo1SelectSpin" => GoboSpin,
            "Prism1" => Prism,
            "Prism1Pos" => PrismIndex,
            "Prism1PosRotate" => PrismSpin,
            "Shutter1" => Shutter,
            s if s.starts_with("Shutter1Strobe") || s == "StrobeFrequency" => Strobe,
            _ => return None,
        })
    }
}

/// A range of a channel's values that selects a wheel's slot.
#[derive(Debug, Clone, PartialEq)]
pub struct ChannelSet {
    /// The first value of its range (the next set's start ends it), at the channel's
    /// resolution.
    pub dmx_from: u32,
    /// The wheel's slot it selects: 0 open (or out), `k` the `k`-th slot atmo keeps.
    pub slot: usize,
    /// Whether its name says the shutter is closed.
    pub closed: bool,
}

/// A span of a channel's values and what they do.
#[derive(Debug, Clone, PartialEq)]
pub struct Function {
    /// Its attribute; `None` for a function atmo does not model (the channel does
    /// nothing in its span).
    pub attribute: Option<Attribute>,
    /// The first value of its span, at the channel's resolution; the span ends where the
    /// next function of the channel starts.
    pub dmx_from: u32,
    /// The physical values at the span's first and last value (linear between).
    pub physical: [f32; 2],
    /// The slots its values select, for a wheel (in order of `dmx_from`).
    pub sets: Vec<ChannelSet>,
    /// Whether its name says the shutter is closed.
    pub closed: bool,
    /// Only while another channel (an index into [`Mode::channels`]) has a value in
    /// this range (GDTF's `ModeMaster`, `ModeFrom`, `ModeTo`).
    pub mode_master: Option<(usize, [u32; 2])>,
}

/// One DMX channel of a mode: one byte, or coarse and fine bytes.
#[derive(Debug, Clone, PartialEq)]
pub struct Channel {
    /// Its name, for messages.
    pub name: String,
    /// Its bytes' offsets from the fixture's start address, 1-based, coarse first.
    pub offsets: Vec<u16>,
    /// Its functions, in order of `dmx_from` (the first starts at 0).
    pub functions: Vec<Function>,
}

impl Channel {
    /// The channel's value in `levels` of a fixture at `address` (1-based; the mode's
    /// footprint fits the universe), at its resolution.
    pub fn value(&self, levels: &Levels, address: u16) -> u32 {
        self.offsets.iter().fold(0u32, |v, &o| {
            (v << 8) | levels[(address + o - 2) as usize] as u32
        })
    }

    /// The largest value the channel takes.
    pub fn max(&self) -> u32 {
        ((1u64 << (8 * self.offsets.len())) - 1) as u32
    }
}

/// A fixture's DMX mode: its channels and its wheels' colours.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Mode {
    /// The mode's name.
    pub name: String,
    /// Its channels (an attribute may have more than one; the last one set wins).
    pub channels: Vec<Channel>,
    /// The colour wheel's slots as linear RGB (slot `k` is `colours[k - 1]`; 0 white).
    pub colours: Vec<Vec3>,
}

/// The most bytes a channel takes (GDTF allows 32-bit channels).
const MAX_BYTES: usize = 4;

impl Mode {
    /// How many channels the mode takes from its start address: its highest offset.
    pub fn footprint(&self) -> u16 {
        self.channels
            .iter()
            .flat_map(|c| c.offsets.iter().copied())
            .max()
            .unwrap_or(0)
    }

    /// Checks what a decoder relies on: offsets in 1..=512, at most four bytes a
    /// channel, functions in order from 0, sets in order, mode masters that exist.
    pub fn validate(&self, at: &str) -> Result<()> {
        for c in &self.channels {
            let bad =
                |why: String| Err(Error::Invalid(format!("{at}: channel {:?}: {why}", c.name)));
            if c.offsets.is_empty() || c.offsets.len() > MAX_BYTES {
                return bad(format!(
                    "{} bytes: allowed 1 to {MAX_BYTES}",
                    c.offsets.len()
                ));
            }
            if let Some(o) = c
                .offsets
                .iter()
                .find(|&&o| !(1..=UNIVERSE_SIZE as u16).contains(&o))
            {
                return bad(format!("offset {o}: allowed 1 to {UNIVERSE_SIZE}"));
            }
            if c.functions.first().is_none_or(|f| f.dmx_from != 0) {
                return bad("its first function must start at DMX value 0".into());
            }
            let max = c.max();
            for f in &c.functions {
                if f.dmx_from > max {
                    return bad(format!(
                        "a function starts at {}, past its largest value {max}",
                        f.dmx_from
                    ));
                }
                if f.sets.windows(2).any(|w| w[1].dmx_from < w[0].dmx_from) {
                    return bad("its channel sets are not in DMX order".into());
                }
                if let Some((m, _)) = f.mode_master {
                    if m >= self.channels.len() {
                        return bad("a function's mode master is not a channel of the mode".into());
                    }
                }
            }
            if c.functions
                .windows(2)
                .any(|w| w[1].dmx_from < w[0].dmx_from)
            {
                return bad("its functions are not in DMX order".into());
            }
        }
        Ok(())
    }

    /// A mode from a personality's channel names, for a fixture without a GDTF file
    /// (docs/previz.md lists them): each name takes the next channel, and a name
    /// followed by `NAME_fine` takes two (coarse, fine). Pan, tilt and zoom span the
    /// fixture's `ranges` (pan, tilt, zoom, degrees); the gobo channel splits its values
    /// into `slots + 1` equal bands (open, then each gobo).
    pub fn personality(
        names: &[String],
        ranges: [[f32; 2]; 3],
        slots: usize,
        at: &str,
    ) -> Result<Mode> {
        let mut channels: Vec<Channel> = Vec::new();
        let mut offset = 0u16;
        for (i, name) in names.iter().enumerate() {
            offset += 1;
            if let Some(coarse) = name.strip_suffix("_fine") {
                match channels.last_mut() {
                    Some(c) if c.name == coarse && c.offsets.len() < 2 => {
                        c.offsets.push(offset);
                        rescale(c, 257);
                        continue;
                    }
                    _ => {
                        return Err(Error::Invalid(format!(
                            "{at}.channels[{i}] = {name:?} must follow {coarse:?}"
                        )))
                    }
                }
            }
            let function = |attribute, physical: [f32; 2]| Function {
                attribute: Some(attribute),
                dmx_from: 0,
                physical,
                sets: Vec::new(),
                closed: false,
                mode_master: None,
            };
            let spans = |attribute, spans: &[(u32, [f32; 2])]| -> Vec<Function> {
                spans
                    .iter()
                    .map(|&(dmx_from, physical)| Function {
                        dmx_from,
                        ..function(attribute, physical)
                    })
                    .collect()
            };
            // A wheel: bands of values from each `(dmx_from, slot)`.
            let wheel = |attribute, bands: Vec<(u32, usize)>| {
                vec![Function {
                    sets: bands
                        .into_iter()
                        .map(|(dmx_from, slot)| ChannelSet {
                            dmx_from,
                            slot,
                            closed: false,
                        })
                        .collect(),
                    ..function(attribute, [0.0, 0.0])
                }]
            };
            // A speed: stopped, one way slow to fast, stopped, the other way.
            let spin = |attribute| {
                let slow = 360.0 / 127.0;
                spans(
                    attribute,
                    &[
                        (0, [0.0, 0.0]),
                        (1, [slow, 360.0]),
                        (128, [0.0, 0.0]),
                        (129, [-slow, -360.0]),
                    ],
                )
            };
            use Attribute::*;
            let functions = match name.as_str() {
                "pan" => vec![function(Pan, ranges[0])],
                "tilt" => vec![function(Tilt, ranges[1])],
                "zoom" => vec![function(Zoom, ranges[2])],
                "iris" => vec![function(Iris, [1.0, 0.05])],
                "dimmer" => vec![function(Dimmer, [0.0, 1.0])],
                "red" => vec![function(Red, [0.0, 1.0])],
                "green" => vec![function(Green, [0.0, 1.0])],
                "blue" => vec![function(Blue, [0.0, 1.0])],
                "cyan" => vec![function(Cyan, [0.0, 1.0])],
                "magenta" => vec![function(Magenta, [0.0, 1.0])],
                "yellow" => vec![function(Yellow, [0.0, 1.0])],
                "gobo" => wheel(
                    Gobo,
                    (0..=slots)
                        .map(|slot| ((slot * 256 / (slots + 1)) as u32, slot))
                        .collect(),
                ),
                "gobo_index" => vec![function(GoboIndex, [0.0, 360.0])],
                "gobo_spin" => spin(GoboSpin),
                "prism" => wheel(Prism, vec![(0, 0), (128, 1)]),
                "prism_index" => vec![function(PrismIndex, [0.0, 360.0])],
                "prism_spin" => spin(PrismSpin),
                "shutter" => {
                    let mut f = spans(Shutter, &[(0, [0.0, 0.0]), (16, [1.0, 1.0])]);
                    f[0].closed = true;
                    f.push(Function {
                        dmx_from: 128,
                        ..function(Strobe, [1.0, 25.0])
                    });
                    f
                }
                _ => {
                    return Err(Error::Invalid(format!(
                        "{at}.channels[{i}] = {name:?}: allowed {} (each may be followed \
                         by NAME_fine)",
                        PERSONALITY.join(", ")
                    )))
                }
            };
            if channels.iter().any(|c| c.name == *name) {
                return Err(Error::Invalid(format!(
                    "{at}.channels[{i}] = {name:?} is named twice"
                )));
            }
            channels.push(Channel {
                name: name.clone(),
                offsets: vec![offset],
                functions,
            });
        }
        let mode = Mode {
            name: "personality".into(),
            channels,
            colours: Vec::new(),
        };
        mode.validate(at)?;
        Ok(mode)
    }
}

/// The channel names a personality may use ([`Mode::personality`]).
pub const PERSONALITY: [&str; 18] = [
    "pan",
    "tilt",
    "zoom",
    "iris",
    "dimmer",
    "red",
    "green",
    "blue",
    "cyan",
    "magenta",
    "yellow",
    "gobo",
    "gobo_index",
    "gobo_spin",
    "prism",
    "prism_index",
    "prism_spin",
    "shutter",
];

/// A channel given a fine byte: its values' starts scaled by `factor` (257 mirrors a
/// byte into two, as GDTF does: 255 is 65535).
fn rescale(channel: &mut Channel, factor: u32) {
    for f in &mut channel.functions {
        f.dmx_from *= factor;
        f.sets.iter_mut().for_each(|s| s.dmx_from *= factor);
    }
}

/// How a gobo or a prism turns: held at an angle, or turning.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Turn {
    /// At this angle, degrees.
    Index(f32),
    /// At this speed, degrees per second.
    Spin(f32),
}

/// What a fixture's channels say at one moment; `None` where its mode has no channel
/// for the attribute (the fixture keeps its scene's start).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Reading {
    pub pan_deg: Option<f32>,
    pub tilt_deg: Option<f32>,
    pub zoom_deg: Option<f32>,
    pub iris: Option<f32>,
    pub dimmer: Option<f32>,
    /// Additive colour (1 where a primary has no channel).
    pub rgb: Option<Vec3>,
    /// Subtractive flags (0 where a flag has no channel).
    pub cmy: Option<Vec3>,
    /// The colour wheel's filter (white at its open slot).
    pub wheel: Option<Vec3>,
    pub gobo: Option<usize>,
    pub gobo_turn: Option<Turn>,
    pub prism_in: Option<bool>,
    pub prism_turn: Option<Turn>,
    /// The shutter: `Some(0.0)` closed, `Some(f)` strobing at `f` Hz, `None` open (or
    /// no shutter channel).
    pub strobe_hz: Option<f32>,
}

/// A fixture's place on the desk: its universe, start address and mode.
#[derive(Debug, Clone, PartialEq)]
pub struct Patch {
    /// The universe (sACN's number; Art-Net's port-address plus one, as desks show it).
    pub universe: u16,
    /// The first channel, 1-based.
    pub address: u16,
    pub mode: Mode,
}

impl Patch {
    /// A patch, checked: the mode valid and its footprint inside the universe.
    pub fn new(universe: u16, address: u16, mode: Mode, at: &str) -> Result<Patch> {
        mode.validate(at)?;
        crate::error::check_range(
            &format!("{at}.universe"),
            universe as f64,
            1.0,
            MAX_UNIVERSE as f64,
        )?;
        let last = UNIVERSE_SIZE as u16 + 1 - mode.footprint().max(1);
        crate::error::check_range(&format!("{at}.address"), address as f64, 1.0, last as f64)
            .map_err(|e| {
                Error::Invalid(format!(
                    "{e} (the mode {:?} takes {} channels)",
                    mode.name,
                    mode.footprint()
                ))
            })?;
        Ok(Patch {
            universe,
            address,
            mode,
        })
    }

    /// What the fixture's channels say in its universe's `levels`.
    pub fn read(&self, levels: &Levels) -> Reading {
        let mode = &self.mode;
        let values: Vec<u32> = mode
            .channels
            .iter()
            .map(|c| c.value(levels, self.address))
            .collect();
        let mut r = Reading::default();
        let (mut rgb, mut cmy) = (None::<Vec3>, None::<Vec3>);
        for (c, channel) in mode.channels.iter().enumerate() {
            let v = values[c];
            // The last function that starts at or below the value and whose mode master
            // (if any) is in its range; its span ends where the next such one starts.
            let live = |f: &&Function| {
                f.mode_master
                    .is_none_or(|(m, [lo, hi])| (lo..=hi).contains(&values[m]))
            };
            let mut active = channel.functions.iter().filter(live).peekable();
            let mut chosen = None;
            while let Some(f) = active.next() {
                if f.dmx_from > v {
                    break;
                }
                let end = active.peek().map_or(channel.max(), |n| {
                    n.dmx_from.saturating_sub(1).max(f.dmx_from)
                });
                chosen = Some((f, end));
            }
            let Some((f, end)) = chosen else { continue };
            let Some(attribute) = f.attribute else {
                continue;
            };
            let w = if end > f.dmx_from {
                (v.min(end) - f.dmx_from) as f32 / (end - f.dmx_from) as f32
            } else {
                0.0
            };
            let x = f.physical[0] + w * (f.physical[1] - f.physical[0]);
            let set = f.sets.iter().take_while(|s| s.dmx_from <= v).last();
            let slot = set.map_or(0, |s| s.slot);
            let closed = f.closed || set.is_some_and(|s| s.closed);
            use Attribute::*;
            let unit = x.clamp(0.0, 1.0);
            match attribute {
                Pan => r.pan_deg = Some(x),
                Tilt => r.tilt_deg = Some(x),
                Zoom => r.zoom_deg = Some(x),
                Iris => r.iris = Some(x),
                Dimmer => r.dimmer = Some(unit),
                Red | Green | Blue => {
                    let k = attribute as usize - Red as usize;
                    rgb.get_or_insert(Vec3::ONE)[k] = unit;
                }
                Cyan | Magenta | Yellow => {
                    let k = attribute as usize - Cyan as usize;
                    cmy.get_or_insert(Vec3::ZERO)[k] = unit;
                }
                ColourWheel => {
                    r.wheel = Some(match slot {
                        0 => Vec3::ONE,
                        k => mode.colours.get(k - 1).copied().unwrap_or(Vec3::ONE),
                    })
                }
                Gobo => r.gobo = Some(slot),
                GoboIndex => r.gobo_turn = Some(Turn::Index(x)),
                GoboSpin => r.gobo_turn = Some(Turn::Spin(x)),
                Prism => r.prism_in = Some(slot != 0),
                PrismIndex => r.prism_turn = Some(Turn::Index(x)),
                PrismSpin => r.prism_turn = Some(Turn::Spin(x)),
                Shutter => r.strobe_hz = closed.then_some(0.0),
                Strobe => r.strobe_hz = Some(x.max(0.0)),
            }
        }
        (r.rgb, r.cmy) = (rgb, cmy);
        r
    }
}

impl Reading {
    /// The state a fixture whose state without DMX is `rest` (its scene's start, with
    /// its lamp's `white`) is in: each attribute with a channel as the channel says,
    /// clamped to the fixture's `limits` (pan, tilt, zoom, degrees), the rest as at
    /// rest. The colour is `white` through the additive, subtractive and wheel filters
    /// where the mode has any. Angles of gobo and prism are the playback's.
    pub fn state(&self, rest: &State, white: Vec3, limits: [[f32; 2]; 3]) -> State {
        let mut s = *rest;
        let c = &mut s.channels;
        let clamp = |x: f32, [lo, hi]: [f32; 2]| x.clamp(lo, hi);
        let set = |slot: &mut f32, value: Option<f32>| {
            if let Some(v) = value {
                *slot = v;
            }
        };
        set(&mut c[0], self.pan_deg.map(|x| clamp(x, limits[0])));
        set(&mut c[1], self.tilt_deg.map(|x| clamp(x, limits[1])));
        set(&mut c[2], self.zoom_deg.map(|x| clamp(x, limits[2])));
        set(&mut c[3], self.iris.map(|x| x.clamp(0.05, 1.0)));
        set(&mut c[4], self.dimmer);
        if self.rgb.is_some() || self.cmy.is_some() || self.wheel.is_some() {
            let colour = white
                * self.rgb.unwrap_or(Vec3::ONE)
                * (Vec3::ONE - self.cmy.unwrap_or(Vec3::ZERO))
                * self.wheel.unwrap_or(Vec3::ONE);
            c[5..8].copy_from_slice(&colour.to_array());
        }
        if let Some(g) = self.gobo {
            s.gobo = g;
        }
        if let Some(p) = self.prism_in {
            s.prism_in = p;
        }
        s
    }
}

#[cfg(test)]
mod tests;
