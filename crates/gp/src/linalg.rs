//! Dense symmetric positive-definite solves: Cholesky (faer) with a logged jitter retry.
//!
//! faer's dense Cholesky was the fastest option measured on this machine (STACK.md:
//! 1.6 ms for 500 x 500 versus 4.7 ms nalgebra). Matrices cross the boundary as
//! column-major slices, so no copies are made for the factorisation input.

use crate::{GpError, Result};
use faer::linalg::solvers::{DenseSolveCore, Solve};
use faer::{Mat, MatMut, MatRef, Side};
use nalgebra::DMatrix;

/// Jitter ladder, relative to the mean of the diagonal: tried in order after a plain
/// factorisation fails.
const JITTER_LADDER: [f64; 6] = [1e-10, 1e-8, 1e-6, 1e-5, 1e-4, 1e-3];

/// A Cholesky factorisation `A + jitter I = L Lᵀ`.
pub struct Cholesky {
    llt: faer::linalg::solvers::Llt<f64>,
    /// Absolute jitter that was added to the diagonal (0 when none was needed).
    pub jitter: f64,
}

fn view(a: &DMatrix<f64>) -> MatRef<'_, f64> {
    MatRef::from_column_major_slice(a.as_slice(), a.nrows(), a.ncols())
}

fn view_mut(a: &mut DMatrix<f64>) -> MatMut<'_, f64> {
    let (r, c) = (a.nrows(), a.ncols());
    MatMut::from_column_major_slice_mut(a.as_mut_slice(), r, c)
}

impl Cholesky {
    /// Factorises the symmetric matrix `a` (only its lower triangle is read). If the plain
    /// factorisation fails, retries with `jitter = c * mean(diag a)` for `c` in 1e-10..1e-3,
    /// pushing one line per retry into `notes` (`what` names the matrix in the note).
    pub fn new(a: &DMatrix<f64>, what: &str, notes: &mut Vec<String>) -> Result<Self> {
        let n = a.nrows();
        if n != a.ncols() {
            return crate::invalid(format!(
                "{what}: Cholesky of a non-square {n}x{} matrix",
                a.ncols()
            ));
        }
        if let Ok(llt) = view(a).llt(Side::Lower) {
            return Ok(Self { llt, jitter: 0.0 });
        }
        let mean_diag = (0..n).map(|i| a[(i, i)].abs()).sum::<f64>() / n.max(1) as f64;
        let scale = if mean_diag > 0.0 && mean_diag.is_finite() {
            mean_diag
        } else {
            1.0
        };
        let mut jittered = a.clone();
        let mut last = 0.0;
        for c in JITTER_LADDER {
            let jitter = c * scale;
            for i in 0..n {
                jittered[(i, i)] = a[(i, i)] + jitter;
            }
            last = jitter;
            match view(&jittered).llt(Side::Lower) {
                Ok(llt) => {
                    notes.push(format!(
                        "{what}: not positive definite, added jitter {jitter:.3e} to the diagonal"
                    ));
                    return Ok(Self { llt, jitter });
                }
                Err(_) => continue,
            }
        }
        Err(GpError::NotPositiveDefinite {
            what: what.to_string(),
            jitter: last,
        })
    }

    /// Dimension of the factorised matrix.
    pub fn dim(&self) -> usize {
        self.llt.L().nrows()
    }

    /// Solves `A X = B` for all columns of `B` at once (two triangular solves).
    pub fn solve(&self, b: &DMatrix<f64>) -> DMatrix<f64> {
        let mut x = b.clone();
        self.llt.solve_in_place(view_mut(&mut x));
        x
    }

    /// `log |A| = 2 Σ log L_ii`.
    pub fn log_det(&self) -> f64 {
        let l = self.llt.L();
        (0..l.nrows()).map(|i| l[(i, i)].ln()).sum::<f64>() * 2.0
    }

    /// The lower-triangular factor `L` as an nalgebra matrix.
    pub fn lower(&self) -> DMatrix<f64> {
        let l = self.llt.L();
        DMatrix::from_fn(
            l.nrows(),
            l.ncols(),
            |i, j| if i >= j { l[(i, j)] } else { 0.0 },
        )
    }

    /// `A⁻¹` from the factor (`L⁻ᵀ L⁻¹`, LAPACK `potri`). Only used where the *elements* of
    /// the inverse are needed (the trace term of the marginal-likelihood gradient,
    /// `tr(A⁻¹ ∂A/∂θ)`), never to solve a system.
    pub fn inverse_elements(&self) -> DMatrix<f64> {
        let inv: Mat<f64> = self.llt.inverse();
        let n = inv.nrows();
        let mut out = DMatrix::zeros(n, n);
        for (j, col) in out.as_mut_slice().chunks_exact_mut(n.max(1)).enumerate() {
            col.copy_from_slice(inv.col_as_slice(j));
        }
        out
    }

