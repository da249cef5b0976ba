//! Folders of binary PLY frames, `<dir>/NNNNNN.ply` plus the frame-rate sidecar
//! ([`crate::sequence::RATE_FILE`]): byte for byte what [`super::ply::encode_ply`] writes per
//! frame (binary little-endian, `double x y z`, `list uchar int vertex_indices`), at the cost of
//! the vertex bytes alone.
//!
//! Every frame of a body shares its header and its face block, so both are encoded once
//! ([`PlyFrames::new`]); a frame is then its header, `24 · V` coordinate bytes and the shared
//! face bytes, written with two `write` calls and no copy of the faces. The folder is replaced
//! atomically ([`crate::atomic::write_dir_atomic`]: filled under a temporary sibling name,
//! then renamed), so its frames need no temporary names of their own; each frame's data is
//! flushed to disk (`fsync`) before the rename, as `write_atomic` does for single files. The
//! frames of one folder are written one after another: callers that write several folders
//! write them in parallel.

use std::io::Write;
use std::path::Path;

use nalgebra::Vector3;

use crate::error::{Error, Result};
use crate::sequence::RATE_FILE;

/// The shared part of every frame of one body (header and faces).
pub struct PlyFrames {
    n_vertices: usize,
    header: Vec<u8>,
    faces: Vec<u8>,
}

impl PlyFrames {
    /// Encodes the header and the face block of a body of `n_vertices` vertices.
    pub fn new(n_vertices: usize, faces: &[[u32; 3]]) -> PlyFrames {
        let header = format!(
            "ply\nformat binary_little_endian 1.0\ncomment surfcap\nelement vertex {n_vertices}\n\
             property double x\nproperty double y\nproperty double z\nelement face {}\n\
             property list uchar int vertex_indices\nend_header\n",
            faces.len()
        )
        .into_bytes();
        let mut bytes = Vec::with_capacity(13 * faces.len());
        for f in faces {
            bytes.push(3);
            for &i in f {
                bytes.extend_from_slice(&(i as i32).to_le_bytes());
            }
        }
        PlyFrames {
            n_vertices,
            header,
            faces: bytes,
        }
    }

    /// Vertices of the body.
    pub fn n_vertices(&self) -> usize {
        self.n_vertices
    }

    /// Bytes of one frame file.
    pub fn frame_len(&self) -> usize {
        self.header.len() + 24 * self.n_vertices + self.faces.len()
    }

    /// Header and coordinates of `frame` into `buf` (cleared first); the frame file is `buf`
    /// followed by the face bytes.
    fn encode_head(&self, frame: &[Vector3<f64>], buf: &mut Vec<u8>) {
        buf.clear();
        buf.reserve(self.header.len() + 24 * frame.len());
        buf.extend_from_slice(&self.header);
        for p in frame {
            for c in [p.x, p.y, p.z] {
                buf.extend_from_slice(&c.to_le_bytes());
            }
        }
    }

    /// The whole file of `frame`, as one buffer (for tests and small writers).
    pub fn encode(&self, frame: &[Vector3<f64>]) -> Vec<u8> {
        let mut buf = Vec::new();
        self.encode_head(frame, &mut buf);
        buf.extend_from_slice(&self.faces);
        buf
    }

    /// Writes `frames` as the folder `dir` (replaced atomically; other files of an existing
    /// folder kept, its frame files and rate file not), with `fps` in the rate sidecar. Every
    /// frame must have the body's vertex count.
    pub fn write_dir(&self, dir: &Path, frames: &[Vec<Vector3<f64>>], fps: Option<f64>) -> Result<()> {
        self.write_dir_counting(dir, frames, fps, &|| ())
    }

    /// [`PlyFrames::write_dir`], calling `on_frame` after each frame is written (a progress bar).
    pub fn write_dir_counting(
        &self,
        dir: &Path,
        frames: &[Vec<Vector3<f64>>],
        fps: Option<f64>,
        on_frame: &dyn Fn(),
    ) -> Result<()> {
        if let Some(f) = frames.iter().find(|f| f.len() != self.n_vertices) {
            return Err(self.wrong_size(dir, f.len()));
        }
        self.write_dir_streamed(dir, fps, |push| {
            frames.iter().try_for_each(|f| {
                push(f)?;
                on_frame();
                Ok(())
            })
        })
    }

