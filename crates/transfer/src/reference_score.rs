//! Scoring a transfer against a **reference** rather than ground truth: the
//! target performing the same named motion its own way (docs/FORMATS.md,
//! "Reference performances"), whose length and timing differ from the
//! source's, so frame `i` of the transfer is not the instant of frame `i`
//! of the reference.
//!
//! Time normalisation: prediction frame `i` of `n` is compared with the
//! reference at the same fraction of its length, `u = i (m - 1) / (n - 1)`
//! of its `m` frames, the vertices interpolated linearly between frames
//! `floor(u)` and `ceil(u)`. Each comparison is the pose error of
//! `transfer-eval`: the prediction frame rigidly aligned to the reference
//! frame (Procrustes, no scale), then the RMS vertex distance.
//!
//! Timing-free: the same pose error averaged along the least-cost monotone
//! alignment of the two sequences' frames (CVPR eq. 7's DTW without key-poses,
//! over the squared pose errors; [`dtw_rms`]). A reference that steps on the
//! other foot first, or pauses where the source does not, costs the
//! time-normalised score what it does not cost this one: it says how close
//! the transfer's poses, in their order, come to the reference's.
//!
//! The same measures of "the target standing still" (its rest mesh repeated
//! for every frame) say what the scores are worth: a transfer that does not
//! beat it has not moved the target the way the reference moves.

use gp::dtw::{dtw_path, DtwOptions};
use mesh_core::rigid::procrustes;
use mesh_core::sequence::MeshSequence;
use mesh_core::{Error, Result};
use nalgebra::{DMatrix, Vector3};
use rayon::prelude::*;

/// The reference at fraction `i / (n - 1)` of its length (`n` the
/// prediction's frame count; a one-frame prediction reads the first frame).
pub fn reference_at(reference: &MeshSequence, i: usize, n: usize) -> Vec<Vector3<f64>> {
    let m = reference.n_frames();
    let u = if n > 1 { i as f64 * (m - 1) as f64 / (n - 1) as f64 } else { 0.0 };
    let a = (u.floor() as usize).min(m - 1);
    let b = (a + 1).min(m - 1);
    let t = u - a as f64;
    reference.frames[a].iter().zip(&reference.frames[b]).map(|(p, q)| p * (1.0 - t) + q * t).collect()
}

/// RMS distances from `a` to `b` after rigidly aligning `a` onto `b`, and as placed.
fn rms_pose_and_placed(a: &[Vector3<f64>], b: &[Vector3<f64>]) -> (f64, f64) {
    let m = procrustes(a, b, None);
    let n = a.len().max(1) as f64;
    let pose: f64 = a.iter().zip(b).map(|(p, q)| (m.apply(p) - q).norm_squared()).sum();
    let placed: f64 = a.iter().zip(b).map(|(p, q)| (p - q).norm_squared()).sum();
    ((pose / n).sqrt(), (placed / n).sqrt())
}

/// Per-frame (pose, placed) errors of `frame(i)` (for `i` in `0..n`) against
/// the time-normalised `reference`.
fn score_frames(
    n: usize,
    frame: impl Fn(usize) -> Vec<Vector3<f64>>,
    reference: &MeshSequence,
) -> Vec<(f64, f64)> {
    (0..n).map(|i| rms_pose_and_placed(&frame(i), &reference_at(reference, i, n))).collect()
}

/// RMS pose error along the least-cost monotone alignment of `frames`
/// (`n`, rows) with `reference`'s frames (columns): the squared pose error of
/// every frame pair is the cost, the path runs corner to corner with CVPR
/// eq. 7's run-length limit, and the score is the root of its mean cost per
/// node. `None` when no such path exists (one sequence more than four times
/// the other's length).
pub fn dtw_rms(n: usize, frame: impl Fn(usize) -> Vec<Vector3<f64>> + Sync, reference: &MeshSequence) -> Option<f64> {
    let m = reference.n_frames();
    let rows: Vec<Vec<f64>> = (0..n)
        .into_par_iter()
        .map(|i| {
            let f = frame(i);
            reference.frames.iter().map(|r| rms_pose_and_placed(&f, r).0.powi(2)).collect()
        })
        .collect();
    let cost = DMatrix::from_fn(n, m, |i, j| rows[i][j]);
    let path = dtw_path(&cost, &[], &DtwOptions::default()).ok()?;
    let sum: f64 = path.iter().map(|&(i, j)| cost[(i, j)]).sum();
    Some((sum / path.len() as f64).sqrt())
}

