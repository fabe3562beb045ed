//! 3D Studio meshes (`.3ds`), the geometry MVR files carry for truss and scenery: the
//! triangles of every object's mesh, nothing else (materials, lights, cameras and
//! keyframes are skipped).
//!
//! A 3DS file is a tree of chunks, each a 16-bit id and a 32-bit length (its 6-byte
//! header included), little-endian. The triangles are in `MAIN (0x4d4d) > EDITOR
//! (0x3d3d) > OBJECT (0x4000, a name then chunks) > TRIMESH (0x4100) > VERTICES (0x4110:
//! a 16-bit count and xyz floats) and FACES (0x4120: a 16-bit count and three 16-bit
//! indices and flags each)`; the vertices are stored where the mesh stands (its local
//! frame, chunk 0x4160, is informative). Written here: the format is these few chunks,
//! and the crates that read it bring a renderer's scene graph with them. Every length
//! and index is checked: a malformed file is an error naming where, never a panic.

use glam::Vec3;

const MAIN: u16 = 0x4d4d;
const EDITOR: u16 = 0x3d3d;
const OBJECT: u16 = 0x4000;
const TRIMESH: u16 = 0x4100;
const VERTICES: u16 = 0x4110;
const FACES: u16 = 0x4120;

/// The chunks directly inside `bytes`, as `(id, body)`.
fn chunks(bytes: &[u8]) -> impl Iterator<Item = Result<(u16, &[u8]), String>> {
    let mut at = 0usize;
    std::iter::from_fn(move || {
        if at >= bytes.len() {
            return None;
        }
        let Some(header) = bytes.get(at..at + 6) else {
            at = bytes.len();
            return Some(Err(format!("a chunk header cut off at byte {at}")));
        };
        let id = u16::from_le_bytes([header[0], header[1]]);
        let length = u32::from_le_bytes([header[2], header[3], header[4], header[5]]) as usize;
        let end = at
            .checked_add(length)
            .filter(|&e| length >= 6 && e <= bytes.len());
        let Some(end) = end else {
            let e = format!("chunk {id:#06x} at byte {at} claims {length} bytes, past its parent");
            at = bytes.len();
            return Some(Err(e));
        };
        let body = &bytes[at + 6..end];
        at = end;
        Some(Ok((id, body)))
    })
}

/// The triangles of every mesh in the 3DS file `bytes`, in the file's units; at most
/// `limit` of them (a larger mesh is an error: the caller's memory budget).
pub fn triangles(bytes: &[u8], limit: usize) -> Result<Vec<[Vec3; 3]>, String> {
    if bytes.get(..2) != Some(&MAIN.to_le_bytes()[..]) {
        return Err("not a 3DS file (it does not start with chunk 0x4d4d)".into());
    }
    let mut out = Vec::new();
    for chunk in chunks(bytes) {
        let (id, main) = chunk?;
        if id != MAIN {
            return Err(format!(
                "not a 3DS file (its first chunk is {id:#06x}, not 0x4d4d)"
            ));
        }
        for chunk in chunks(main) {
            let (id, editor) = chunk?;
            if id != EDITOR {
                continue;
            }
            for chunk in chunks(editor) {
                let (id, object) = chunk?;
                if id != OBJECT {
                    continue;
                }
                // The object's name, NUL-terminated, then its chunks.
                let name_end = object
                    .iter()
                    .position(|&b| b == 0)
                    .ok_or("an object's name is not terminated")?;
                for chunk in chunks(&object[name_end + 1..]) {
                    let (id, mesh) = chunk?;
                    if id == TRIMESH {
                        trimesh(mesh, limit, &mut out)?;
                    }
                }
            }
        }
    }
    Ok(out)
}

