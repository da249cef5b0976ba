//! `align`: rigid alignment of every frame of a motion to the subject's
//! template, and the per-frame rigid displacement (transfer paper §4,
//! "Rigid Transformation").
//!
//! For frame `i` with vertices `V_i`, orthogonal Procrustes gives the pose
//! `P_i = (R_i, t_i)` minimising `Σ |R_i T + t_i - V_i|²` over the template
//! `T`. The aligned frame is `P_i⁻¹ V_i` (the body brought back to the
//! template's position and heading). The displacement of frame `i` is the
//! motion from the previous pose expressed in the previous frame's body
//! coordinates, `D_i = P_{i-1}⁻¹ P_i`, so it does not depend on heading; it is
//! stored as the 6-vector `(t_x, t_y, t_z, h_1, h_2, h_3)` with `h = log R`.
//! `D_0` is the identity: every motion starts where its first frame stands,
//! and `P_0` records where that is.

use mesh_core::artifact::Artifact;
use mesh_core::rigid::{procrustes, relative_in_body_frame, RigidMotion};
use mesh_core::sequence::MeshSequence;
use mesh_core::{Error, Result, TriMesh};
use nalgebra::{Vector3, Vector6};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// A motion after alignment: the aligned frames, each frame's world pose and
/// its displacement from the previous frame.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct AlignedMotion {
    /// Faces shared by every frame (the subject's topology).
    pub faces: Vec<[u32; 3]>,
    /// Aligned vertex positions, one vector per frame.
    pub frames: Vec<Vec<Vector3<f64>>>,
    /// World pose `P_i` of each frame: `world = P_i(aligned)`.
    pub poses: Vec<RigidMotion>,
    /// Displacements `D_i = P_{i-1}⁻¹ P_i` as 6-vectors (`D_0 = 0`).
    pub displacements: Vec<[f64; 6]>,
}

impl Artifact for AlignedMotion {
    const KIND: &'static str = "aligned-motion";
    const VERSION: u32 = 1;
}

impl AlignedMotion {
    pub fn n_frames(&self) -> usize {
        self.frames.len()
    }

    /// The frames back in world coordinates (inverse of alignment).
    pub fn world_frames(&self) -> Vec<Vec<Vector3<f64>>> {
        self.frames.iter().zip(&self.poses).map(|(f, p)| p.apply_all(f)).collect()
    }
}

/// Aligns every frame of `motion` to `template` (same topology required).
pub fn align_motion(template: &TriMesh, motion: &MeshSequence) -> Result<AlignedMotion> {
    if motion.n_vertices() != template.n_vertices() || motion.faces != template.faces {
        return Err(Error::invalid(format!(
            "motion has {} vertices and {} faces but the template has {} and {}: not the same topology",
            motion.n_vertices(),
            motion.n_faces(),
            template.n_vertices(),
            template.n_faces()
        )));
    }
    if motion.n_frames() == 0 {
        return Err(Error::invalid("motion has no frames"));
    }
    let poses: Vec<RigidMotion> = motion
        .frames
        .par_iter()
        .map(|frame| procrustes(&template.vertices, frame, None))
        .collect();
    let frames: Vec<Vec<Vector3<f64>>> = motion
        .frames
        .par_iter()
        .zip(&poses)
        .map(|(frame, pose)| pose.inverse().apply_all(frame))
        .collect();
    let mut displacements = vec![[0.0; 6]];
    for w in poses.windows(2) {
        let d: Vector6<f64> = relative_in_body_frame(&w[0], &w[1]).to_6vec();
        displacements.push(d.into());
    }
    Ok(AlignedMotion { faces: motion.faces.clone(), frames, poses, displacements })
}

#[cfg(test)]
mod tests {
    use super::*;
    use mesh_core::rigid::{integrate, so3_exp};
    use mesh_core::shapes;

    /// A rigidly moving, slightly bending cylinder: alignment must bring every
    /// frame back onto the template and the displacements must integrate back
    /// to the true poses.
    #[test]
    fn recovers_known_poses_and_displacements() {
        let template = shapes::cylinder(12, 16, 0.1, 1.0);
        let mut truth = Vec::new();
        let mut frames = Vec::new();
        for i in 0..8 {
            let s = i as f64;
            let pose = RigidMotion::new(
                so3_exp(&Vector3::new(0.05 * s, 0.3 * s, -0.02 * s)),
                Vector3::new(0.1 * s, 0.01 * s * s, -0.2 * s),
            );
            frames.push(pose.apply_all(&template.vertices));
            truth.push(pose);
        }
        let seq = MeshSequence::new(template.faces.clone(), frames);
        let aligned = align_motion(&template, &seq).unwrap();
        for f in &aligned.frames {
            for (a, b) in f.iter().zip(&template.vertices) {
                assert!((a - b).norm() < 1e-9);
            }
        }
        let steps: Vec<RigidMotion> = aligned.displacements[1..]
            .iter()
            .map(|d| RigidMotion::from_6vec(&Vector6::from_column_slice(d)))
            .collect();
        let integrated = integrate(&aligned.poses[0], &steps);
        for (a, b) in integrated.iter().zip(&truth) {
            assert!((a.translation - b.translation).norm() < 1e-9);
            assert!((a.rotation.matrix() - b.rotation.matrix()).norm() < 1e-9);
        }
        // A pure heading change applied to the whole motion leaves the
        // displacements unchanged (they are expressed in body coordinates).
        let heading = RigidMotion::new(so3_exp(&Vector3::new(0.0, 1.2, 0.0)), Vector3::new(3.0, 0.0, 1.0));
        let turned = MeshSequence::new(
            template.faces.clone(),
            seq.frames.iter().map(|f| heading.apply_all(f)).collect(),
        );
        let aligned2 = align_motion(&template, &turned).unwrap();
        for (a, b) in aligned.displacements.iter().zip(&aligned2.displacements) {
            for k in 0..6 {
                assert!((a[k] - b[k]).abs() < 1e-9, "{a:?} vs {b:?}");
            }
        }
    }

    #[test]
    fn rejects_other_topology() {
        let template = shapes::cylinder(12, 16, 0.1, 1.0);
        let other = shapes::cylinder(10, 16, 0.1, 1.0);
        let seq = MeshSequence::new(other.faces.clone(), vec![other.vertices.clone()]);
        let err = align_motion(&template, &seq).unwrap_err().to_string();
        assert!(err.contains("not the same topology"), "{err}");
    }
}
