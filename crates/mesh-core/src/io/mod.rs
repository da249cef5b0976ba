//! Mesh file input and output: PLY ([`ply`]) and OBJ ([`obj`]); folders of binary PLY frames
//! ([`ply_frames`]); the PC2 point cache beside a template OBJ ([`pc2`]); Alembic mesh caches
//! ([`alembic`], on the Ogawa container [`ogawa`]).
//!
//! [`read_mesh`] and [`write_mesh`] pick the format from the file extension
//! (`.ply` or `.obj`, case-insensitive). Reading validates the mesh (finite
//! coordinates, face indices in range); every error is one line naming the
//! file. Writing is atomic (temporary file, then rename).
//!
//! Tolerated as MeshLab tolerates them, because the geometry is unambiguous:
//! a degenerate face (fewer than 3 corners, or a triangle of its fan that
//! repeats a vertex) is skipped, with one warning per file giving the count.
//! Everything whose meaning is ambiguous stays an error (OBJ index 0, a
//! malformed number such as `3.1+e2`, an index out of range).

pub mod alembic;
pub mod alembic_xform;
pub mod obj;
pub mod ogawa;
pub mod pc2;
pub mod ply;
pub mod ply_frames;

use std::path::Path;

pub use obj::{read_obj, write_obj};
pub use ply::{
    read_ply, write_ply, write_ply_ascii, write_ply_with, PlyEncoding, PlyOptions, PlyPrecision,
};

use crate::error::{Error, Result};
use crate::mesh::TriMesh;

/// Appends polygon `poly` (vertex indices) fan-triangulated to `faces`:
/// `(p0, p1, p2), (p0, p2, p3), ...`, leaving out every triangle that repeats
/// a vertex (and the whole polygon if it has fewer than 3 corners). Returns 1
/// if anything was left out (one degenerate face), else 0.
pub fn push_fan(faces: &mut Vec<[u32; 3]>, poly: &[u32]) -> usize {
    if poly.len() < 3 {
        return 1;
    }
    let mut skipped = 0;
    for j in 1..poly.len() - 1 {
        let t = [poly[0], poly[j], poly[j + 1]];
        if t[0] == t[1] || t[1] == t[2] || t[0] == t[2] {
            skipped = 1;
        } else {
            faces.push(t);
        }
    }
    skipped
}

/// The one warning per file a reader gives for skipped degenerate faces.
fn warn_skipped_faces(path: &Path, skipped: usize) {
    if skipped > 0 {
        crate::warn!(
            "{}: skipped {skipped} degenerate face(s) (fewer than 3 distinct corners)",
            path.display()
        );
    }
}

/// Mesh file formats known by extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MeshFormat {
    Ply,
    Obj,
}

impl MeshFormat {
    /// The format named by `path`'s extension, if any.
    pub fn from_path(path: &Path) -> Option<Self> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        match ext.as_str() {
            "ply" => Some(MeshFormat::Ply),
            "obj" => Some(MeshFormat::Obj),
            _ => None,
        }
    }
}

fn format_of(path: &Path) -> Result<MeshFormat> {
    MeshFormat::from_path(path).ok_or_else(|| {
        Error::file(
            path,
            "unsupported mesh format (expected a .ply or .obj file)",
        )
    })
}

/// Reads a PLY or OBJ mesh, dispatching on the extension.
pub fn read_mesh(path: impl AsRef<Path>) -> Result<TriMesh> {
    let path = path.as_ref();
    match format_of(path)? {
        MeshFormat::Ply => read_ply(path),
        MeshFormat::Obj => read_obj(path),
    }
}

/// A sequence's first frame, read by [`read_first_frame`]; its later frames are read with
/// [`read_mesh_like`].
pub enum FirstFrame {
    Ply(ply::PlyFirstFrame),
    Obj(TriMesh),
}

impl FirstFrame {
    pub fn mesh(&self) -> &TriMesh {
        match self {
            FirstFrame::Ply(f) => &f.mesh,
            FirstFrame::Obj(m) => m,
        }
    }

    pub fn into_mesh(self) -> TriMesh {
        match self {
            FirstFrame::Ply(f) => f.mesh,
            FirstFrame::Obj(m) => m,
        }
    }
}

/// Reads a sequence's first frame as [`read_mesh`] does.
pub fn read_first_frame(path: impl AsRef<Path>) -> Result<FirstFrame> {
    let path = path.as_ref();
    match format_of(path)? {
        MeshFormat::Ply => ply::read_ply_first(path).map(FirstFrame::Ply),
        MeshFormat::Obj => read_obj(path).map(FirstFrame::Obj),
    }
}

/// Reads a later frame of the sequence that starts with `first`, as [`read_mesh`] does (the
/// same mesh); a binary PLY frame with the first's header and face bytes takes its faces
/// without parsing them again ([`ply::read_ply_like`]).
pub fn read_mesh_like(path: impl AsRef<Path>, first: &FirstFrame) -> Result<TriMesh> {
    let path = path.as_ref();
    match (format_of(path)?, first) {
        (MeshFormat::Ply, FirstFrame::Ply(f)) => ply::read_ply_like(path, f),
        _ => read_mesh(path),
    }
}

/// Writes a mesh as binary PLY or OBJ, dispatching on the extension.
pub fn write_mesh(path: impl AsRef<Path>, mesh: &TriMesh) -> Result<()> {
    let path = path.as_ref();
    match format_of(path)? {
        MeshFormat::Ply => write_ply(path, mesh),
        MeshFormat::Obj => write_obj(path, mesh),
    }
}
