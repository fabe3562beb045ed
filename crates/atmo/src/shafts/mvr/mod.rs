//! MVR files (My Virtual Rig, DIN SPEC 15801): a rig as previsualisation tools and
//! consoles exchange it, a zip of `GeneralSceneDescription.xml`, the fixtures' GDTF
//! files and the geometry of truss and scenery (3DS).
//!
//! [`read`] gives a [`Rig`]: every `Fixture` with its GDTF file, DMX mode, patch and
//! where it hangs, and the triangles of every `Truss`, `SceneObject` and
//! `VideoScreen` (their `Geometry3D` files, directly or through a `Symbol` of a
//! `Symdef`), each placed by the product of its ancestors' `Matrix`es. MVR's frame is
//! z up in millimetres; the rig is given in atmo's, y up in metres: MVR's `(x, y, z)`
//! is atmo's `(x, z, -y)`. A fixture's beam leaves along its local -z at rest and a
//! positive tilt swings it toward local +y, as GDTF draws fixtures.
//!
//! The archive is untrusted: every entry is refused past its size and the run's memory
//! budget before it is read, names with folders are refused (MVR has none), the XML
//! is read without a DTD (no entity expansion), nesting past [`MAX_DEPTH`] and meshes
//! past [`MAX_TRIANGLES`] are refused; every refusal names what and where.

pub mod three_ds;

use std::collections::HashMap;

use glam::{Mat3, Vec3};

use crate::error::{Error, Result};

/// The deepest nesting of groups, layers and symbols read.
pub const MAX_DEPTH: usize = 64;

/// The most triangles of truss and scenery a rig may have.
pub const MAX_TRIANGLES: usize = 4_000_000;

/// What a triangle of a rig's geometry holds in memory, bytes (the mesh's own and its
/// BVH's share, as OBJ meshes are counted).
const TRIANGLE_BYTES: u64 = 128;

/// The largest GeneralSceneDescription.xml read, bytes.
const DESCRIPTION_LIMIT: u64 = 64 << 20;

/// A placement: a rotation (columns: the local x, y and z axes) and an offset.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Placement {
    pub rotation: Mat3,
    /// mm in MVR's frame while reading.
    pub offset: Vec3,
}

impl Placement {
    const IDENTITY: Placement = Placement {
        rotation: Mat3::IDENTITY,
        offset: Vec3::ZERO,
    };

    /// `self` after `local`: a point of `local`'s frame placed in `self`'s parent.
    fn then(&self, local: &Placement) -> Placement {
        Placement {
            rotation: self.rotation * local.rotation,
            offset: self.rotation * local.offset + self.offset,
        }
    }

    fn apply(&self, p: Vec3) -> Vec3 {
        self.rotation * p + self.offset
    }
}

/// MVR's frame (z up, mm) to atmo's (y up, m), for a point.
pub fn to_atmo(p: Vec3) -> Vec3 {
    Vec3::new(p.x, p.z, -p.y) * 1e-3
}

/// The same for a direction (unit stays unit).
fn direction_to_atmo(d: Vec3) -> Vec3 {
    Vec3::new(d.x, d.z, -d.y)
}

/// A fixture of the rig.
#[derive(Debug, Clone, PartialEq)]
pub struct RigFixture {
    /// Its name and fixture ID, for messages and cues.
    pub name: String,
    pub fixture_id: String,
    /// The GDTF file in the archive and the DMX mode.
    pub spec: String,
    pub mode: String,
    /// Where its origin hangs, m, and its frame in atmo's: the beam at rest
    /// (`axis`) and where a positive tilt swings it (`front`), unit.
    pub origin: Vec3,
    pub rotation: Mat3,
    pub axis: Vec3,
    pub front: Vec3,
    /// Its first break's universe and address; `None` when unpatched (address 0).
    pub patch: Option<(u16, u16)>,
}

impl RigFixture {
    /// Where a point of the fixture's GDTF frame (metres, z up) is in atmo's.
    pub fn place(&self, local_m: Vec3) -> Vec3 {
        self.origin + direction_to_atmo(self.rotation * local_m)
    }
}

