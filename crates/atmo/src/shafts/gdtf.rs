//! GDTF fixture files (General Device Type Format, DIN SPEC 15800): a zip holding
//! `description.xml` and the media it names, as lighting consoles and visualisers
//! exchange fixtures. atmo reads what a moving head's light needs from one DMX mode:
//! the beam (its `Beam` geometry's beam and field angles, luminous flux and colour
//! temperature), the pan, tilt and zoom ranges (the physical ranges of the mode's
//! `Pan`, `Tilt` and `Zoom` channel functions), the gobo wheel (the wheel a `Gobo`
//! channel function of the mode names, its slots' images from `wheels/` in the zip) and
//! the prism (the first slot with facets of the wheel a `Prism` channel function names,
//! each facet's `Rotation` turning the beam).
//!
//! GDTF's beam angle is where the intensity is half the peak, its field angle where it
//! is a tenth; atmo's beam is full intensity and its field zero, with a smoothstep
//! between ([`super::spotlight::Falloff::Smooth`]). [`to_smooth_edge`] places atmo's
//! edges so that the half and tenth points fall at GDTF's angles.

use glam::Vec3;

use super::show::Prism;
use super::spotlight::Gobo;
#[cfg(feature = "gdtf")]
use super::spotlight::Sampling;
#[cfg(feature = "gdtf")]
use crate::error::{Error, Result};

/// The most luminous flux a fixture's beam may give, lm: a hundred times the
/// brightest stage fixtures.
pub const MAX_FLUX_LM: f32 = 1e7;

/// What a fixture's GDTF file gives for one mode.
#[derive(Debug, Clone)]
pub struct GdtfFixture {
    /// The fixture type's name.
    pub name: String,
    /// GDTF's beam angle (half intensity), degrees, full.
    pub beam_deg: f32,
    /// GDTF's field angle (a tenth of the intensity), degrees, full.
    pub field_deg: f32,
    /// The beam's luminous flux, lm.
    pub luminous_flux_lm: f32,
    /// The lamp's colour temperature, K.
    pub kelvin: f32,
    /// Pan's physical range in the mode, degrees, if the mode has pan.
    pub pan_range_deg: Option<[f32; 2]>,
    /// Tilt's.
    pub tilt_range_deg: Option<[f32; 2]>,
    /// Zoom's (GDTF's beam angle), degrees.
    pub zoom_range_deg: Option<[f32; 2]>,
    /// The gobos of the mode's gobo wheel, in slot order (slots without an image, such
    /// as "Open", left out).
    pub wheel: Vec<Gobo>,
    /// The prism of the mode's prism wheel, if it has one.
    pub prism: Option<GdtfPrism>,
    /// The mode's channels, as a desk drives them.
    pub dmx: super::dmx::Mode,
    /// Where the beam starts in the fixture's frame (z up), m: its `Beam` geometry's
    /// place through the geometries it hangs from (each one's `Position`;
    /// [`super::gdtf_body`] walks them).
    pub beam_offset: Vec3,
    /// The body its geometries' models draw ([`super::gdtf_body`]; empty without any).
    #[cfg(feature = "gdtf")]
    pub body: super::gdtf_body::GdtfBody,
}

/// A prism as a GDTF wheel's slot gives it: one beam direction a facet.
#[derive(Debug, Clone, PartialEq)]
pub struct GdtfPrism {
    /// The wheel and the slot, to name in messages.
    pub wheel: String,
    pub slot: String,
    /// Each facet's beam, a unit vector in the beam geometry's frame, where the beam
    /// without the prism leaves along -z: the facet's `Rotation` applied to -z.
    pub facets: Vec<Vec3>,
}

impl GdtfPrism {
    /// How far a facet's beam may be off the circle atmo's prisms have, degrees: in its
    /// angle off the axis and in its direction around it.
    pub const TOLERANCE_DEG: f32 = 1.0;

    /// The facets' angles off the beam's axis and their directions around it (from +x
    /// toward +y), degrees.
    pub fn angles_deg(&self) -> Vec<[f32; 2]> {
        self.facets
            .iter()
            .map(|d| {
                let off = (-d.z).clamp(-1.0, 1.0).acos().to_degrees();
                [off, d.y.atan2(d.x).to_degrees()]
            })
            .collect()
    }

