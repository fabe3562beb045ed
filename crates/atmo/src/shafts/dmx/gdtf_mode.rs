//! A GDTF file's DMX mode as a [`Mode`]: its `DMXChannel`s (offsets, coarse first),
//! their `LogicalChannel`s' `ChannelFunction`s (DMX start, physical range, mode master)
//! and `ChannelSet`s (wheel slots), read as DIN SPEC 15800 writes them.

use glam::Vec3;

use super::{Attribute, Channel, ChannelSet, Function, Mode};

/// What a wheel's slot is to atmo, by GDTF's `WheelSlotIndex` (1-based, every slot).
#[derive(Debug, Clone, Default)]
pub struct Wheels {
    /// The gobo wheel: atmo's slot of each GDTF slot (0: open, or an image-less slot).
    pub gobo: (String, Vec<usize>),
    /// The prism wheel: 1 where the slot has facets, 0 where it is open.
    pub prism: (String, Vec<usize>),
    /// The colour wheel: each slot's colour (linear RGB).
    pub colour: (String, Vec<Vec3>),
}

/// A DMX value as GDTF writes it, `value/bytes` (`s` after the byte count: shifted,
/// otherwise mirrored: `255/1` is `65535/2`), at a channel of `bytes` bytes.
pub fn dmx_value(text: &str, bytes: usize) -> Result<u32, String> {
    let bad = || format!("DMX value {text:?} is not VALUE/BYTES (as 255/1 or 32768/2)");
    let (value, count) = text.trim().split_once('/').ok_or_else(bad)?;
    let (count, shifted) = match count.strip_suffix('s') {
        Some(c) => (c, true),
        None => (count, false),
    };
    let value: u64 = value.trim().parse().map_err(|_| bad())?;
    let count: usize = count.trim().parse().map_err(|_| bad())?;
    if !(1..=4).contains(&count) || value >= 1u64 << (8 * count) {
        return Err(bad());
    }
    let full = |n: usize| (1u64 << (8 * n)) - 1;
    let at = if count >= bytes {
        value >> (8 * (count - bytes))
    } else if shifted {
        value << (8 * (bytes - count))
    } else {
        value * full(bytes) / full(count)
    };
    Ok(at.min(full(bytes)) as u32)
}

/// A colour as GDTF writes it, CIE `x,y,Y` (Y 0-100), as linear sRGB (white 1).
pub fn colour_xyy(text: &str) -> Option<Vec3> {
    let v: Vec<f32> = text
        .split(',')
        .map(|s| s.trim().parse().ok())
        .collect::<Option<_>>()?;
    let [x, y, big_y] = v[..] else { return None };
    if !(y > 1e-4 && x >= 0.0 && (0.0..=100.0).contains(&big_y)) {
        return None;
    }
    let lum = big_y / 100.0;
    let xyz = Vec3::new(x * lum / y, lum, (1.0 - x - y) * lum / y);
    // XYZ (D65) to linear sRGB, IEC 61966-2-1.
    let rgb = Vec3::new(
        3.2406 * xyz.x - 1.5372 * xyz.y - 0.4986 * xyz.z,
        -0.9689 * xyz.x + 1.8758 * xyz.y + 0.0415 * xyz.z,
        0.0557 * xyz.x - 0.2040 * xyz.y + 1.0570 * xyz.z,
    );
    Some(rgb.max(Vec3::ZERO).min(Vec3::ONE))
}

