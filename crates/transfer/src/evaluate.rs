//! `evaluate`: per-vertex RMS error of a transferred sequence against the
//! ground truth (paper §7, "Quantitative Evaluation").
//!
//! - `rms_pose_m`: each predicted frame is first rigidly aligned to its truth
//!   frame (Procrustes, no scale), so only the pose (shape) error remains;
//! - `rms_placed_m`: as placed in the world, no alignment.
//!
//! Both are `sqrt(mean over frames and vertices of |p - t|²)`, in metres.

use mesh_core::rigid::procrustes;
use mesh_core::sequence::MeshSequence;
use mesh_core::{Error, Result};
use nalgebra::Vector3;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// One line of results.json.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct EvalRecord {
    pub direction: String,
    pub motion: String,
    pub method: String,
    pub placement: String,
    /// `dense` (DTW pairs) or `keyposes` (key-pose pairs only).
    pub training: String,
    pub rms_pose_m: f64,
    pub rms_placed_m: f64,
    pub frames: usize,
}

/// Sum of squared distances between matching points.
fn sum_sq(a: &[Vector3<f64>], b: &[Vector3<f64>]) -> f64 {
    a.iter().zip(b).map(|(p, q)| (p - q).norm_squared()).sum()
}

/// `(rms_pose_m, rms_placed_m)` of `pred` against `truth` (same frame count,
/// same vertex count).
pub fn rms_errors(pred: &MeshSequence, truth: &MeshSequence) -> Result<(f64, f64)> {
    if pred.n_frames() != truth.n_frames() {
        return Err(Error::invalid(format!(
            "the prediction has {} frames but the truth {}",
            pred.n_frames(),
            truth.n_frames()
        )));
    }
    if pred.n_frames() == 0 {
        return Err(Error::invalid("no frames to compare"));
    }
    if pred.n_vertices() != truth.n_vertices() {
        return Err(Error::invalid(format!(
            "the prediction has {} vertices per frame but the truth {}: not the target's topology",
            pred.n_vertices(),
            truth.n_vertices()
        )));
    }
    let (pose, placed) = pred
        .frames
        .par_iter()
        .zip(&truth.frames)
        .map(|(p, t)| {
            let m = procrustes(p, t, None);
            (sum_sq(&m.apply_all(p), t), sum_sq(p, t))
        })
        .collect::<Vec<_>>()
        .into_iter()
        .fold((0.0, 0.0), |(a, b), (c, d)| (a + c, b + d));
    let n = (pred.n_frames() * pred.n_vertices()) as f64;
    Ok(((pose / n).sqrt(), (placed / n).sqrt()))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn seq(frames: Vec<Vec<[f64; 3]>>) -> MeshSequence {
        MeshSequence::new(
            vec![[0, 1, 2]],
            frames
                .into_iter()
                .map(|f| {
                    f.into_iter()
                        .map(|p| Vector3::new(p[0], p[1], p[2]))
                        .collect()
                })
                .collect(),
        )
    }

    /// Hand-computed: frame 0 is the truth stretched along x (pose error
    /// remains after alignment), frame 1 is the truth shifted by 0.3 m (no
    /// pose error, only placement error).
    #[test]
    fn hand_computed_case() {
        let truth = seq(vec![
            vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]],
            vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
        ]);
        let pred = seq(vec![
            // Stretched by 2 about the origin: centroid 2 vs 1; after the
            // optimal rigid alignment (a translation by -1 along x) the points
            // are (-1, 1, 3) vs (0, 1, 2): squared errors 1, 0, 1.
            vec![[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [4.0, 0.0, 0.0]],
            vec![[0.3, 0.0, 0.0], [1.3, 0.0, 0.0], [0.3, 1.0, 0.0]],
        ]);
        let (pose, placed) = rms_errors(&pred, &truth).unwrap();
        // Pose: (1 + 0 + 1 + 0) / 6 vertices.
        assert!((pose - (2.0f64 / 6.0).sqrt()).abs() < 1e-9, "{pose}");
        // Placed: frame 0 squared errors 0, 1, 4; frame 1: 3 x 0.09.
        assert!(
            (placed - ((5.0 + 0.27) / 6.0f64).sqrt()).abs() < 1e-12,
            "{placed}"
        );
    }

    #[test]
    fn rejects_mismatched_sequences() {
        let a = seq(vec![vec![[0.0; 3]; 3]]);
        let b = seq(vec![vec![[0.0; 3]; 3], vec![[0.0; 3]; 3]]);
        assert!(rms_errors(&a, &b)
            .unwrap_err()
            .to_string()
            .contains("1 frames but the truth 2"));
        let c = MeshSequence::new(vec![[0, 1, 2]], vec![vec![Vector3::zeros(); 4]]);
        assert!(rms_errors(&a, &c)
            .unwrap_err()
            .to_string()
            .contains("not the target's topology"));
    }
}