    /// The slot as atmo's circular prism ([`Prism`]): its facet count and their mean
    /// angle off the axis, if the facets are [`Prism::FACETS`] copies of the beam
    /// turned the same angle off it (up to [`Prism::MAX_ANGLE_DEG`]), evenly around it, within
    /// [`GdtfPrism::TOLERANCE_DEG`]; otherwise an error naming the slot and saying what
    /// differs. Where the facets' circle starts is not kept: the head's `prism_deg`
    /// attribute turns it.
    pub fn circular(&self) -> std::result::Result<Prism, String> {
        let at = format!("prism wheel {:?} slot {:?}", self.wheel, self.slot);
        let n = self.facets.len();
        let [fewest, most] = Prism::FACETS;
        if !(fewest as usize..=most as usize).contains(&n) {
            return Err(format!(
                "{at} has {n} facets; atmo's prisms have {fewest} to {most} (give the \
                 fixture `prism = {{ facets = ..., angle_deg = ... }}` in the scene instead)"
            ));
        }
        let angles = self.angles_deg();
        let mean = angles.iter().map(|[off, _]| off).sum::<f32>() / n as f32;
        let refuse = |what: String| {
            Err(format!(
                "{at}: {what}; atmo's prisms are circular, every facet turned the same \
                 angle off the beam, evenly around it (within {} deg): give the fixture \
                 `prism = {{ facets = ..., angle_deg = ... }}` in the scene instead",
                Self::TOLERANCE_DEG
            ))
        };
        let listed = |k: usize| {
            angles
                .iter()
                .map(|a| format!("{:.1}", a[k]))
                .collect::<Vec<_>>()
                .join(", ")
        };
        if !(0.0..=Prism::MAX_ANGLE_DEG).contains(&mean)
            || angles
                .iter()
                .any(|[off, _]| (off - mean).abs() > Self::TOLERANCE_DEG)
        {
            return refuse(format!(
                "its facets are turned {} deg off the beam (atmo: one angle, 0 to {})",
                listed(0),
                Prism::MAX_ANGLE_DEG
            ));
        }
        // Evenly around: each facet's direction, taken in turn around the circle, a
        // whole number of steps of 360 / n from the first (facets along the axis have
        // no direction, and only a circle of angle 0 has them all there).
        let step = 360.0 / n as f32;
        let mut around: Vec<f32> = angles.iter().map(|a| a[1].rem_euclid(360.0)).collect();
        around.sort_by(f32::total_cmp);
        let even = mean <= Self::TOLERANCE_DEG
            || around.iter().enumerate().all(|(k, a)| {
                // A facet `off` degrees around from its place is sin(mean) off degrees
                // away from it on the sphere of directions.
                let off = (a - around[0] - k as f32 * step).abs();
                off * mean.to_radians().sin() <= Self::TOLERANCE_DEG
            });
        if !even {
            return refuse(format!(
                "its facets point {} deg around the beam, not {step:.1} deg apart",
                listed(1)
            ));
        }
        Ok(Prism {
            facets: n as u32,
            angle_deg: mean,
        })
    }
}

/// The largest `description.xml` read, bytes.
#[cfg(feature = "gdtf")]
const DESCRIPTION_LIMIT: u64 = 16 << 20;

