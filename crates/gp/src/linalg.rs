//! Dense symmetric positive-definite solves: the one Cholesky factorisation of the project
//! (faer, sequential) with a logged jitter retry, and the products around it.
//!
//! faer's dense Cholesky was the fastest option measured on this machine (1.6 ms for
//! 500 x 500 versus 4.7 ms nalgebra). Matrices cross the boundary as column-major slices, so
//! no copies are made for the factorisation input. The factorisation and its solves always run
//! on the calling thread: parallelism, where any, lives above them (one GP, one chain or one
//! body part per thread).

use crate::{GpError, Result};
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::{cholesky_in_place, cholesky_in_place_scratch};
use faer::linalg::triangular_solve::{solve_lower_triangular_in_place, solve_upper_triangular_in_place};
use faer::reborrow::ReborrowMut;
use faer::{Mat, MatMut, MatRef, Par, Side};
use nalgebra::DMatrix;

/// Jitter ladder: after a plain factorisation fails, `c · mean |diag|` is added to the diagonal
/// for `c` = 1e-10, 1e-9, ..., 1e-3 in turn.
pub const JITTER_LADDER: [f64; 8] = [1e-10, 1e-9, 1e-8, 1e-7, 1e-6, 1e-5, 1e-4, 1e-3];

/// A Cholesky factorisation `A + jitter I = L Lᵀ`.
#[derive(Clone, Debug)]
pub struct Cholesky {
    /// The lower-triangular factor `L` (its strict upper triangle is zero).
    pub l: Mat<f64>,
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

/// Factors the lower triangle of `l` in place (faer uses the strict upper triangle as scratch,
/// zeroed afterwards). False when a pivot is not positive or an entry is not finite.
fn factor_in_place(l: &mut Mat<f64>) -> bool {
    let n = l.nrows();
    if !(0..n).all(|j| l.col_as_slice(j)[j..].iter().all(|v| v.is_finite())) {
        return false;
    }
    let mut mem = MemBuffer::new(cholesky_in_place_scratch::<f64>(n, Par::Seq, Default::default()));
    if cholesky_in_place(l.as_mut(), Default::default(), Par::Seq, MemStack::new(&mut mem), Default::default()).is_err() {
        return false;
    }
    for j in 1..n {
        l.col_as_slice_mut(j)[..j].fill(0.0);
    }
    true
}

impl Cholesky {
    /// Factorises the symmetric matrix `k` (only its lower triangle is read). If the plain
    /// factorisation fails, retries with `jitter = c · mean |diag k|` along [`JITTER_LADDER`];
    /// the jitter used is returned in [`Cholesky::jitter`] for the caller to log. `what` names
    /// the matrix in the error.
    pub fn factor(k: MatRef<'_, f64>, what: &str) -> Result<Self> {
        let n = k.nrows();
        if n != k.ncols() {
            return crate::invalid(format!("{what}: Cholesky of a non-square {n}x{} matrix", k.ncols()));
        }
        let mut l = k.to_owned();
        if factor_in_place(&mut l) {
            return Ok(Self { l, jitter: 0.0 });
        }
        let mean_diag = (0..n).map(|i| k[(i, i)].abs()).sum::<f64>() / n.max(1) as f64;
        let scale = if mean_diag > 0.0 && mean_diag.is_finite() { mean_diag } else { 1.0 };
        let mut last = 0.0;
        for c in JITTER_LADDER {
            let jitter = c * scale;
            let mut l = k.to_owned();
            for i in 0..n {
                l[(i, i)] += jitter;
            }
            last = jitter;
            if factor_in_place(&mut l) {
                return Ok(Self { l, jitter });
            }
        }
        Err(GpError::NotPositiveDefinite { what: what.to_string(), jitter: last })
    }

    /// [`Cholesky::factor`] of an nalgebra matrix, pushing one line into `notes` when jitter
    /// was needed.
    pub fn new(a: &DMatrix<f64>, what: &str, notes: &mut Vec<String>) -> Result<Self> {
        let c = Self::factor(view(a), what)?;
        if c.jitter > 0.0 {
            notes.push(format!("{what}: not positive definite, added jitter {:.3e} to the diagonal", c.jitter));
        }
        Ok(c)
    }

