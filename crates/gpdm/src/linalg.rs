//! Dense linear algebra on faer matrices, always sequential (`Par::Seq`): rayon
//! parallelism, if any, lives above this level (one chain or one body part per thread).
//!
//! Only Cholesky factorisations and triangular solves: no explicit inverse is formed.

use faer::linalg::matmul::matmul;
use faer::linalg::triangular_solve::{
    solve_lower_triangular_in_place, solve_upper_triangular_in_place,
};
use faer::reborrow::ReborrowMut;
use faer::{Accum, Mat, MatMut, MatRef, Par};
use std::sync::Mutex;

/// The project's one Cholesky factorisation (with its jitter ladder), shared with the GP
/// regression; the GPDM objective's structured products with it are [`CholeskyProducts`].
pub use gp::linalg::Cholesky;

/// How [`CholeskyProducts::sandwich_lower_split`] runs its first solve.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Split {
    /// One solve with all right-hand sides, on this thread.
    None,
    /// Two halves of right-hand sides under `rayon::join`: an idle worker of the current pool
    /// may take one (call on a worker). Handing a half to the pool from a thread outside it
    /// (`in_place_scope`) was measured 18 % slower per evaluation on leg_l: that thread
    /// cannot run pool jobs, so it waits until a busy worker gets to the half.
    Join,
}

/// Recycled matrix buffers: the objective allocates the same few N × N matrices at every
/// evaluation, and at N = 446 freeing and re-allocating them cost ~1600 page faults per
/// evaluation (18 % of the CPU time in the kernel). [`zeros_recycled`] reuses a buffer
/// of the same shape handed back by [`recycle`]; at most [`POOL_BYTES`] are kept.
static POOL: Mutex<Vec<Mat<f64>>> = Mutex::new(Vec::new());

/// Bytes of matrix buffers the pool keeps at most.
pub const POOL_BYTES: usize = 64 << 20;

fn pool() -> std::sync::MutexGuard<'static, Vec<Mat<f64>>> {
    POOL.lock().unwrap_or_else(|e| e.into_inner())
}

/// An `nrows × ncols` zero matrix, in a recycled buffer of the same shape when there is one.
pub fn zeros_recycled(nrows: usize, ncols: usize) -> Mat<f64> {
    match take_recycled(nrows, ncols) {
        Some(mut m) => {
            m.as_mut().fill(0.0);
            m
        }
        None => Mat::zeros(nrows, ncols),
    }
}

/// An `nrows × ncols` matrix with unspecified entries (a recycled buffer's old values, which
/// may be anything, NaN included; zeros when none is pooled), for callers that write every
/// entry they later read: saves [`zeros_recycled`]'s fill (memset was ~5 % of a fit).
pub(crate) fn unspecified_recycled(nrows: usize, ncols: usize) -> Mat<f64> {
    take_recycled(nrows, ncols).unwrap_or_else(|| Mat::zeros(nrows, ncols))
}

fn take_recycled(nrows: usize, ncols: usize) -> Option<Mat<f64>> {
    let mut p = pool();
    p.iter()
        .position(|m| m.nrows() == nrows && m.ncols() == ncols)
        .map(|i| p.swap_remove(i))
}

/// Sets the strict upper triangle of a square matrix to zero.
pub(crate) fn zero_strict_upper(m: &mut Mat<f64>) {
    let r = m.nrows();
    for j in 1..m.ncols() {
        m.col_as_slice_mut(j)[..j.min(r)].fill(0.0);
    }
}

/// Hands a matrix's buffer back for [`zeros_recycled`] (dropped when the pool is full or the
/// matrix is small).
pub fn recycle(m: Mat<f64>) {
    let bytes = |m: &Mat<f64>| m.nrows() * m.ncols() * 8;
    if bytes(&m) < 64 << 10 {
        return;
    }
    let mut p = pool();
    if p.iter().map(bytes).sum::<usize>() + bytes(&m) <= POOL_BYTES {
        p.push(m);
    }
}

/// Column-block width of [`CholeskyProducts::half_solve_trapezoidal`] and the leaf size of
/// `lower_back_solve`'s recursion (measured at N = 192 and 446, `profile_objective` in crates/studies:
/// 32 fastest by 3-5 % over 64, 96, 128).
pub const BLOCK: usize = 32;