/// Reads the fixture of the GDTF file's `bytes` in DMX mode `mode`; `origin` names the
/// file in messages. Every missing or malformed piece (not a zip, no description, XML
/// that does not parse, no such mode, a number that is not one, a gobo image that does
/// not decode) is an error naming it, never a panic.
#[cfg(feature = "gdtf")]
pub fn read(bytes: &[u8], origin: &str, mode: &str, sampling: Sampling) -> Result<GdtfFixture> {
    let fail = |why: String| Error::Invalid(format!("GDTF file {origin}: {why}"));
    let mut zip = zip::ZipArchive::new(std::io::Cursor::new(bytes))
        .map_err(|e| fail(format!("not a readable zip ({e})")))?;
    let text = zip_entry(&mut zip, "description.xml", DESCRIPTION_LIMIT)
        .map_err(fail)?
        .ok_or_else(|| fail("no description.xml in the zip".into()))?;
    let text = String::from_utf8(text).map_err(|_| fail("description.xml is not UTF-8".into()))?;
    let doc =
        roxmltree::Document::parse(&text).map_err(|e| fail(format!("description.xml: {e}")))?;
    let fixture = doc
        .descendants()
        .find(|n| n.has_tag_name("FixtureType"))
        .ok_or_else(|| fail("description.xml has no FixtureType".into()))?;
    let number = |node: roxmltree::Node, name: &str, default: f32| -> Result<f32> {
        match node.attribute(name) {
            None => Ok(default),
            Some(text) => match text.trim().parse::<f32>() {
                Ok(x) if x.is_finite() => Ok(x),
                _ => Err(fail(format!(
                    "{} {:?}: {name} = {text:?} is not a number",
                    node.tag_name().name(),
                    node.attribute("Name").unwrap_or("")
                ))),
            },
        }
    };
    let beam = fixture
        .descendants()
        .find(|n| n.has_tag_name("Beam"))
        .ok_or_else(|| fail("the fixture has no Beam geometry: it emits no light".into()))?;
    // GDTF's defaults where the file leaves an attribute out.
    let (beam_deg, field_deg) = (
        number(beam, "BeamAngle", 25.0)?,
        number(beam, "FieldAngle", 25.0)?,
    );
    let luminous_flux_lm = number(beam, "LuminousFlux", 10_000.0)?;
    let kelvin = number(beam, "ColorTemperature", 6000.0)?;
    // What a luminaire can be: past these the light's arithmetic gives NaN (a flux of
    // 3e38 lm) or no beam at all (an angle of 0 or over 180 degrees).
    let within = |name: &str, x: f32, (lo, hi): (f32, f32), open: bool| -> Result<()> {
        if (if open { x > lo } else { x >= lo }) && x <= hi {
            return Ok(());
        }
        let bracket = if open { "(" } else { "[" };
        Err(fail(format!(
            "Beam {:?}: {name} = {x}: allowed {bracket}{lo}, {hi}]",
            beam.attribute("Name").unwrap_or("")
        )))
    };
    within("BeamAngle", beam_deg, (0.0, 180.0), true)?;
    within("FieldAngle", field_deg, (0.0, 180.0), true)?;
    within("LuminousFlux", luminous_flux_lm, (0.0, MAX_FLUX_LM), true)?;
    within("ColorTemperature", kelvin, (1000.0, 40000.0), false)?;
    let modes: Vec<roxmltree::Node> = fixture
        .descendants()
        .filter(|n| n.has_tag_name("DMXMode"))
        .collect();
    let dmx_mode = modes
        .iter()
        .find(|m| m.attribute("Name") == Some(mode))
        .ok_or_else(|| {
            let names: Vec<&str> = modes.iter().filter_map(|m| m.attribute("Name")).collect();
            fail(format!(
                "no DMX mode {mode:?}; the file's modes: {}",
                if names.is_empty() {
                    "none".into()
                } else {
                    names.join(", ")
                }
            ))
        })?;
    let functions: Vec<roxmltree::Node> = dmx_mode
        .descendants()
        .filter(|n| n.has_tag_name("ChannelFunction"))
        .collect();
    let range = |attribute: &str| -> Result<Option<[f32; 2]>> {
        let Some(f) = functions
            .iter()
            .find(|f| f.attribute("Attribute") == Some(attribute))
        else {
            return Ok(None);
        };
        let (a, b) = (
            number(*f, "PhysicalFrom", 0.0)?,
            number(*f, "PhysicalTo", 1.0)?,
        );
        Ok(Some([a.min(b), a.max(b)]))
    };
    let (pan_range_deg, tilt_range_deg, zoom_range_deg) =
        (range("Pan")?, range("Tilt")?, range("Zoom")?);
    if let Some([narrow, wide]) = zoom_range_deg {
        if !(narrow > 0.0 && wide <= 180.0) {
            return Err(fail(format!(
                "the Zoom channel's PhysicalFrom..PhysicalTo is {narrow}..{wide} degrees: \
                 allowed within (0, 180]"
            )));
        }
    }
    let mut wheel = Vec::new();
    let mut wheels = super::dmx::gdtf_mode::Wheels::default();
    let gobo = wheel_turned_by(fixture, &functions, "gobo", |a| a.starts_with("Gobo"));
    if let Some(node) = gobo.map_err(fail)? {
        let name = node.attribute("Name").unwrap_or("");
        wheels.gobo.0 = name.to_string();
        for slot in slots(node) {
            let Some(media) = slot.attribute("MediaFileName").filter(|m| !m.is_empty()) else {
                wheels.gobo.1.push(0);
                continue;
            };
            wheels.gobo.1.push(wheel.len() + 1);
            let image = [format!("wheels/{media}"), format!("wheels/{media}.png")]
                .iter()
                .find_map(|path| {
                    zip_entry(&mut zip, path, crate::files::DATA_LIMIT_BYTES).transpose()
                })
                .transpose()
                .map_err(fail)?
                .ok_or_else(|| {
                    fail(format!(
                        "wheel {name:?} slot {:?}: no wheels/{media}(.png) in the zip",
                        slot.attribute("Name").unwrap_or("")
                    ))
                })?;
            wheel.push(
                super::scene::gobo_from_image(&image, &format!("wheels/{media}"), sampling)
                    .map_err(|e| fail(e.to_string()))?,
            );
        }
    }
    // The prism: the first slot with facets of the wheel a "Prism1" channel turns (not
    // "Prism1Pos" and the like, which move a prism already in).
    let mut prism = None;
    let prism_wheel = wheel_turned_by(fixture, &functions, "prism", |a| {
        a.strip_prefix("Prism")
            .is_some_and(|n| !n.is_empty() && n.bytes().all(|b| b.is_ascii_digit()))
    });
    if let Some(node) = prism_wheel.map_err(fail)? {
        let name = node.attribute("Name").unwrap_or("");
        wheels.prism = (
            name.to_string(),
            slots(node)
                .iter()
                .map(|s| s.children().any(|f| f.has_tag_name("PrismFacet")) as usize)
                .collect(),
        );
        let slot = node.children().find(|slot| {
            slot.has_tag_name("Slot") && slot.children().any(|f| f.has_tag_name("PrismFacet"))
        });
        if let Some(slot) = slot {
            let slot_name = slot.attribute("Name").unwrap_or("").to_string();
            let facets =
                slot.children()
                    .filter(|f| f.has_tag_name("PrismFacet"))
                    .map(|f| {
                        facet_beam(f.attribute("Rotation").unwrap_or("{1,0,0}{0,1,0}{0,0,1}"))
                            .map_err(|why| {
                                fail(format!(
                                    "prism wheel {name:?} slot {slot_name:?}: a facet's \
                                 Rotation {why}"
                                ))
                            })
                    })
                    .collect::<Result<Vec<Vec3>>>()?;
            prism = Some(GdtfPrism {
                wheel: name.to_string(),
                slot: slot_name,
                facets,
            });
        }
    }
    let colour_wheel = wheel_turned_by(fixture, &functions, "colour", |a| a == "Color1");
    if let Some(node) = colour_wheel.map_err(fail)? {
        wheels.colour = (
            node.attribute("Name").unwrap_or("").to_string(),
            slots(node)
                .iter()
                .map(|s| {
                    s.attribute("Color")
                        .and_then(super::dmx::gdtf_mode::colour_xyy)
                        .unwrap_or(Vec3::ONE)
                })
                .collect(),
        );
    }
    let dmx = super::dmx::gdtf_mode::read(*dmx_mode, &wheels)
        .map_err(|why| fail(format!("DMX mode {mode:?}: {why}")))?;
    dmx.validate(&format!("GDTF file {origin}: DMX mode {mode:?}"))?;
    // The geometries the mode's pan and tilt channels move.
    let moved_by = |attribute: &str| {
        dmx_mode
            .descendants()
            .filter(|n| n.has_tag_name("DMXChannel"))
            .find(|c| {
                c.descendants().any(|l| {
                    l.has_tag_name("LogicalChannel") && l.attribute("Attribute") == Some(attribute)
                })
            })
            .and_then(|c| c.attribute("Geometry"))
    };
    let body = super::gdtf_body::read(
        fixture,
        beam,
        moved_by("Pan"),
        moved_by("Tilt"),
        &mut |file| {
            let name = if file.contains('.') {
                format!("models/3ds/{file}")
            } else {
                format!("models/3ds/{file}.3ds")
            };
            zip_entry(&mut zip, &name, crate::files::DATA_LIMIT_BYTES)
        },
    )
    .map_err(|why| fail(format!("the fixture's models: {why}")))?;
    Ok(GdtfFixture {
        beam_offset: body.beam_offset,
        body,
        dmx,
        name: fixture.attribute("Name").unwrap_or("").to_string(),
        beam_deg,
        field_deg,
        luminous_flux_lm,
        kelvin,
        pan_range_deg,
        tilt_range_deg,
        zoom_range_deg,
        wheel,
        prism,
    })
}

