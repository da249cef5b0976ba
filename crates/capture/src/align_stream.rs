//! Aligning a motion's frame files into an aligned-motion artifact a few frames at a time, so
//! that a motion of any length is aligned holding a bounded number of frames: each block of
//! frames is read, checked and aligned (in parallel), and its aligned frames are appended to the
//! artifact's payload in a temporary file, which is renamed onto the output once the motion is
//! complete ([`mesh_core::artifact::write_artifact_streamed`]). The file is that of
//! [`crate::align::align_motion_on`] on the whole motion saved with [`Artifact::save`], byte for
//! byte: a frame's alignment depends on no other frame, and the payload's length is known
//! before its first byte (every frame has the template's vertex count, and every coordinate is
//! a fixed-width `f64`).
//!
//! What is held besides the block: the template, each frame's pose (a few hundred bytes a
//! frame, needed for the displacements written after the frames).

use std::path::PathBuf;

use mesh_core::artifact::{encoded_len, encoded_seq_len, write_artifact_streamed, Artifact, Header};
use mesh_core::io::{read_first_frame, read_mesh_like};
use mesh_core::rigid::RigidMotion;
use mesh_core::sequence::check_like_first;
use mesh_core::{Error, Result, TriMesh};
use nalgebra::Vector3;
use rayon::prelude::*;

use crate::align::{align_frame, check_anchor, check_topology, displacements, AlignedMotion, CaptureInfo};

/// Frames read and aligned at a time per thread: enough to keep every thread busy.
const FRAMES_PER_THREAD: usize = 2;

/// A motion's frame files, in order, to be aligned to `template` on the `anchor` vertices
/// ([`crate::align::anchor_vertices`]; empty: every vertex).
pub struct FrameFiles<'a> {
    pub template: &'a TriMesh,
    pub anchor: &'a [u32],
    pub files: &'a [PathBuf],
    /// Frames read and aligned at a time (at least 1); [`FrameFiles::new`] takes two per thread.
    pub block: usize,
}

impl<'a> FrameFiles<'a> {
    pub fn new(template: &'a TriMesh, anchor: &'a [u32], files: &'a [PathBuf]) -> Self {
        let block = FRAMES_PER_THREAD * rayon::current_num_threads().max(1);
        FrameFiles { template, anchor, files, block }
    }

