//! Cross-validation on the training motions: an estimate of a transfer model's pose error on a
//! new motion from its training motions alone, without ground truth.
//!
//! The folds hold out, by [`FoldUnit`]:
//! - `halves` (default): each half of each training pair `p` (one motion of both subjects, with
//!   its DTW correspondences), split at the middle of its source frames; the model is trained
//!   again on the other pairs and the other half of `p`.
//! - `motions`: each whole pair `p` (leave one motion out); the model is trained again on the
//!   other pairs. More pessimistic: a held-out motion is often farther from the other motions
//!   than a new motion is from all of them.
//!
//! The held-out model transfers the held-out source frames; each source frame `i` of the
//! held-out correspondences is compared with the target frame `j` they pair it
//! with (the median of its `j`s when the path pairs it with several: a source frame at half the
//! target's frame rate pairs with two), as `transfer-eval`'s `rms_pose_m` compares a
//! prediction with the truth: the predicted target parts (limbs turned by the limb
//! orientation) assembled into the target mesh, rigidly aligned to the target's aligned frame
//! (Procrustes, no scale; [`crate::evaluate::pose_sq_error`]), the RMS over its vertices.
//!
//! Every held-out model refits its affine means, prior mix and limb orientation. Its GPs'
//! hyperparameters (kernel and noise) are, by [`Hyperparameters`]:
//! - `fixed` (default): the full model's, each GP conditioned on the remaining rows (one
//!   factorisation per GP, no optimisation). Optimistic where the hyperparameters learnt from
//!   a motion help predict it: the zero-mean GP's estimate, not the affine mean's, whose
//!   residual GP carries almost nothing.
//! - `refit`: learnt again on the remaining rows, as the full model learnt them, once per fold
//!   and mean function (configurations that differ only in the prior's weight or the limb
//!   orientation share them, as in the full training). Nothing the held-out motion taught the
//!   full model reaches its prediction; up to 3.3x the cost of `fixed`.
//!
//! Either way every source frame of every pair's correspondences is compared once.
//! `cv_rms_pose_m` pools every compared frame: the root of the mean over frames and vertices of
//! the squared distances, as `rms_pose_m` pools a motion's frames; a motion's error pools its
//! halves.

use std::collections::BTreeMap;
use std::path::PathBuf;

use capture::motion_stream::read_frames;
use capture::part_pca::PcaModel;
use mesh_core::{Error, Result};
use nalgebra::{DMatrix, Vector3};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::evaluate::pose_sq_error;
use crate::gpr_model::{train_rows, FixedHyperparameters, GprModel, Method, OrientationOptions, Regression};
use crate::limb_orientation::{self, LimbOrientation, PairLogs};
use crate::predict::{displacement_matrix, predict};
use crate::training_rows::{PairData, TrainingRows};

/// One held-out motion's error.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MotionError {
    /// The motion's name (its correspondences' source motion).
    pub motion: String,
    /// The compared frames (source frames of its correspondences).
    pub frames: usize,
    /// RMS per vertex over those frames, pose only (metres).
    pub rms_pose_m: f64,
}

/// The cross-validated error of one configuration.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CrossValidation {
    /// Pooled over every held-out motion's frames (metres).
    pub cv_rms_pose_m: f64,
    /// Per held-out motion, in the order of the pairs.
    pub motions: Vec<MotionError>,
}

/// A training pair with what leaving it out needs besides its coefficients.
pub struct HeldOut {
    /// The motion's name.
    pub motion: String,
    /// The direction's target aligned motion of the pair: the truth its frames are compared to.
    pub truth: PathBuf,
}

/// Where a held-out model's GP hyperparameters come from (see the module's documentation).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Hyperparameters {
    /// The full model's, conditioned on each fold's remaining motions.
    #[default]
    Fixed,
    /// Learnt again on each fold's remaining motions.
    Refit,
}

