//! A GDTF fixture's body as its file draws it: the models of its geometry tree
//! (`Geometries`: `Geometry`, `Axis` and the rest, each placed by its `Position` in its
//! parent's frame), each a 3DS mesh from the zip's `models/3ds/` scaled to the model's
//! `Length`, `Width` and `Height` (x, y, z), or, without a file, the primitive those
//! dimensions give (a cylinder for `Cylinder`, a box otherwise). Parts under the
//! geometry the mode's pan channel moves turn with pan, those under the tilt channel's
//! with pan and tilt, about those geometries' origins.

use glam::{Mat4, Vec3};

use crate::shafts::mvr::three_ds;

/// The most triangles a fixture's models may have.
pub const MAX_TRIANGLES: usize = 500_000;

/// What turns a part of a body.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Turns {
    Not,
    Pan,
    PanAndTilt,
}

/// One model placed in the fixture, and what turns it.
#[derive(Debug, Clone, PartialEq)]
pub struct BodyPart {
    pub turns: Turns,
    /// Its triangles at rest, in the fixture's GDTF frame (z up, m).
    pub triangles: Vec<[Vec3; 3]>,
}

/// A fixture's body at rest in its GDTF frame.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct GdtfBody {
    pub parts: Vec<BodyPart>,
    /// The origins pan and tilt turn about (the pan and tilt geometries'), m.
    pub pan_pivot: Vec3,
    pub tilt_pivot: Vec3,
    /// Where the beam starts (its `Beam` geometry's origin), m; 0 where that place is
    /// not finite or over 100 m off.
    pub beam_offset: Vec3,
}

impl GdtfBody {
    /// Whether it has anything to draw.
    pub fn is_empty(&self) -> bool {
        self.parts.iter().all(|p| p.triangles.is_empty())
    }
}

/// A `Position` matrix as GDTF writes it: four rows of four numbers, the translation in
/// the last column; `None` where it does not parse.
pub fn position(text: &str) -> Option<Mat4> {
    let v: Vec<f32> = text
        .split(['{', '}', ','])
        .map(str::trim)
        .filter(|t| !t.is_empty())
        .map(|t| t.parse::<f32>().ok().filter(|x| x.is_finite()))
        .collect::<Option<_>>()?;
    let rows: [f32; 16] = v.try_into().ok()?;
    Some(Mat4::from_cols_array(&rows).transpose())
}

/// The triangles of a box or a 16-sided cylinder (along z) centred on the origin, of
/// `size` (x, y, z), m.
fn primitive(kind: &str, size: Vec3) -> Vec<[Vec3; 3]> {
    let h = 0.5 * size;
    if kind == "Cylinder" {
        let ring = |k: usize, z: f32| {
            let a = std::f32::consts::TAU * k as f32 / 16.0;
            Vec3::new(h.x * a.cos(), h.y * a.sin(), z)
        };
        let (top, bottom) = (Vec3::new(0.0, 0.0, h.z), Vec3::new(0.0, 0.0, -h.z));
        return (0..16)
            .flat_map(|k| {
                let (a, b) = (ring(k, h.z), ring(k + 1, h.z));
                let (c, d) = (ring(k, -h.z), ring(k + 1, -h.z));
                [[a, b, d], [a, d, c], [top, b, a], [bottom, c, d]]
            })
            .collect();
    }
    let mut out = Vec::with_capacity(12);
    crate::shafts::show::cuboid(
        &mut out,
        Vec3::ZERO,
        [(Vec3::X, h.x), (Vec3::Y, h.y), (Vec3::Z, h.z)],
    );
    out
}

/// Gives a model file's bytes by its `File` name, `None` where the zip lacks it.
pub type ModelFile<'a> = dyn FnMut(&str) -> Result<Option<Vec<u8>>, String> + 'a;

