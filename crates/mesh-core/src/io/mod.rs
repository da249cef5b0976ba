//! Mesh file input and output: PLY ([`ply`]) and OBJ ([`obj`]).
//!
//! [`read_mesh`] and [`write_mesh`] pick the format from the file extension
//! (`.ply` or `.obj`, case-insensitive). Reading validates the mesh (finite
//! coordinates, face indices in range, no repeated index); every error is one
//! line naming the file. Writing is atomic (temporary file, then rename).

pub mod obj;
pub mod ply;

use std::path::Path;

pub use obj::{read_obj, write_obj};
pub use ply::{
    read_ply, write_ply, write_ply_ascii, write_ply_with, PlyEncoding, PlyOptions, PlyPrecision,
};

use crate::error::{Error, Result};
use crate::mesh::TriMesh;

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

/// Writes a mesh as binary PLY or OBJ, dispatching on the extension.
pub fn write_mesh(path: impl AsRef<Path>, mesh: &TriMesh) -> Result<()> {
    let path = path.as_ref();
    match format_of(path)? {
        MeshFormat::Ply => write_ply(path, mesh),
        MeshFormat::Obj => write_obj(path, mesh),
    }
}