/// What one fold holds out (see the module's documentation).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum FoldUnit {
    /// Each half of each training motion, the rest of the motion trained on.
    #[default]
    Halves,
    /// Each whole training motion.
    Motions,
}

impl FoldUnit {
    /// The flag's value naming it.
    pub fn name(self) -> &'static str {
        match self {
            FoldUnit::Halves => "halves",
            FoldUnit::Motions => "motions",
        }
    }
}

/// One fold: the training pair it holds out (or part of) and its correspondences kept for
/// training (`None`: the whole pair is held out) and compared.
#[derive(Clone, Debug)]
pub struct Fold {
    pub pair: usize,
    pub kept: Option<PairData>,
    pub compared: Vec<[usize; 2]>,
}

/// The folds of `pairs` by `unit`, in pair order (a pair's first half first). A half whose
/// source frames have no correspondence is no fold; a pair with a single source frame is held
/// out whole.
pub fn folds_of(pairs: &[PairData], unit: FoldUnit) -> Vec<Fold> {
    let mut folds = Vec::new();
    for (p, data) in pairs.iter().enumerate() {
        let sources: Vec<usize> = compared_frames(&data.pairs).iter().map(|&[i, _]| i).collect();
        let (Some(&lo), Some(&hi)) = (sources.first(), sources.last()) else { continue };
        if unit == FoldUnit::Motions || lo == hi {
            folds.push(Fold { pair: p, kept: None, compared: compared_frames(&data.pairs) });
            continue;
        }
        // Source frames below `mid` make the first half.
        let mid = lo + (hi + 1 - lo) / 2;
        for first in [true, false] {
            let held = |i: usize| (i < mid) == first;
            let mut kept = data.clone();
            kept.pairs.retain(|&[i, _]| !held(i));
            kept.keyposes.retain(|&[i, _]| !held(i));
            let compared = compared_frames(&data.pairs.iter().copied().filter(|&[i, _]| held(i)).collect::<Vec<_>>());
            folds.push(Fold { pair: p, kept: Some(kept), compared });
        }
    }
    folds
}

/// A configuration to cross-validate: how its regressors and limb orientation are trained
/// ([`Regression::fixed`] holding the full model's hyperparameters, used with
/// [`Hyperparameters::Fixed`]).
pub struct Candidate<'a> {
    pub regression: Regression<'a>,
    pub orientation: OrientationOptions<'a>,
}

/// The training set the candidates are cross-validated on: the pairs (direction order) with
/// their motions, the frame ratio and whether only the key-poses are learnt from, the two
/// PCA models and their part names.
pub struct Folds<'a> {
    pub unit: FoldUnit,
    pub hyperparameters: Hyperparameters,
    pub pairs: &'a [PairData],
    pub held_out: &'a [HeldOut],
    pub frame_ratio: f64,
    pub keyposes_only: bool,
    pub part_names: &'a [String],
    pub source_pca: &'a PcaModel,
    pub target_pca: &'a PcaModel,
}

/// The `(source frame, target frame)` pairs compared for a held-out pair: each source frame of
/// its correspondences once, with the median target frame it is paired with.
pub fn compared_frames(pairs: &[[usize; 2]]) -> Vec<[usize; 2]> {
    let mut by_source: BTreeMap<usize, Vec<usize>> = BTreeMap::new();
    for &[i, j] in pairs {
        by_source.entry(i).or_default().push(j);
    }
    by_source
        .into_iter()
        .map(|(i, mut js)| {
            js.sort_unstable();
            [i, js[js.len() / 2]]
        })
        .collect()
}

