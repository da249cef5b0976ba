//! Writing variations: [`VariationFormat::Ply`] as folders of PLY frames, `<dir>/var<k>/NNNNNN.ply`
//! plus the frame-rate sidecar ([`mesh_core::io::ply_frames::PlyFrames`]: the header and face
//! block encoded once per body); [`VariationFormat::Pc2`] as `var<k>.obj` (its first frame, with
//! the faces) plus `var<k>.pc2` (every frame, float32: docs/FORMATS.md), the pair written by
//! [`mesh_core::io::pc2`]: a quarter of the PLY folder's bytes, in the form Blender's Mesh Cache
//! modifier and 3ds Max read. The frames of one folder are written one after another: callers
//! write several variations in parallel.

use std::path::Path;

use mesh_core::io::ply_frames::PlyFrames;
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
                if frames.is_empty() {
                    return Err(Error::invalid(format!("{}: variation {k} has no frames", dir.display())));
                }
                if let Some(f) = frames.iter().find(|f| f.len() != self.ply.n_vertices()) {
                    return Err(Error::invalid(format!(
                        "{}: a frame of {} vertices, the body has {}",
                        dir.display(),
                        f.len(),
                        self.ply.n_vertices()
                    )));
                }
                let (obj, pc2) = (dir.join(format!("var{k}.obj")), dir.join(format!("var{k}.pc2")));
                mesh_core::io::pc2::write_pair(&obj, &pc2, &self.faces, frames)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
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

    /// PC2 output reads back through `mesh-import`'s reader as the frames rounded to float32,
    /// with the body's faces.
    #[test]
    fn pc2_variations_read_back_as_float32_frames() {
        let (frames, faces) = body();
        let w = VariationWriter::new(VariationFormat::Pc2, frames[0].len(), &faces);
        let dir = tempfile::tempdir().unwrap();
        w.write(dir.path(), 3, &frames, Some(25.0)).unwrap();
        let back = mesh_core::io::pc2::read_obj_pc2(&dir.path().join("var3.obj"), &dir.path().join("var3.pc2")).unwrap();
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
}
