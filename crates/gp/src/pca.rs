//! Principal component analysis of a part's vertex coordinates (section 4, "PCA Dimension
//! Reduction"): each aligned part pose (a row of `3 x vertices` coordinates) becomes
//! `m` coefficients (`m = 20` in the paper).
//!
//! The data matrix is `F x D` with possibly `D >> F`, so the fit never forms the `D x D`
//! covariance: it eigen-decomposes the `F x F` Gram matrix `G = X̄ X̄ᵀ` of the centred data
//! (`X̄ = X - 1 μᵀ`), `G = U Λ Uᵀ`, and the principal axes are `v_k = X̄ᵀ u_k / sqrt(λ_k)`
//! (the right singular vectors of `X̄`). Component variances are `λ_k / (F - 1)`. When the
//! frames outnumber the dimensions (`F > D`: minutes-long training motions, e.g. synth's `long`
//! preset, 12,000 frames of a 700-D part), it eigen-decomposes the `D x D` matrix `X̄ᵀ X̄`
//! instead, whose eigenvectors are the axes and whose eigenvalues are the same `λ_k`: the cost
//! is `O(F D² + D³)` instead of `O(F² D + F³)` (the `F x F` route took over 11 minutes for one
//! part of 12,000 frames).

use crate::{check_finite, invalid, linalg, Result};
use nalgebra::{DMatrix, DVector};
use serde::{Deserialize, Serialize};

/// The paper's number of coefficients per part.
pub const PAPER_COMPONENTS: usize = 20;

/// How many components to keep.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum Components {
    /// A fixed count, capped at the rank of the centred data.
    Count(usize),
    /// The fewest components whose cumulative explained-variance ratio reaches this
    /// fraction (in `(0, 1]`).
    ExplainedVariance(f64),
}

impl Default for Components {
    fn default() -> Self {
        Components::Count(PAPER_COMPONENTS)
    }
}

/// A fitted PCA basis.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Pca {
    /// Data mean `μ` (length `D`).
    pub mean: DVector<f64>,
    /// Principal axes as **rows** (`m x D`, orthonormal rows).
    pub components: DMatrix<f64>,
    /// Variance along each kept axis, decreasing (`λ_k / (F - 1)`).
    pub variances: Vec<f64>,
    /// Total variance of the data (sum over all axes).
    pub total_variance: f64,
    /// Rank of the centred data (number of non-negligible axes).
    pub rank: usize,
}

impl Pca {
    /// Fits the basis on the rows of `data` (`F x D`, `F >= 2`).
    pub fn fit(data: &DMatrix<f64>, choice: Components) -> Result<Self> {
        let (f, d) = (data.nrows(), data.ncols());
        if choice == Components::Count(0) {
            return invalid("the PCA needs at least 1 component, got 0");
        }
        if f < 2 || d == 0 {
            return invalid(format!(
                "PCA needs at least 2 frames and 1 dimension, got {f} x {d}"
            ));
        }
        check_finite("PCA data", data)?;
        let mean = data.row_mean().transpose();
        let mut centred = data.clone();
        for mut row in centred.row_iter_mut() {
            row -= mean.transpose();
        }
        let by_frames = f <= d;
        let gram = if by_frames { &centred * centred.transpose() } else { centred.transpose() * &centred };
        let (lambda, u) = linalg::symmetric_eigen(&gram)?;
        let total: f64 = lambda.iter().map(|v| v.max(0.0)).sum();
        let tol = lambda[0].max(0.0) * (f.max(d) as f64) * f64::EPSILON * 10.0;
        let rank = lambda.iter().take_while(|&&v| v > tol && v > 0.0).count();
        let m = match choice {
            Components::Count(m) => m.min(rank),
            Components::ExplainedVariance(r) => {
                if !(r > 0.0 && r <= 1.0) {
                    return invalid(format!(
                        "explained-variance ratio must be in (0, 1], got {r}"
                    ));
                }
                let mut acc = 0.0;
                let mut m = rank;
                for (k, v) in lambda.iter().take(rank).enumerate() {
                    acc += v;
                    if acc >= r * total * (1.0 - 1e-12) {
                        m = k + 1;
                        break;
                    }
                }
                m
            }
        };
        // v_k = X̄ᵀ u_k / sqrt(λ_k) (or the eigenvector itself for F > D), stored as rows.
        let u_m = u.columns(0, m);
        let components = if by_frames {
            let mut c = (centred.transpose() * u_m).transpose();
            for k in 0..m {
                let s = lambda[k].sqrt();
                c.row_mut(k).unscale_mut(s);
            }
            c
        } else {
            u_m.transpose()
        };
        let denom = (f - 1) as f64;
        Ok(Self {
            mean,
            components,
            variances: lambda[..m].iter().map(|v| v / denom).collect(),
            total_variance: total / denom,
            rank,
        })
    }

    /// Number of kept components `m`.
    pub fn n_components(&self) -> usize {
        self.components.nrows()
    }

    /// Data dimension `D`.
    pub fn dim(&self) -> usize {
        self.mean.len()
    }

    /// Fraction of the total variance explained by each kept component.
    pub fn explained_variance_ratio(&self) -> Vec<f64> {
        let t = self.total_variance.max(f64::MIN_POSITIVE);
        self.variances.iter().map(|v| v / t).collect()
    }

    fn check_dim(&self, n: usize, what: &str) -> Result<()> {
        if n != self.dim() {
            return invalid(format!(
                "PCA {what}: data has {n} columns, the basis expects {}",
                self.dim()
            ));
        }
        Ok(())
    }

    /// Coefficients `(x - μ) Vᵀ` of every row of `data` (`F x D` -> `F x m`).
    pub fn encode(&self, data: &DMatrix<f64>) -> Result<DMatrix<f64>> {
        self.check_dim(data.ncols(), "encode")?;
        let mut c = data * self.components.transpose();
        let mc = &self.components * &self.mean;
        for mut row in c.row_iter_mut() {
            row -= mc.transpose();
        }
        Ok(c)
    }

    /// Reconstruction `μ + c V` of every row of `coeffs` (`F x m` -> `F x D`).
    pub fn decode(&self, coeffs: &DMatrix<f64>) -> Result<DMatrix<f64>> {
        if coeffs.ncols() != self.n_components() {
            return invalid(format!(
                "PCA decode: {} coefficients per row, the basis has {}",
                coeffs.ncols(),
                self.n_components()
            ));
        }
        let mut x = coeffs * &self.components;
        for mut row in x.row_iter_mut() {
            row += self.mean.transpose();
        }
        Ok(x)
    }

    /// Root-mean-square difference per coordinate between `data` and its reconstruction
    /// `decode(encode(data))`.
    pub fn reconstruction_rms(&self, data: &DMatrix<f64>) -> Result<f64> {
        let rec = self.decode(&self.encode(data)?)?;
        Ok(((rec - data).norm_squared() / data.len().max(1) as f64).sqrt())
    }
}
