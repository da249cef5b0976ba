//! Wavefront OBJ input and output (positions and faces only).
//!
//! Reading keeps the file's vertex numbering: vertex `i` of the mesh is the
//! `i`-th `v` line, whether or not a face uses it, and faces of all objects
//! and groups are merged (OBJ indices are global). Faces may be polygons,
//! with `v`, `v/vt`, `v//vn` or `v/vt/vn` corners and negative (relative)
//! indices; they are fan-triangulated like PLY polygons. Every other
//! statement (normals, texture coordinates, materials, groups, lines) is
//! ignored.
//!
//! Deviation from the brief (which named tobj): tobj 4.0.5 renumbers vertices
//! in order of first use by a face and drops unused ones (`add_vertex` in its
//! `lib.rs`), which would break the vertex correspondence that sequences and
//! the capture-set curves rely on. The format subset needed here is small
//! enough to read directly.

use std::fmt::Write as _;
use std::io::Write;
use std::path::Path;

use nalgebra::Vector3;

use crate::atomic::write_atomic;
use crate::error::{Error, Result};
use crate::mesh::TriMesh;

/// Reads and validates an OBJ mesh; errors are one line naming the file.
pub fn read_obj(path: impl AsRef<Path>) -> Result<TriMesh> {
    let path = path.as_ref();
    let bytes = crate::input::read_regular_file(path)?;
    parse_obj(&bytes).map_err(|msg| Error::file(path, msg))
}

/// Parses OBJ text held in memory; the mesh is validated.
pub fn parse_obj(bytes: &[u8]) -> std::result::Result<TriMesh, String> {
    let text = std::str::from_utf8(bytes).map_err(|e| format!("not a text OBJ file ({e})"))?;
    let mut vertices = Vec::new();
    let mut faces = Vec::new();
    let mut poly: Vec<u32> = Vec::with_capacity(8);
    for (ln, line) in text.lines().enumerate() {
        let ln = ln + 1;
        let mut tok = line.split_whitespace();
        match tok.next() {
            Some("v") => {
                let mut xyz = [0.0; 3];
                for c in &mut xyz {
                    let t = tok
                        .next()
                        .ok_or_else(|| format!("line {ln}: vertex needs 3 coordinates"))?;
                    *c = t
                        .parse()
                        .map_err(|_| format!("line {ln}: bad coordinate '{t}'"))?;
                }
                vertices.push(Vector3::new(xyz[0], xyz[1], xyz[2]));
            }
            Some("f") => {
                poly.clear();
                for t in tok {
                    let first = t.split('/').next().unwrap_or_default();
                    let i: i64 = first
                        .parse()
                        .map_err(|_| format!("line {ln}: bad face index '{t}'"))?;
                    let n = vertices.len() as i64;
                    let idx = match i {
                        0 => {
                            return Err(format!("line {ln}: face index 0 (OBJ indices start at 1)"))
                        }
                        i if i > 0 => i - 1,
                        i => n + i,
                    };
                    if idx < 0 || idx > u32::MAX as i64 {
                        return Err(format!("line {ln}: face index {i} out of range"));
                    }
                    poly.push(idx as u32);
                }
                if poly.len() < 3 {
                    return Err(format!(
                        "line {ln}: face has {} vertices; at least 3 are needed",
                        poly.len()
                    ));
                }
                for j in 1..poly.len() - 1 {
                    faces.push([poly[0], poly[j], poly[j + 1]]);
                }
            }
            _ => {}
        }
    }
    let mesh = TriMesh { vertices, faces };
    mesh.validate().map_err(|e| e.to_string())?;
    Ok(mesh)
}

/// Writes `mesh` as OBJ (`v x y z` printed to round-trip exactly, 1-based
/// `f a b c`), atomically.
pub fn write_obj(path: impl AsRef<Path>, mesh: &TriMesh) -> Result<()> {
    write_atomic(path.as_ref(), |w| encode_obj(w, mesh))
}

/// Serialises `mesh` as OBJ into `w`.
pub fn encode_obj(w: &mut dyn Write, mesh: &TriMesh) -> std::io::Result<()> {
    let mut s = String::with_capacity(mesh.vertices.len() * 40 + mesh.faces.len() * 20);
    for v in &mesh.vertices {
        let _ = writeln!(s, "v {} {} {}", v.x, v.y, v.z);
    }
    for f in &mesh.faces {
        let _ = writeln!(s, "f {} {} {}", f[0] + 1, f[1] + 1, f[2] + 1);
    }
    w.write_all(s.as_bytes())
}