/// The beam through a prism facet whose GDTF `Rotation` is `text`, a 3 x 3 matrix
/// written `{a,b,c}{d,e,f}{g,h,i}`: the matrix applied to the beam's -z, a unit
/// vector; an error saying what is wrong with the text (not nine numbers, not a
/// rotation).
#[cfg(feature = "gdtf")]
fn facet_beam(text: &str) -> std::result::Result<Vec3, String> {
    let bad =
        || format!("{text:?} is not three rows of three numbers, {{a,b,c}}{{d,e,f}}{{g,h,i}}");
    let (mut numbers, mut rows) = (Vec::with_capacity(9), 0);
    for row in text.split('}').map(str::trim).filter(|r| !r.is_empty()) {
        rows += 1;
        for x in row.strip_prefix('{').ok_or_else(bad)?.split(',') {
            let x = x.trim().parse::<f32>().ok().filter(|x| x.is_finite());
            numbers.push(x.ok_or_else(bad)?);
        }
    }
    if rows != 3 || numbers.len() != 9 {
        return Err(bad());
    }
    // The third column, negated: the image of -z.
    let beam = -Vec3::new(numbers[2], numbers[5], numbers[8]);
    if (beam.length() - 1.0).abs() > 1e-3 {
        return Err(format!(
            "{text:?} is not a rotation (it takes the beam to a vector of length {})",
            beam.length()
        ));
    }
    Ok(beam.normalize())
}