/// The cross-validated error of every candidate (in their order). Needs at least two pairs.
/// Each fold reads its held-out motion's target frames once, for all candidates.
pub fn cross_validate(folds: &Folds, candidates: &[Candidate]) -> Result<Vec<CrossValidation>> {
    let n = folds.pairs.len();
    if n < 2 || folds.held_out.len() != n {
        return Err(Error::invalid(format!("cross-validation needs two or more training pairs, got {n}")));
    }
    let method = candidates.first().map(|c| c.regression.method).ok_or_else(|| Error::invalid("no configuration to cross-validate"))?;
    // Per candidate, per pair: (sum of squared pose errors, frames compared).
    let mut sums = vec![vec![(0.0, 0); n]; candidates.len()];
    let logs = orientation_logs(folds, candidates)?;
    for fold in folds_of(folds.pairs, folds.unit) {
        let p = fold.pair;
        let kept = fold.kept.filter(|k| !k.pairs.is_empty());
        // The fold's pairs: the others in order, then what it keeps of pair `p`.
        let order: Vec<usize> = (0..n).filter(|&q| q != p).chain(kept.is_some().then_some(p)).collect();
        let others: Vec<PairData> = folds.pairs.iter().enumerate().filter(|&(q, _)| q != p).map(|(_, d)| d.clone()).chain(kept).collect();
        let rows = TrainingRows::new(method, folds.part_names, &others, folds.frame_ratio, folds.keyposes_only)?;
        drop(others);
        let compared = fold.compared;
        let mut learnt: Vec<FixedHyperparameters> = Vec::with_capacity(candidates.len());
        let mut predicted = Vec::with_capacity(candidates.len());
        for (c, candidate) in candidates.iter().enumerate() {
            let fixed = match folds.hyperparameters {
                Hyperparameters::Fixed => candidate.regression.fixed,
                // A candidate with an earlier one's mean function takes the GPs learnt for it.
                Hyperparameters::Refit => candidates[..c].iter().position(|e| e.regression.mean == candidate.regression.mean).map(|e| &learnt[e]),
            };
            let regression = Regression { fixed, ..candidate.regression };
            let model = train_held_out(folds, &regression, &candidate.orientation, &rows, logs.as_ref(), &order)?;
            predicted.push(predict_held_out(folds, &model, &folds.pairs[p], &compared)?);
            learnt.push(FixedHyperparameters::of(&model)?);
        }
        let errors = held_out_errors(&folds.held_out[p], &compared, &predicted)?;
        for (c, e) in errors.into_iter().enumerate() {
            sums[c][p].0 += e;
            sums[c][p].1 += compared.len();
        }
    }
    Ok(sums
        .into_iter()
        .map(|per_pair| {
            let nv = folds.target_pca.n_vertices.max(1) as f64;
            let pooled: f64 = per_pair.iter().map(|(e, _)| e).sum();
            let frames: usize = per_pair.iter().map(|(_, f)| f).sum();
            CrossValidation {
                cv_rms_pose_m: (pooled / (frames.max(1) as f64 * nv)).sqrt(),
                motions: per_pair
                    .iter()
                    .zip(folds.held_out)
                    .map(|(&(e, f), h)| MotionError { motion: h.motion.clone(), frames: f, rms_pose_m: (e / (f.max(1) as f64 * nv)).sqrt() })
                    .collect(),
            }
        })
        .collect())
}

/// The candidate `--config auto` keeps, an index of `errors` (cross-validated errors of the
/// same folds): the first (the default configuration) unless another one is clearly better,
/// its error lower than the first's on the held-out motions by more than one standard error:
/// the mean over motions of the paired differences of their errors plus its standard error is
/// below zero. Of the clearly better ones, the lowest pooled error (the earliest on a tie).
///
/// The one-standard-error rule of model selection (Hastie, Tibshirani and Friedman, *The
/// Elements of Statistical Learning*, 2nd ed., section 7.10), paired by motion: the estimates of
/// the configurations lie within a few per cent of each other and the held-out frames of a
/// motion are near its other half, so the lowest estimate alone picks a configuration that
/// does worse on new motions as often as not (docs/studies/47-mean-ensemble.md).
pub fn keep(errors: &[CrossValidation]) -> usize {
    let Some(first) = errors.first() else { return 0 };
    let clearly_better = |e: &CrossValidation| {
        let d: Vec<f64> = e
            .motions
            .iter()
            .zip(&first.motions)
            .filter(|(a, b)| a.frames > 0 && b.frames > 0)
            .map(|(a, b)| a.rms_pose_m - b.rms_pose_m)
            .collect();
        let m = d.len() as f64;
        if d.len() < 2 {
            return false;
        }
        let mean = d.iter().sum::<f64>() / m;
        let sd = (d.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (m - 1.0)).sqrt();
        mean + sd / m.sqrt() < 0.0
    };
    (1..errors.len())
        .filter(|&c| clearly_better(&errors[c]))
        .min_by(|&a, &b| errors[a].cv_rms_pose_m.total_cmp(&errors[b].cv_rms_pose_m).then(a.cmp(&b)))
        .unwrap_or(0)
}

