//! Covariance functions of the GPDM (3DV eqs. 4 and 6) and their gradients.
//!
//! Both kernels are instances of one family
//! `k(x, x') = var · exp(-γ/2 ‖x − x'‖²) + lin · xᵀx' + δ(x, x') / prec`:
//! - pose mapping, 3DV eq. 4: `k_Y` with `(var, γ, lin, prec) = (α1, α2, 0, α3)`;
//! - dynamics, 3DV eq. 6: `k_X` with `(var, γ, lin, prec) = (β1, β2, β3, β4)`.
//!
//! `δ(x, x')` is the Kronecker delta on training indices (the noise term), so it appears on
//! the diagonal of a Gram matrix and never in a cross-covariance with a test point.

use crate::linalg::{unspecified_recycled, zero_strict_upper};
use crate::vexp::exp_fast;
use faer::{Mat, MatRef};
use serde::{Deserialize, Serialize};

/// Parameters of the RBF + linear + white-noise kernel.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct RbfLinear {
    /// RBF output scale (α1 or β1).
    pub var: f64,
    /// RBF inverse squared width γ (α2 or β2).
    pub gamma: f64,
    /// Linear term weight (0 for the pose kernel, β3 for the dynamics).
    pub lin: f64,
    /// Noise precision: the noise variance is `1/prec` (α3 or β4).
    pub prec: f64,
}

impl RbfLinear {
    /// Pose kernel `k_Y` of 3DV eq. 4 from `α = [α1, α2, α3]`.
    pub fn pose(alpha: [f64; 3]) -> Self {
        RbfLinear {
            var: alpha[0],
            gamma: alpha[1],
            lin: 0.0,
            prec: alpha[2],
        }
    }

    /// Dynamics kernel `k_X` of 3DV eq. 6 from `β = [β1, β2, β3, β4]`.
    pub fn dynamics(beta: [f64; 4]) -> Self {
        RbfLinear {
            var: beta[0],
            gamma: beta[1],
            lin: beta[2],
            prec: beta[3],
        }
    }

    /// `k(x, x)` for a point taken as a new (noisy) observation: `var + lin ‖x‖² + 1/prec`.
    pub fn self_cov(&self, x: &[f64]) -> f64 {
        self.var + self.lin * x.iter().map(|v| v * v).sum::<f64>() + 1.0 / self.prec
    }

    /// Gram matrix on the rows of `x` (n × d), with its noise-free RBF part kept for the
    /// gradients. Only the lower triangles are filled (the strict upper triangles are zero):
    /// the Cholesky factorisation and [`RbfLinear::gradients`] read the lower triangle only.
    ///
    /// Column j of the lower triangle is built in three store loops over the contiguous rows
    /// `i ≥ j`: squared distances (one pass per latent coordinate), then
    /// `var · exp(−γ/2 s)` with the vectorisable [`exp_fast`] (2 ulp of libm), then the linear
    /// term (skipped when `lin = 0`, the pose kernel).
    pub fn gram(&self, x: MatRef<'_, f64>) -> Gram {
        let mut g = self.gram_lower(x);
        zero_strict_upper(&mut g.k);
        zero_strict_upper(&mut g.rbf);
        g
    }

