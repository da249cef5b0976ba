//! Dense linear algebra on faer matrices, always sequential (`Par::Seq`): rayon
//! parallelism, if any, lives above this level (one chain or one body part per thread).
//!
//! Only Cholesky factorisations and triangular solves: no explicit inverse is formed.

use crate::error::{GpdmError, Result};
use dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::{cholesky_in_place, cholesky_in_place_scratch};
use faer::linalg::matmul::matmul;
use faer::linalg::triangular_solve::{
    solve_lower_triangular_in_place, solve_upper_triangular_in_place,
};
use faer::reborrow::ReborrowMut;
use faer::{Accum, Mat, MatMut, MatRef, Par};

/// Number of jitter retries after the plain factorisation fails.
const JITTER_RETRIES: usize = 6;

/// Cholesky factor `K + jitter I = L Lᵀ` of a symmetric positive definite matrix.
#[derive(Clone, Debug)]
pub struct Cholesky {
    /// Lower-triangular factor (the strict upper triangle is zero).
    pub l: Mat<f64>,
    /// Diagonal jitter that had to be added (0 when the plain factorisation succeeded).
    pub jitter: f64,
}

impl Cholesky {
    /// Factors `k`; on failure retries with jitter `1e-10·mean(diag)·10^i`, i = 0..6.
    /// The jitter used is returned in [`Cholesky::jitter`] so that callers can log it.
    pub fn factor(k: MatRef<'_, f64>, what: &'static str) -> Result<Self> {
        let n = k.nrows();
        let mean_diag = (0..n).map(|i| k[(i, i)]).sum::<f64>() / n.max(1) as f64;
        let base = 1e-10 * mean_diag.abs().max(f64::MIN_POSITIVE);
        let mut mem = MemBuffer::new(cholesky_in_place_scratch::<f64>(
            n,
            Par::Seq,
            Default::default(),
        ));
        let mut last_pivot = 0;
        let mut jitter = 0.0;
        for attempt in 0..=JITTER_RETRIES {
            jitter = if attempt == 0 {
                0.0
            } else {
                base * 10f64.powi(attempt as i32 - 1)
            };
            let mut l = k.to_owned();
            for i in 0..n {
                l[(i, i)] += jitter;
            }
            let ok = if l.as_ref().is_all_finite() {
                cholesky_in_place(
                    l.as_mut(),
                    Default::default(),
                    Par::Seq,
                    MemStack::new(&mut mem),
                    Default::default(),
                )
                .map_err(|e| match e {
                    faer::linalg::cholesky::llt::factor::LltError::NonPositivePivot { index } => {
                        index
                    }
                })
            } else {
                Err(0)
            };
            match ok {
                Ok(_) => {
                    for j in 0..n {
                        for i in 0..j {
                            l[(i, j)] = 0.0;
                        }
                    }
                    return Ok(Cholesky { l, jitter });
                }
                Err(p) => last_pivot = p,
            }
        }
        Err(GpdmError::NotPositiveDefinite {
            what,
            pivot: last_pivot,
            jitter,
        })
    }

    /// `ln |K| = 2 Σ ln L_ii`.
    pub fn logdet(&self) -> f64 {
        2.0 * (0..self.l.nrows())
            .map(|i| self.l[(i, i)].ln())
            .sum::<f64>()
    }

    /// `rhs ← L⁻¹ rhs`.
    pub fn half_solve_in_place(&self, rhs: MatMut<'_, f64>) {
        solve_lower_triangular_in_place(self.l.as_ref(), rhs, Par::Seq);
    }

    /// `rhs ← L⁻ᵀ rhs`.
    pub fn half_solve_t_in_place(&self, rhs: MatMut<'_, f64>) {
        solve_upper_triangular_in_place(self.l.as_ref().transpose(), rhs, Par::Seq);
    }

    /// `rhs ← K⁻¹ rhs` by two triangular solves.
    pub fn solve_in_place(&self, mut rhs: MatMut<'_, f64>) {
        self.half_solve_in_place(rhs.rb_mut());
        self.half_solve_t_in_place(rhs);
    }

    /// `K⁻¹ rhs`.
    pub fn solve(&self, rhs: MatRef<'_, f64>) -> Mat<f64> {
        let mut out = rhs.to_owned();
        self.solve_in_place(out.as_mut());
        out
    }

    /// `L⁻ᵀ Q L⁻¹` for a symmetric `Q`, by two triangular solves with n right-hand sides.
    /// This is how `K⁻¹ (·) K⁻¹`-type gradient matrices are formed without an inverse. The
    /// result is symmetric up to rounding; callers read its lower triangle.
    pub fn sandwich(&self, q: MatRef<'_, f64>) -> Mat<f64> {
        // E = L⁻ᵀ Q ; result = E L⁻¹ = (L⁻ᵀ Eᵀ)ᵀ, solved in place on the transposed view.
        let mut e = q.to_owned();
        self.half_solve_t_in_place(e.as_mut());
        self.half_solve_t_in_place(e.as_mut().transpose_mut());
        e
    }
}

/// `A Bᵀ`, sequential.
pub fn mul_abt(a: MatRef<'_, f64>, b: MatRef<'_, f64>) -> Mat<f64> {
    let mut out = Mat::zeros(a.nrows(), b.nrows());
    matmul(
        out.as_mut(),
        Accum::Replace,
        a,
        b.transpose(),
        1.0,
        Par::Seq,
    );
    out
}

/// `A B`, sequential.
pub fn mul(a: MatRef<'_, f64>, b: MatRef<'_, f64>) -> Mat<f64> {
    let mut out = Mat::zeros(a.nrows(), b.ncols());
    matmul(out.as_mut(), Accum::Replace, a, b, 1.0, Par::Seq);
    out
}

/// View a column-major nalgebra matrix as a faer matrix (no copy).
pub fn view(m: &nalgebra::DMatrix<f64>) -> MatRef<'_, f64> {
    MatRef::from_column_major_slice(m.as_slice(), m.nrows(), m.ncols())
}

/// Copy a faer matrix into a nalgebra matrix.
pub fn to_na(m: MatRef<'_, f64>) -> nalgebra::DMatrix<f64> {
    nalgebra::DMatrix::from_fn(m.nrows(), m.ncols(), |i, j| m[(i, j)])
}
