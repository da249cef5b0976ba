//! Mesh-or-sequence paths for the stage binaries: a path is either one mesh file
//! (`.ply`/`.obj`) or a directory of frames (`000000.ply`, `000001.ply`, ...), read and
//! written with `mesh_core::io` / `mesh_core::sequence` (atomic writes).

use crate::{Error, Result};
use mesh_core::io::{read_mesh, write_mesh};
use mesh_core::sequence::MeshSequence;
use mesh_core::TriMesh;
use nalgebra::Vector3;
use std::path::Path;

/// Frames sharing one topology, and whether they came from a directory.
#[derive(Clone, Debug)]
pub struct Frames {
    pub faces: Vec<[u32; 3]>,
    pub frames: Vec<Vec<Vector3<f64>>>,
    pub is_dir: bool,
}

/// Reads one mesh file (one frame) or a frame directory.
pub fn read_frames(path: &Path) -> Result<Frames> {
    if path.is_dir() {
        let s = MeshSequence::load_dir(path)?;
        Ok(Frames {
            faces: s.faces,
            frames: s.frames,
            is_dir: true,
        })
    } else {
        let m = read_mesh(path)?;
        Ok(Frames {
            faces: m.faces,
            frames: vec![m.vertices],
            is_dir: false,
        })
    }
}

/// Writes a frame directory (`as_dir`) or a single mesh file (exactly one frame).
pub fn write_frames(
    path: &Path,
    faces: &[[u32; 3]],
    frames: Vec<Vec<Vector3<f64>>>,
    as_dir: bool,
) -> Result<()> {
    if as_dir {
        return MeshSequence::new(faces.to_vec(), frames).write_dir(path);
    }
    let [vertices]: [Vec<Vector3<f64>>; 1] = frames.try_into().map_err(|v: Vec<_>| {
        Error::file(
            path,
            format!("{} frames cannot go into one mesh file", v.len()),
        )
    })?;
    write_mesh(path, &TriMesh::new(vertices, faces.to_vec()))
}

/// Checks that two inputs share one topology; names both paths in the error.
pub fn check_same_topology(a: &Frames, pa: &Path, b: &Frames, pb: &Path) -> Result<()> {
    let (na, nb) = (a.frames[0].len(), b.frames[0].len());
    if na != nb || a.faces != b.faces {
        return Err(Error::file(
            pb,
            format!(
                "topology differs from {} ({nb} vs {na} vertices, {} vs {} faces)",
                pa.display(),
                b.faces.len(),
                a.faces.len()
            ),
        ));
    }
    Ok(())
}