    /// [`RbfLinear::gram`] with the strict upper triangles unspecified (not written; the
    /// buffers are recycled without a zero fill): for the objective, whose Cholesky and
    /// [`RbfLinear::gradients`] read only the lower triangles.
    pub(crate) fn gram_lower(&self, x: MatRef<'_, f64>) -> Gram {
        let n = x.nrows();
        let d = x.ncols();
        if d == 0 {
            // No coordinates: every distance and dot product is 0.
            return self.gram_lower(Mat::<f64>::zeros(n, 1).as_ref());
        }
        let copy;
        let x = if x.row_stride() == 1 {
            x
        } else {
            copy = x.to_owned();
            copy.as_ref()
        };
        let cols: Vec<&[f64]> = (0..d).map(|c| col_slice(x, c)).collect();
        let mut rbf = unspecified_recycled(n, n);
        let mut k = unspecified_recycled(n, n);
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the CPU supports AVX2 (checked just above).
            unsafe { self.gram_fill_avx2(&cols, &mut rbf, &mut k) };
            return Gram { k, rbf };
        }
        self.gram_fill(&cols, &mut rbf, &mut k);
        Gram { k, rbf }
    }

    /// [`RbfLinear::gram_fill`] compiled with 256-bit vectors. Same IEEE operations in the
    /// same order (no FMA contraction), so the results are bit-identical to the baseline build.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn gram_fill_avx2(&self, cols: &[&[f64]], rbf: &mut Mat<f64>, k: &mut Mat<f64>) {
        self.gram_fill(cols, rbf, k)
    }

    /// The column loop of [`RbfLinear::gram`] (lower triangles of `rbf` and `k`).
    #[inline(always)]
    fn gram_fill(&self, cols: &[&[f64]], rbf: &mut Mat<f64>, k: &mut Mat<f64>) {
        let n = rbf.nrows();
        let half_gamma = -0.5 * self.gamma;
        let noise = 1.0 / self.prec;
        for j in 0..n {
            let rcol = &mut rbf.col_as_slice_mut(j)[j..n];
            let kcol = &mut k.col_as_slice_mut(j)[j..n];
            // Squared distances, accumulated over the coordinates in order (the first one
            // stores: the buffers are not zeroed).
            set_sq_dist(rcol, &cols[0][j..], cols[0][j]);
            for col in &cols[1..] {
                add_sq_dist(rcol, &col[j..], col[j]);
            }
            rbf_of_sq_dist(rcol, self.var, half_gamma);
            if self.lin != 0.0 {
                set_scaled(kcol, &cols[0][j..], cols[0][j]);
                for col in &cols[1..] {
                    add_scaled(kcol, &col[j..], col[j]);
                }
                lin_plus(kcol, rcol, self.lin);
            } else {
                kcol.copy_from_slice(rcol);
            }
            kcol[0] += noise;
        }
    }

    /// Cross-covariance `k(a_i, b_j)` (no noise term), `n_a × n_b`.
    pub fn cross(&self, a: MatRef<'_, f64>, b: MatRef<'_, f64>) -> Mat<f64> {
        let d = a.ncols();
        let row_major = |m: MatRef<'_, f64>| -> Vec<f64> {
            (0..m.nrows())
                .flat_map(|i| (0..d).map(move |c| m[(i, c)]))
                .collect()
        };
        let (ar, br) = (row_major(a), row_major(b));
        let half_gamma = -0.5 * self.gamma;
        let mut out = Mat::<f64>::zeros(a.nrows(), b.nrows());
        if d == 0 {
            return Mat::from_fn(a.nrows(), b.nrows(), |_, _| self.var);
        }
        for (j, bj) in br.chunks_exact(d).enumerate() {
            let col = out
                .col_mut(j)
                .try_as_col_major_mut()
                .expect("contiguous")
                .as_slice_mut();
            for (o, ai) in col.iter_mut().zip(ar.chunks_exact(d)) {
                let (mut s, mut dot) = (0.0, 0.0);
                for (u, v) in ai.iter().zip(bj) {
                    s += (u - v) * (u - v);
                    dot += u * v;
                }
                let arg = half_gamma * s;
                let r = if arg > -700.0 {
                    self.var * arg.exp()
                } else {
                    0.0
                };
                *o = r + self.lin * dot;
            }
        }
        out
    }

    /// Chain rule through `K(X)`: given `G = ∂L/∂K` (symmetric; its lower triangle is read)
    /// returns `∂L/∂(var, γ, lin, prec)` and `∂L/∂X`, where
    /// `∂L/∂x_i = Σ_j 2 G_ij (−γ K_rbf,ij (x_i − x_j) + lin x_j)`.
    ///
    /// Column by column of the lower triangle (`i > j` contiguous in `G` and `K_rbf`), one
    /// loop per latent coordinate with four-lane accumulators for the reductions; the linear
    /// term's contribution to `∂L/∂X` is skipped when `lin = 0` (`∂L/∂lin` is always returned).
    pub fn gradients(
        &self,
        gram: &Gram,
        x: MatRef<'_, f64>,
        g: MatRef<'_, f64>,
    ) -> ([f64; 4], Mat<f64>) {
        let n = g.nrows();
        let d = x.ncols();
        if d == 0 {
            // No coordinates: same kernel as one all-zero coordinate; no X gradient.
            let (p, _) = self.gradients(gram, Mat::<f64>::zeros(n, 1).as_ref(), g);
            return (p, Mat::zeros(n, 0));
        }
        let (copy_x, copy_g);
        let x = if x.row_stride() == 1 {
            x
        } else {
            copy_x = x.to_owned();
            copy_x.as_ref()
        };
        let g = if g.row_stride() == 1 {
            g
        } else {
            copy_g = g.to_owned();
            copy_g.as_ref()
        };
        let rbf = gram.rbf.as_ref();
        let cols: Vec<&[f64]> = (0..d).map(|c| col_slice(x, c)).collect();
        let mut dx = Mat::<f64>::zeros(n, d);
        #[cfg(target_arch = "x86_64")]
        let [gv, gg, gl, tr] = if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the CPU supports AVX2 (checked just above).
            unsafe { self.gradients_fill_avx2(&cols, g, rbf, &mut dx) }
        } else {
            self.gradients_fill(&cols, g, rbf, &mut dx, false)
        };
        #[cfg(not(target_arch = "x86_64"))]
        let [gv, gg, gl, tr] = self.gradients_fill(&cols, g, rbf, &mut dx, false);
        ([gv / self.var, gg, gl, -tr / (self.prec * self.prec)], dx)
    }

    /// [`RbfLinear::gradients_fill`] compiled with 256-bit vectors (bit-identical results).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn gradients_fill_avx2(
        &self,
        cols: &[&[f64]],
        g: MatRef<'_, f64>,
        rbf: MatRef<'_, f64>,
        dx: &mut Mat<f64>,
    ) -> [f64; 4] {
        self.gradients_fill(cols, g, rbf, dx, true)
    }

    /// The column loop of [`RbfLinear::gradients`]: accumulates `∂L/∂X` into `dx` and returns
    /// the raw sums `[Σ G∘K_rbf, ∂L/∂γ, ∂L/∂lin, tr G]`.
    #[inline(always)]
    fn gradients_fill(
        &self,
        cols: &[&[f64]],
        g: MatRef<'_, f64>,
        rbf: MatRef<'_, f64>,
        dx: &mut Mat<f64>,
        avx2: bool,
    ) -> [f64; 4] {
        let n = g.nrows();
        let mut wbuf = vec![0.0; n];
        let (mut gv, mut gg, mut gl, mut tr) = (0.0, 0.0, 0.0, 0.0);
        let m2g = -2.0 * self.gamma;
        let lin2 = 2.0 * self.lin;
        for j in 0..n {
            let gcol = &col_slice(g, j)[j..n];
            let rcol = &col_slice(rbf, j)[j..n];
            let (gjj, rjj) = (gcol[0], rcol[0]);
            let (gcol, rcol) = (&gcol[1..], &rcol[1..]);
            tr += gjj;
            // w_i = G_ij K_rbf,ij (i > j); off-diagonal pairs count twice (G, K symmetric).
            let w = &mut wbuf[..gcol.len()];
            for ((w, &gi), &ri) in w.iter_mut().zip(gcol).zip(rcol) {
                *w = gi * ri;
            }
            gv += gjj * rjj + 2.0 * sum4(w);
            for (c, col) in cols.iter().enumerate() {
                let xj = col[j];
                let xs = &col[j + 1..];
                let dcol = dx.col_as_slice_mut(c);
                let (head, tail) = dcol.split_at_mut(j + 1);
                let b = lin2 * xj;
                let t = &mut tail[..xs.len()];
                #[cfg(target_arch = "x86_64")]
                // SAFETY: the slices have equal lengths (checked inside); this loop runs only
                // from `gradients_fill_avx2`'s AVX2 context or after the same feature check.
                let (sw, ss, sg) = if avx2 {
                    unsafe { x86::pair_sums_avx2(xs, xj, w, gcol, t, m2g, b) }
                } else {
                    pair_sums(xs, xj, w, gcol, t, m2g, b)
                };
                #[cfg(not(target_arch = "x86_64"))]
                let (sw, ss, sg) = pair_sums(xs, xj, w, gcol, t, m2g, b);
                gg -= ss;
                gl += 2.0 * xj * sg + gjj * xj * xj;
                // ∂/∂x_j of the pairs (i, j), i > j, plus the diagonal's linear term.
                head[j] += -m2g * sw + lin2 * (sg + gjj * xj);
            }
        }
        [gv, gg, gl, tr]
    }
}

