//! `transfer-eval`: per-vertex RMS error of a transferred sequence against the
//! ground truth (paper §7, "Quantitative Evaluation").
//!
//! - `rms_pose_m`: each predicted frame is first rigidly aligned to its truth
//!   frame (Procrustes, no scale), so only the pose (shape) error remains;
//! - `rms_placed_m`: as placed in the world, no alignment.
//!
//! Both are `sqrt(mean over frames and vertices of |p - t|²)`, in metres.
//!
//! - `foot_sliding_m`: where the truth's feet are planted (its contact
//!   annotations, `truth_contacts` in `subject.json`), the mean horizontal
//!   motion per frame of the prediction's sole centroids
//!   (`mesh_core::feet::contact_sliding`); `truth_foot_sliding_m` is the same
//!   measure on the truth itself, for scale.
//!
//! Without truth (a lab's own test motions) the record holds what can be known
//! from the source alone ([`without_truth`]): `foot_sliding_m` on the source's
//! contacts (detected on its meshes, as `gpr-predict` plants the feet), the
//! source's own sliding on them (`source_foot_sliding_m`), and `floor_offset_m`:
//! over the frames where the source stands on a foot, the median height of the
//! lowest point of the transfer's standing legs above the target's floor (the
//! lowest leg point of its template, a captured frame).

use crate::feet::TargetFeet;
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
    /// Pose error against the truth; `null` without truth.
    pub rms_pose_m: Option<f64>,
    pub rms_placed_m: Option<f64>,
    pub frames: usize,
    /// Sliding of the prediction's planted feet (m per frame), where contacts are known
    /// (the truth's, or without truth the source's).
    pub foot_sliding_m: Option<f64>,
    /// The same measure on the truth.
    pub truth_foot_sliding_m: Option<f64>,
    /// Without truth: the source's own sliding on its contacts.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub source_foot_sliding_m: Option<f64>,
    /// Median height of the prediction's planted soles above the target's floor (m).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub floor_offset_m: Option<f64>,
    /// `rms_pose_m` of each frame (empty without truth).
    pub frame_pose_m: Vec<f64>,
    /// Scored against a reference performance (`transfer-eval --time-normalise`): its frame count
    /// (the errors are then time-normalised, `crate::reference_score`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reference_frames: Option<usize>,
    /// With `--time-normalise` and `--template`: the pose error of the template held still.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub still_rms_pose_m: Option<f64>,
    /// With `--time-normalise`: the pose error along the timing-free alignment of the prediction's
    /// frames with the reference's (`crate::reference_score::dtw_rms`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub dtw_rms_pose_m: Option<f64>,
    /// With `--time-normalise` and `--template`: the same for the template held still.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub still_dtw_rms_pose_m: Option<f64>,
}

/// What a transfer shows without truth, measured on the source's contacts.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SourceMeasures {
    pub foot_sliding_m: Option<f64>,
    pub source_foot_sliding_m: Option<f64>,
    pub floor_offset_m: Option<f64>,
}