/// The body of the fixture node `fixture` (a `FixtureType`) in a mode whose pan and tilt
/// channels move the geometries named `pan` and `tilt`, and where its geometry `beam`
/// starts; `model_file` gives a model file's bytes (`models/3ds/NAME.3ds`), if the zip
/// has it. An error names what is wrong (a model file that is not 3DS, too many
/// triangles).
pub fn read(
    fixture: roxmltree::Node,
    beam: roxmltree::Node,
    pan: Option<&str>,
    tilt: Option<&str>,
    model_file: &mut ModelFile,
) -> Result<GdtfBody, String> {
    let models: std::collections::HashMap<&str, roxmltree::Node> = fixture
        .descendants()
        .filter(|n| n.has_tag_name("Model"))
        .filter_map(|n| n.attribute("Name").map(|name| (name, n)))
        .collect();
    let mut body = GdtfBody::default();
    let mut meshes: std::collections::HashMap<String, Vec<[Vec3; 3]>> = Default::default();
    let mut total = 0usize;
    let Some(geometries) = fixture.children().find(|n| n.has_tag_name("Geometries")) else {
        return Ok(body);
    };
    // Depth first, each node with its frame and what turns it.
    let mut stack: Vec<(roxmltree::Node, Mat4, Turns, usize)> = geometries
        .children()
        .filter(|n| n.is_element())
        .map(|n| (n, Mat4::IDENTITY, Turns::Not, 0))
        .collect();
    while let Some((node, parent, turns, depth)) = stack.pop() {
        if depth > 64 {
            return Err("geometries nested deeper than 64".into());
        }
        let frame = parent
            * node
                .attribute("Position")
                .and_then(position)
                .unwrap_or(Mat4::IDENTITY);
        if node == beam {
            let offset = frame.w_axis.truncate();
            if offset.is_finite() && offset.length() < 100.0 {
                body.beam_offset = offset;
            }
        }
        let name = node.attribute("Name");
        let turns = if name.is_some() && name == tilt {
            body.tilt_pivot = frame.w_axis.truncate();
            Turns::PanAndTilt
        } else if name.is_some() && name == pan && turns == Turns::Not {
            body.pan_pivot = frame.w_axis.truncate();
            Turns::Pan
        } else {
            turns
        };
        // The beam's own model is the lens, not the body.
        let model = node
            .attribute("Model")
            .filter(|_| !node.has_tag_name("Beam"))
            .and_then(|m| models.get(m));
        if let Some(model) = model {
            let number = |key: &str| {
                model
                    .attribute(key)
                    .and_then(|t| t.trim().parse::<f32>().ok())
                    .filter(|x| x.is_finite() && *x > 0.0 && *x < 100.0)
                    .unwrap_or(0.0)
            };
            let size = Vec3::new(number("Length"), number("Width"), number("Height"));
            let file = model.attribute("File").unwrap_or("").trim();
            let key = format!("{file}/{size}");
            if !meshes.contains_key(&key) {
                let read = if file.is_empty() {
                    None
                } else {
                    model_file(file)?
                };
                let mesh = match read {
                    Some(bytes) => {
                        let mesh = three_ds::triangles(&bytes, MAX_TRIANGLES - total)
                            .map_err(|e| format!("model {file:?}: {e}"))?;
                        scaled(mesh, size)
                    }
                    None if size.min_element() > 0.0 => {
                        primitive(model.attribute("PrimitiveType").unwrap_or(""), size)
                    }
                    None => Vec::new(),
                };
                meshes.insert(key.clone(), mesh);
            }
            let mesh = &meshes[&key];
            total += mesh.len();
            if total > MAX_TRIANGLES {
                return Err(format!("models of more than {MAX_TRIANGLES} triangles"));
            }
            let placed = mesh
                .iter()
                .map(|t| t.map(|p| frame.transform_point3(p)))
                .collect();
            body.parts.push(BodyPart {
                turns,
                triangles: placed,
            });
        }
        stack.extend(
            node.children()
                .filter(|n| n.is_element())
                .map(|n| (n, frame, turns, depth + 1)),
        );
    }
    Ok(body)
}