/// `r_i ← (x_i − x_j)²`.
#[inline(always)]
fn set_sq_dist(r: &mut [f64], xs: &[f64], xj: f64) {
    for (r, &xi) in r.iter_mut().zip(xs) {
        let t = xi - xj;
        *r = t * t;
    }
}

/// `k_i ← x_i x_j`.
#[inline(always)]
fn set_scaled(k: &mut [f64], xs: &[f64], xj: f64) {
    for (k, &xi) in k.iter_mut().zip(xs) {
        *k = xi * xj;
    }
}

/// `r_i += (x_i − x_j)²` (a function of its own: no-alias slices, so the loop vectorises).
#[inline(always)]
fn add_sq_dist(r: &mut [f64], xs: &[f64], xj: f64) {
    for (r, &xi) in r.iter_mut().zip(xs) {
        let t = xi - xj;
        *r += t * t;
    }
}

/// `r_i ← var · exp(−γ/2 r_i)`; `exp_fast` returns 0 below −700 (no subnormal arithmetic),
/// as the libm version's early exit did.
#[inline(always)]
fn rbf_of_sq_dist(r: &mut [f64], var: f64, half_gamma: f64) {
    for r in r.iter_mut() {
        *r = var * exp_fast(half_gamma * *r);
    }
}

/// `k_i += x_i x_j`.
#[inline(always)]
fn add_scaled(k: &mut [f64], xs: &[f64], xj: f64) {
    for (k, &xi) in k.iter_mut().zip(xs) {
        *k += xi * xj;
    }
}