/// The limb log-orientations of every training pair's frames, when a candidate fits a limb
/// orientation (the candidates share the limbs measured in their attachment's frame).
fn orientation_logs(folds: &Folds, candidates: &[Candidate]) -> Result<Option<PairLogs>> {
    let Some(first) = candidates.iter().find(|c| c.orientation.weight != 0.0) else { return Ok(None) };
    if candidates.iter().any(|c| c.orientation.weight != 0.0 && c.orientation.attached != first.orientation.attached) {
        return Err(Error::invalid("cross-validated configurations measure their limbs in different frames"));
    }
    let frames = limb_orientation::frames(folds.target_pca, first.orientation.attached)?;
    let pairs: Vec<(&[DMatrix<f64>], &[DMatrix<f64>])> = folds.pairs.iter().map(|d| (d.source_coeffs.as_slice(), d.target_coeffs.as_slice())).collect();
    PairLogs::new(folds.source_pca, folds.target_pca, &frames, &pairs).map(Some)
}

/// A candidate's model trained on a fold's remaining `rows`, made from the pairs `order` names
/// (indices of `folds.pairs`); its limb orientation fitted from `logs`, the pairs'
/// log-orientations (the map [`crate::gpr_model::train_orientation`] fits on the same rows).
fn train_held_out(folds: &Folds, regression: &Regression, orientation: &OrientationOptions, rows: &TrainingRows, logs: Option<&PairLogs>, order: &[usize]) -> Result<GprModel> {
    let mut model: GprModel = train_rows(regression, folds.part_names, rows)?;
    if orientation.weight != 0.0 {
        let logs = logs.ok_or_else(|| Error::invalid("limb orientation without the pairs' log-orientations"))?;
        let set = if regression.method == Method::KeyposeAffine { rows.keys() } else { &rows.data };
        let maps = (0..folds.part_names.len()).map(|k| logs.fit(k, &set.origin, &|q| order[q])).collect::<Result<_>>()?;
        model.orientation = Some(LimbOrientation { weight: orientation.weight, maps });
    }
    Ok(model)
}

/// The target meshes (assembled, in the aligned frame) `model` predicts for the source frames
/// of `compared` of the held-out pair.
fn predict_held_out(folds: &Folds, model: &GprModel, held_out: &PairData, compared: &[[usize; 2]]) -> Result<Vec<Vec<Vector3<f64>>>> {
    let sources: Vec<usize> = compared.iter().map(|&[i, _]| i).collect();
    if let Some(&i) = sources.iter().find(|&&i| i >= held_out.source_disp.len()) {
        return Err(Error::invalid(format!("source frame {i} of the correspondences is outside the motion ({} frames)", held_out.source_disp.len())));
    }
    let xs: Vec<DMatrix<f64>> = held_out.source_coeffs.iter().map(|c| c.select_rows(sources.iter())).collect();
    let disp: Vec<[f64; 6]> = sources.iter().map(|&i| held_out.source_disp[i]).collect();
    let pred = predict(model, &xs, &displacement_matrix(&disp), false)?;
    let mut decoded = folds.target_pca.decode(&pred.coeffs)?;
    if let Some(o) = &model.orientation {
        crate::limb_orientation::apply(o, folds.source_pca, folds.target_pca, &xs, &mut decoded)?;
    }
    let plan = capture::assemble::plan(folds.target_pca)?;
    Ok(capture::assemble::assemble(&plan, folds.target_pca, &decoded))
}