    /// [`Cholesky::factor`] without the copy: factors `k` (only its lower triangle is read)
    /// in place, taking ownership. If the plain factorisation fails, the destroyed `k` is
    /// rebuilt by `original` and [`Cholesky::factor`]'s jitter retries run on it.
    pub fn factor_owned(mut k: Mat<f64>, what: &str, original: impl FnOnce() -> Mat<f64>) -> Result<Self> {
        if k.nrows() == k.ncols() && factor_in_place(&mut k) {
            return Ok(Self { l: k, jitter: 0.0 });
        }
        drop(k);
        Self::factor(original().as_ref(), what)
    }

    /// Dimension of the factorised matrix.
    pub fn dim(&self) -> usize {
        self.l.nrows()
    }

    /// `log |A| = 2 Σ log L_ii`.
    pub fn log_det(&self) -> f64 {
        2.0 * (0..self.l.nrows()).map(|i| self.l[(i, i)].ln()).sum::<f64>()
    }

    /// `rhs ← L⁻¹ rhs`.
    pub fn half_solve_in_place(&self, rhs: MatMut<'_, f64>) {
        solve_lower_triangular_in_place(self.l.as_ref(), rhs, Par::Seq);
    }

    /// `rhs ← L⁻ᵀ rhs`.
    pub fn half_solve_t_in_place(&self, rhs: MatMut<'_, f64>) {
        solve_upper_triangular_in_place(self.l.as_ref().transpose(), rhs, Par::Seq);
    }

    /// `rhs ← A⁻¹ rhs` by two triangular solves.
    pub fn solve_in_place(&self, mut rhs: MatMut<'_, f64>) {
        self.half_solve_in_place(rhs.rb_mut());
        self.half_solve_t_in_place(rhs);
    }

    /// Solves `A X = B` for all columns of `B` at once.
    pub fn solve(&self, b: &DMatrix<f64>) -> DMatrix<f64> {
        let mut x = b.clone();
        self.solve_in_place(view_mut(&mut x));
        x
    }

    /// [`Cholesky::solve`] on a faer matrix.
    pub fn solve_mat(&self, rhs: MatRef<'_, f64>) -> Mat<f64> {
        let mut out = rhs.to_owned();
        self.solve_in_place(out.as_mut());
        out
    }

    /// `L⁻ᵀ Q L⁻¹` for a symmetric `Q`, by two triangular solves with n right-hand sides.
    /// This is how `A⁻¹ (·) A⁻¹`-type gradient matrices are formed without an inverse. The
    /// result is symmetric up to rounding; callers read its lower triangle.
    pub fn sandwich(&self, q: MatRef<'_, f64>) -> Mat<f64> {
        // E = L⁻ᵀ Q ; result = E L⁻¹ = (L⁻ᵀ Eᵀ)ᵀ, solved in place on the transposed view.
        let mut e = q.to_owned();
        self.half_solve_t_in_place(e.as_mut());
        self.half_solve_t_in_place(e.as_mut().transpose_mut());
        e
    }

    /// The factor `L` as an nalgebra matrix.
    pub fn lower(&self) -> DMatrix<f64> {
        let l = &self.l;
        DMatrix::from_fn(l.nrows(), l.ncols(), |i, j| l[(i, j)])
    }

    /// `A⁻¹` from the factor (`L⁻ᵀ L⁻¹`, LAPACK `potri`). Only used where the *elements* of
    /// the inverse are needed (the trace term of the marginal-likelihood gradient,
    /// `tr(A⁻¹ ∂A/∂θ)`), never to solve a system.
    pub fn inverse_elements(&self) -> DMatrix<f64> {
        let lower = self.inverse_lower();
        let n = lower.nrows();
        DMatrix::from_fn(n, n, |i, j| if i >= j { lower[(i, j)] } else { lower[(j, i)] })
    }