/// `k_i ← r_i + lin k_i`.
#[inline(always)]
fn lin_plus(k: &mut [f64], r: &[f64], lin: f64) {
    for (k, &r) in k.iter_mut().zip(r) {
        *k = r + lin * *k;
    }
}

/// One latent coordinate of column j in [`RbfLinear::gradients`]: with `δ_i = x_i − x_j`,
/// updates `t_i += m2g w_i δ_i + b G_i` and returns `(Σ w_i δ_i, Σ w_i δ_i², Σ G_i x_i)`,
/// each with four lane accumulators (fixed order, vectorisable). A function of its own so
/// that its slices carry no-alias information into the loop.
#[inline(always)]
fn pair_sums(
    xs: &[f64],
    xj: f64,
    w: &[f64],
    gcol: &[f64],
    t: &mut [f64],
    m2g: f64,
    b: f64,
) -> (f64, f64, f64) {
    let m = xs.len();
    let (w, gcol, t) = (&w[..m], &gcol[..m], &mut t[..m]);
    let (mut aw, mut ass, mut ag) = ([0.0; 4], [0.0; 4], [0.0; 4]);
    for q in 0..m / 4 {
        for l in 0..4 {
            let i = 4 * q + l;
            let dl = xs[i] - xj;
            let wd = w[i] * dl;
            aw[l] += wd;
            ass[l] += wd * dl;
            ag[l] += gcol[i] * xs[i];
            t[i] += m2g * wd + b * gcol[i];
        }
    }
    for i in m / 4 * 4..m {
        let dl = xs[i] - xj;
        let wd = w[i] * dl;
        aw[0] += wd;
        ass[0] += wd * dl;
        ag[0] += gcol[i] * xs[i];
        t[i] += m2g * wd + b * gcol[i];
    }
    (hsum(aw), hsum(ass), hsum(ag))
}