    /// Writes the folder `dir` as [`PlyFrames::write_dir`] does, from frames made one at a
    /// time: `frames` hands each frame in order to the function it is given, so a sequence of
    /// any length is written holding one frame. Files are written first and flushed once all
    /// are written (each reopened for it: a long sequence holds no open file per frame). If
    /// `frames` or a write fails, `dir` is left as it was.
    pub fn write_dir_streamed<F>(&self, dir: &Path, fps: Option<f64>, frames: F) -> Result<()>
    where
        F: FnOnce(&mut dyn FnMut(&[Vector3<f64>]) -> Result<()>) -> Result<()>,
    {
        if let Some(fps) = fps {
            crate::frame_rate::check_fps(fps).map_err(|e| Error::invalid(format!("{}: {e}", dir.display())))?;
        }
        let keep = |p: &Path| crate::sequence::frame_number(p).is_none() && !crate::sequence::is_rate_file(p);
        crate::atomic::write_dir_atomic(dir, &keep, |tmp| {
            let mut buf = Vec::new();
            let mut paths = Vec::new();
            frames(&mut |frame: &[Vector3<f64>]| {
                if frame.len() != self.n_vertices {
                    return Err(self.wrong_size(dir, frame.len()));
                }
                let path = tmp.join(format!("{:06}.ply", paths.len()));
                self.encode_head(frame, &mut buf);
                let mut file = std::fs::File::create(&path).map_err(|e| Error::io(&path, e))?;
                file.write_all(&buf)
                    .and_then(|()| file.write_all(&self.faces))
                    .map_err(|e| Error::io(&path, e))?;
                paths.push(path);
                Ok(())
            })?;
            // Written first, flushed after: the disk sees the whole folder's data at once.
            for path in &paths {
                std::fs::File::open(path).and_then(|f| f.sync_all()).map_err(|e| Error::io(path, e))?;
            }
            if let Some(fps) = fps {
                let path = tmp.join(RATE_FILE);
                let text = serde_json::json!({ "fps": fps }).to_string() + "\n";
                std::fs::write(&path, text).map_err(|e| Error::io(&path, e))?;
            }
            Ok(())
        })
    }

    fn wrong_size(&self, dir: &Path, n: usize) -> Error {
        Error::invalid(format!("{}: a frame of {n} vertices, the body has {}", dir.display(), self.n_vertices))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::ply::{encode_ply, PlyOptions};
    use crate::mesh::TriMesh;
    use crate::sequence::MeshSequence;

    fn body() -> (Vec<Vec<Vector3<f64>>>, Vec<[u32; 3]>) {
        let m = crate::shapes::icosphere(2);
        let frames = (0..3)
            .map(|t| {
                m.vertices
                    .iter()
                    .map(|p| p * (1.0 + 0.1 * t as f64) + Vector3::new(0.3, -1.7e-9, t as f64))
                    .collect()
            })
            .collect();
        (frames, m.faces)
    }

    #[test]
    fn frames_are_the_bytes_the_single_mesh_ply_writer_writes() {
        let (frames, faces) = body();
        let w = PlyFrames::new(frames[0].len(), &faces);
        for f in &frames {
            let mut want = Vec::new();
            encode_ply(&mut want, &TriMesh::new(f.clone(), faces.clone()), PlyOptions::default()).unwrap();
            assert_eq!(w.encode(f), want);
            assert_eq!(w.frame_len(), want.len());
        }
        let dir = tempfile::tempdir().unwrap();
        let a = dir.path().join("a");
        w.write_dir(&a, &frames, Some(25.0)).unwrap();
        for (i, f) in frames.iter().enumerate() {
            let mut want = Vec::new();
            encode_ply(&mut want, &TriMesh::new(f.clone(), faces.clone()), PlyOptions::default()).unwrap();
            assert_eq!(std::fs::read(a.join(format!("{i:06}.ply"))).unwrap(), want);
        }
        assert_eq!(crate::sequence::read_rate(&a).unwrap(), Some(25.0));
        let back = MeshSequence::load_dir(&a).unwrap();
        assert_eq!(back.frames, frames);
    }

    #[test]
    fn rewriting_a_folder_drops_old_frames_and_keeps_other_files() {
        let (frames, faces) = body();
        let w = PlyFrames::new(frames[0].len(), &faces);
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("v");
        w.write_dir(&out, &frames, Some(25.0)).unwrap();
        std::fs::write(out.join("notes.txt"), "mine").unwrap();
        w.write_dir(&out, &frames[..1], None).unwrap();
        let mut names: Vec<String> = std::fs::read_dir(&out)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        assert_eq!(names, ["000000.ply", "notes.txt"]);
        let err = w.write_dir(&out, &[frames[0][..5].to_vec()], None).unwrap_err().to_string();
        assert!(err.contains("5 vertices"), "{err}");
        assert!(out.join("000000.ply").exists(), "a failed write leaves the folder");
    }
}
