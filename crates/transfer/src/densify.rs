//! `dtw-densify`: dense pose correspondences for one training pair from its
//! sparse key-poses (CVPR §5.1, eqs. 1-7).
//!
//! Per part, a Bayesian linear regression from the key-poses' source to
//! target PCA coefficients gives every (source frame, target frame) pair a
//! cost `-log P^k_ij` (CVPR eq. 5); the costs add over parts (eq. 6) and the
//! least-cost continuous, monotonic path through the key-poses with at most 3
//! vertical or horizontal steps in a row is the dense correspondence (CVPR eq. 7).

use gp::blr::{cost_matrix, PartFrames};
use gp::dtw::{dtw_path, DtwOptions};
use mesh_core::artifact::Artifact;
use mesh_core::{Error, Result};
use nalgebra::DMatrix;
use serde::{Deserialize, Serialize};

/// The paper's observation noise of the key-pose regression (CVPR eq. 1).
pub const PAPER_SIGMA2: f64 = 0.01;

/// Dense correspondences of one training pair.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Correspondences {
    pub source_motion: String,
    pub target_motion: String,
    /// The key-poses the path was forced through.
    pub keyposes: Vec<[usize; 2]>,
    /// The path: `(source frame, target frame)` pairs in order.
    pub pairs: Vec<[usize; 2]>,
}

impl Artifact for Correspondences {
    const KIND: &'static str = "correspondences";
    const VERSION: u32 = 1;

    /// A path: at least one pair, both frame indices non-decreasing from pair to pair, and
    /// every key-pose on it. (Whether the indices lie inside the two motions is checked where
    /// the motions are known, `gpr_model::training_set`.)
    fn validate(&self) -> std::result::Result<(), String> {
        if self.pairs.is_empty() {
            return Err("no frame pairs".into());
        }
        if let Some(w) = self.pairs.windows(2).find(|w| w[1][0] < w[0][0] || w[1][1] < w[0][1]) {
            return Err(format!("frame pairs {:?} then {:?}: the path goes backwards", w[0], w[1]));
        }
        if let Some(k) = self.keyposes.iter().find(|k| self.pairs.binary_search(k).is_err()) {
            return Err(format!("key-pose {k:?} is not on the path"));
        }
        Ok(())
    }
}

/// How far a path is from the true correspondences: for every source frame,
/// the distance in target frames between the path's (mean) match and the
/// true one.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PathError {
    pub mean_frames: f64,
    pub max_frames: f64,
    /// Same, in seconds at the target's frame rate.
    pub mean_seconds: f64,
}

/// Computes the dense path from per-part coefficients of both motions.
pub fn densify(
    source_parts: &[DMatrix<f64>],
    target_parts: &[DMatrix<f64>],
    keyposes: &[[usize; 2]],
    sigma2: f64,
) -> Result<Vec<[usize; 2]>> {
    if source_parts.len() != target_parts.len() {
        return Err(Error::invalid(format!(
            "the source has {} parts and the target {}: the part trees must match",
            source_parts.len(),
            target_parts.len()
        )));
    }
    let parts: Vec<PartFrames> = source_parts
        .iter()
        .zip(target_parts)
        .map(|(s, t)| PartFrames { source: s, target: t })
        .collect();
    let keys: Vec<(usize, usize)> = keyposes.iter().map(|k| (k[0], k[1])).collect();
    let cost = cost_matrix(&parts, &keys, sigma2).map_err(|e| Error::invalid(e.to_string()))?;
    let path = dtw_path(&cost, &keys, &DtwOptions::default()).map_err(|e| Error::invalid(e.to_string()))?;
    Ok(path.into_iter().map(|(i, j)| [i, j]).collect())
}

/// Compares `path` with true per-source-frame correspondences `truth`.
pub fn path_error(path: &[[usize; 2]], truth: &[[usize; 2]], target_fps: f64) -> PathError {
    let n_src = truth.iter().map(|p| p[0] + 1).max().unwrap_or(0);
    let mut sum = vec![0.0; n_src];
    let mut count = vec![0usize; n_src];
    for &[i, j] in path {
        if i < n_src {
            sum[i] += j as f64;
            count[i] += 1;
        }
    }
    let errs: Vec<f64> = truth
        .iter()
        .filter(|t| count[t[0]] > 0)
        .map(|t| (sum[t[0]] / count[t[0]] as f64 - t[1] as f64).abs())
        .collect();
    let mean = errs.iter().sum::<f64>() / errs.len().max(1) as f64;
    let max = errs.iter().cloned().fold(0.0, f64::max);
    PathError { mean_frames: mean, max_frames: max, mean_seconds: mean / target_fps }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Target frames are a time-warped copy of source frames through a
    /// linear map per part: the densified path must follow the warp.
    #[test]
    fn recovers_a_known_time_warp() {
        let fs = 40;
        let warp = |i: usize| -> usize { ((i as f64 / (fs - 1) as f64).powf(1.3) * 79.0).round() as usize };
        let signal = |t: f64| -> Vec<f64> { vec![(t * 6.0).sin(), (t * 3.0).cos(), t * t, (t * 9.0).sin() * 0.5] };
        let src = DMatrix::from_fn(fs, 4, |i, c| signal(i as f64 / (fs - 1) as f64)[c]);
        // Target: 80 frames of the same motion under a different linear map.
        let map = DMatrix::from_row_slice(3, 4, &[1.0, 0.5, 0.0, 0.2, -0.3, 1.0, 0.4, 0.0, 0.0, 0.1, 1.0, 0.7]);
        let inv_warp = |j: usize| -> f64 { (j as f64 / 79.0).powf(1.0 / 1.3) };
        let tgt = DMatrix::from_fn(80, 3, |j, r| {
            let x = signal(inv_warp(j));
            (0..4).map(|c| map[(r, c)] * x[c]).sum()
        });
        let keys = vec![[0, 0], [10, warp(10)], [20, warp(20)], [30, warp(30)], [fs - 1, 79]];
        let path = densify(&[src], &[tgt], &keys, PAPER_SIGMA2).unwrap();
        let truth: Vec<[usize; 2]> = (0..fs).map(|i| [i, warp(i)]).collect();
        let err = path_error(&path, &truth, 50.0);
        assert!(err.mean_frames < 1.5, "{err:?}");
        assert_eq!(path.first(), Some(&[0, 0]));
        assert_eq!(path.last(), Some(&[fs - 1, 79]));
        for k in &keys {
            assert!(path.contains(k));
        }
    }
}