/// AVX2 versions of the reductions: the same IEEE operations in the same lane order as the
/// portable code (no FMA), so the results are bit-identical.
#[cfg(target_arch = "x86_64")]
mod x86 {
    use std::arch::x86_64::*;

    /// [`super::pair_sums`] with 256-bit vectors.
    ///
    /// # Safety
    /// The CPU must support AVX2.
    #[target_feature(enable = "avx2")]
    pub(super) unsafe fn pair_sums_avx2(
        xs: &[f64],
        xj: f64,
        w: &[f64],
        gcol: &[f64],
        t: &mut [f64],
        m2g: f64,
        b: f64,
    ) -> (f64, f64, f64) {
        let m = xs.len();
        assert!(w.len() >= m && gcol.len() >= m && t.len() >= m);
        let (vxj, vm2g, vb) = (_mm256_set1_pd(xj), _mm256_set1_pd(m2g), _mm256_set1_pd(b));
        let (mut aw, mut ass, mut ag) = (
            _mm256_setzero_pd(),
            _mm256_setzero_pd(),
            _mm256_setzero_pd(),
        );
        let (px, pw, pg, pt) = (xs.as_ptr(), w.as_ptr(), gcol.as_ptr(), t.as_mut_ptr());
        for q in 0..m / 4 {
            let i = 4 * q;
            // SAFETY: i + 3 < m ≤ every slice's length.
            unsafe {
                let xi = _mm256_loadu_pd(px.add(i));
                let gi = _mm256_loadu_pd(pg.add(i));
                let dl = _mm256_sub_pd(xi, vxj);
                let wd = _mm256_mul_pd(_mm256_loadu_pd(pw.add(i)), dl);
                aw = _mm256_add_pd(aw, wd);
                ass = _mm256_add_pd(ass, _mm256_mul_pd(wd, dl));
                ag = _mm256_add_pd(ag, _mm256_mul_pd(gi, xi));
                let upd = _mm256_add_pd(_mm256_mul_pd(vm2g, wd), _mm256_mul_pd(vb, gi));
                _mm256_storeu_pd(pt.add(i), _mm256_add_pd(_mm256_loadu_pd(pt.add(i)), upd));
            }
        }
        let lanes = |v: __m256d| -> [f64; 4] {
            let mut a = [0.0; 4];
            // SAFETY: a holds four f64.
            unsafe { _mm256_storeu_pd(a.as_mut_ptr(), v) };
            a
        };
        let (mut aw, mut ass, mut ag) = (lanes(aw), lanes(ass), lanes(ag));
        for i in m / 4 * 4..m {
            let dl = xs[i] - xj;
            let wd = w[i] * dl;
            aw[0] += wd;
            ass[0] += wd * dl;
            ag[0] += gcol[i] * xs[i];
            t[i] += m2g * wd + b * gcol[i];
        }
        (super::hsum(aw), super::hsum(ass), super::hsum(ag))
    }
}

/// Column `c` of a matrix with unit row stride, as a slice of length `nrows`.
fn col_slice(m: MatRef<'_, f64>, c: usize) -> &[f64] {
    m.col(c)
        .try_as_col_major()
        .expect("unit row stride")
        .as_slice()
}

/// Sum of four lanes, in a fixed order.
#[inline(always)]
fn hsum(a: [f64; 4]) -> f64 {
    (a[0] + a[1]) + (a[2] + a[3])
}

/// `Σ a_i` with four independent accumulators (vectorisable).
fn sum4(a: &[f64]) -> f64 {
    let mut acc = [0.0; 4];
    let mut it = a.chunks_exact(4);
    for c in &mut it {
        for l in 0..4 {
            acc[l] += c[l];
        }
    }
    for (l, &v) in it.remainder().iter().enumerate() {
        acc[l] += v;
    }
    hsum(acc)
}

/// A Gram matrix with the pieces its gradient needs.
#[derive(Clone, Debug)]
pub struct Gram {
    /// Full kernel matrix including the noise diagonal.
    pub k: Mat<f64>,
    /// RBF part `var · exp(-γ/2 ‖x_i − x_j‖²)`.
    pub rbf: Mat<f64>,
}