/// A model file's mesh scaled, axis by axis, so that its bounds measure `size` (GDTF's
/// dimensions; a file's own units may be millimetres or metres), its origin kept.
fn scaled(mesh: Vec<[Vec3; 3]>, size: Vec3) -> Vec<[Vec3; 3]> {
    let (lo, hi) = mesh.iter().flatten().fold(
        (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
        |(lo, hi), p| (lo.min(*p), hi.max(*p)),
    );
    let extent = hi - lo;
    let scale = Vec3::select(
        extent.cmpgt(Vec3::splat(1e-9)) & size.cmpgt(Vec3::ZERO),
        size / extent.max(Vec3::splat(1e-9)),
        Vec3::ONE,
    );
    mesh.into_iter().map(|t| t.map(|p| p * scale)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Shape;
    use crate::shafts::spotlight::Sampling;

    /// The test spot's models: base, yoke and head from its 3DS files, the yoke
    /// panning about its origin, the head tilting about its own; posed as a scene
    /// fixture, the base stays, and the head's lens (its face 0.2 m from the tilt pivot,
    /// the lamp's place) faces where the beam goes, at pans and tilts (within 80 deg,
    /// where nothing of the yoke reaches further along the beam).
    #[test]
    fn a_fixtures_models_turn_with_its_beam() {
        let bytes = crate::shafts::gdtf::example_fixture();
        let file =
            crate::shafts::gdtf::read(&bytes, "spot", "Standard", Sampling::Bilinear).unwrap();
        let body = &file.body;
        let turns: Vec<Turns> = body.parts.iter().map(|p| p.turns).collect();
        assert_eq!(turns.len(), 3);
        for t in [Turns::Not, Turns::Pan, Turns::PanAndTilt] {
            assert!(turns.contains(&t), "{turns:?}");
        }
        assert!((body.pan_pivot - Vec3::new(0.0, 0.0, -0.06)).length() < 1e-6);
        assert!((body.tilt_pivot - Vec3::new(0.0, 0.0, -0.31)).length() < 1e-6);
        // The Beam 0.17 m under the tilt pivot.
        assert!((file.beam_offset - Vec3::new(0.0, 0.0, -0.48)).length() < 1e-6);
        let head = || crate::shafts::show::Fixture {
            model: Some(std::sync::Arc::new(body.clone())),
            body: true,
            ..crate::shafts::show::tests::head()
        };
        let f = head();
        let base_at_rest = f.body(0.0, 0.0);
        for (pan, tilt) in [(0.0, 0.0), (90.0, 30.0), (-120.0, -75.0), (200.0, 60.0)] {
            let (beam, _) = f.aim(pan, tilt);
            let object = f.body(pan, tilt);
            let Shape::Mesh(mesh) = &object.shape else {
                panic!("a mesh")
            };
            let reach = mesh
                .triangles()
                .iter()
                .flat_map(|t| [t[0], t[0] + t[1], t[0] + t[2]])
                .map(|v| (v - f.position).dot(beam))
                .fold(f32::MIN, f32::max);
            assert!(
                (reach - 0.2).abs() < 1e-3,
                "pan {pan} tilt {tilt}: the lens {reach} m ahead"
            );
            assert!(!object.casts_shadow);
            // The base (highest above the head, 0.31 + 0.06 up to 0.37 + 0.06) stays.
            let top = |o: &crate::shafts::objects::Object| o.shape.bounds().unwrap().max.y;
            assert!((top(&object) - top(&base_at_rest)).abs() < 1e-4);
        }
    }

    /// A model without a file is its primitive, centred, measuring its dimensions.
    #[test]
    fn primitives_measure_their_dimensions() {
        let size = Vec3::new(0.4, 0.3, 0.2);
        for (kind, count) in [("Cube", 12), ("Cylinder", 64), ("Head", 12)] {
            let tris = primitive(kind, size);
            assert_eq!(tris.len(), count, "{kind}");
            let (lo, hi) = tris.iter().flatten().fold(
                (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
                |(lo, hi), p| (lo.min(*p), hi.max(*p)),
            );
            assert!(
                (hi - lo - size).abs().max_element() < 1e-6,
                "{kind}: {lo} .. {hi}"
            );
            assert!((hi + lo).abs().max_element() < 1e-6, "{kind} is centred");
        }
    }
}
