//! GDTF fixture files (General Device Type Format, DIN SPEC 15800): a zip holding
//! `description.xml` and the media it names, as lighting consoles and visualisers
//! exchange fixtures. atmo reads what a moving head's light needs from one DMX mode:
//! the beam (its `Beam` geometry's beam and field angles, luminous flux and colour
//! temperature), the pan, tilt and zoom ranges (the physical ranges of the mode's
//! `Pan`, `Tilt` and `Zoom` channel functions) and the gobo wheel (the wheel a `Gobo`
//! channel function of the mode names, its slots' images from `wheels/` in the zip).
//!
//! GDTF's beam angle is where the intensity is half the peak, its field angle where it
//! is a tenth; atmo's beam is full intensity and its field zero, with a smoothstep
//! between ([`super::spotlight::Falloff::Smooth`]). [`to_smooth_edge`] places atmo's
//! edges so that the half and tenth points fall at GDTF's angles.

use super::spotlight::Gobo;
#[cfg(feature = "gdtf")]
use super::spotlight::Sampling;
#[cfg(feature = "gdtf")]
use crate::error::{Error, Result};

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
    let text = entry(&mut zip, "description.xml", DESCRIPTION_LIMIT)
        .map_err(&fail)?
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
    // The wheel a gobo channel of this mode turns.
    let wheel_name = functions.iter().find_map(|f| {
        f.attribute("Attribute")
            .filter(|a| a.starts_with("Gobo"))
            .and(f.attribute("Wheel"))
    });
    let mut wheel = Vec::new();
    if let Some(name) = wheel_name {
        let node = fixture
            .descendants()
            .find(|n| n.has_tag_name("Wheel") && n.attribute("Name") == Some(name))
            .ok_or_else(|| {
                fail(format!(
                    "the gobo channel names wheel {name:?}, which the file lacks"
                ))
            })?;
        for slot in node.children().filter(|n| n.has_tag_name("Slot")) {
            let Some(media) = slot.attribute("MediaFileName").filter(|m| !m.is_empty()) else {
                continue;
            };
            let image = [format!("wheels/{media}"), format!("wheels/{media}.png")]
                .iter()
                .find_map(|path| entry(&mut zip, path, crate::files::DATA_LIMIT_BYTES).transpose())
                .transpose()
                .map_err(&fail)?
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
    Ok(GdtfFixture {
        name: fixture.attribute("Name").unwrap_or("").to_string(),
        beam_deg,
        field_deg,
        luminous_flux_lm,
        kelvin,
        pan_range_deg,
        tilt_range_deg,
        zoom_range_deg,
        wheel,
    })
}

/// The bytes of the zip's entry `name`, `None` if there is none; an entry claiming
/// more than `limit` bytes is refused before it is read.
#[cfg(feature = "gdtf")]
fn entry(
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
    crate::budget::check(
        &format!("{name} in a GDTF file"),
        size,
        "the GDTF file's contents",
    )
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
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../scenes/fixtures/atmo-spot.gdtf"
        );
        let bytes = std::fs::read(path).unwrap();
        let mut zip = zip::ZipArchive::new(std::io::Cursor::new(&bytes[..])).unwrap();
        let text = entry(&mut zip, "description.xml", DESCRIPTION_LIMIT)
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
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../scenes/fixtures/atmo-spot.gdtf"
        );
        let bytes = std::fs::read(path).unwrap();
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
        assert_eq!((f.wheel[0].width, f.wheel[0].height), (256, 256));
        let basic = read(&bytes, "atmo-spot.gdtf", "Basic", Sampling::Bilinear).unwrap();
        assert_eq!(basic.pan_range_deg, Some([-180.0, 180.0]));
        assert_eq!((basic.zoom_range_deg, basic.wheel.len()), (None, 0));
    }

    #[test]
    fn malformed_gdtf_files_are_errors_naming_what_is_wrong() {
        let good = description("", "");
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
        ];
        for (bytes, mode, want) in cases {
            let got = error(&bytes, mode);
            assert!(got.contains(want), "want {want:?}, got {got:?}");
            assert!(got.starts_with("GDTF file bad.gdtf"), "{got}");
        }
    }
}
