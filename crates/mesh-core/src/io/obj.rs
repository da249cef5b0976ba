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
    read_obj_bytes(path, &bytes)
}

/// [`read_obj`] of the bytes of `path`, already read.
pub fn read_obj_bytes(path: &Path, bytes: &[u8]) -> Result<TriMesh> {
    let (mesh, skipped) = parse(bytes).map_err(|msg| Error::file(path, msg))?;
    super::warn_skipped_faces(path, skipped);
    Ok(mesh)
}

/// Parses OBJ text held in memory; the mesh is validated.
pub fn parse_obj(bytes: &[u8]) -> std::result::Result<TriMesh, String> {
    parse(bytes).map(|(mesh, _)| mesh)
}

/// The validated mesh and the number of degenerate faces skipped. Lines are
/// decoded as UTF-8 where they are (a Latin-1 byte in a comment or a group
/// name is harmless); a `v` or `f` line that is not text fails on its numbers.
fn parse(bytes: &[u8]) -> std::result::Result<(TriMesh, usize), String> {
    let text = String::from_utf8_lossy(bytes);
    let mut skipped = 0;
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
                        .map_err(|_| format!("line {ln}: bad coordinate '{}'", short(t)))?;
                }
                vertices.push(Vector3::new(xyz[0], xyz[1], xyz[2]));
            }
            Some("f") => {
                poly.clear();
                for t in tok {
                    let first = t.split('/').next().unwrap_or_default();
                    let i: i64 = first
                        .parse()
                        .map_err(|_| format!("line {ln}: bad face index '{}'", short(t)))?;
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
                skipped += super::push_fan(&mut faces, &poly);
            }
            _ => {}
        }
    }
    if vertices.is_empty() {
        return Err("no vertices (no 'v' lines)".into());
    }
    let mesh = TriMesh { vertices, faces };
    mesh.validate().map_err(|e| e.to_string())?;
    Ok((mesh, skipped))
}

/// A token quoted in a message, cut to 40 characters.
fn short(t: &str) -> String {
    match t.char_indices().nth(40) {
        Some((cut, _)) => format!("{}...", &t[..cut]),
        None => t.to_string(),
    }
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
