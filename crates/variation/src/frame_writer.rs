//! Writing variations as folders of PLY frames, `<dir>/NNNNNN.ply` plus the frame-rate sidecar
//! (`mesh_core::sequence::RATE_FILE`): byte for byte what `MeshSequence::write_dir_at` writes
//! (`mesh_core::io::ply::encode_ply`: binary little-endian, `double x y z`, `list uchar int
//! vertex_indices`), at the cost of the vertex bytes alone.
//!
//! Every frame of a body shares its header and its face block, so both are encoded once
//! ([`PlyFrames::new`]); a frame is then its header, `24 · V` coordinate bytes and the shared
//! face bytes, written with two `write` calls and no copy of the faces. The folder is replaced
//! atomically (`mesh_core::atomic::write_dir_atomic`: filled under a temporary sibling name,
//! then renamed), so its frames need no temporary names of their own; each frame's data is
//! flushed to disk (`fsync`) before the rename, as `write_atomic` does for single files. The
//! frames of one folder are written one after another: callers write several folders in
//! parallel (one per variation).
//!
//! [`VariationFormat::Pc2`] writes a variation as `var<k>.obj` (its first frame, with the faces)
//! plus `var<k>.pc2` (every frame, float32: docs/FORMATS.md), each file atomically: a quarter
//! of the PLY folder's bytes, in the form Blender's Mesh Cache modifier and 3ds Max read.

use std::io::Write;
use std::path::Path;

use mesh_core::sequence::RATE_FILE;
use mesh_core::{Error, Result};
use nalgebra::Vector3;

/// How a variation is written.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum VariationFormat {
    /// A folder of binary PLY frames, `var<k>/NNNNNN.ply`, with its rate sidecar.
    #[default]
    Ply,
    /// `var<k>.obj` (the first frame with the faces) plus the `var<k>.pc2` point cache.
    Pc2,
}

/// Writes the variations of one body in a [`VariationFormat`].
pub struct VariationWriter {
    format: VariationFormat,
    ply: PlyFrames,
    faces: Vec<[u32; 3]>,
}

impl VariationWriter {
    pub fn new(format: VariationFormat, n_vertices: usize, faces: &[[u32; 3]]) -> VariationWriter {
        VariationWriter { format, ply: PlyFrames::new(n_vertices, faces), faces: faces.to_vec() }
    }

    /// Writes variation `k` of a sequence under `dir` (`dir/var<k>/` or `dir/var<k>.obj` +
    /// `dir/var<k>.pc2`); `fps` goes in the PLY folder's rate sidecar (PC2 has no rate field).
    pub fn write(&self, dir: &Path, k: usize, frames: &[Vec<Vector3<f64>>], fps: Option<f64>) -> Result<()> {
        match self.format {
            VariationFormat::Ply => self.ply.write_dir(&dir.join(format!("var{k}")), frames, fps),
            VariationFormat::Pc2 => {
                let Some(first) = frames.first() else {
                    return Err(Error::invalid(format!("{}: variation {k} has no frames", dir.display())));
                };
                if let Some(f) = frames.iter().find(|f| f.len() != self.ply.n_vertices) {
                    return Err(Error::invalid(format!(
                        "{}: a frame of {} vertices, the body has {}",
                        dir.display(),
                        f.len(),
                        self.ply.n_vertices
                    )));
                }
                let mesh = mesh_core::mesh::TriMesh::new(first.clone(), self.faces.clone());
                mesh_core::io::write_obj(dir.join(format!("var{k}.obj")), &mesh)?;
                export::pc2::write_pc2(dir.join(format!("var{k}.pc2")), frames)
            }
        }
    }
}

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
    /// folder kept, its frame files not), with `fps` in the rate sidecar. Every frame must
    /// have the body's vertex count.
    pub fn write_dir(&self, dir: &Path, frames: &[Vec<Vector3<f64>>], fps: Option<f64>) -> Result<()> {
        if let Some(f) = frames.iter().find(|f| f.len() != self.n_vertices) {
            return Err(Error::invalid(format!(
                "{}: a frame of {} vertices, the body has {}",
                dir.display(),
                f.len(),
                self.n_vertices
            )));
        }
        if let Some(f) = fps.filter(|f| !(f.is_finite() && *f > 0.0)) {
            return Err(Error::invalid(format!("frame rate must be a positive number, got {f}")));
        }
        let keep = |p: &Path| !is_frame_file(p) && p.file_name().is_none_or(|n| n != RATE_FILE);
        mesh_core::atomic::write_dir_atomic(dir, &keep, |tmp| {
            let mut buf = Vec::new();
            let mut files = Vec::with_capacity(frames.len());
            for (i, frame) in frames.iter().enumerate() {
                let path = tmp.join(format!("{i:06}.ply"));
                self.encode_head(frame, &mut buf);
                let mut file = std::fs::File::create(&path).map_err(|e| Error::io(&path, e))?;
                file.write_all(&buf)
                    .and_then(|()| file.write_all(&self.faces))
                    .map_err(|e| Error::io(&path, e))?;
                files.push((file, path));
            }
            // Written first, flushed after: the disk sees the whole folder's data at once.
            for (file, path) in &files {
                file.sync_all().map_err(|e| Error::io(path, e))?;
            }
            if let Some(fps) = fps {
                let path = tmp.join(RATE_FILE);
                let text = serde_json::json!({ "fps": fps }).to_string() + "\n";
                std::fs::write(&path, text).map_err(|e| Error::io(&path, e))?;
            }
            Ok(())
        })
    }
}