fn trimesh(mesh: &[u8], limit: usize, out: &mut Vec<[Vec3; 3]>) -> Result<(), String> {
    let mut vertices: Vec<Vec3> = Vec::new();
    for chunk in chunks(mesh) {
        let (id, body) = chunk?;
        let count = |b: &[u8]| -> Result<usize, String> {
            b.get(..2)
                .map(|c| u16::from_le_bytes([c[0], c[1]]) as usize)
                .ok_or_else(|| format!("chunk {id:#06x} without its count"))
        };
        match id {
            VERTICES => {
                let n = count(body)?;
                let data = body
                    .get(2..2 + 12 * n)
                    .ok_or_else(|| format!("{n} vertices claimed, {} bytes given", body.len()))?;
                vertices = data
                    .as_chunks::<12>()
                    .0
                    .iter()
                    .map(|v| {
                        let f = |k: usize| f32::from_le_bytes([v[k], v[k + 1], v[k + 2], v[k + 3]]);
                        Vec3::new(f(0), f(4), f(8))
                    })
                    .collect();
                if vertices.iter().any(|v| !v.is_finite()) {
                    return Err("a vertex is not finite".into());
                }
            }
            FACES => {
                let n = count(body)?;
                let data = body
                    .get(2..2 + 8 * n)
                    .ok_or_else(|| format!("{n} faces claimed, {} bytes given", body.len()))?;
                if out.len() + n > limit {
                    return Err(format!("more than {limit} triangles"));
                }
                for face in data.as_chunks::<8>().0 {
                    let index = |k: usize| u16::from_le_bytes([face[k], face[k + 1]]) as usize;
                    let corner = |k: usize| {
                        vertices.get(index(k)).copied().ok_or_else(|| {
                            format!(
                                "a face names vertex {} of {} (faces before vertices?)",
                                index(k),
                                vertices.len()
                            )
                        })
                    };
                    let tri = [corner(0)?, corner(2)?, corner(4)?];
                    // Degenerate faces (zero area) are dropped, as OBJ's are.
                    if (tri[1] - tri[0]).cross(tri[2] - tri[0]).length_squared() > 0.0 {
                        out.push(tri);
                    }
                }
            }
            _ => {}
        }
    }
    Ok(())
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    fn chunk(id: u16, body: &[u8]) -> Vec<u8> {
        let mut c = id.to_le_bytes().to_vec();
        c.extend_from_slice(&(body.len() as u32 + 6).to_le_bytes());
        c.extend_from_slice(body);
        c
    }

    /// A 3DS file of one object whose mesh has `vertices` and `faces`.
    pub(crate) fn file(vertices: &[[f32; 3]], faces: &[[u16; 3]]) -> Vec<u8> {
        let mut v = (vertices.len() as u16).to_le_bytes().to_vec();
        for p in vertices {
            p.iter().for_each(|x| v.extend_from_slice(&x.to_le_bytes()));
        }
        let mut f = (faces.len() as u16).to_le_bytes().to_vec();
        for t in faces {
            t.iter().for_each(|i| f.extend_from_slice(&i.to_le_bytes()));
            f.extend_from_slice(&0u16.to_le_bytes());
        }
        let mesh = [chunk(VERTICES, &v), chunk(FACES, &f)].concat();
        let object = [b"box\0".to_vec(), chunk(TRIMESH, &mesh)].concat();
        chunk(MAIN, &chunk(EDITOR, &chunk(OBJECT, &object)))
    }

    #[test]
    fn a_mesh_reads_as_its_triangles_and_a_bad_one_is_refused() {
        let bytes = file(
            &[
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [0.0, 2.0, 0.0],
                [0.0, 0.0, 3.0],
            ],
            &[[0, 1, 2], [0, 2, 3], [0, 0, 1]],
        );
        let tris = triangles(&bytes, 100).unwrap();
        assert_eq!(tris.len(), 2, "the degenerate face is dropped");
        assert_eq!(
            tris[1],
            [
                Vec3::ZERO,
                Vec3::new(0.0, 2.0, 0.0),
                Vec3::new(0.0, 0.0, 3.0)
            ]
        );
        assert!(triangles(&bytes, 1)
            .unwrap_err()
            .contains("more than 1 triangles"));
        let bad = file(&[[0.0; 3]], &[[0, 1, 2]]);
        assert!(triangles(&bad, 100).unwrap_err().contains("vertex 1 of 1"));
        for cut in 1..bytes.len() {
            // Cut anywhere: an error or fewer triangles, never a panic.
            let _ = triangles(&bytes[..cut], 100);
        }
        assert!(triangles(b"PK\x03\x04xxxxxx", 100)
            .unwrap_err()
            .contains("not a 3DS"));
    }
}