/// Median of the values (None when empty).
fn median(mut v: Vec<f64>) -> Option<f64> {
    if v.is_empty() {
        return None;
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    Some(if n % 2 == 1 { v[n / 2] } else { 0.5 * (v[n / 2 - 1] + v[n / 2]) })
}

/// The prediction's sliding and floor offset on the source's `contacts` (per frame `[left,
/// right]`, one per prediction frame): `target` the target's soles, legs and floor, and
/// `source` (placed source frames with its `source_soles`) for the source's own sliding.
pub fn without_truth(
    pred: &MeshSequence,
    target: &TargetFeet,
    contacts: &[[bool; 2]],
    source: (&[Vec<Vector3<f64>>], &[Vec<u32>]),
    up: &Vector3<f64>,
) -> Result<SourceMeasures> {
    let n = pred.n_vertices();
    if let Some(v) = target.soles.iter().chain(&target.legs).flatten().find(|&&v| v as usize >= n) {
        return Err(Error::invalid(format!("foot vertex {v} is beyond the prediction's {n} vertices")));
    }
    if contacts.len() != pred.n_frames() {
        return Err(Error::invalid(format!(
            "{} source contact frames for {} predicted frames",
            contacts.len(),
            pred.n_frames()
        )));
    }
    // Where the source stands on a foot, the lowest point of the transfer's leg on that side
    // is on its floor.
    let lowest = crate::feet::lowest_points(&pred.frames, &target.legs, up);
    let heights: Vec<f64> = contacts
        .iter()
        .enumerate()
        .filter(|(_, c)| c[0] || c[1])
        .map(|(t, c)| (0..2).filter(|&f| c[f]).map(|f| lowest[f][t]).fold(f64::INFINITY, f64::min) - target.floor)
        .collect();
    Ok(SourceMeasures {
        foot_sliding_m: mesh_core::feet::contact_sliding(&pred.frames, &target.soles, contacts, up),
        source_foot_sliding_m: mesh_core::feet::contact_sliding(source.0, source.1, contacts, up),
        floor_offset_m: median(heights),
    })
}

/// Sum of squared distances between matching points.
fn sum_sq(a: &[Vector3<f64>], b: &[Vector3<f64>]) -> f64 {
    a.iter().zip(b).map(|(p, q)| (p - q).norm_squared()).sum()
}

/// The squared pose error of one frame: the sum over vertices of `|R p + t - q|²` after the
/// rigid alignment (Procrustes, no scale) of `pred` to `truth` that minimises it (the frame's
/// share of [`rms_errors`]' `rms_pose_m`).
pub fn pose_sq_error(pred: &[Vector3<f64>], truth: &[Vector3<f64>]) -> f64 {
    let m = procrustes(pred, truth, None);
    sum_sq(&m.apply_all(pred), truth)
}

/// `(rms_pose_m, rms_placed_m)` of `pred` against `truth` (same frame count,
/// same vertex count).
pub fn rms_errors(pred: &MeshSequence, truth: &MeshSequence) -> Result<(f64, f64)> {
    rms_errors_per_frame(pred, truth).map(|(pose, placed, _)| (pose, placed))
}

/// [`rms_errors`] and the pose error of every frame.
pub fn rms_errors_per_frame(
    pred: &MeshSequence,
    truth: &MeshSequence,
) -> Result<(f64, f64, Vec<f64>)> {
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
    let per_frame: Vec<(f64, f64)> = pred
        .frames
        .par_iter()
        .zip(&truth.frames)
        .map(|(p, t)| (pose_sq_error(p, t), sum_sq(p, t)))
        .collect();
    let (pose, placed) = per_frame
        .iter()
        .fold((0.0, 0.0), |(a, b), (c, d)| (a + c, b + d));
    let nv = pred.n_vertices().max(1) as f64;
    let frames = per_frame.iter().map(|(p, _)| (p / nv).sqrt()).collect();
    let n = (pred.n_frames() * pred.n_vertices()) as f64;
    Ok(((pose / n).sqrt(), (placed / n).sqrt(), frames))
}

/// `(prediction, truth)` foot sliding on the truth's `contacts` (per frame `[left, right]`)
/// with the target's `soles` ([`mesh_core::feet::soles`]); `None` where no foot is planted in
/// two consecutive frames.
pub fn foot_sliding(
    pred: &MeshSequence,
    truth: &MeshSequence,
    soles: &[Vec<u32>],
    contacts: &[[bool; 2]],
    up: &Vector3<f64>,
) -> Result<(Option<f64>, Option<f64>)> {
    let n = pred.n_vertices();
    if let Some(v) = soles.iter().flatten().find(|&&v| v as usize >= n) {
        return Err(Error::invalid(format!(
            "sole vertex {v} is beyond the prediction's {n} vertices"
        )));
    }
    if contacts.len() != truth.n_frames() {
        return Err(Error::invalid(format!(
            "{} contact frames for {} truth frames",
            contacts.len(),
            truth.n_frames()
        )));
    }
    Ok((
        mesh_core::feet::contact_sliding(&pred.frames, soles, contacts, up),
        mesh_core::feet::contact_sliding(&truth.frames, soles, contacts, up),
    ))
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

    /// A foot planted in the truth and dragged 2 cm per frame in the prediction slides
    /// 0.02 m/frame; the truth itself 0; vertical motion does not count.
    #[test]
    fn foot_sliding_on_the_truths_contacts() {
        let still = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        let truth = seq(vec![still.clone(); 4]);
        let pred = seq(
            (0..4)
                .map(|i| {
                    let d = 0.02 * i as f64;
                    vec![[d, 0.01 * i as f64, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]
                })
                .collect(),
        );
        let soles = vec![vec![0u32], vec![]];
        let contacts = vec![[true, false]; 4];
        let (p, t) = foot_sliding(&pred, &truth, &soles, &contacts, &Vector3::y()).unwrap();
        assert!((p.unwrap() - 0.02).abs() < 1e-12, "{p:?}");
        assert_eq!(t, Some(0.0));
        let none = vec![[false, false]; 4];
        assert_eq!(foot_sliding(&pred, &truth, &soles, &none, &Vector3::y()).unwrap(), (None, None));
        assert!(foot_sliding(&pred, &truth, &[vec![7]], &contacts, &Vector3::y()).is_err());
    }

    /// Without truth: a transfer whose standing leg's lowest point is 3 cm above the target's
    /// floor (at 0.5 m) wherever the source stands has a floor offset of 3 cm (the left leg's
    /// second point, lower but in the air when the right foot stands, does not count), frames
    /// where the source is in the air left out; dragged 2 cm per frame it slides 0.02 m/frame,
    /// the still source 0.
    #[test]
    fn floor_offset_and_sliding_on_the_sources_contacts() {
        let pred = seq(
            (0..5)
                .map(|i| {
                    let lift = if i == 2 { 0.4 } else { 0.0 };
                    let left_low = if i == 4 { 0.51 } else { 0.9 };
                    vec![[0.02 * i as f64, 0.53 + lift, 0.0], [1.0, 0.53 + lift, 0.0], [0.0, 1.5, 0.0], [0.0, left_low, 0.0]]
                })
                .collect(),
        );
        let source: Vec<Vec<Vector3<f64>>> = vec![vec![Vector3::new(0.0, 0.0, 0.0); 4]; 5];
        let soles = [vec![0u32], vec![1u32]];
        let target = TargetFeet { soles: soles.clone(), legs: [vec![0, 3], vec![1]], floor: 0.5 };
        let contacts = vec![[true, false], [true, false], [false, false], [true, false], [false, true]];
        let m = without_truth(&pred, &target, &contacts, (&source, &soles), &Vector3::y()).unwrap();
        assert!((m.floor_offset_m.unwrap() - 0.03).abs() < 1e-12, "{m:?}");
        assert!((m.foot_sliding_m.unwrap() - 0.02).abs() < 1e-12, "{m:?}");
        assert_eq!(m.source_foot_sliding_m, Some(0.0));
        let air = vec![[false, false]; 5];
        let m = without_truth(&pred, &target, &air, (&source, &soles), &Vector3::y()).unwrap();
        assert_eq!((m.floor_offset_m, m.foot_sliding_m), (None, None));
        assert!(without_truth(&pred, &target, &contacts[..4], (&source, &soles), &Vector3::y()).is_err());
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
