//! `[mvr]`: a rig from an MVR file in a scene ([`crate::shafts::mvr`]): each fixture
//! becomes a `[[fixture]]` as if the file had it (its GDTF file from the archive, or
//! the one `replace` names for its type; its patch; hung where the MVR puts it, the
//! lamp at its GDTF beam's place), and the truss and scenery one object.

use std::collections::BTreeMap;
use std::sync::Arc;

use super::*;
use crate::shafts::mvr;
use crate::shafts::show::body_object;

/// What a rig adds to a scene.
pub(super) struct Rig {
    pub(super) fixtures: Vec<FixtureSpec>,
    /// The truss and scenery (one mesh), and the dark fixtures' bodies.
    pub(super) objects: Vec<Object>,
}

impl MvrSpec {
    /// The rig of the MVR file, read with its GDTF files (counted among the scene's
    /// files); fixture names are made unique by their fixture ID. A fixture type atmo
    /// cannot light (its GDTF has no beam or lacks the mode) refuses the rig, naming
    /// each such type and how many, unless `keep_dark`.
    pub(super) fn load(&self, assets: &Assets, taken: &[String]) -> Result<Rig> {
        check_range("mvr.albedo", self.albedo as f64, 0.0, 1.0)?;
        let path = assets.path(&self.file);
        let origin = path.display().to_string();
        let rig = assets.read(
            &format!("MVR file {origin}"),
            || {
                let bytes =
                    crate::files::read_bounded(&path, "MVR file", crate::files::DATA_LIMIT_BYTES)?;
                mvr::read(&bytes, &origin)
            },
            |rig| {
                rig.triangles.len() as u64 * 128
                    + rig.gdtf.values().map(|g| g.len() as u64).sum::<u64>()
            },
        )?;
        for (name, bytes) in rig.gdtf {
            assets.embed(assets.path(&self.file.join(&name)), Arc::new(bytes));
        }
        let mut names: std::collections::HashSet<String> = taken.iter().cloned().collect();
        let (mut fixtures, mut objects) = (Vec::new(), Vec::new());
        let mut refused: BTreeMap<String, (usize, String)> = BTreeMap::new();
        for f in &rig.fixtures {
            let (gdtf, mode) = match self.replace.iter().find(|r| r.spec == f.spec) {
                Some(r) => (r.gdtf.clone(), r.mode.clone()),
                None => (self.file.join(&f.spec), f.mode.clone()),
            };
            let light = match assets.fixture(&gdtf, &mode, Sampling::Bilinear) {
                Ok(light) => light,
                Err(e) => {
                    let entry = refused.entry(f.spec.clone()).or_insert((0, e.to_string()));
                    entry.0 += 1;
                    if self.keep_dark {
                        objects.push(body_object(f.origin, f.axis, f.front, 0.0, 0.0));
                    }
                    continue;
                }
            };
            let mut name = match f.fixture_id.as_str() {
                "" => f.name.clone(),
                id => format!("{} {id}", f.name),
            };
            let base = name.clone();
            for k in 2.. {
                if names.insert(name.clone()) {
                    break;
                }
                name = format!("{base} ({k})");
            }
            fixtures.push(FixtureSpec {
                name,
                // The lamp where the body puts it: the head's tilt pivot with models,
                // else the beam's own place.
                position: f
                    .place(if light.body.is_empty() {
                        light.beam_offset
                    } else {
                        light.body.tilt_pivot
                    })
                    .to_array(),
                axis: f.axis.to_array(),
                front: f.front.to_array(),
                gdtf: Some(gdtf),
                mode: Some(mode),
                intensity: None,
                pan_range_deg: None,
                tilt_range_deg: None,
                zoom_range_deg: None,
                field_ratio: None,
                falloff: FalloffSpec::default(),
                gobo_wheel: None,
                gobo_sampling: SamplingSpec::default(),
                gobo_rotation_deg: 0.0,
                start: AttributesSpec::default(),
                prism: None,
                dmx: f.patch.map(|(universe, address)| DmxSpec {
                    universe: universe as u32,
                    address: address as u32,
                    channels: None,
                }),
                body: self.bodies,
            });
        }
        if !refused.is_empty() && !self.keep_dark {
            let list: Vec<String> = refused
                .iter()
                .map(|(spec, (count, why))| format!("{spec:?} ({count} fixtures): {why}"))
                .collect();
            return Err(Error::Invalid(format!(
                "mvr.file {}: atmo cannot light these fixture types: {}. Give each a GDTF \
                 file with a beam, `replace = [{{ spec = \"...\", gdtf = \"...\", mode = \
                 \"...\" }}]`, or `keep_dark = true` to draw them unlit",
                self.file.display(),
                list.join("; ")
            )));
        }
        if !rig.triangles.is_empty() {
            objects.push(Object {
                shape: Shape::Mesh(Mesh::new(rig.triangles)),
                albedo: Vec3::splat(self.albedo),
                casts_shadow: true,
            });
        }
        Ok(Rig { fixtures, objects })
    }
}