/// A frame file name as `MeshSequence` numbers them: digits, then `.ply` or `.obj`.
fn is_frame_file(p: &Path) -> bool {
    let ext_ok = p
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("ply") || e.eq_ignore_ascii_case("obj"));
    let stem_ok = p
        .file_stem()
        .and_then(|s| s.to_str())
        .is_some_and(|s| !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit()));
    ext_ok && stem_ok
}

#[cfg(test)]
mod tests {
    use super::*;
    use mesh_core::io::ply::{encode_ply, PlyOptions};
    use mesh_core::mesh::TriMesh;
    use mesh_core::sequence::MeshSequence;

    fn body() -> (Vec<Vec<Vector3<f64>>>, Vec<[u32; 3]>) {
        let m = mesh_core::shapes::icosphere(2);
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
    fn frames_are_the_bytes_mesh_core_writes() {
        let (frames, faces) = body();
        let w = PlyFrames::new(frames[0].len(), &faces);
        for f in &frames {
            let mut want = Vec::new();
            encode_ply(&mut want, &TriMesh::new(f.clone(), faces.clone()), PlyOptions::default()).unwrap();
            assert_eq!(w.encode(f), want);
            assert_eq!(w.frame_len(), want.len());
        }
        // Whole folders, sidecar included, equal MeshSequence's.
        let dir = tempfile::tempdir().unwrap();
        let (a, b) = (dir.path().join("a"), dir.path().join("b"));
        w.write_dir(&a, &frames, Some(25.0)).unwrap();
        MeshSequence::new(faces.clone(), frames.clone()).write_dir_at(&b, Some(25.0)).unwrap();
        let list = |d: &Path| {
            let mut v: Vec<_> = std::fs::read_dir(d)
                .unwrap()
                .map(|e| e.unwrap().file_name())
                .collect();
            v.sort();
            v
        };
        assert_eq!(list(&a), list(&b));
        for name in list(&a) {
            assert_eq!(std::fs::read(a.join(&name)).unwrap(), std::fs::read(b.join(&name)).unwrap());
        }
        let back = MeshSequence::load_dir(&a).unwrap();
        assert_eq!(back.frames, frames);
    }

    /// PC2 output reads back through `mesh-import`'s reader as the frames rounded to float32,
    /// with the body's faces.
    #[test]
    fn pc2_variations_read_back_as_float32_frames() {
        let (frames, faces) = body();
        let w = VariationWriter::new(VariationFormat::Pc2, frames[0].len(), &faces);
        let dir = tempfile::tempdir().unwrap();
        w.write(dir.path(), 3, &frames, Some(25.0)).unwrap();
        let back = export::pc2::read_obj_pc2(&dir.path().join("var3.obj"), &dir.path().join("var3.pc2")).unwrap();
        assert_eq!(back.faces, faces);
        let f32_of = |f: &Vec<Vector3<f64>>| -> Vec<Vector3<f64>> {
            f.iter().map(|p| p.map(|c| c as f32 as f64)).collect()
        };
        assert_eq!(back.frames, frames.iter().map(f32_of).collect::<Vec<_>>());
        assert!(!dir.path().join("var3").exists());
        let err = w.write(dir.path(), 0, &[], None).unwrap_err().to_string();
        assert!(err.contains("no frames"), "{err}");
        let err = w.write(dir.path(), 0, &[frames[0][..5].to_vec()], None).unwrap_err().to_string();
        assert!(err.contains("5 vertices"), "{err}");
        // The PLY format writes what PlyFrames does.
        let ply = VariationWriter::new(VariationFormat::Ply, frames[0].len(), &faces);
        ply.write(dir.path(), 1, &frames, Some(25.0)).unwrap();
        assert_eq!(MeshSequence::load_dir(dir.path().join("var1")).unwrap().frames, frames);
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
