//! An affine mean function for GP regression: `m(x) = Wᵀ [x; 1]`, fitted by ridge-regularised
//! least squares on the training pairs, with the GP then trained on the residuals
//! `Y - m(X)` (Rasmussen & Williams §2.7, "explicit basis functions", with the basis
//! coefficients fixed at their least-squares estimate).
//!
//! Why: a zero-mean GP (CVPR eq. 11) predicts `K_* α`, which falls back toward the prior
//! mean, 0 (the PCA mean pose), or toward training poses, as the input moves away from the
//! training inputs. With the affine mean, far from the data the prediction degrades to the
//! best linear mapping between the two subjects' coefficient spaces instead.
//!
//! ```text
//! W = argmin ‖[X 1] W - Y‖² + λ ‖W‖²,   (Xᵀ_1 X_1 + λ I) W = Xᵀ_1 Y,   X_1 = [X 1]
//! ```
//! solved by Cholesky (no inverse formed); `λ = ridge · tr(Xᵀ_1 X_1) / (m + 1)`, a relative
//! regulariser. At [`DEFAULT_RIDGE`] it only matters when `X` is rank deficient (fewer pairs
//! than input dimensions, e.g. key-poses only); larger values shrink the map along the input
//! directions the training inputs barely span.

use crate::linalg::Cholesky;
use crate::{check_finite, invalid, Result};
use nalgebra::DMatrix;
use serde::{Deserialize, Serialize};

/// Default relative ridge of [`AffineMean::fit`].
pub const DEFAULT_RIDGE: f64 = 1e-6;

/// `m(x) = Wᵀ [x; 1]` with `W` of shape `(d + 1) x p`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct AffineMean {
    /// Rows `0..d` multiply the input, row `d` is the offset.
    pub w: DMatrix<f64>,
}

fn with_ones(x: &DMatrix<f64>) -> DMatrix<f64> {
    let (n, d) = x.shape();
    DMatrix::from_fn(n, d + 1, |r, c| if c < d { x[(r, c)] } else { 1.0 })
}

impl AffineMean {
    /// The shape prediction relies on, for a map read from a file: `(d + 1) x p` finite
    /// weights. The error is the problem.
    pub fn validate(&self, d: usize, p: usize) -> std::result::Result<(), String> {
        if self.w.shape() != (d + 1, p) {
            return Err(format!("affine mean of {} x {} for {d} inputs and {p} outputs", self.w.nrows(), self.w.ncols()));
        }
        if !self.w.iter().all(|v| v.is_finite()) {
            return Err("affine mean has a non-finite weight".into());
        }
        Ok(())
    }

    /// Ridge least squares of `y` (`n x p`) on `[x 1]` (`x`: `n x d`); `ridge` relative to
    /// the mean diagonal of `X_1ᵀ X_1`. `notes` receives any jitter retry of the solve.
    pub fn fit(
        x: &DMatrix<f64>,
        y: &DMatrix<f64>,
        ridge: f64,
        notes: &mut Vec<String>,
    ) -> Result<Self> {
        Self::fit_toward(x, y, ridge, None, notes)
    }

    /// As [`AffineMean::fit`], shrunk toward `prior` (`(d + 1) x p`) instead of zero:
    /// `W = argmin ‖Y - X_1 W‖² + λ ‖W - W_0‖²`, i.e. `(X_1ᵀ X_1 + λ I) W = X_1ᵀ Y + λ W_0`.
    pub fn fit_toward(
        x: &DMatrix<f64>,
        y: &DMatrix<f64>,
        ridge: f64,
        prior: Option<&DMatrix<f64>>,
        notes: &mut Vec<String>,
    ) -> Result<Self> {
        if x.nrows() == 0 || x.nrows() != y.nrows() {
            return invalid(format!(
                "affine mean: {} input rows and {} output rows",
                x.nrows(),
                y.nrows()
            ));
        }
        if !(ridge >= 0.0 && ridge.is_finite()) {
            return invalid(format!("affine mean: ridge must be >= 0, got {ridge}"));
        }
        check_finite("affine mean inputs", x)?;
        check_finite("affine mean outputs", y)?;
        let x1 = with_ones(x);
        let mut a = x1.tr_mul(&x1);
        let k = a.nrows();
        let lambda = ridge * (0..k).map(|i| a[(i, i)]).sum::<f64>() / k as f64;
        for i in 0..k {
            a[(i, i)] += lambda;
        }
        let mut rhs = x1.tr_mul(y);
        if let Some(w0) = prior {
            if w0.shape() != rhs.shape() {
                return invalid(format!(
                    "affine mean: prior of shape {:?}, the map is {:?}",
                    w0.shape(),
                    rhs.shape()
                ));
            }
            check_finite("affine mean prior", w0)?;
            rhs += w0 * lambda;
        }
        let chol = Cholesky::new(&a, "affine mean normal equations", notes)?;
        Ok(AffineMean { w: chol.solve(&rhs) })
    }