    /// Aligns every frame and writes the aligned motion, with `capture` and `header`, to `out`.
    /// The first problem in frame order is the error (an unreadable frame names its file, a
    /// frame 0 of another topology than the template is "not the same topology", a later frame
    /// unlike frame 0 names its file), and then nothing is left at `out`.
    pub fn align_into(&self, capture: &CaptureInfo, header: &Header, out: &std::path::Path) -> Result<()> {
        check_anchor(self.template, self.anchor)?;
        let Some(first_path) = self.files.first() else {
            return Err(Error::invalid("motion has no frames"));
        };
        let n_frames = self.files.len();
        let faces = &self.template.faces;
        // Sizes of the fields of `AlignedMotion`, in its order (see `motion_stream::FIELDS`).
        let pose_len = encoded_len(&RigidMotion::identity())?;
        let frame_len = encoded_len(&self.template.vertices)?;
        let per_frame_seq = |element_len: u64| encoded_seq_len(n_frames) + n_frames as u64 * element_len;
        let payload_len = encoded_len(faces)?
            + per_frame_seq(frame_len)
            + per_frame_seq(pose_len)
            + per_frame_seq(encoded_len(&[0.0f64; 6])?)
            + encoded_len(self.anchor)?
            + encoded_len(capture)?;
        // Frame 0 first: its topology must be the template's, and the later frames are read
        // like it.
        let first = read_first_frame(first_path)?;
        check_topology(self.template, first.mesh().n_vertices(), &first.mesh().faces)?;
        let bar = mesh_core::cli::stage_progress(n_frames as u64, "frames aligned");
        let written = write_artifact_streamed(out, AlignedMotion::KIND, AlignedMotion::VERSION, header, payload_len, |w| {
            w.encode(faces)?;
            w.seq_len(n_frames)?;
            let mut poses: Vec<RigidMotion> = Vec::with_capacity(n_frames);
            for (b, block) in self.files.chunks(self.block.max(1)).enumerate() {
                let aligned: Vec<Result<(RigidMotion, Vec<Vector3<f64>>)>> = block
                    .par_iter()
                    .enumerate()
                    .map(|(i, path)| {
                        let read;
                        let mesh = if b == 0 && i == 0 {
                            first.mesh()
                        } else {
                            read = read_mesh_like(path, &first)?;
                            check_like_first(first_path, self.template.n_vertices(), faces, path, &read)?;
                            &read
                        };
                        let a = align_frame(self.template, &mesh.vertices, self.anchor);
                        bar.inc(1);
                        Ok(a)
                    })
                    .collect();
                for a in aligned {
                    let (pose, frame) = a?;
                    w.encode(&frame)?;
                    poses.push(pose);
                }
            }
            w.encode(&poses)?;
            w.encode(&displacements(self.template, self.anchor, &poses))?;
            w.encode(self.anchor)?;
            w.encode(capture)
        });
        bar.finish_and_clear();
        written
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::align::align_motion_on;
    use mesh_core::artifact::InputRecord;
    use mesh_core::io::write_ply;
    use mesh_core::shapes::cylinder;
    use std::path::Path;

    /// A bending, turning, travelling cylinder of `n` frames written as `dir/000000.ply`, ...
    fn motion_files(dir: &Path, n: usize) -> (TriMesh, Vec<PathBuf>) {
        let t = cylinder(6, 9, 0.1, 1.0);
        let files = (0..n)
            .map(|i| {
                let a = i as f64 * 0.3;
                let (s, c) = a.sin_cos();
                let v: Vec<Vector3<f64>> = t
                    .vertices
                    .iter()
                    .map(|p| {
                        let bent = Vector3::new(p.x + 0.2 * s * p.y * p.y, p.y, p.z);
                        Vector3::new(c * bent.x + s * bent.z + 0.1 * a, bent.y, -s * bent.x + c * bent.z)
                    })
                    .collect();
                let path = dir.join(format!("{i:06}.ply"));
                write_ply(&path, &TriMesh::new(v, t.faces.clone())).unwrap();
                path
            })
            .collect();
        (t, files)
    }

    fn header() -> Header {
        Header { inputs: vec![InputRecord { path: "x".into(), sha256: "y".into() }], ..Header::new("align", "0") }
    }

    fn capture() -> CaptureInfo {
        CaptureInfo { fps: 25.0, up: [0.0, 0.0, 1.0], template_sha256: "ab".repeat(32) }
    }

    /// The streamed file is the in-memory alignment saved, byte for byte, whatever the block
    /// size and on every vertex or on some.
    #[test]
    fn streamed_file_is_the_saved_in_memory_alignment() {
        let dir = tempfile::tempdir().unwrap();
        let (t, files) = motion_files(dir.path(), 11);
        let read = mesh_core::sequence::MeshSequence::load_files(&files).unwrap();
        for anchor in [vec![], vec![0, 3, 7, 20, 33]] {
            let mut held = align_motion_on(&t, &read, &anchor).unwrap();
            held.capture = capture();
            let want = dir.path().join("held.aligned");
            held.save(&want, &header()).unwrap();
            let want = std::fs::read(&want).unwrap();
            for block in [1, 2, 4, 11, 64] {
                let out = dir.path().join(format!("streamed-{block}.aligned"));
                FrameFiles { template: &t, anchor: &anchor, files: &files, block }
                    .align_into(&capture(), &header(), &out)
                    .unwrap();
                assert!(std::fs::read(&out).unwrap() == want, "block {block}, anchor {anchor:?}: bytes differ");
            }
        }
    }

    /// A frame cut short in the middle of the motion fails naming that frame, and leaves neither
    /// the output nor a temporary file; so does a later frame of another topology.
    #[test]
    fn a_bad_frame_mid_stream_leaves_no_output() {
        let dir = tempfile::tempdir().unwrap();
        let frames = dir.path().join("frames");
        std::fs::create_dir(&frames).unwrap();
        let (t, files) = motion_files(&frames, 12);
        let out_dir = dir.path().join("out");
        std::fs::create_dir(&out_dir).unwrap();
        let out = out_dir.join("m.aligned");
        let bytes = std::fs::read(&files[7]).unwrap();
        std::fs::write(&files[7], &bytes[..bytes.len() - 40]).unwrap();
        let err = FrameFiles { template: &t, anchor: &[], files: &files, block: 3 }
            .align_into(&capture(), &header(), &out)
            .unwrap_err()
            .to_string();
        assert!(err.contains("000007.ply"), "{err}");
        assert_eq!(std::fs::read_dir(&out_dir).unwrap().count(), 0, "output or temporary left behind");

        std::fs::write(&files[7], &bytes).unwrap();
        let other = cylinder(5, 9, 0.1, 1.0);
        write_ply(&files[9], &other).unwrap();
        let err = FrameFiles { template: &t, anchor: &[], files: &files, block: 3 }
            .align_into(&capture(), &header(), &out)
            .unwrap_err()
            .to_string();
        assert!(err.contains("000009.ply") && err.contains("first frame (000000.ply)"), "{err}");
        assert_eq!(std::fs::read_dir(&out_dir).unwrap().count(), 0, "output or temporary left behind");

        let err = FrameFiles { template: &other, anchor: &[], files: &files[..3], block: 3 }
            .align_into(&capture(), &header(), &out)
            .unwrap_err()
            .to_string();
        assert!(err.contains("not the same topology"), "{err}");
        assert!(!out.exists());
    }
}
