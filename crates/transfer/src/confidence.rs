//! Per-frame confidence of a transfer, for users without ground truth: how far each source
//! frame is from what the model was trained on, per body part and for the displacement.
//!
//! - `variance_ratio`: the GP's latent predictive variance (CVPR eq. 12) divided by its
//!   prior variance `k(x, x)`: 0 on the training inputs, 1 where the training data says
//!   nothing. For the affine key-pose baseline there is no GP: `null`.
//! - `nearest_distance`: the Euclidean distance from the source coefficients to the nearest
//!   training input, divided by the training inputs' RMS distance to their mean (so 1 is "as
//!   far from the nearest training pose as a typical training pose is from the mean pose").
//!
//! Written by `gpr-predict --confidence` as JSON: `{"parts": [...], "frames": N,
//! "variance_ratio": {part: [per frame]}, "nearest_distance": {part: [per frame]}}`, the
//! displacement under the name `displacement`.

use std::collections::BTreeMap;

use mesh_core::{Error, Result};
use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::gpr_model::{GprModel, Regressor};

/// Per-frame confidence figures of one transfer (see the module documentation).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Confidence {
    /// Part names, then `displacement`.
    pub parts: Vec<String>,
    pub frames: usize,
    pub variance_ratio: BTreeMap<String, Series>,
    pub nearest_distance: BTreeMap<String, Series>,
}

/// One figure per frame, or `None` where a regressor has no GP.
type Series = Option<Vec<f64>>;

/// `(variance ratio, normalised nearest distance)` per row of `xs` for one regressor.
fn of_regressor(reg: &Regressor, xs: &DMatrix<f64>) -> Result<(Series, Series)> {
    let Some(gpr) = reg.gp() else {
        return Ok((None, None));
    };
    let mut notes = Vec::new();
    let (_, var) = gpr
        .predict_with_variance(xs, &mut notes)
        .map_err(|e| Error::invalid(e.to_string()))?;
    for n in notes {
        mesh_core::warn!("confidence: {n}");
    }
    let ratio = ratio_to_prior(&var, &gpr.kernel.diag(xs));
    Ok((Some(ratio), Some(nearest_distances(gpr.inputs(), xs))))
}

/// Latent predictive variances over the prior variances `k(x, x)`, clamped to [0, 1]
/// (1 where the prior variance is 0).
pub fn ratio_to_prior(var: &DVector<f64>, prior: &DVector<f64>) -> Vec<f64> {
    var.iter()
        .zip(prior.iter())
        .map(|(v, p)| if *p > 0.0 { (v / p).clamp(0.0, 1.0) } else { 1.0 })
        .collect()
}

/// Distance from each row of `xs` to the nearest row of `train`, divided by the RMS distance
/// of `train`'s rows to their mean (1 when that spread is 0).
pub fn nearest_distances(train: &DMatrix<f64>, xs: &DMatrix<f64>) -> Vec<f64> {
    let (n, d) = train.shape();
    let mean: Vec<f64> = (0..d).map(|c| train.column(c).sum() / n.max(1) as f64).collect();
    let spread = ((0..n)
        .map(|r| (0..d).map(|c| (train[(r, c)] - mean[c]).powi(2)).sum::<f64>())
        .sum::<f64>()
        / n.max(1) as f64)
        .sqrt();
    let scale = if spread > 0.0 { spread } else { 1.0 };
    (0..xs.nrows())
        .into_par_iter()
        .map(|i| {
            let best = (0..n)
                .map(|r| (0..d).map(|c| (train[(r, c)] - xs[(i, c)]).powi(2)).sum::<f64>())
                .fold(f64::INFINITY, f64::min);
            best.sqrt() / scale
        })
        .collect()
}

/// The confidence of `model` at source coefficients `source_coeffs` (per part, `N x m_k`)
/// and source displacements `source_disp` (`N x 6`).
pub fn confidence(
    model: &GprModel,
    source_coeffs: &[DMatrix<f64>],
    source_disp: &DMatrix<f64>,
) -> Result<Confidence> {
    if source_coeffs.len() != model.parts.len() {
        return Err(Error::invalid(format!(
            "{} coefficient blocks for the model's {} parts",
            source_coeffs.len(),
            model.parts.len()
        )));
    }
    let mut names = model.part_names.clone();
    names.push("displacement".into());
    let mut inputs: Vec<(&Regressor, &DMatrix<f64>)> =
        model.parts.iter().zip(source_coeffs).collect();
    inputs.push((&model.displacement, source_disp));
    let figures = inputs
        .par_iter()
        .map(|(reg, xs)| of_regressor(reg, xs))
        .collect::<Result<Vec<_>>>()?;
    let mut variance_ratio = BTreeMap::new();
    let mut nearest_distance = BTreeMap::new();
    for (name, (v, d)) in names.iter().zip(figures) {
        variance_ratio.insert(name.clone(), v);
        nearest_distance.insert(name.clone(), d);
    }
    Ok(Confidence { parts: names, frames: source_disp.nrows(), variance_ratio, nearest_distance })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Distances are exact on a hand-made set: training rows at 0 and 2 on a line (mean 1,
    /// RMS spread 1); a query at 2 is on a training input, one at 5 is 3 away.
    #[test]
    fn nearest_distances_are_normalised_by_the_spread() {
        let train = DMatrix::from_row_slice(2, 1, &[0.0, 2.0]);
        let xs = DMatrix::from_row_slice(3, 1, &[2.0, 5.0, 1.0]);
        assert_eq!(nearest_distances(&train, &xs), vec![0.0, 3.0, 1.0]);
    }
}