/// What an MVR file holds for atmo.
#[derive(Debug, Clone, Default)]
pub struct Rig {
    pub fixtures: Vec<RigFixture>,
    /// The triangles of truss and scenery, atmo's frame, m.
    pub triangles: Vec<[Vec3; 3]>,
    /// Geometry files that were not read, and why (a glTF model, a missing file).
    pub skipped: Vec<String>,
    /// The archive's GDTF files by name.
    pub gdtf: HashMap<String, Vec<u8>>,
}

/// A DMX address as MVR writes it: absolute (`513` is universe 2, channel 1) or
/// `Universe.Address`; 0 is unpatched.
pub fn address(text: &str) -> std::result::Result<Option<(u16, u16)>, String> {
    let bad = || format!("DMX address {text:?} is not a number or UNIVERSE.ADDRESS");
    let (universe, channel) = match text.trim().split_once('.') {
        Some((u, a)) => (
            u.trim().parse::<u64>().map_err(|_| bad())?,
            a.trim().parse::<u64>().map_err(|_| bad())?,
        ),
        None => {
            let absolute = text.trim().parse::<u64>().map_err(|_| bad())?;
            if absolute == 0 {
                return Ok(None);
            }
            ((absolute - 1) / 512 + 1, (absolute - 1) % 512 + 1)
        }
    };
    if !(1..=crate::shafts::dmx::MAX_UNIVERSE as u64).contains(&universe)
        || !(1..=512).contains(&channel)
    {
        return Err(format!(
            "DMX address {text:?}: universe {universe}, channel {channel}; allowed universes \
             1 to 63999 and channels 1 to 512"
        ));
    }
    Ok(Some((universe as u16, channel as u16)))
}

/// A matrix as MVR writes it, `{u}{v}{w}{o}` (four vectors of three numbers).
pub fn matrix(text: &str) -> std::result::Result<Placement, String> {
    let bad = || format!("Matrix {text:?} is not four vectors {{u}}{{v}}{{w}}{{o}}");
    let rows: Vec<Vec3> = text
        .split('}')
        .map(str::trim)
        .filter(|r| !r.is_empty())
        .map(|r| {
            let r = r.strip_prefix('{').ok_or_else(bad)?;
            let v: Vec<f32> = r
                .split(',')
                .map(|x| x.trim().parse::<f32>().ok().filter(|x| x.is_finite()))
                .collect::<Option<_>>()
                .ok_or_else(bad)?;
            match v[..] {
                [x, y, z] => Ok(Vec3::new(x, y, z)),
                _ => Err(bad()),
            }
        })
        .collect::<std::result::Result<_, String>>()?;
    let [u, v, w, o] = rows[..] else {
        return Err(bad());
    };
    if o.abs().max_element() > 1e9 {
        return Err(format!("Matrix {text:?}: an offset past 1,000 km"));
    }
    Ok(Placement {
        rotation: Mat3::from_cols(u, v, w),
        offset: o,
    })
}