/// A wheel's slots, in order (GDTF's `WheelSlotIndex` 1 is the first).
#[cfg(feature = "gdtf")]
fn slots<'a, 'i>(wheel: roxmltree::Node<'a, 'i>) -> Vec<roxmltree::Node<'a, 'i>> {
    wheel
        .children()
        .filter(|n| n.has_tag_name("Slot"))
        .collect()
}

/// The wheel that the first of the mode's channel `functions` whose attribute passes
/// `is` names, if one does (`what` names the channel in the message if the fixture
/// lacks that wheel).
#[cfg(feature = "gdtf")]
fn wheel_turned_by<'a, 'i>(
    fixture: roxmltree::Node<'a, 'i>,
    functions: &[roxmltree::Node<'a, 'i>],
    what: &str,
    is: impl Fn(&str) -> bool,
) -> std::result::Result<Option<roxmltree::Node<'a, 'i>>, String> {
    let Some(name) = functions.iter().find_map(|f| {
        f.attribute("Attribute")
            .filter(|a| is(a))
            .and(f.attribute("Wheel"))
    }) else {
        return Ok(None);
    };
    fixture
        .descendants()
        .find(|n| n.has_tag_name("Wheel") && n.attribute("Name") == Some(name))
        .map(Some)
        .ok_or_else(|| format!("the {what} channel names wheel {name:?}, which the file lacks"))
}

/// The bytes of the zip's entry `name`, `None` if there is none; an entry claiming
/// more than `limit` bytes, or past the run's memory budget, is refused before it is
/// read (GDTF and MVR files alike).
#[cfg(feature = "gdtf")]
pub(crate) fn zip_entry(
    zip: &mut zip::ZipArchive<std::io::Cursor<&[u8]>>,
    name: &str,
    limit: u64,
) -> std::result::Result<Option<Vec<u8>>, String> {
    let mut file = match zip.by_name(name) {
        Ok(f) => f,
        Err(zip::result::ZipError::FileNotFound) => return Ok(None),
        Err(e) => return Err(format!("{name}: {e}")),
    };
    let size = file.size();
    if size > limit {
        return Err(format!(
            "{name} is {size} bytes, above the limit of {limit}"
        ));
    }
    crate::budget::check(&format!("{name} from a zip"), size, "the zip's contents")
        .map_err(|e| e.to_string())?;
    let mut bytes = Vec::with_capacity(size as usize);
    use std::io::Read;
    // Read no more than the size the entry claims (a lying header cannot grow it).
    file.by_ref()
        .take(size)
        .read_to_end(&mut bytes)
        .map_err(|e| format!("{name}: {e}"))?;
    Ok(Some(bytes))
}

/// atmo's smooth edge for a beam whose intensity is half its peak at `beam_deg` and a
/// tenth at `field_deg` (full angles, GDTF's and lamp makers' definitions): the full
/// angles where atmo's profile is 1 and 0, `(beam, field)`. With the smoothstep
/// `s(x) = 3x^2 - 2x^3` of `x = (F - theta) / (F - B)` in half angles, `s = 1/2` at
/// `x = 1/2` and `s = 1/10` at `x = X10` put the half point midway between `B` and
/// `F` and the tenth point at `F - X10 (F - B)`. Where that would need a negative beam,
/// the beam is 0 and the field keeps the half point.
pub fn to_smooth_edge(beam_deg: f32, field_deg: f32) -> (f32, f32) {
    // s(X10) = 0.1: the root in (0, 1/2) of 2x^3 - 3x^2 + 0.1.
    const X10: f32 = 0.195_800_6;
    let (b, f) = (0.5 * beam_deg, 0.5 * field_deg.max(beam_deg));
    let spread = (f - b) / (0.5 - X10);
    let (lo, hi) = (b - 0.5 * spread, b + 0.5 * spread);
    if lo >= 0.0 {
        (2.0 * lo, 2.0 * hi)
    } else {
        (0.0, 4.0 * b)
    }
}