/// Per candidate, the summed squared pose error of its `predicted` meshes against the truth
/// frames `compared` points to, read in one pass over the held-out motion's file.
fn held_out_errors(held_out: &HeldOut, compared: &[[usize; 2]], predicted: &[Vec<Vec<Vector3<f64>>>]) -> Result<Vec<f64>> {
    let mut wanted: BTreeMap<usize, Vec<usize>> = BTreeMap::new();
    for (c, &[_, j]) in compared.iter().enumerate() {
        wanted.entry(j).or_default().push(c);
    }
    let mut sums = vec![0.0; predicted.len()];
    let mut frame = 0;
    let (info, _) = read_frames(&held_out.truth, |truth| {
        if let Some(cs) = wanted.remove(&frame) {
            for (sum, meshes) in sums.iter_mut().zip(predicted) {
                let per_frame: Vec<f64> = cs.par_iter().map(|&c| meshes[c].as_slice()).map(|m| {
                    if m.len() == truth.len() { Ok(pose_sq_error(m, &truth)) } else { Err(m.len()) }
                }).collect::<std::result::Result<_, usize>>()
                .map_err(|n| Error::invalid(format!("{} vertices per frame, the prediction {n}: not the target's topology", truth.len())))?;
                *sum += per_frame.iter().sum::<f64>();
            }
        }
        frame += 1;
        Ok(())
    })?;
    if let Some((j, _)) = wanted.into_iter().next() {
        return Err(Error::file(
            &held_out.truth,
            format!("target frame {j} of the correspondences is outside the motion ({} frames)", info.n_frames),
        ));
    }
    Ok(sums)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each source frame is compared once, with the median of the target frames the path pairs
    /// it with: one when the path steps diagonally, the upper of two at twice the rate, the
    /// middle one of three.
    #[test]
    fn each_source_frame_is_compared_once_with_its_median_target_frame() {
        let path = [[0, 0], [0, 1], [1, 2], [1, 3], [2, 4], [3, 4], [4, 5], [4, 6], [4, 7]];
        assert_eq!(compared_frames(&path), vec![[0, 1], [1, 3], [2, 4], [3, 4], [4, 6]]);
    }

    fn errors(per_motion: &[f64]) -> CrossValidation {
        let motions: Vec<MotionError> = per_motion.iter().enumerate().map(|(m, &e)| MotionError { motion: format!("m{m}"), frames: 10, rms_pose_m: e }).collect();
        let pooled = (per_motion.iter().map(|e| e * e).sum::<f64>() / per_motion.len() as f64).sqrt();
        CrossValidation { cv_rms_pose_m: pooled, motions }
    }

    /// `keep`: the first candidate unless another's per-motion errors are lower by more than
    /// one standard error of their mean difference; of those, the lowest pooled error.
    #[test]
    fn auto_keeps_the_first_candidate_unless_another_is_better_by_a_standard_error() {
        let first = errors(&[0.030, 0.040, 0.050, 0.020]);
        // Lower pooled error, but one motion much worse: differences -0.004, -0.004, -0.004,
        // +0.008 (mean -0.001, standard error 0.003).
        let mixed = errors(&[0.026, 0.036, 0.046, 0.028]);
        assert!(mixed.cv_rms_pose_m < first.cv_rms_pose_m);
        assert_eq!(keep(&[first.clone(), mixed.clone()]), 0);
        // Lower on every motion by 2-4 mm: differences mean -0.003, standard error 0.0004.
        let better = errors(&[0.027, 0.037, 0.046, 0.018]);
        assert_eq!(keep(&[first.clone(), mixed.clone(), better.clone()]), 2);
        // Two clearly better: the lower pooled error; a tie goes to the earlier.
        let best = errors(&[0.020, 0.030, 0.040, 0.015]);
        assert_eq!(keep(&[first.clone(), better.clone(), best.clone()]), 2);
        assert_eq!(keep(&[first.clone(), best.clone(), best.clone()]), 1);
        // Equal errors are not better; one candidate is kept; one motion gives no standard error.
        assert_eq!(keep(&[first.clone(), first.clone()]), 0);
        assert_eq!(keep(std::slice::from_ref(&first)), 0);
        assert_eq!(keep(&[errors(&[0.05]), errors(&[0.01])]), 0);
    }

    fn pair(pairs: Vec<[usize; 2]>, keyposes: Vec<[usize; 2]>) -> PairData {
        PairData { source_coeffs: vec![], target_coeffs: vec![], source_disp: vec![], target_disp: vec![], pairs, keyposes }
    }

    /// Halves: every source frame of every pair is compared once, in the fold of its half; a
    /// half-fold keeps for training exactly the other half's correspondences and key-poses, so
    /// no fold trains on a source frame it compares. Motions: one fold per pair, nothing kept.
    #[test]
    fn each_half_of_each_motion_is_held_out_once_and_never_trained_on() {
        // Source frames 2-9 at twice the target's rate (pairs with two target frames each).
        let a = pair((2..10).flat_map(|i| [[i, 2 * i], [i, 2 * i + 1]]).collect(), vec![[2, 4], [5, 10], [9, 18]]);
        let b = pair(vec![[0, 0], [1, 0], [2, 1], [3, 2], [4, 2]], vec![[0, 0], [4, 2]]);
        let single = pair(vec![[7, 3], [7, 4]], vec![]);
        let pairs = [a, b, single];
        let folds = folds_of(&pairs, FoldUnit::Halves);
        assert_eq!(folds.iter().map(|f| f.pair).collect::<Vec<_>>(), vec![0, 0, 1, 1, 2]);
        for (p, data) in pairs.iter().enumerate() {
            let mine: Vec<&Fold> = folds.iter().filter(|f| f.pair == p).collect();
            let mut compared: Vec<[usize; 2]> = mine.iter().flat_map(|f| f.compared.clone()).collect();
            compared.sort();
            assert_eq!(compared, compared_frames(&data.pairs), "pair {p}: every source frame once");
            for f in &mine {
                let held: Vec<usize> = f.compared.iter().map(|&[i, _]| i).collect();
                match &f.kept {
                    Some(kept) => {
                        let others: Vec<[usize; 2]> = data.pairs.iter().copied().filter(|[i, _]| !held.contains(i)).collect();
                        assert_eq!(kept.pairs, others, "pair {p}: the other half's correspondences");
                        assert!(kept.keyposes.iter().all(|[i, _]| !held.contains(i)), "pair {p}: {:?}", kept.keyposes);
                        assert!(!kept.pairs.is_empty() && !held.is_empty());
                    }
                    None => assert_eq!(mine.len(), 1, "a pair of one source frame is held out whole"),
                }
            }
        }
        // The halves of `a` split its source frames 2-9 at 6; `b`'s 0-4 at 2 (frames 0-1 first).
        assert_eq!(folds[0].compared.iter().map(|&[i, _]| i).collect::<Vec<_>>(), vec![2, 3, 4, 5]);
        assert_eq!(folds[2].compared.iter().map(|&[i, _]| i).collect::<Vec<_>>(), vec![0, 1]);
        assert_eq!(folds[0].kept.as_ref().unwrap().keyposes, vec![[9, 18]]);

        let whole = folds_of(&pairs, FoldUnit::Motions);
        assert_eq!(whole.len(), 3);
        for (p, f) in whole.iter().enumerate() {
            assert!(f.pair == p && f.kept.is_none() && f.compared == compared_frames(&pairs[p].pairs));
        }
    }
}