/// Reads the MVR file `bytes` (`origin` names it in messages).
pub fn read(bytes: &[u8], origin: &str) -> Result<Rig> {
    let fail = |why: String| Error::Invalid(format!("MVR file {origin}: {why}"));
    let mut zip = zip::ZipArchive::new(std::io::Cursor::new(bytes))
        .map_err(|e| fail(format!("not a readable zip ({e})")))?;
    let text =
        crate::shafts::gdtf::zip_entry(&mut zip, "GeneralSceneDescription.xml", DESCRIPTION_LIMIT)
            .map_err(fail)?
            .ok_or_else(|| fail("no GeneralSceneDescription.xml in the zip".into()))?;
    let text = String::from_utf8(text)
        .map_err(|_| fail("GeneralSceneDescription.xml is not UTF-8".into()))?;
    let options = roxmltree::ParsingOptions {
        allow_dtd: false,
        nodes_limit: 4_000_000,
        ..roxmltree::ParsingOptions::default()
    };
    let doc = roxmltree::Document::parse_with_options(&text, options)
        .map_err(|e| fail(format!("GeneralSceneDescription.xml: {e}")))?;
    let scene = doc
        .descendants()
        .find(|n| n.has_tag_name("Scene"))
        .ok_or_else(|| fail("GeneralSceneDescription.xml has no Scene".into()))?;
    let symdefs: HashMap<&str, roxmltree::Node> = scene
        .descendants()
        .filter(|n| n.has_tag_name("Symdef"))
        .filter_map(|n| n.attribute("uuid").map(|u| (u, n)))
        .collect();
    let mut reader = Reader {
        zip,
        symdefs,
        rig: Rig::default(),
        meshes: HashMap::new(),
    };
    for layer in scene
        .children()
        .filter(|n| n.has_tag_name("Layers"))
        .flat_map(|l| l.children().filter(|n| n.has_tag_name("Layer")))
    {
        let at = reader.placement(layer).map_err(fail)?;
        reader.children(layer, &at, 0).map_err(fail)?;
    }
    Ok(reader.rig)
}

struct Reader<'a, 'i> {
    zip: zip::ZipArchive<std::io::Cursor<&'a [u8]>>,
    symdefs: HashMap<&'i str, roxmltree::Node<'i, 'i>>,
    rig: Rig,
    /// Each geometry file's triangles in its own frame, read once.
    meshes: HashMap<String, std::sync::Arc<Vec<[Vec3; 3]>>>,
}