    /// Lower triangle (diagonal included) of `A⁻¹` from the factor (`L⁻ᵀ L⁻¹`: triangular
    /// inverse then triangular product, LAPACK `potri`); the strict upper triangle is 0. For
    /// contractions with symmetric matrices that read lower triangles only: skips the
    /// mirroring and the copy of [`Cholesky::inverse_elements`].
    pub fn inverse_lower(&self) -> Mat<f64> {
        use faer::linalg::cholesky::llt::inverse;
        let n = self.dim();
        let mut out = Mat::zeros(n, n);
        let mut mem = MemBuffer::new(inverse::inverse_scratch::<f64>(n, Par::Seq));
        inverse::inverse(out.as_mut(), self.l.as_ref(), Par::Seq, MemStack::new(&mut mem));
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

/// Items per block of [`blocks`].
pub const BLOCK: usize = 2048;

/// `0..n` cut into consecutive ranges of about [`BLOCK`] items, equal to within one (one range
/// when `n <= BLOCK`): the sparse GP works through its `M x F` matrices a block of columns at
/// a time, the limb orientation through its training rows a block of rows at a time. No range
/// is shorter than `BLOCK / 2` unless `n` is, so each block's product takes the same path as
/// the whole matrix's would (nalgebra multiplies matrices of at most 5 rows or columns by
/// another loop), and every entry is the same to the bit.
pub fn blocks(n: usize) -> impl Iterator<Item = std::ops::Range<usize>> {
    let count = n.div_ceil(BLOCK).max(1);
    (0..count).map(move |b| b * n / count..(b + 1) * n / count)
}

/// `out = A B[:, cols]`, the column block read in place (`out` reallocated only when its
/// shape differs).
pub(crate) fn mul_columns_into(out: &mut DMatrix<f64>, a: &DMatrix<f64>, b: &DMatrix<f64>, cols: std::ops::Range<usize>) {
    assert_eq!(a.ncols(), b.nrows(), "mul_columns_into: inner dimensions differ");
    if out.shape() != (a.nrows(), cols.len()) {
        *out = DMatrix::zeros(a.nrows(), cols.len());
    }
    faer::linalg::matmul::matmul(
        view_mut(out),
        faer::Accum::Replace,
        view(a),
        view(b).subcols(cols.start, cols.len()),
        1.0,
        faer::get_global_parallelism(),
    );
}

/// `out += A C[rows, :]ᵀ`, the row block read in place.
pub(crate) fn add_mul_tr_rows(out: &mut DMatrix<f64>, a: &DMatrix<f64>, c: &DMatrix<f64>, rows: std::ops::Range<usize>) {
    assert_eq!(a.ncols(), c.ncols(), "add_mul_tr_rows: column counts differ");
    assert_eq!(out.shape(), (a.nrows(), rows.len()), "add_mul_tr_rows: output shape");
    faer::linalg::matmul::matmul(
        view_mut(out),
        faer::Accum::Add,
        view(a),
        view(c).subrows(rows.start, rows.len()).transpose(),
        1.0,
        faer::get_global_parallelism(),
    );
}

/// Eigenvalues `λ` of the symmetric `a` (lower triangle read; `n x n`) and `Uᵀ R` for its
/// eigenvectors `U` (in the order of `λ`, unsorted), without forming `U`: the sparse GP's
/// signal-variance profile needs only the spectrum and the projections of `R = A Y`
/// (`n x m`, `m` small). Householder tridiagonalisation `a = Q T Qᵀ` (faer, `4/3 n³`), `Qᵀ R`
/// by the same reflectors, then the implicit QL algorithm with Wilkinson shifts on `T`
/// (Numerical Recipes' `tqli`, Golub & Van Loan §8.3), each plane rotation applied to the rows
/// of `Qᵀ R` instead of accumulated into `U`: `O(n² m)` after the reduction, where the full
/// eigen-decomposition with vectors costs about `9 n³`.
pub fn symmetric_eigen_projected(a: &DMatrix<f64>, r: &DMatrix<f64>) -> Result<(Vec<f64>, DMatrix<f64>)> {
    use faer::dyn_stack::{MemBuffer, MemStack};
    use faer::linalg::evd::tridiag;
    let n = a.nrows();
    assert!(a.ncols() == n && r.nrows() == n, "symmetric_eigen_projected: shapes");
    let mut w = r.clone();
    if n == 0 {
        return Ok((Vec::new(), w));
    }
    let par = faer::Par::Seq;
    let mut trid = Mat::<f64>::zeros(n, n);
    trid.copy_from_triangular_lower(view(a));
    let bs = faer::linalg::qr::no_pivoting::factor::recommended_block_size::<f64>(n, n);
    let mut householder = Mat::<f64>::zeros(bs, n.saturating_sub(1));
    let params: faer::Spec<tridiag::TridiagParams, f64> = Default::default();
    let mut mem = MemBuffer::new(faer::dyn_stack::StackReq::any_of(&[
        tridiag::tridiag_in_place_scratch::<f64>(n, par, params),
        faer::linalg::householder::apply_block_householder_sequence_transpose_on_the_left_in_place_scratch::<f64>(
            n.saturating_sub(1),
            bs,
            w.ncols(),
        ),
    ]));
    tridiag::tridiag_in_place(trid.as_mut(), householder.as_mut(), par, MemStack::new(&mut mem), params);
    if n > 1 {
        let (rows, cols) = (w.nrows(), w.ncols());
        let wm = MatMut::from_column_major_slice_mut(w.as_mut_slice(), rows, cols);
        faer::linalg::householder::apply_block_householder_sequence_transpose_on_the_left_in_place_with_conj(
            trid.as_ref().submatrix(1, 0, n - 1, n - 1),
            householder.as_ref(),
            faer::Conj::No,
            wm.subrows_mut(1, n - 1),
            par,
            MemStack::new(&mut mem),
        );
    }
    let mut d: Vec<f64> = (0..n).map(|i| trid[(i, i)]).collect();
    let mut e: Vec<f64> = (0..n).map(|i| if i + 1 < n { trid[(i + 1, i)] } else { 0.0 }).collect();
    let m_cols = w.ncols();
    let tiny = f64::EPSILON * d.iter().zip(&e).map(|(a, b)| a.abs() + 2.0 * b.abs()).fold(0.0, f64::max);
    // Rows i and i+1 of W turned by (c, s): the transpose of the rotation tqli applies to the
    // columns of the eigenvector matrix.
    let rotate = |w: &mut DMatrix<f64>, i: usize, c: f64, s: f64| {
        for k in 0..m_cols {
            let (a, b) = (w[(i, k)], w[(i + 1, k)]);
            w[(i + 1, k)] = s * a + c * b;
            w[(i, k)] = c * a - s * b;
        }
    };
    for l in 0..n {
        let mut iter = 0;
        loop {
            // Find a negligible off-diagonal element e[mm] splitting the matrix: relative to
            // its neighbours, or below ε |T| (the accuracy of any backward-stable method; the
            // relative test alone never splits a cluster of zero eigenvalues).
            let mut mm = l;
            while mm + 1 < n {
                let dd = d[mm].abs() + d[mm + 1].abs();
                if e[mm].abs() <= f64::EPSILON * dd || e[mm].abs() <= tiny {
                    break;
                }
                mm += 1;
            }
            if mm == l {
                break;
            }
            iter += 1;
            if iter > 60 {
                return Err(GpError::Invalid("tridiagonal QL: no convergence after 60 iterations".into()));
            }
            let mut g = (d[l + 1] - d[l]) / (2.0 * e[l]);
            let mut rr = g.hypot(1.0);
            g = d[mm] - d[l] + e[l] / (g + rr.copysign(g));
            let (mut s, mut c, mut p) = (1.0, 1.0, 0.0);
            let mut i = mm;
            let mut underflow = false;
            while i > l {
                i -= 1;
                let f = s * e[i];
                let b = c * e[i];
                rr = f.hypot(g);
                e[i + 1] = rr;
                if rr == 0.0 {
                    d[i + 1] -= p;
                    e[mm] = 0.0;
                    underflow = true;
                    break;
                }
                s = f / rr;
                c = g / rr;
                g = d[i + 1] - p;
                rr = (d[i] - g) * s + 2.0 * c * b;
                p = s * rr;
                d[i + 1] = g + p;
                g = c * rr - b;
                rotate(&mut w, i, c, s);
            }
            if underflow {
                continue;
            }
            d[l] -= p;
            e[l] = g;
            e[mm] = 0.0;
        }
    }
    Ok((d, w))
}

#[cfg(test)]
mod tests {
    /// The blocks tile `0..n` in order, at most `BLOCK` + 1 and, past one block, at least
    /// `BLOCK / 2` items each.
    #[test]
    fn blocks_tile_the_range() {
        for n in [0, 1, 5, 2047, 2048, 2049, 4097, 10_000, 105_900] {
            let blocks: Vec<_> = blocks(n).collect();
            assert_eq!(blocks.first().map(|b| b.start), Some(0), "{n}");
            assert_eq!(blocks.last().map(|b| b.end), Some(n), "{n}");
            assert!(blocks.windows(2).all(|w| w[0].end == w[1].start), "{n}");
            assert!(blocks.iter().all(|b| b.len() <= BLOCK + 1), "{n}");
            if blocks.len() > 1 {
                assert!(blocks.iter().all(|b| b.len() >= BLOCK / 2), "{n}");
            }
        }
    }

    use super::*;

    /// The eigenvalues and the projections' squared norms per eigenvalue equal those of the
    /// full decomposition (`Uᵀ R` with `U` from [`symmetric_eigen`]), on matrices with clusters
    /// of equal eigenvalues (these sine matrices have one at 1/4; `U` is not unique there but
    /// each eigenspace's projection norm is) and a rank-deficient one.
    #[test]
    fn projected_eigen_matches_the_full_decomposition() {
        for (n, rank) in [(1, 1), (2, 2), (7, 7), (40, 40), (300, 300), (60, 12)] {
            let b = DMatrix::from_fn(n, rank, |i, j| ((i * 7 + j * 13) as f64 * 0.37).sin() + if i == j { 0.5 } else { 0.0 });
            let a = &b * b.transpose();
            let r = DMatrix::from_fn(n, 3, |i, j| ((i + 2 * j) as f64 * 0.91).cos());
            let (lam, w) = symmetric_eigen_projected(&a, &r).unwrap();
            let (lam_full, u) = symmetric_eigen(&a).unwrap();
            let w_full = u.tr_mul(&r);
            let mut got: Vec<(f64, f64)> = lam.iter().zip(w.row_iter()).map(|(l, r)| (*l, r.norm_squared())).collect();
            let mut want: Vec<(f64, f64)> = lam_full.iter().zip(w_full.row_iter()).map(|(l, r)| (*l, r.norm_squared())).collect();
            got.sort_by(|x, y| x.0.total_cmp(&y.0));
            want.sort_by(|x, y| x.0.total_cmp(&y.0));
            let scale = a.amax().max(1.0);
            // Within a cluster of equal eigenvalues only the cluster's total weight is unique:
            // compare cumulative weights where the spectrum has a gap.
            let (mut cg, mut cw) = (0.0, 0.0);
            for (k, (g, wv)) in got.iter().zip(&want).enumerate() {
                assert!((g.0 - wv.0).abs() < 1e-11 * scale, "n {n}: eigenvalue {} vs {}", g.0, wv.0);
                cg += g.1;
                cw += wv.1;
                if got.get(k + 1).is_none_or(|next| next.0 - g.0 > 1e-8 * scale) {
                    assert!((cg - cw).abs() < 1e-9 * r.norm_squared().max(1.0), "n {n}: cumulative weight {cg} vs {cw}");
                }
            }
            assert!((cg - r.norm_squared()).abs() < 1e-9 * r.norm_squared(), "n {n}: projections keep the norm");
        }
    }
}