/// The GPDM objective's products with a Cholesky factor: solves against lower-trapezoidal
/// right-hand sides and the lower triangle of `L⁻ᵀ Q L⁻¹`, on recycled buffers.
pub trait CholeskyProducts {
    /// `Z = L⁻¹ R` for a lower-trapezoidal `R` (n × r, `R_ij = 0` for `i < j`, r ≤ n), e.g. the
    /// factor of [`PivotedCholesky`]. `Z` is lower-trapezoidal too; each column block
    /// `[j0, j1)` is solved against the trailing block `L[j0.., j0..]` only (rows above `j0`
    /// are zero in `R` and stay zero in `Z`): ~n³/6 multiply-adds for r = n instead of n³/2.
    fn half_solve_trapezoidal(&self, r: MatRef<'_, f64>) -> Mat<f64>;
    /// [`CholeskyProducts::half_solve_trapezoidal`] with column blocks of width `bs` (benchmarks).
    fn half_solve_trapezoidal_blocked(&self, r: MatRef<'_, f64>, bs: usize) -> Mat<f64>;
    /// Lower triangle of `L⁻ᵀ Q L⁻¹` for a symmetric `Q` of which only the lower triangle is
    /// read (the buffer is reused; its strict upper triangle is overwritten). The strict
    /// upper triangle of the result is unspecified: [`crate::kernel::RbfLinear::gradients`]
    /// reads the lower one. `F = Q L⁻¹` by one full solve (n³/2; on a rayon worker its
    /// right-hand sides in two `rayon::join`ed halves, [`Split::Join`], so that an idle thread,
    /// e.g. the one whose objective term finished first, takes one: 5-9 % less time per evaluation
    /// at N = 446 on 2 threads, neutral at N = 192), then the lower triangle of
    /// `L⁻ᵀ F` by `lower_back_solve` (n³/6 instead of n³/2). Same result as
    /// [`Cholesky::sandwich`] up to rounding. The strict upper triangle of `Q` is filled from
    /// the lower one in cache-sized tiles first.
    fn sandwich_lower(&self, q: Mat<f64>) -> Mat<f64>;
    /// [`CholeskyProducts::sandwich_lower`] with the first solve's two halves of right-hand sides run
    /// as chosen by `split` (see [`Split`]). Same result for every choice.
    fn sandwich_lower_split(&self, q: Mat<f64>, split: Split) -> Mat<f64>;
}

impl CholeskyProducts for Cholesky {
    fn half_solve_trapezoidal(&self, r: MatRef<'_, f64>) -> Mat<f64> {
        self.half_solve_trapezoidal_blocked(r, BLOCK)
    }

    fn half_solve_trapezoidal_blocked(&self, r: MatRef<'_, f64>, bs: usize) -> Mat<f64> {
        let n = self.l.nrows();
        assert_eq!(r.nrows(), n, "R must have as many rows as L");
        let mut z = unspecified_recycled(n, r.ncols());
        z.copy_from(r);
        let mut j0 = 0;
        while j0 < r.ncols() {
            let j1 = (j0 + bs.max(1)).min(r.ncols());
            solve_lower_triangular_in_place(
                self.l.as_ref().submatrix(j0, j0, n - j0, n - j0),
                z.as_mut().submatrix_mut(j0, j0, n - j0, j1 - j0),
                Par::Seq,
            );
            j0 = j1;
        }
        z
    }

    fn sandwich_lower(&self, q: Mat<f64>) -> Mat<f64> {
        let split = if rayon::current_thread_index().is_some() {
            Split::Join
        } else {
            Split::None
        };
        self.sandwich_lower_split(q, split)
    }

    fn sandwich_lower_split(&self, mut q: Mat<f64>, split: Split) -> Mat<f64> {
        let n = self.l.nrows();
        mirror_lower(q.as_mut());
        // Fᵀ = L⁻ᵀ Q (Q symmetric), so F = Q L⁻¹, stored in q.
        if split == Split::Join && n >= 2 * BLOCK {
            let (a, b) = q.as_mut().transpose_mut().split_at_col_mut(n / 2);
            rayon::join(
                || self.half_solve_t_in_place(a),
                || self.half_solve_t_in_place(b),
            );
        } else {
            self.half_solve_t_in_place(q.as_mut().transpose_mut());
        }
        lower_back_solve(self.l.as_ref(), q.as_mut());
        q
    }
}

/// Copies the strict lower triangle of a square matrix onto its strict upper triangle, in
/// 32 × 32 tiles so that the transposed (strided) reads stay in cache.
fn mirror_lower(mut q: MatMut<'_, f64>) {
    const TILE: usize = 32;
    let n = q.nrows();
    for jb in (0..n).step_by(TILE) {
        let je = (jb + TILE).min(n);
        for ib in (0..je).step_by(TILE) {
            let ie = (ib + TILE).min(n);
            for j in jb..je {
                for i in ib..ie.min(j) {
                    let v = q[(j, i)];
                    q[(i, j)] = v;
                }
            }
        }
    }
}

/// Lower triangle of `L⁻ᵀ F` in place (only the lower triangle of `F` is read), recursive:
/// with rows/cols split at h, `G21 = L22⁻ᵀ F21`, `G22 = lower(L22⁻ᵀ F22)`,
/// `G11 = lower(L11⁻ᵀ (F11 − L21ᵀ G21))` (back substitution for row i reads rows ≥ i only,
/// so the lower triangles suffice). n³/6 multiply-adds in large GEMMs.
fn lower_back_solve(l: MatRef<'_, f64>, f: MatMut<'_, f64>) {
    use faer::linalg::matmul::triangular::{matmul as tri_matmul, BlockStructure as B};
    let n = l.nrows();
    if n <= BLOCK {
        solve_upper_triangular_in_place(l.transpose(), f, Par::Seq);
        return;
    }
    let h = n / 2;
    let (l11, l21, l22) = (
        l.submatrix(0, 0, h, h),
        l.submatrix(h, 0, n - h, h),
        l.submatrix(h, h, n - h, n - h),
    );
    let (mut f11, _, mut f21, f22) = f.split_at_mut(h, h);
    solve_upper_triangular_in_place(l22.transpose(), f21.rb_mut(), Par::Seq);
    lower_back_solve(l22, f22);
    tri_matmul(
        f11.rb_mut(),
        B::TriangularLower,
        Accum::Add,
        l21.transpose(),
        B::Rectangular,
        f21.as_ref(),
        B::Rectangular,
        -1.0,
        Par::Seq,
    );
    lower_back_solve(l11, f11);
}

/// Pivoted Cholesky factor `Pᵀ S P = R Rᵀ` of a symmetric positive semi-definite `S`, with
/// `R` lower-trapezoidal n × r (r = numerical rank) and `P` the permutation `perm`
/// (`(Pᵀ S P)_ij = S_{perm[i], perm[j]}`).
#[derive(Clone, Debug)]
pub struct PivotedCholesky {
    /// Pivot order: row i of `R` belongs to row `perm[i]` of `S`.
    pub perm: Vec<usize>,
    /// Lower-trapezoidal factor, n × r.
    pub r: Mat<f64>,
}

/// Relative stopping tolerance of [`PivotedCholesky::factor`]: stop when the largest remaining
/// Schur-complement diagonal is ≤ `PIVOT_RTOL · max_i S_ii`. What is dropped is a PSD
/// remainder `S_rest` with `tr(S_rest) ≤ n · PIVOT_RTOL · max S_ii` (rounding level for
/// n ≲ 1000), i.e. `tr(K⁻¹ S)` moves by at most `tr(S_rest)/λ_min(K)`.
pub const PIVOT_RTOL: f64 = 1e-14;

impl PivotedCholesky {
    /// Unblocked right-looking pivoted Cholesky (LAPACK `dpstf2` order of operations,
    /// ~n² r / 2 multiply-adds on the lower triangle; run once per data set). Pivots on the
    /// largest remaining diagonal and stops at [`PIVOT_RTOL`]. An all-zero `S` gives r = 0.
    pub fn factor(s: MatRef<'_, f64>) -> Self {
        let n = s.nrows();
        assert_eq!(s.ncols(), n, "S must be square");
        let mut a = s.to_owned();
        let mut perm: Vec<usize> = (0..n).collect();
        let max_diag = (0..n).map(|i| s[(i, i)]).fold(0.0, f64::max);
        let tol = PIVOT_RTOL * max_diag;
        let mut rank = 0;
        for k in 0..n {
            // Pivot: largest remaining diagonal (the trailing Schur complement lives in
            // a[k.., k..], lower triangle; columns < k hold R).
            let (p, dmax) = (k..n)
                .map(|i| (i, a[(i, i)]))
                .fold((k, f64::NEG_INFINITY), |b, c| if c.1 > b.1 { c } else { b });
            if !(dmax > tol) {
                break;
            }
            if p != k {
                perm.swap(k, p);
                // Symmetric swap of rows/cols k and p in the lower triangle, plus the R rows.
                for j in 0..k {
                    let t = a[(k, j)];
                    a[(k, j)] = a[(p, j)];
                    a[(p, j)] = t;
                }
                let t = a[(k, k)];
                a[(k, k)] = a[(p, p)];
                a[(p, p)] = t;
                for i in k + 1..p {
                    let t = a[(i, k)];
                    a[(i, k)] = a[(p, i)];
                    a[(p, i)] = t;
                }
                for i in p + 1..n {
                    let t = a[(i, k)];
                    a[(i, k)] = a[(i, p)];
                    a[(i, p)] = t;
                }
            }
            let piv = dmax.sqrt();
            a[(k, k)] = piv;
            for i in k + 1..n {
                a[(i, k)] /= piv;
            }
            // Trailing update, lower triangle: a[i, j] -= a[i, k] a[j, k], k < j ≤ i.
            for j in k + 1..n {
                let ajk = a[(j, k)];
                for i in j..n {
                    let v = a[(i, k)];
                    a[(i, j)] -= v * ajk;
                }
            }
            rank = k + 1;
        }
        let r = Mat::from_fn(n, rank, |i, j| if i >= j { a[(i, j)] } else { 0.0 });
        PivotedCholesky { perm, r }
    }
}

/// Lower triangle of `Z Zᵀ` for a lower-trapezoidal `Z` (n × r, r ≤ n); the strict upper
/// triangle of the result is zero. Top r rows: triangular × triangular (r³/6); the rows below:
/// a rectangular block times a triangle and a lower-triangular SYRK.
pub fn lower_zzt(z: MatRef<'_, f64>) -> Mat<f64> {
    lower_zzt_scaled(z, 1.0)
}

/// [`lower_zzt`] times `alpha`, applied inside the products (no extra pass over the result).
pub fn lower_zzt_scaled(z: MatRef<'_, f64>, alpha: f64) -> Mat<f64> {
    let mut out = lower_zzt_scaled_only(z, alpha);
    zero_strict_upper(&mut out);
    out
}

/// [`lower_zzt_scaled`] with the strict upper triangle unspecified (not written: for
/// [`CholeskyProducts::sandwich_lower`], which reads the lower one).
pub(crate) fn lower_zzt_scaled_only(z: MatRef<'_, f64>, alpha: f64) -> Mat<f64> {
    use faer::linalg::matmul::triangular::{matmul as tri_matmul, BlockStructure as B};
    let (n, r) = (z.nrows(), z.ncols());
    if r == 0 {
        return zeros_recycled(n, n);
    }
    let mut out = unspecified_recycled(n, n);
    let zt = z.submatrix(0, 0, r, r);
    let zb = z.submatrix(r, 0, n - r, r);
    tri_matmul(
        out.as_mut().submatrix_mut(0, 0, r, r),
        B::TriangularLower,
        Accum::Replace,
        zt,
        B::TriangularLower,
        zt.transpose(),
        B::TriangularUpper,
        alpha,
        Par::Seq,
    );
    if n > r {
        tri_matmul(
            out.as_mut().submatrix_mut(r, 0, n - r, r),
            B::Rectangular,
            Accum::Replace,
            zb,
            B::Rectangular,
            zt.transpose(),
            B::TriangularUpper,
            alpha,
            Par::Seq,
        );
        tri_matmul(
            out.as_mut().submatrix_mut(r, r, n - r, n - r),
            B::TriangularLower,
            Accum::Replace,
            zb,
            B::Rectangular,
            zb.transpose(),
            B::Rectangular,
            alpha,
            Par::Seq,
        );
    }
    out
}

/// Lower triangle of `alpha · W Wᵀ` for a general (tall) `W`; the strict upper triangle is
/// zero. Half the multiply-adds of [`mul_abt`].
pub fn lower_wwt_scaled(w: MatRef<'_, f64>, alpha: f64) -> Mat<f64> {
    let mut out = lower_wwt_scaled_only(w, alpha);
    zero_strict_upper(&mut out);
    out
}

/// [`lower_wwt_scaled`] with the strict upper triangle unspecified (not written).
pub(crate) fn lower_wwt_scaled_only(w: MatRef<'_, f64>, alpha: f64) -> Mat<f64> {
    use faer::linalg::matmul::triangular::{matmul as tri_matmul, BlockStructure as B};
    let n = w.nrows();
    if w.ncols() == 0 {
        return zeros_recycled(n, n);
    }
    let mut out = unspecified_recycled(n, n);
    tri_matmul(
        out.as_mut(),
        B::TriangularLower,
        Accum::Replace,
        w,
        B::Rectangular,
        w.transpose(),
        B::Rectangular,
        alpha,
        Par::Seq,
    );
    out
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