/// The mode `mode` (a `DMXMode` node) of a fixture whose wheels are `wheels`; an error
/// naming the channel where a value does not parse.
pub fn read(mode: roxmltree::Node, wheels: &Wheels) -> Result<Mode, String> {
    let dmx_channels: Vec<roxmltree::Node> = mode
        .descendants()
        .filter(|n| n.has_tag_name("DMXChannel"))
        .collect();
    // A channel's name as mode masters name it: its Name, or Geometry_Attribute.
    let name_of = |c: &roxmltree::Node| -> String {
        c.attribute("Name").map(str::to_string).unwrap_or_else(|| {
            let attribute = c
                .descendants()
                .find(|n| n.has_tag_name("LogicalChannel"))
                .and_then(|l| l.attribute("Attribute"))
                .unwrap_or("");
            format!("{}_{attribute}", c.attribute("Geometry").unwrap_or(""))
        })
    };
    // The channels atmo drives: break 1, with offsets (a virtual channel has none).
    let kept: Vec<(roxmltree::Node, Vec<u16>)> = dmx_channels
        .iter()
        .filter(|c| {
            matches!(
                c.attribute("DMXBreak"),
                None | Some("1") | Some("Overwrite")
            )
        })
        .filter_map(|c| {
            let text = c.attribute("Offset").unwrap_or("");
            let offsets: Option<Vec<u16>> = text
                .split(',')
                .map(|o| o.trim().parse::<u16>().ok())
                .collect();
            offsets.filter(|o| !o.is_empty()).map(|o| (*c, o))
        })
        .collect();
    let names: Vec<String> = kept.iter().map(|(c, _)| name_of(c)).collect();
    let mut channels = Vec::with_capacity(kept.len());
    for ((node, offsets), name) in kept.iter().zip(&names) {
        let bytes = offsets.len();
        if !(1..=4).contains(&bytes) {
            return Err(format!(
                "DMX channel {name:?} has {bytes} offsets: allowed 1 to 4"
            ));
        }
        let at = |why: String| format!("DMX channel {name:?}: {why}");
        let mut functions = Vec::new();
        for f in node
            .descendants()
            .filter(|n| n.has_tag_name("ChannelFunction"))
        {
            let number = |key: &str, default: f32| -> Result<f32, String> {
                f.attribute(key).map_or(Ok(default), |t| {
                    t.trim()
                        .parse::<f32>()
                        .ok()
                        .filter(|x| x.is_finite())
                        .ok_or_else(|| at(format!("{key} = {t:?} is not a number")))
                })
            };
            let value = |key: &str, bytes: usize| -> Result<Option<u32>, String> {
                f.attribute(key)
                    .map(|t| dmx_value(t, bytes).map_err(at))
                    .transpose()
            };
            let attribute = f.attribute("Attribute").and_then(Attribute::from_gdtf);
            let wheel = f.attribute("Wheel").unwrap_or("");
            let slot_of = |index: usize| -> usize {
                let pick = |(w, slots): &(String, Vec<usize>)| {
                    if w == wheel {
                        slots.get(index.wrapping_sub(1)).copied().unwrap_or(0)
                    } else {
                        0
                    }
                };
                match attribute {
                    Some(Attribute::Gobo) => pick(&wheels.gobo),
                    Some(Attribute::Prism) => pick(&wheels.prism),
                    Some(Attribute::ColourWheel) if wheels.colour.0 == wheel => index,
                    _ => 0,
                }
            };
            let closed = |n: &roxmltree::Node| {
                n.attribute("Name")
                    .is_some_and(|s| s.to_ascii_lowercase().contains("closed"))
            };
            let mut sets = Vec::new();
            for s in f.children().filter(|n| n.has_tag_name("ChannelSet")) {
                let dmx_from = s
                    .attribute("DMXFrom")
                    .map_or(Ok(0), |t| dmx_value(t, bytes).map_err(at))?;
                let slot = s
                    .attribute("WheelSlotIndex")
                    .and_then(|t| t.trim().parse::<usize>().ok())
                    .map_or(0, slot_of);
                sets.push(ChannelSet {
                    dmx_from,
                    slot,
                    closed: closed(&s),
                });
            }
            sets.sort_by_key(|s| s.dmx_from);
            let mode_master = match f.attribute("ModeMaster") {
                None => None,
                Some(master) => {
                    let channel = master.split('.').next().unwrap_or("");
                    let Some(k) = names.iter().position(|n| n == channel) else {
                        return Err(at(format!(
                            "ModeMaster {master:?} is not a channel of the mode"
                        )));
                    };
                    let master_bytes = kept[k].1.len();
                    let from = value("ModeFrom", master_bytes)?.unwrap_or(0);
                    let to = value("ModeTo", master_bytes)?.unwrap_or(u32::MAX);
                    Some((k, [from, to]))
                }
            };
            functions.push(Function {
                attribute,
                dmx_from: value("DMXFrom", bytes)?.unwrap_or(0),
                physical: [number("PhysicalFrom", 0.0)?, number("PhysicalTo", 1.0)?],
                sets,
                closed: closed(&f),
                mode_master,
            });
        }
        functions.sort_by_key(|f| f.dmx_from);
        if functions.first().is_none_or(|f| f.dmx_from != 0) {
            functions.insert(
                0,
                Function {
                    attribute: None,
                    dmx_from: 0,
                    physical: [0.0, 0.0],
                    sets: Vec::new(),
                    closed: false,
                    mode_master: None,
                },
            );
        }
        // A wheel function without sets: its span split evenly over the wheel's slots.
        for f in &mut functions {
            let slots = match f.attribute {
                Some(Attribute::Gobo) => wheels.gobo.1.len(),
                Some(Attribute::Prism) => wheels.prism.1.len(),
                Some(Attribute::ColourWheel) => wheels.colour.1.len(),
                _ => continue,
            };
            if f.sets.is_empty() && slots > 0 {
                let full = ((1u64 << (8 * bytes)) - 1) as u32;
                let span = (full - f.dmx_from) as u64 + 1;
                f.sets = (0..slots)
                    .map(|k| ChannelSet {
                        dmx_from: f.dmx_from + (span * k as u64 / slots as u64) as u32,
                        slot: match f.attribute {
                            Some(Attribute::Gobo) => wheels.gobo.1[k],
                            Some(Attribute::Prism) => wheels.prism.1[k],
                            _ => k + 1,
                        },
                        closed: false,
                    })
                    .collect();
            }
        }
        channels.push(Channel {
            name: name.clone(),
            offsets: offsets.clone(),
            functions,
        });
    }
    Ok(Mode {
        name: mode.attribute("Name").unwrap_or("").to_string(),
        channels,
        colours: wheels.colour.1.clone(),
    })
}
