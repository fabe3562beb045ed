//! The files a scene names, read through the bounded reader: photometric profiles
//! (IES, EULUMDAT), gobo images, GDTF fixtures and OBJ meshes.

use std::cell::{Cell, RefCell};
use std::collections::HashMap;
use std::sync::Arc;

use super::*;

/// What messages call the files a scene holds.
pub(super) const FILES: &str = "the scene's gobos, photometric files, GDTF files and meshes";

/// The files of one scene as they are read: each gobo, profile and GDTF file once,
/// however many lights, wheel slots and fixtures name it (a wheel listing one image
/// 200 times held 200 copies), and what they hold together counted in every budget
/// check made while the next is read ([`crate::budget::beside`]).
pub(super) struct Assets<'a> {
    /// Where relative paths start.
    folder: &'a Path,
    /// What the files read so far hold, bytes.
    held: Cell<u64>,
    gobos: RefCell<HashMap<PathBuf, Gobo>>,
    profiles: RefCell<HashMap<PathBuf, Arc<Photometry>>>,
    fixtures: RefCell<HashMap<(PathBuf, String), gdtf::GdtfFixture>>,
    /// GDTF files that came inside an MVR file, by the path they are named by
    /// (the MVR's path joined with the entry's name).
    embedded: RefCell<HashMap<PathBuf, Arc<Vec<u8>>>>,
}

