//! The Semantic Deformation Transfer baseline (Baran, Vlasic, Grinspun, Popović 2009, the
//! paper's reference [3]): a source pose is written as an **affine** combination of the
//! source key-poses (least squares, weights summing to 1), and the same weights combine the
//! target key-poses.
//!
//! With source key-poses `s_0 .. s_{L-1}` and target key-poses `t_0 .. t_{L-1}`:
//! `w_1.. = argmin |x - s_0 - Σ_{k>=1} w_k (s_k - s_0)|²` (minimum-norm solution by SVD when
//! the key-poses are affinely dependent), `w_0 = 1 - Σ_{k>=1} w_k`, `y = Σ_k w_k t_k`.
//!
//! Deviation: Baran et al. combine poses in a rotation/scale feature space of deformation
//! gradients; here poses are whatever vectors the caller passes (PCA coefficients of parts, or
//! the whole body), which is how the CVPR 2017 paper compares against it.

use crate::{check_finite, invalid, Result};
use nalgebra::DMatrix;
use serde::{Deserialize, Serialize};

/// Key-pose pairs of the affine mapping.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct AffineKeypose {
    /// Source key-poses as rows (`L x D_s`).
    pub source_keys: DMatrix<f64>,
    /// Target key-poses as rows (`L x D_t`).
    pub target_keys: DMatrix<f64>,
}

impl AffineKeypose {
    /// Stores `L >= 1` key-pose pairs (rows of `source_keys` and `target_keys`).
    pub fn fit(source_keys: &DMatrix<f64>, target_keys: &DMatrix<f64>) -> Result<Self> {
        if source_keys.nrows() != target_keys.nrows() || source_keys.nrows() == 0 {
            return invalid(format!(
                "affine key-pose mapping: {} source and {} target key-poses (need equal, >= 1)",
                source_keys.nrows(),
                target_keys.nrows()
            ));
        }
        check_finite("source key-poses", source_keys)?;
        check_finite("target key-poses", target_keys)?;
        Ok(Self {
            source_keys: source_keys.clone(),
            target_keys: target_keys.clone(),
        })
    }

    /// What [`AffineKeypose::fit`] guarantees, for a mapping read from a file. The error is
    /// the problem.
    pub fn validate(&self) -> std::result::Result<(), String> {
        if self.source_keys.nrows() != self.target_keys.nrows() || self.source_keys.nrows() == 0 {
            return Err(format!(
                "affine key-pose mapping of {} source and {} target key-poses",
                self.source_keys.nrows(),
                self.target_keys.nrows()
            ));
        }
        if !self.source_keys.iter().chain(self.target_keys.iter()).all(|v| v.is_finite()) {
            return Err("affine key-pose mapping has a non-finite key-pose".into());
        }
        Ok(())
    }

    /// Affine weights (`N x L`, rows sum to 1) of every row of `xs` (`N x D_s`).
    pub fn weights(&self, xs: &DMatrix<f64>) -> Result<DMatrix<f64>> {
        let (l, ds) = (self.source_keys.nrows(), self.source_keys.ncols());
        if xs.ncols() != ds {
            return invalid(format!(
                "affine key-pose mapping: inputs have {} columns, expected {ds}",
                xs.ncols()
            ));
        }
        let n = xs.nrows();
        let mut w = DMatrix::zeros(n, l);
        if l == 1 {
            w.fill(1.0);
            return Ok(w);
        }
        let s0 = self.source_keys.row(0);
        // Columns s_k - s_0, k = 1..L-1 (D_s x (L-1)).
        let basis = DMatrix::from_fn(ds, l - 1, |r, c| self.source_keys[(c + 1, r)] - s0[r]);
        let rhs = DMatrix::from_fn(ds, n, |r, c| xs[(c, r)] - s0[r]);
        let svd = basis.svd(true, true);
        let tol = svd.singular_values.max() * (ds.max(l) as f64) * f64::EPSILON * 10.0;
        let sol = svd
            .solve(&rhs, tol)
            .map_err(|e| crate::GpError::Invalid(e.to_string()))?;
        for i in 0..n {
            let mut sum = 0.0;
            for k in 1..l {
                w[(i, k)] = sol[(k - 1, i)];
                sum += sol[(k - 1, i)];
            }
            w[(i, 0)] = 1.0 - sum;
        }
        Ok(w)
    }

    /// Transferred poses `W T` (`N x D_t`) for the rows of `xs`.
    pub fn predict(&self, xs: &DMatrix<f64>) -> Result<DMatrix<f64>> {
        check_finite("affine key-pose inputs", xs)?;
        Ok(self.weights(xs)? * &self.target_keys)
    }
}
