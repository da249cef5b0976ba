//! Bayesian linear regression association cost for temporal densification, CVPR eqs. 1-6.
//!
//! Per body part, target pose `y = M x + ε`, `ε ~ N(0, σ² I)` with `σ² = 0.01` (CVPR eqs. 1-2),
//! a unit Gaussian prior on the rows of `M`, and `L` key-pose pairs. In the paper's notation
//! `X = (x_1 .. x_L)` and `Y = (y_1 .. y_L)` stack the key-poses as **columns**; here they are
//! passed as rows (`L x m_s`, `L x m_t`), i.e. the transposes. With `A = X Xᵀ/σ² + I`:
//! - posterior mean of `M` (CVPR eq. 3): `M̄ = Y Xᵀ A⁻ᵀ / σ²`;
//! - predictive mean at `x_i` (CVPR eq. 4): `μ_i = M̄ x_i`;
//! - predictive variance (CVPR eq. 4): `Σ_i = (x_iᵀ A⁻¹ x_i) I`, isotropic;
//! - association cost (CVPR eq. 5): `-log P^k_ij = ½ |y_j - μ_i|² / (x_iᵀ A⁻¹ x_i)`;
//! - whole body (CVPR eq. 6): the product over parts becomes a **sum** of the per-part costs.
//!
//! `A` is factorised once (Cholesky, it is `I` plus a PSD matrix) and solved against; it is
//! never inverted. The predictive variance is that of `M x` (no added `σ²`), as in CVPR eq. 4; it is
//! floored at `1e-300` so that a source pose at the PCA origin gives a large finite cost
//! instead of `0/0`.

use crate::{check_finite, invalid, Result};
use nalgebra::{DMatrix, DVector};

/// The paper's noise variance for the key-pose linear model (after CVPR eq. 1).
pub const PAPER_SIGMA2: f64 = 0.01;

/// Smallest predictive variance used in the cost (see the module doc).
const VAR_FLOOR: f64 = 1e-300;

/// A per-part Bayesian linear map fitted on key-pose pairs.
#[derive(Clone, Debug)]
pub struct Blr {
    /// `M̄ᵀ` (`m_s x m_t`), so that predictive means are `X_s M̄ᵀ` for row-stacked inputs.
    mean_map_t: DMatrix<f64>,
    chol_a: nalgebra::Cholesky<f64, nalgebra::Dyn>,
    pub sigma2: f64,
}

impl Blr {
    /// Fits CVPR eq. 3 on key-pose pairs given as rows: `xk` (`L x m_s`), `yk` (`L x m_t`).
    pub fn fit(xk: &DMatrix<f64>, yk: &DMatrix<f64>, sigma2: f64) -> Result<Self> {
        if xk.nrows() != yk.nrows() || xk.nrows() == 0 {
            return invalid(format!(
                "Bayesian linear regression: {} source and {} target key-poses (need equal, >= 1)",
                xk.nrows(),
                yk.nrows()
            ));
        }
        if !(sigma2 > 0.0 && sigma2.is_finite()) {
            return invalid(format!("noise variance must be > 0, got {sigma2}"));
        }
        check_finite("source key-poses", xk)?;
        check_finite("target key-poses", yk)?;
        let ms = xk.ncols();
        // A = X Xᵀ / σ² + I (paper's column-stacked X = xkᵀ).
        let a = xk.transpose() * xk / sigma2 + DMatrix::identity(ms, ms);
        let chol_a = nalgebra::Cholesky::new(a).ok_or_else(|| {
            crate::GpError::Invalid("A = X Xᵀ/σ² + I not positive definite".into())
        })?;
        // M̄ᵀ = A⁻¹ X Yᵀ / σ²  (A symmetric).
        let mean_map_t = chol_a.solve(&(xk.transpose() * yk / sigma2));
        Ok(Self {
            mean_map_t,
            chol_a,
            sigma2,
        })
    }

