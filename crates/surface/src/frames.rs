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

/// Frames of a directory read a block at a time ([`FrameBlocks::block`]), each checked against
/// the directory's first frame, so that a long sequence is never held whole.
pub struct FrameBlocks {
    files: Vec<std::path::PathBuf>,
    /// The first frame's vertex count and faces.
    pub n_vertices: usize,
    pub faces: Vec<[u32; 3]>,
}

/// Frames per block of [`FrameBlocks`]: about 32 MiB of vertices, at least one frame.
pub fn frames_per_block(n_vertices: usize) -> usize {
    ((32 << 20) / (24 * n_vertices.max(1))).max(1)
}

impl FrameBlocks {
    /// The frame files of `dir` (its first frame read for the topology).
    pub fn open(dir: &Path) -> Result<Self> {
        let files = mesh_core::sequence::frame_files(dir)?;
        let first = files
            .first()
            .ok_or_else(|| Error::file(dir, "no frames (000000.ply, ...) in this directory"))?;
        let m = read_mesh(first)?;
        Ok(FrameBlocks { n_vertices: m.vertices.len(), faces: m.faces, files })
    }

    pub fn n_frames(&self) -> usize {
        self.files.len()
    }

    /// Frames `range`, each checked against the first frame (the error names the file).
    pub fn block(&self, range: std::ops::Range<usize>) -> Result<Vec<Vec<Vector3<f64>>>> {
        let start = range.start;
        let s = MeshSequence::load_files(&self.files[range])?;
        if let Some(first) = s.frames.first() {
            let mesh = TriMesh::new(first.clone(), s.faces.clone());
            mesh_core::sequence::check_like_first(&self.files[0], self.n_vertices, &self.faces, &self.files[start], &mesh)?;
        }
        Ok(s.frames)
    }

    /// Every `stride`-th frame, `stride` the smallest power of two whose frames fit in `budget`
    /// bytes (1 when all fit; at least the first frame is read); returns them and the stride.
    pub fn strided_within(&self, budget: usize) -> Result<(Vec<Vec<Vector3<f64>>>, usize)> {
        let frame_bytes = 24 * self.n_vertices.max(1);
        let mut stride = 1;
        while stride < self.files.len() && self.files.len().div_ceil(stride).saturating_mul(frame_bytes) > budget {
            stride *= 2;
        }
        // Every file is checked against the first, which the stride keeps.
        let files: Vec<_> = self.files.iter().step_by(stride).cloned().collect();
        Ok((MeshSequence::load_files(&files)?.frames, stride))
    }
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

#[cfg(test)]
mod tests {
    use super::*;

    /// A directory read block by block is the directory read whole; a frame of another
    /// topology in a later block is an error naming its file.
    #[test]
    fn blocks_read_the_directory_in_order_and_check_every_frame() {
        let dir = tempfile::tempdir().unwrap();
        let faces = vec![[0, 1, 2], [0, 2, 3]];
        let frames: Vec<Vec<Vector3<f64>>> =
            (0..7).map(|i| (0..4).map(|v| Vector3::new(i as f64, v as f64, 0.5 * (i * v) as f64)).collect()).collect();
        MeshSequence::new(faces.clone(), frames.clone()).write_dir(dir.path()).unwrap();
        let blocks = FrameBlocks::open(dir.path()).unwrap();
        assert_eq!((blocks.n_frames(), blocks.n_vertices, &blocks.faces), (7, 4, &faces));
        let read: Vec<_> = [0..3, 3..6, 6..7].into_iter().flat_map(|r| blocks.block(r).unwrap()).collect();
        assert_eq!(read, frames);
        let (strided, stride) = blocks.strided_within(3 * 4 * 24).unwrap();
        assert_eq!((stride, strided), (4, vec![frames[0].clone(), frames[4].clone()]));
        write_mesh(&dir.path().join("000005.ply"), &TriMesh::new(frames[5].clone(), vec![[0, 1, 2]])).unwrap();
        let e = blocks.block(3..6).unwrap_err().to_string();
        assert!(e.contains("000005.ply") && e.contains("faces"), "{e}");
        assert!(blocks.block(0..3).is_ok());
    }
}