/// The bytes of the example fixture, scenes/fixtures/atmo-spot.gdtf, for tests.
#[cfg(test)]
pub(crate) fn example_fixture() -> Vec<u8> {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../scenes/fixtures/atmo-spot.gdtf"
    );
    std::fs::read(path).expect("the example fixture is in the repository")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_smooth_edge_puts_half_and_tenth_where_gdtf_does() {
        let smooth = |x: f32| super::super::spotlight::Falloff::Smooth.shape(x);
        for (beam, field) in [(20.0, 30.0), (10.0, 12.0), (25.0, 25.0)] {
            let (b, f) = to_smooth_edge(beam, field);
            let profile = |full: f32| {
                let x = ((0.5 * f - 0.5 * full) / (0.5 * (f - b)).max(1e-9)).clamp(0.0, 1.0);
                smooth(x)
            };
            assert!(
                (profile(beam) - 0.5).abs() < 1e-3 || f == b,
                "{beam} {field}: {b} {f}"
            );
            if field > beam {
                assert!(
                    (profile(field) - 0.1).abs() < 1e-3,
                    "{beam} {field}: {b} {f}"
                );
            }
        }
        // A wide field for a narrow beam: the beam's edge at 0.
        assert_eq!(to_smooth_edge(10.0, 40.0), (0.0, 20.0));
    }
}

#[cfg(all(test, feature = "gdtf"))]
mod reading {
    use std::io::Write;

    use super::*;

    /// A zip of `entries` (name, bytes).
    fn zip_of(entries: &[(&str, &[u8])]) -> Vec<u8> {
        let mut out = zip::ZipWriter::new(std::io::Cursor::new(Vec::new()));
        for (name, bytes) in entries {
            out.start_file(*name, zip::write::SimpleFileOptions::default())
                .unwrap();
            out.write_all(bytes).unwrap();
        }
        out.finish().unwrap().into_inner()
    }

    /// The example fixture's description with `from` replaced by `to`.
    fn description(from: &str, to: &str) -> Vec<u8> {
        let bytes = example_fixture();
        let mut zip = zip::ZipArchive::new(std::io::Cursor::new(&bytes[..])).unwrap();
        let text = zip_entry(&mut zip, "description.xml", DESCRIPTION_LIMIT)
            .unwrap()
            .unwrap();
        String::from_utf8(text)
            .unwrap()
            .replace(from, to)
            .into_bytes()
    }

    fn error(bytes: &[u8], mode: &str) -> String {
        read(bytes, "bad.gdtf", mode, Sampling::Bilinear)
            .expect_err("the file should be refused")
            .to_string()
    }

    #[test]
    fn the_example_fixture_reads_in_both_modes() {
        let bytes = example_fixture();
        let f = read(&bytes, "atmo-spot.gdtf", "Standard", Sampling::Bilinear).unwrap();
        assert_eq!(f.name, "atmo Spot 300");
        assert_eq!(
            (f.beam_deg, f.field_deg, f.luminous_flux_lm, f.kelvin),
            (18.0, 24.0, 12000.0, 6500.0)
        );
        assert_eq!(f.pan_range_deg, Some([-270.0, 270.0]));
        assert_eq!(f.tilt_range_deg, Some([-135.0, 135.0]));
        assert_eq!(f.zoom_range_deg, Some([8.0, 36.0]));
        // The wheel's two images (the open slot has none), as the PNGs in the zip.
        assert_eq!(f.wheel.len(), 2);
        assert_eq!(f.wheel[0].size(), (256, 256));
        // The prism wheel's three facets, 8 deg off the beam toward 90, 210 and 330 deg.
        let prism = f
            .prism
            .as_ref()
            .expect("the Standard mode has a prism channel");
        assert_eq!(
            (prism.wheel.as_str(), prism.slot.as_str()),
            ("Prism1", "3-Facet")
        );
        for ([off, around], want) in prism.angles_deg().into_iter().zip([90.0, -150.0, -30.0]) {
            assert!(
                (off - 8.0).abs() < 1e-3 && (around - want).abs() < 1e-3,
                "{off} {around}"
            );
        }
        let circle = prism.circular().unwrap();
        assert_eq!(circle.facets, 3);
        assert!((circle.angle_deg - 8.0).abs() < 1e-3);
        let basic = read(&bytes, "atmo-spot.gdtf", "Basic", Sampling::Bilinear).unwrap();
        assert_eq!(basic.pan_range_deg, Some([-180.0, 180.0]));
        assert_eq!((basic.zoom_range_deg, basic.wheel.len()), (None, 0));
        assert!(basic.prism.is_none());
    }