impl<'i> Reader<'_, 'i> {
    /// The node's own `Matrix` (identity without one).
    fn placement(&self, node: roxmltree::Node) -> std::result::Result<Placement, String> {
        match node.children().find(|n| n.has_tag_name("Matrix")) {
            None => Ok(Placement::IDENTITY),
            Some(m) => matrix(m.text().unwrap_or("")).map_err(|e| {
                format!(
                    "{} {:?}: {e}",
                    node.tag_name().name(),
                    node.attribute("name").unwrap_or("")
                )
            }),
        }
    }

    /// What `node` holds in its `ChildList`s and `Geometries`, placed by `at`: groups
    /// and objects (their geometry) recursively, fixtures, geometry files, and symbols
    /// (their `Symdef`'s list), every level at most [`MAX_DEPTH`] deep.
    fn children(
        &mut self,
        node: roxmltree::Node<'i, 'i>,
        at: &Placement,
        depth: usize,
    ) -> std::result::Result<(), String> {
        if depth > MAX_DEPTH {
            return Err(format!(
                "objects and symbols nested deeper than {MAX_DEPTH}"
            ));
        }
        let lists = node
            .children()
            .filter(|n| n.has_tag_name("ChildList") || n.has_tag_name("Geometries"));
        for list in lists {
            for child in list.children().filter(|n| n.is_element()) {
                let here = at.then(&self.placement(child)?);
                match child.tag_name().name() {
                    "GroupObject" | "Truss" | "SceneObject" | "VideoScreen" | "Support" => {
                        self.children(child, &here, depth + 1)?
                    }
                    "Fixture" => self.fixture(child, &here)?,
                    "Geometry3D" => {
                        let file = child
                            .attribute("fileName")
                            .or(child.attribute("file"))
                            .unwrap_or("");
                        self.geometry_file(file, &here)?;
                    }
                    "Symbol" => {
                        let uuid = child.attribute("symdef").unwrap_or("");
                        let def = *self.symdefs.get(uuid).ok_or_else(|| {
                            format!("a Symbol names Symdef {uuid:?}, which the file lacks")
                        })?;
                        self.children(def, &here, depth + 1)?;
                    }
                    _ => {}
                }
            }
        }
        Ok(())
    }

    fn fixture(
        &mut self,
        node: roxmltree::Node,
        at: &Placement,
    ) -> std::result::Result<(), String> {
        let name = node.attribute("name").unwrap_or("").to_string();
        let text = |tag: &str| {
            node.children()
                .find(|n| n.has_tag_name(tag))
                .and_then(|n| n.text())
                .unwrap_or("")
                .trim()
                .to_string()
        };
        let (spec, mode, fixture_id) = (text("GDTFSpec"), text("GDTFMode"), text("FixtureID"));
        let first_break = node
            .descendants()
            .filter(|n| n.has_tag_name("Address"))
            .min_by_key(|n| {
                n.attribute("break")
                    .and_then(|b| b.parse::<u32>().ok())
                    .unwrap_or(0)
            });
        let patch = match first_break.and_then(|a| a.text()) {
            None => None,
            Some(t) => address(t).map_err(|e| format!("Fixture {name:?}: {e}"))?,
        };
        let rotation = at.rotation;
        let unit = |v: Vec3| direction_to_atmo(rotation * v).normalize_or_zero();
        let (axis, front) = (unit(Vec3::NEG_Z), unit(Vec3::Y));
        if axis == Vec3::ZERO || front == Vec3::ZERO {
            return Err(format!(
                "Fixture {name:?}: its Matrix does not turn (it collapses the fixture)"
            ));
        }
        self.rig.fixtures.push(RigFixture {
            name,
            fixture_id,
            spec: spec.clone(),
            mode,
            origin: to_atmo(at.offset),
            rotation,
            axis,
            front,
            patch,
        });
        if !spec.is_empty() && !self.rig.gdtf.contains_key(&spec) {
            let file = if spec.ends_with(".gdtf") {
                spec.clone()
            } else {
                format!("{spec}.gdtf")
            };
            if let Some(bytes) = self.entry(&file, crate::files::DATA_LIMIT_BYTES)? {
                self.rig.gdtf.insert(spec, bytes);
            }
        }
        Ok(())
    }

    /// The entry `name` of the archive, if there; a name with a folder is refused.
    fn entry(&mut self, name: &str, limit: u64) -> std::result::Result<Option<Vec<u8>>, String> {
        if name.contains(['/', '\\']) || name.contains("..") {
            return Err(format!(
                "{name:?}: MVR files keep every file at the archive's root"
            ));
        }
        crate::shafts::gdtf::zip_entry(&mut self.zip, name, limit)
    }

    fn geometry_file(&mut self, file: &str, at: &Placement) -> std::result::Result<(), String> {
        let name = if file.contains('.') {
            file.to_string()
        } else {
            format!("{file}.3ds")
        };
        let mesh = match self.meshes.get(&name) {
            Some(mesh) => mesh.clone(),
            None => {
                if !name.to_ascii_lowercase().ends_with(".3ds") {
                    self.rig
                        .skipped
                        .push(format!("{name}: only 3DS geometry is read"));
                    return Ok(());
                }
                let Some(bytes) = self.entry(&name, crate::files::DATA_LIMIT_BYTES)? else {
                    self.rig.skipped.push(format!("{name}: not in the archive"));
                    return Ok(());
                };
                let left = MAX_TRIANGLES - self.rig.triangles.len();
                let mesh = std::sync::Arc::new(
                    three_ds::triangles(&bytes, left).map_err(|e| format!("{name}: {e}"))?,
                );
                self.meshes.insert(name.clone(), mesh.clone());
                mesh
            }
        };
        let total = self.rig.triangles.len() + mesh.len();
        if total > MAX_TRIANGLES {
            return Err(format!(
                "more than {MAX_TRIANGLES} triangles of truss and scenery"
            ));
        }
        crate::budget::check(
            "the MVR's truss and scenery",
            total as u64 * TRIANGLE_BYTES,
            "--memory-limit (or a lighter MVR)",
        )
        .map_err(|e| e.to_string())?;
        // 3DS geometry in an MVR is in millimetres, as its matrices are.
        self.rig
            .triangles
            .extend(mesh.iter().map(|t| t.map(|p| to_atmo(at.apply(p)))));
        Ok(())
    }
}

#[cfg(test)]
mod tests;