    /// Predictive means `μ_i` (rows, `N x m_t`) and variances `x_iᵀ A⁻¹ x_i` (CVPR eq. 4) for the
    /// rows of `xs` (`N x m_s`).
    pub fn predict(&self, xs: &DMatrix<f64>) -> Result<(DMatrix<f64>, DVector<f64>)> {
        if xs.ncols() != self.mean_map_t.nrows() {
            return invalid(format!(
                "Bayesian linear regression: inputs have {} columns, the model expects {}",
                xs.ncols(),
                self.mean_map_t.nrows()
            ));
        }
        let mu = xs * &self.mean_map_t;
        let l = self.chol_a.l();
        let v = l
            .solve_lower_triangular(&xs.transpose())
            .ok_or_else(|| crate::GpError::Invalid("singular factor of A".into()))?;
        let var = DVector::from_iterator(xs.nrows(), v.column_iter().map(|c| c.norm_squared()));
        Ok((mu, var))
    }

    /// `-log P^k_ij` (CVPR eq. 5) for every source frame `i` (rows of `xs`, `f_s x m_s`) and target
    /// frame `j` (rows of `ys`, `f_t x m_t`): an `f_s x f_t` matrix.
    pub fn neg_log_cost(&self, xs: &DMatrix<f64>, ys: &DMatrix<f64>) -> Result<DMatrix<f64>> {
        if ys.ncols() != self.mean_map_t.ncols() {
            return invalid(format!(
                "Bayesian linear regression: target frames have {} columns, the model gives {}",
                ys.ncols(),
                self.mean_map_t.ncols()
            ));
        }
        let (mu, var) = self.predict(xs)?;
        Ok(DMatrix::from_fn(xs.nrows(), ys.nrows(), |i, j| {
            let d2 = (ys.row(j) - mu.row(i)).norm_squared();
            0.5 * d2 / var[i].max(VAR_FLOOR)
        }))
    }
}

/// One body part of one training pair: source and target frames (rows) of the part's PCA
/// coefficients.
pub struct PartFrames<'a> {
    pub source: &'a DMatrix<f64>,
    pub target: &'a DMatrix<f64>,
}

/// Whole-body association cost (CVPR eq. 6 as a sum of eq. 5 over parts): fits one [`Blr`] per
/// part on the key-pose pairs `keys` = `(source frame, target frame)` and returns the
/// `f_s x f_t` matrix of `-log P_ij`.
pub fn cost_matrix(
    parts: &[PartFrames<'_>],
    keys: &[(usize, usize)],
    sigma2: f64,
) -> Result<DMatrix<f64>> {
    let Some(first) = parts.first() else {
        return invalid("association cost needs at least one part");
    };
    let (fs, ft) = (first.source.nrows(), first.target.nrows());
    if keys.is_empty() {
        return invalid("association cost needs at least one key-pose pair");
    }
    let mut total = DMatrix::zeros(fs, ft);
    for (k, p) in parts.iter().enumerate() {
        if p.source.nrows() != fs || p.target.nrows() != ft {
            return invalid(format!(
                "part {k}: {} x {} frames, part 0 has {fs} x {ft}",
                p.source.nrows(),
                p.target.nrows()
            ));
        }
        if let Some(&(i, j)) = keys.iter().find(|&&(i, j)| i >= fs || j >= ft) {
            return invalid(format!(
                "key-pose ({i}, {j}) outside the {fs} x {ft} sequences"
            ));
        }
        let xk = DMatrix::from_fn(keys.len(), p.source.ncols(), |r, c| {
            p.source[(keys[r].0, c)]
        });
        let yk = DMatrix::from_fn(keys.len(), p.target.ncols(), |r, c| {
            p.target[(keys[r].1, c)]
        });
        total += Blr::fit(&xk, &yk, sigma2)?.neg_log_cost(p.source, p.target)?;
    }
    Ok(total)
}