impl<'a> Assets<'a> {
    pub(super) fn new(folder: &'a Path) -> Assets<'a> {
        Assets {
            folder,
            held: Cell::new(0),
            gobos: RefCell::default(),
            profiles: RefCell::default(),
            fixtures: RefCell::default(),
            embedded: RefCell::default(),
        }
    }

    /// What the files read hold, bytes.
    pub(super) fn held(&self) -> u64 {
        self.held.get()
    }

    /// `file` from the scene's folder.
    pub(super) fn path(&self, file: &Path) -> PathBuf {
        self.folder.join(file)
    }

    /// `load`, with what is held counted in its checks, then what it keeps counted too:
    /// refused if the files together pass the budget.
    pub(super) fn read<T>(
        &self,
        what: &str,
        load: impl FnOnce() -> Result<T>,
        kept: impl Fn(&T) -> u64,
    ) -> Result<T> {
        let value = crate::budget::beside(self.held(), FILES, load)?;
        let held = self.held().saturating_add(kept(&value));
        crate::budget::check(&format!("{FILES} with {what}"), held, FILES)?;
        self.held.set(held);
        Ok(value)
    }

    /// The gobo image `file`, looked up with `sampling`.
    pub(super) fn gobo(&self, file: &Path, sampling: Sampling) -> Result<Gobo> {
        let path = self.path(file);
        if let Some(gobo) = self.gobos.borrow().get(&path) {
            return Ok(gobo.with_sampling(sampling));
        }
        let what = format!("gobo {}", path.display());
        let gobo = self.read(&what, || load_gobo(&path, sampling), Gobo::bytes)?;
        self.gobos.borrow_mut().insert(path, gobo.clone());
        Ok(gobo)
    }

    /// The photometric file `file`: IES LM-63, or EULUMDAT when `eulumdat`.
    pub(super) fn profile(&self, file: &Path, eulumdat: bool) -> Result<Arc<Photometry>> {
        let path = self.path(file);
        if let Some(profile) = self.profiles.borrow().get(&path) {
            return Ok(profile.clone());
        }
        let what = format!("photometric file {}", path.display());
        let profile = self.read(
            &what,
            || load_photometry(&path, eulumdat).map(Arc::new),
            |p| p.bytes(),
        )?;
        self.profiles.borrow_mut().insert(path, profile.clone());
        Ok(profile)
    }

    /// The fixture of GDTF file `file` in DMX `mode`, its gobos looked up with
    /// `sampling`.
    /// Names the GDTF file `bytes` (from an MVR file) `path`, for [`Assets::fixture`].
    #[cfg(feature = "gdtf")]
    pub(super) fn embed(&self, path: PathBuf, bytes: Arc<Vec<u8>>) {
        self.embedded.borrow_mut().insert(path, bytes);
    }

    pub(super) fn fixture(
        &self,
        file: &Path,
        mode: &str,
        sampling: Sampling,
    ) -> Result<gdtf::GdtfFixture> {
        let key = (self.path(file), mode.to_string());
        let cached = self.fixtures.borrow().get(&key).cloned();
        let mut fixture = match cached {
            Some(fixture) => fixture,
            None => {
                let what = format!("GDTF file {}", key.0.display());
                let fixture = self.read(
                    &what,
                    || match self.embedded.borrow().get(&key.0) {
                        #[cfg(feature = "gdtf")]
                        Some(bytes) => {
                            gdtf::read(bytes, &key.0.display().to_string(), mode, sampling)
                        }
                        _ => read_gdtf(&key.0, mode, sampling),
                    },
                    |f| {
                        let gobos: u64 = f.wheel.iter().map(Gobo::bytes).sum();
                        #[cfg(feature = "gdtf")]
                        let models: u64 = f
                            .body
                            .parts
                            .iter()
                            .map(|p| 36 * p.triangles.len() as u64)
                            .sum();
                        #[cfg(not(feature = "gdtf"))]
                        let models = 0;
                        gobos + models
                    },
                )?;
                self.fixtures.borrow_mut().insert(key, fixture.clone());
                fixture
            }
        };
        for gobo in &mut fixture.wheel {
            *gobo = gobo.with_sampling(sampling);
        }
        Ok(fixture)
    }

    /// The mesh of OBJ file `file`, each vertex mapped by `place` (a mesh is placed as
    /// it is read, so each object reads its own).
    pub(super) fn mesh(&self, file: &Path, place: impl Fn(Vec3) -> Vec3) -> Result<Mesh> {
        let path = self.path(file);
        let what = format!("OBJ file {}", path.display());
        self.read(&what, || load_obj(&path, place), Mesh::bytes)
    }
}

/// The farthest off the axis a measured profile is drawn, degrees: the field of a
/// spotlight's square light map and shadow map must stay below 90 (`field_deg` below
/// 180); light a file gives beyond it is left out.
pub const MEASURED_REACH_DEG: f32 = 85.0;

/// A photometric file (through the bounded reader): IES LM-63, or EULUMDAT when
/// `eulumdat`; errors name the file.
pub fn load_photometry(path: &Path, eulumdat: bool) -> Result<Photometry> {
    let what = if eulumdat {
        "EULUMDAT file"
    } else {
        "IES file"
    };
    let text = crate::files::read_text(path, what, crate::files::TEXT_LIMIT_BYTES)?;
    let origin = path.display().to_string();
    if eulumdat {
        Photometry::from_eulumdat(&text, &origin)
    } else {
        Photometry::from_ies(&text, &origin)
    }
}

/// The largest gobo image, pixels a side: four times a projector's finest gobo, and
/// 50 MB as texels.
pub const GOBO_MAX_SIDE: u32 = 4096;

/// A gobo from an image file (through the bounded reader); errors name the file.
pub fn load_gobo(path: &Path, sampling: Sampling) -> Result<Gobo> {
    let bytes = crate::files::read_bounded(path, "gobo image", crate::files::DATA_LIMIT_BYTES)?;
    gobo_from_image(&bytes, &path.display().to_string(), sampling)
}

/// A gobo from the bytes of an image file (PNG, or what the build's image features
/// read); `origin` names it in messages. The size is read from the header and checked
/// before anything is decoded: a small file can claim a huge image.
pub fn gobo_from_image(bytes: &[u8], origin: &str, sampling: Sampling) -> Result<Gobo> {
    use image::ImageDecoder as _;
    let bad = |e: image::ImageError| Error::Invalid(format!("gobo {origin}: {e}"));
    let decoder = image::ImageReader::new(std::io::Cursor::new(bytes))
        .with_guessed_format()
        .map_err(|e| Error::Invalid(format!("gobo {origin}: {e}")))?
        .into_decoder()
        .map_err(bad)?;
    let (width, height) = decoder.dimensions();
    if width.max(height) > GOBO_MAX_SIDE {
        return Err(Error::Invalid(format!(
            "gobo {origin}: {width} x {height} pixels is above the limit of {GOBO_MAX_SIDE} a \
             side; scale the image down"
        )));
    }
    // Decoding holds the image as the file stores it (up to 8 bytes a pixel), its
    // 8-bit RGB copy and the texels kept, 3 bytes a pixel each.
    crate::budget::check(
        &format!("gobo {origin} ({width} x {height})"),
        decoder.total_bytes() + 6 * width as u64 * height as u64,
        "the gobo image's size",
    )?;
    let image = image::DynamicImage::from_decoder(decoder)
        .map_err(bad)?
        .to_rgb8();
    Ok(Gobo::new(
        image.width() as usize,
        image.height() as usize,
        image.pixels().map(|p| p.0).collect(),
        sampling,
    ))
}

impl ObjectSpec {
    pub(super) fn validate(&self, at: &str, assets: &Assets) -> Result<Object> {
        let field = |name: &str| format!("{at}.{name}");
        let (shape, a) = match self {
            ObjectSpec::Plane {
                point,
                normal,
                albedo,
            } => (
                Shape::Plane {
                    point: vec3(&field("point"), *point)?,
                    normal: unit_vector(&field("normal"), *normal)?,
                },
                albedo,
            ),
            ObjectSpec::Rect {
                corner,
                edge_a,
                edge_b,
                albedo,
            } => {
                let (ea, eb) = (
                    vec3(&field("edge_a"), *edge_a)?,
                    vec3(&field("edge_b"), *edge_b)?,
                );
                if ea.cross(eb).length() < 1e-9 {
                    return Err(Error::Invalid(format!(
                        "{at}: edge_a and edge_b are zero or parallel: the rectangle has no area"
                    )));
                }
                (
                    Shape::Rect {
                        corner: vec3(&field("corner"), *corner)?,
                        edge_a: ea,
                        edge_b: eb,
                    },
                    albedo,
                )
            }
            ObjectSpec::Sphere {
                center,
                radius,
                albedo,
            } => {
                check_positive(&field("radius"), *radius as f64, 1e6)?;
                (
                    Shape::Sphere {
                        center: vec3(&field("center"), *center)?,
                        radius: *radius,
                    },
                    albedo,
                )
            }
            ObjectSpec::Box { min, max, albedo } => {
                let (min, max) = (vec3(&field("min"), *min)?, vec3(&field("max"), *max)?);
                if !min.cmplt(max).all() {
                    return Err(Error::out_of_range(
                        &field("max"),
                        format!("{max:?}"),
                        &format!("greater than {at}.min = {min:?} on every axis"),
                    ));
                }
                (Shape::Box(Aabb { min, max }), albedo)
            }
            ObjectSpec::Mesh {
                file,
                scale,
                rotate_y_deg,
                translate,
                albedo,
            } => {
                check_positive(&field("scale"), *scale as f64, 1e6)?;
                check_range(&field("rotate_y_deg"), *rotate_y_deg as f64, -360.0, 360.0)?;
                let translate = vec3(&field("translate"), *translate)?;
                let rotation = glam::Mat3::from_rotation_y(rotate_y_deg.to_radians());
                let mesh = assets.mesh(file, |p| rotation * (p * *scale) + translate)?;
                (Shape::Mesh(mesh), albedo)
            }
        };
        Ok(Object {
            shape,
            albedo: albedo(&field("albedo"), *a)?,
            casts_shadow: true,
        })
    }
}

/// The triangles of an OBJ file (all its objects; polygons fanned into triangles;
/// materials ignored), each vertex mapped by `place`. Degenerate triangles are dropped;
/// a file without any triangle, with indices out of range or with non-finite
/// coordinates is an error, never a panic.
#[cfg(feature = "obj")]
pub fn load_obj(path: &Path, place: impl Fn(Vec3) -> Vec3) -> Result<Mesh> {
    let bytes = crate::files::read_bounded(path, "OBJ file", crate::files::DATA_LIMIT_BYTES)?;
    mesh_from_obj(&bytes, &path.display().to_string(), place)
}

/// [`load_obj`] from the bytes of an OBJ file; `origin` names it in messages.
#[cfg(feature = "obj")]
pub fn mesh_from_obj(bytes: &[u8], origin: &str, place: impl Fn(Vec3) -> Vec3) -> Result<Mesh> {
    let fail = |why: String| Error::Invalid(format!("OBJ file {origin}: {why}"));
    let text = std::str::from_utf8(bytes).map_err(|e| fail(format!("not UTF-8 text ({e})")))?;
    let counts = check_obj_indices(text).map_err(fail)?;
    crate::budget::check(
        &format!(
            "the mesh of OBJ file {origin} ({} triangles, {} vertices)",
            counts.triangles, counts.vertices
        ),
        bytes.len() as u64 + counts.bytes(),
        "the mesh's size",
    )?;
    let options = tobj::LoadOptions {
        triangulate: true,
        ..Default::default()
    };
    let (models, _) = tobj::load_obj_buf(&mut std::io::Cursor::new(bytes), &options, |_| {
        Err(tobj::LoadError::OpenFileFailed)
    })
    .map_err(|e| fail(e.to_string()))?;
    let mut triangles = Vec::new();
    for model in &models {
        let (p, idx) = (&model.mesh.positions, &model.mesh.indices);
        let vertex = |i: u32| -> Result<Vec3> {
            let i = i as usize * 3;
            let v = p
                .get(i..i + 3)
                .ok_or_else(|| fail(format!("vertex index {} out of range", i / 3 + 1)))?;
            let v = place(Vec3::new(v[0], v[1], v[2]));
            if v.is_finite() {
                Ok(v)
            } else {
                Err(fail(format!(
                    "vertex {} is not finite where it is placed",
                    i / 3 + 1
                )))
            }
        };
        for t in idx.as_chunks::<3>().0 {
            let [a, b, c] = [vertex(t[0])?, vertex(t[1])?, vertex(t[2])?];
            if (b - a).cross(c - a).length_squared() > 1e-20 {
                triangles.push([a, b, c]);
            }
        }
    }
    if triangles.is_empty() {
        return Err(fail("no triangles".into()));
    }
    Ok(Mesh::new(triangles))
}

/// How many vertices and triangles an OBJ file's text gives (its faces fanned).
#[cfg(feature = "obj")]
#[derive(Debug, Default, PartialEq)]
pub(super) struct ObjCounts {
    pub vertices: u64,
    pub triangles: u64,
}

#[cfg(feature = "obj")]
impl ObjCounts {
    /// What reading the mesh holds beside the text, bytes: tobj's lists, the
    /// triangles, their hierarchy and its build, measured from outside (peak resident
    /// size over 3 M triangles of a 41 MB file, and 1.3 M triangles and 640 k vertices
    /// of a 48 MB one: 135 and about 110 bytes a triangle) and charged at 128 a
    /// triangle and 24 a vertex. Charging the text four times over, as before, left a
    /// file of short face lines undercounted 2.7 times.
    pub fn bytes(&self) -> u64 {
        128 * self.triangles + 24 * self.vertices
    }
}

/// Checks every index of the face and line elements (`f`, `l`) against the vertices,
/// texture coordinates and normals given before it, as OBJ counts them (from 1, or
/// back from the last with a minus sign): tobj turns an index out of range into an
/// arithmetic overflow (found by fuzzing: a panic in debug builds, a wrapped index in
/// release ones), so none reaches it. The message names the line. Gives the counts
/// the mesh is charged by.
#[cfg(feature = "obj")]
pub(super) fn check_obj_indices(text: &str) -> std::result::Result<ObjCounts, String> {
    let mut triangles = 0u64;
    let mut counts = [0i64; 3]; // positions, texture coordinates, normals
    for (k, line) in text.lines().enumerate() {
        let mut words = line.split_whitespace();
        match words.next() {
            Some("v") => counts[0] += 1,
            Some("vt") => counts[1] += 1,
            Some("vn") => counts[2] += 1,
            Some(element @ ("f" | "l")) => {
                let mut corners = 0u64;
                for word in words {
                    corners += 1;
                    for (kind, index) in word.split('/').enumerate().take(3) {
                        if index.is_empty() {
                            continue;
                        }
                        let n = counts[kind];
                        let ok = index
                            .parse::<i64>()
                            .is_ok_and(|i| (1..=n).contains(&i) || (-n..=-1).contains(&i));
                        if !ok {
                            let what = ["vertex", "texture coordinate", "normal"][kind];
                            return Err(format!(
                                "line {}: {what} index {index} is out of range: {n} given before it",
                                k + 1
                            ));
                        }
                    }
                }
                if element == "f" {
                    triangles += corners.saturating_sub(2);
                }
            }
            _ => {}
        }
    }
    Ok(ObjCounts {
        vertices: counts[0] as u64,
        triangles,
    })
}

/// Without atmo's `obj` feature, OBJ meshes are refused with a message saying so.
#[cfg(not(feature = "obj"))]
pub fn load_obj(path: &Path, _place: impl Fn(Vec3) -> Vec3) -> Result<Mesh> {
    Err(Error::Invalid(format!(
        "OBJ file {}: meshes need atmo's `obj` feature, which this build leaves out",
        path.display()
    )))
}