    /// A prism of facets at `(angle off, direction around)` pairs, degrees.
    fn prism_of(facets: &[(f32, f32)]) -> GdtfPrism {
        GdtfPrism {
            wheel: "P".into(),
            slot: "S".into(),
            facets: facets
                .iter()
                .map(|&(off, around)| {
                    let (t, p) = (off.to_radians(), around.to_radians());
                    Vec3::new(t.sin() * p.cos(), t.sin() * p.sin(), -t.cos())
                })
                .collect(),
        }
    }

    #[test]
    fn only_circular_prisms_become_atmo_prisms() {
        // Four facets 10 deg off, a quarter turn apart in any order from any start.
        let four = prism_of(&[(10.0, 30.0), (10.2, 300.0), (9.9, 120.0), (10.0, 210.5)]);
        let p = four.circular().unwrap();
        assert_eq!(p.facets, 4);
        assert!((p.angle_deg - 10.025).abs() < 1e-3, "{}", p.angle_deg);
        // Refused, and why: a linear prism (facets in a row), one facet's angle off,
        // the facets bunched on one side, a facet on the axis amid a ring, too few.
        for (prism, why) in [
            (
                prism_of(&[(6.0, 0.0), (2.0, 0.0), (2.0, 180.0), (6.0, 180.0)]),
                "turned 6.0, 2.0, 2.0, 6.0 deg off the beam",
            ),
            (
                prism_of(&[(8.0, 0.0), (8.0, 120.0), (10.0, 240.0)]),
                "turned 8.0, 8.0, 10.0 deg",
            ),
            (
                prism_of(&[(8.0, 0.0), (8.0, 100.0), (8.0, 240.0)]),
                "point 0.0, 100.0, -120.0 deg around the beam, not 120.0 deg apart",
            ),
            (
                prism_of(&[(0.0, 0.0), (8.0, 0.0), (8.0, 120.0), (8.0, 240.0)]),
                "turned 0.0, 8.0, 8.0, 8.0",
            ),
            (
                prism_of(&[(8.0, 0.0)]),
                "has 1 facets; atmo's prisms have 2 to 16",
            ),
            (
                prism_of(&[(70.0, 0.0), (70.0, 180.0)]),
                "(atmo: one angle, 0 to 60)",
            ),
        ] {
            let got = prism.circular().expect_err("not a circular prism");
            assert!(got.contains(why), "want {why:?} in {got:?}");
            assert!(got.starts_with("prism wheel \"P\" slot \"S\""), "{got}");
            assert!(got.contains("prism = {"), "{got}");
        }
        // Facets all along the axis: a circle of angle 0 wherever they point.
        assert_eq!(
            prism_of(&[(0.0, 0.0), (0.0, 0.0)])
                .circular()
                .unwrap()
                .facets,
            2
        );
    }

    #[test]
    fn facet_rotations_are_read_as_gdtf_writes_them() {
        let beam = facet_beam(" {1,0,0} {0,0.990268,-0.139173}{0,0.139173,0.990268} ").unwrap();
        assert!(
            (beam - Vec3::new(0.0, 0.139173, -0.990268)).length() < 1e-5,
            "{beam}"
        );
        for (text, why) in [
            ("{1,0,0}{0,1,0}", "not three rows of three numbers"),
            ("{1,0,0}{0,1,0}{0,0}", "not three rows of three numbers"),
            ("{1,0,0}{0,1,0}{0,0,x}", "not three rows of three numbers"),
            ("{1,0,0}{0,1,0}{0,0,inf}", "not three rows of three numbers"),
            ("1,0,0}{0,1,0}{0,0,1}", "not three rows of three numbers"),
            (
                "{1,0,0}{0,1,0}{0,0,1}{0,0,1}",
                "not three rows of three numbers",
            ),
            (
                "{1,0,0}{0,1,0}{0,0,2}",
                "not a rotation (it takes the beam to a vector of length 2)",
            ),
        ] {
            let got = facet_beam(text).expect_err(text);
            assert!(got.contains(why), "{text}: want {why:?}, got {got:?}");
        }
    }