    /// Lower triangle (diagonal included) of `A⁻¹` from the factor (`L⁻ᵀ L⁻¹`: triangular
    /// inverse then triangular product, LAPACK `potri`); the strict upper triangle is 0. For
    /// contractions with symmetric matrices that read lower triangles only: skips the
    /// mirroring and the copy of [`Cholesky::inverse_elements`].
    pub(crate) fn inverse_lower(&self) -> Mat<f64> {
        use faer::dyn_stack::{MemBuffer, MemStack};
        use faer::linalg::cholesky::llt::inverse;
        let par = faer::get_global_parallelism();
        let n = self.dim();
        let mut out = Mat::zeros(n, n);
        let mut mem = MemBuffer::new(inverse::inverse_scratch::<f64>(n, par));
        inverse::inverse(out.as_mut(), self.llt.L(), par, MemStack::new(&mut mem));
        out
    }
}

/// Eigen-decomposition of a symmetric matrix (lower triangle read), eigenvalues in
/// **decreasing** order with the matching eigenvectors as columns.
pub fn symmetric_eigen(a: &DMatrix<f64>) -> Result<(Vec<f64>, DMatrix<f64>)> {
    let evd = view(a)
        .self_adjoint_eigen(Side::Lower)
        .map_err(|e| GpError::Invalid(format!("symmetric eigen-decomposition failed: {e:?}")))?;
    let (s, u) = (evd.S().column_vector(), evd.U());
    let n = s.nrows();
    let values = (0..n).rev().map(|i| s[i]).collect();
    let vectors = DMatrix::from_fn(u.nrows(), n, |i, j| u[(i, n - 1 - j)]);
    Ok((values, vectors))
}

/// `L⁻¹ B` in place for a lower-triangular `L` (only its lower triangle is read), by faer's
/// blocked triangular solve: the sparse GP's whitened features `L⁻¹ K_uf` over all pairs.
pub fn lower_solve_in_place(l: &DMatrix<f64>, b: &mut DMatrix<f64>) {
    faer::linalg::triangular_solve::solve_lower_triangular_in_place(
        view(l),
        view_mut(b),
        faer::get_global_parallelism(),
    );
}

/// `L⁻ᵀ B` in place for a lower-triangular `L` (only its lower triangle is read).
pub fn lower_tr_solve_in_place(l: &DMatrix<f64>, b: &mut DMatrix<f64>) {
    faer::linalg::triangular_solve::solve_upper_triangular_in_place(
        view(l).transpose(),
        view_mut(b),
        faer::get_global_parallelism(),
    );
}

/// `A Bᵀ` by faer's blocked matrix product (no transposed copy of `B`). With `symmetric`
/// (`B = A`) only the lower triangle is computed, then mirrored.
pub fn mul_tr(a: &DMatrix<f64>, b: &DMatrix<f64>, symmetric: bool) -> DMatrix<f64> {
    assert_eq!(a.ncols(), b.ncols(), "mul_tr: column counts differ");
    use faer::linalg::matmul::triangular::{matmul, BlockStructure};
    let mut out = DMatrix::zeros(a.nrows(), b.nrows());
    let dst = if symmetric { BlockStructure::TriangularLower } else { BlockStructure::Rectangular };
    matmul(
        view_mut(&mut out),
        dst,
        faer::Accum::Replace,
        view(a),
        BlockStructure::Rectangular,
        view(b).transpose(),
        BlockStructure::Rectangular,
        1.0,
        faer::get_global_parallelism(),
    );
    if symmetric {
        let n = out.nrows();
        for j in 0..n {
            for i in j + 1..n {
                out[(j, i)] = out[(i, j)];
            }
        }
    }
    out
}

/// `A B` by faer's blocked matrix product (the sparse GP's `M x M` by `M x F` products).
pub fn mul(a: &DMatrix<f64>, b: &DMatrix<f64>) -> DMatrix<f64> {
    assert_eq!(a.ncols(), b.nrows(), "mul: inner dimensions differ");
    let mut out = DMatrix::zeros(a.nrows(), b.ncols());
    faer::linalg::matmul::matmul(
        view_mut(&mut out),
        faer::Accum::Replace,
        view(a),
        view(b),
        1.0,
        faer::get_global_parallelism(),
    );
    out
}