    /// Input dimension `d`.
    pub fn input_dim(&self) -> usize {
        self.w.nrows().saturating_sub(1)
    }

    /// `m(x)` for every row of `xs` (`n x d` -> `n x p`).
    pub fn predict(&self, xs: &DMatrix<f64>) -> Result<DMatrix<f64>> {
        if xs.ncols() != self.input_dim() {
            return invalid(format!(
                "affine mean: inputs have {} columns, the mean was fitted on {}",
                xs.ncols(),
                self.input_dim()
            ));
        }
        Ok(with_ones(xs) * &self.w)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An exactly affine map is recovered (to the tiny ridge's shrinkage) and extrapolates.
    #[test]
    fn recovers_an_affine_map_and_extrapolates() {
        let x = DMatrix::from_fn(40, 3, |r, c| (r as f64 * (0.31 + 0.17 * c as f64) + c as f64).sin());
        let w = DMatrix::from_row_slice(3, 2, &[0.5, -1.0, 2.0, 0.3, -0.7, 1.5]);
        let b = [0.25, -0.4];
        let y = DMatrix::from_fn(40, 2, |r, c| (x.row(r) * w.column(c))[0] + b[c]);
        let mut notes = Vec::new();
        let m = AffineMean::fit(&x, &y, 1e-12, &mut notes).unwrap();
        assert!(notes.is_empty());
        // Far outside the training inputs (|x| <= 1 there).
        let far = DMatrix::from_row_slice(1, 3, &[10.0, -8.0, 5.0]);
        let got = m.predict(&far).unwrap();
        for c in 0..2 {
            let want = (far.row(0) * w.column(c))[0] + b[c];
            assert!((got[c] - want).abs() < 1e-8, "{c}: {} vs {want}", got[c]);
        }
        assert!(m.predict(&DMatrix::zeros(1, 2)).is_err());
    }

    /// Fewer samples than dimensions: the ridge keeps the solve well posed and the fit
    /// interpolates the samples closely.
    #[test]
    fn rank_deficient_inputs_are_regularised() {
        let x = DMatrix::from_fn(3, 10, |r, c| ((r * 10 + c) as f64 * 0.9).cos());
        let y = DMatrix::from_fn(3, 1, |r, _| r as f64);
        let mut notes = Vec::new();
        let m = AffineMean::fit(&x, &y, DEFAULT_RIDGE, &mut notes).unwrap();
        let p = m.predict(&x).unwrap();
        for r in 0..3 {
            assert!((p[r] - r as f64).abs() < 1e-3, "{r}: {}", p[r]);
        }
    }

    /// Along an input direction the data never excite the fit keeps the prior's slope (zero
    /// without a prior); along the excited ones it follows the data; a prior of the wrong shape
    /// is an error.
    #[test]
    fn shrinks_toward_the_prior_where_the_data_say_nothing() {
        // Inputs vary in column 0 only; y = 2 x0 + 1.
        let x = DMatrix::from_fn(30, 2, |r, c| if c == 0 { (r as f64 * 0.37).sin() } else { 0.0 });
        let y = DMatrix::from_fn(30, 1, |r, _| 2.0 * x[(r, 0)] + 1.0);
        let prior = DMatrix::from_row_slice(3, 1, &[0.0, 5.0, 0.0]);
        let mut notes = Vec::new();
        let with = AffineMean::fit_toward(&x, &y, 1e-3, Some(&prior), &mut notes).unwrap();
        let without = AffineMean::fit(&x, &y, 1e-3, &mut notes).unwrap();
        assert!((with.w[(0, 0)] - 2.0).abs() < 0.05 && (with.w[(2, 0)] - 1.0).abs() < 0.05);
        assert!((with.w[(1, 0)] - 5.0).abs() < 1e-9, "unexcited slope {}", with.w[(1, 0)]);
        assert!(without.w[(1, 0)].abs() < 1e-9);
        let wrong = DMatrix::zeros(2, 1);
        assert!(AffineMean::fit_toward(&x, &y, 1e-3, Some(&wrong), &mut notes).is_err());
    }
}