    #[test]
    fn malformed_gdtf_files_are_errors_naming_what_is_wrong() {
        let good = description("", "");
        let gobo = |name: &str| {
            std::fs::read(format!(
                "{}/../../scenes/gobos/{name}.png",
                env!("CARGO_MANIFEST_DIR")
            ))
            .unwrap()
        };
        let (spokes, dots) = (gobo("spokes"), gobo("dots"));
        // The description `from` -> `to` with the wheel's images: past the gobos.
        let with_gobos = |from: &str, to: &str| {
            zip_of(&[
                ("description.xml", &description(from, to)),
                ("wheels/spokes.png", &spokes),
                ("wheels/dots.png", &dots),
            ])
        };
        let cases: Vec<(Vec<u8>, &str, &str)> = vec![
            (
                b"not a zip at all".to_vec(),
                "Standard",
                "not a readable zip",
            ),
            (
                zip_of(&[("readme.txt", b"hello")]),
                "Standard",
                "no description.xml",
            ),
            (
                zip_of(&[("description.xml", b"<GDTF><FixtureType")]),
                "Standard",
                "description.xml: ",
            ),
            (
                zip_of(&[("description.xml", b"<GDTF/>")]),
                "Standard",
                "no FixtureType",
            ),
            (
                zip_of(&[("description.xml", &good)]),
                "Extended",
                "no DMX mode \"Extended\"; the file's modes: Standard, Basic",
            ),
            (
                zip_of(&[(
                    "description.xml",
                    &description("BeamAngle=\"18\"", "BeamAngle=\"wide\""),
                )]),
                "Standard",
                "Beam \"Beam\": BeamAngle = \"wide\" is not a number",
            ),
            (
                zip_of(&[("description.xml", &description("<Beam ", "<Lamp "))]),
                "Standard",
                "no Beam geometry",
            ),
            (
                zip_of(&[("description.xml", &good)]),
                "Standard",
                "wheel \"Gobo1\" slot \"Spokes\": no wheels/spokes(.png)",
            ),
            (
                zip_of(&[
                    ("description.xml", &good),
                    ("wheels/spokes.png", b"not a png"),
                ]),
                "Standard",
                "wheels/spokes",
            ),
            (
                zip_of(&[(
                    "description.xml",
                    &description("Wheel=\"Gobo1\"", "Wheel=\"Gobo9\""),
                )]),
                "Standard",
                "names wheel \"Gobo9\", which the file lacks",
            ),
            (
                with_gobos("Wheel=\"Prism1\"", "Wheel=\"Prism9\""),
                "Standard",
                "the prism channel names wheel \"Prism9\", which the file lacks",
            ),
            (
                with_gobos("Rotation=\"{1.000000,", "Rotation=\"{one,"),
                "Standard",
                "prism wheel \"Prism1\" slot \"3-Facet\": a facet's Rotation \"{one,",
            ),
            // Numbers that read but that no luminaire has (each gave a NaN picture or
            // no beam).
            (
                with_gobos("LuminousFlux=\"12000\"", "LuminousFlux=\"3e38\""),
                "Standard",
                "Beam \"Beam\": LuminousFlux = 300000000000000000000000000000000000000: allowed (0, 10000000]",
            ),
            (
                with_gobos("BeamAngle=\"18\"", "BeamAngle=\"0\""),
                "Standard",
                "BeamAngle = 0: allowed (0, 180]",
            ),
            (
                with_gobos("FieldAngle=\"24\"", "FieldAngle=\"400\""),
                "Standard",
                "FieldAngle = 400: allowed (0, 180]",
            ),
            (
                with_gobos("ColorTemperature=\"6500\"", "ColorTemperature=\"-5\""),
                "Standard",
                "ColorTemperature = -5: allowed [1000, 40000]",
            ),
            (
                with_gobos("PhysicalFrom=\"8\" PhysicalTo=\"36\"", "PhysicalFrom=\"8\" PhysicalTo=\"1e30\""),
                "Standard",
                "the Zoom channel's PhysicalFrom..PhysicalTo is 8..1000000000000000000000000000000 degrees",
            ),
        ];
        for (bytes, mode, want) in cases {
            let got = error(&bytes, mode);
            assert!(got.contains(want), "want {want:?}, got {got:?}");
            assert!(got.starts_with("GDTF file bad.gdtf"), "{got}");
        }
    }
}