/// RMS over frames of per-frame RMS errors (all frames have the same vertex
/// count, so this is the RMS over all frames and vertices).
fn rms(per_frame: impl Iterator<Item = f64>) -> f64 {
    let (sum, n) = per_frame.fold((0.0, 0usize), |(s, n), e| (s + e * e, n + 1));
    (sum / n.max(1) as f64).sqrt()
}

/// The scores of a prediction against a reference.
#[derive(Clone, Debug, PartialEq)]
pub struct ReferenceScore {
    /// RMS pose error of the prediction against the time-normalised reference (m).
    pub rms_pose_m: f64,
    /// The same without the alignment, as placed (m).
    pub rms_placed_m: f64,
    /// The pose error of each prediction frame.
    pub frame_pose_m: Vec<f64>,
    /// The same measure for the rest mesh held still (m), when one is given.
    pub still_rms_pose_m: Option<f64>,
    /// RMS pose error along the timing-free alignment ([`dtw_rms`]; m).
    pub dtw_rms_pose_m: Option<f64>,
    /// The same measure for the rest mesh held still (m), when one is given.
    pub still_dtw_rms_pose_m: Option<f64>,
}

/// Scores `prediction` against `reference` (both the target's topology; any
/// frame counts), and `rest` held still for as many frames, if given.
pub fn score_against_reference(
    prediction: &MeshSequence,
    reference: &MeshSequence,
    rest: Option<&[Vector3<f64>]>,
) -> Result<ReferenceScore> {
    let (n, nv) = (prediction.n_frames(), prediction.n_vertices());
    if n == 0 || reference.n_frames() == 0 {
        return Err(Error::invalid("no frames to compare"));
    }
    if reference.n_vertices() != nv {
        return Err(Error::invalid(format!(
            "the prediction has {nv} vertices per frame but the reference {}: not the target's topology",
            reference.n_vertices()
        )));
    }
    if let Some(rest) = rest {
        if rest.len() != nv {
            return Err(Error::invalid(format!(
                "the rest mesh has {} vertices but the prediction {nv}",
                rest.len()
            )));
        }
    }
    let frames = score_frames(n, |i| prediction.frames[i].clone(), reference);
    let still_rms_pose_m = rest.map(|r| rms(score_frames(n, |_| r.to_vec(), reference).iter().map(|e| e.0)));
    Ok(ReferenceScore {
        rms_pose_m: rms(frames.iter().map(|e| e.0)),
        rms_placed_m: rms(frames.iter().map(|e| e.1)),
        frame_pose_m: frames.iter().map(|e| e.0).collect(),
        still_rms_pose_m,
        dtw_rms_pose_m: dtw_rms(n, |i| prediction.frames[i].clone(), reference),
        still_dtw_rms_pose_m: rest.and_then(|r| dtw_rms(n, |_| r.to_vec(), reference)),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use mesh_core::rigid::RigidMotion;
    use nalgebra::{Rotation3, Vector3};

    /// A four-vertex sequence whose tip moves with time `s` in [0, 1].
    fn pose(s: f64) -> Vec<Vector3<f64>> {
        vec![
            Vector3::new(0.0, 0.0, 0.0),
            Vector3::new(1.0, 0.0, 0.0),
            Vector3::new(0.0, 1.0, 0.0),
            Vector3::new(0.3, 0.2, 0.5 + s),
        ]
    }
    fn sequence(n: usize) -> MeshSequence {
        let faces = vec![[0, 1, 2], [0, 1, 3]];
        MeshSequence::new(faces, (0..n).map(|i| pose(i as f64 / (n - 1) as f64)).collect())
    }

    #[test]
    fn a_rigidly_moved_copy_scores_zero() {
        let reference = sequence(9);
        let moved = MeshSequence::new(
            reference.faces.clone(),
            reference
                .frames
                .iter()
                .enumerate()
                .map(|(i, f)| {
                    let m = RigidMotion::new(Rotation3::from_euler_angles(0.3 * i as f64, -0.2, 1.0), Vector3::new(i as f64, 2.0, -1.0));
                    m.apply_all(f)
                })
                .collect(),
        );
        let s = score_against_reference(&moved, &reference, None).unwrap();
        assert!(s.rms_pose_m < 1e-12, "{}", s.rms_pose_m);
        assert!(s.rms_placed_m > 1.0, "as placed the copy is metres away: {}", s.rms_placed_m);
    }

    #[test]
    fn the_same_motion_at_another_frame_count_scores_zero_after_time_normalisation() {
        // The tip moves linearly in time, so interpolating the 5-frame reference is exact.
        let s = score_against_reference(&sequence(17), &sequence(5), None).unwrap();
        assert!(s.rms_pose_m < 1e-12, "{}", s.rms_pose_m);
        assert_eq!(s.frame_pose_m.len(), 17);
    }

    #[test]
    fn standing_still_scores_the_reference_motion_it_misses() {
        let reference = sequence(5);
        let rest = pose(0.0);
        let s = score_against_reference(&reference, &reference, Some(&rest)).unwrap();
        assert!(s.rms_pose_m < 1e-12);
        let still = s.still_rms_pose_m.unwrap();
        // Analytic upper bound: without alignment the tip is off by s in frame s, one vertex in
        // four: sqrt(mean over the 5 frames of s² / 4); alignment can only lower it.
        let unaligned = ((0..5).map(|i| (i as f64 / 4.0).powi(2) / 4.0).sum::<f64>() / 5.0).sqrt();
        assert!(still > 0.05 && still <= unaligned + 1e-12, "{still} vs {unaligned}");
    }

    #[test]
    fn a_retimed_copy_scores_zero_without_timing_but_not_time_normalised() {
        // The reference's poses, some held (runs of at most three repeats, within the
        // alignment's run-length limit): the same poses in the same order, timed otherwise.
        let reference = sequence(6);
        let order = [0, 0, 0, 1, 2, 2, 3, 4, 5, 5];
        let retimed = MeshSequence::new(reference.faces.clone(), order.iter().map(|&j| reference.frames[j].clone()).collect());
        let s = score_against_reference(&retimed, &reference, Some(&pose(0.0))).unwrap();
        assert!(s.dtw_rms_pose_m.unwrap() < 1e-12, "{:?}", s.dtw_rms_pose_m);
        assert!(s.rms_pose_m > 0.02, "time-normalised, the held frames lag: {}", s.rms_pose_m);
        // The rest mesh held still matches frame 0 only; every other reference frame costs it.
        let still = s.still_dtw_rms_pose_m.unwrap();
        assert!(still > 0.05 && still <= s.still_rms_pose_m.unwrap() + 0.1, "{still}");
    }

    #[test]
    fn the_timing_free_score_is_the_least_mean_cost_of_every_monotone_alignment() {
        // Against a brute force over every corner-to-corner path of a 3 x 3 cost matrix with
        // unit steps (runs of at most 3 always hold here).
        let reference = sequence(3);
        let pred = MeshSequence::new(reference.faces.clone(), [0.9, 0.1, 0.6].iter().map(|&s| pose(s)).collect());
        let c = |i: usize, j: usize| rms_pose_and_placed(&pred.frames[i], &reference.frames[j]).0.powi(2);
        fn paths(i: usize, j: usize, acc: Vec<(usize, usize)>, out: &mut Vec<Vec<(usize, usize)>>) {
            let mut acc = acc;
            acc.push((i, j));
            if (i, j) == (2, 2) {
                out.push(acc);
                return;
            }
            for (di, dj) in [(1, 1), (1, 0), (0, 1)] {
                if i + di <= 2 && j + dj <= 2 {
                    paths(i + di, j + dj, acc.clone(), out);
                }
            }
        }
        let mut all = Vec::new();
        paths(0, 0, Vec::new(), &mut all);
        // DTW minimises the summed cost; the score is that path's mean.
        let best = all
            .iter()
            .map(|p| (p.iter().map(|&(i, j)| c(i, j)).sum::<f64>(), p.len()))
            .min_by(|a, b| a.0.total_cmp(&b.0))
            .unwrap();
        let got = dtw_rms(3, |i| pred.frames[i].clone(), &reference).unwrap();
        assert!((got - (best.0 / best.1 as f64).sqrt()).abs() < 1e-12, "{got} vs {best:?}");
    }

    #[test]
    fn another_topology_is_refused() {
        let other = MeshSequence::new(vec![[0, 1, 2]], vec![pose(0.0)[..3].to_vec()]);
        let err = score_against_reference(&other, &sequence(3), None).unwrap_err().to_string();
        assert!(err.contains("not the target's topology"), "{err}");
    }
}
