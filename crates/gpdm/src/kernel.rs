//! Covariance functions of the GPDM (paper eqs. 4 and 6) and their gradients.
//!
//! Both kernels are instances of one family
//! `k(x, x') = var · exp(-γ/2 ‖x − x'‖²) + lin · xᵀx' + δ(x, x') / prec`:
//! - pose mapping, eq. 4: `k_Y` with `(var, γ, lin, prec) = (α1, α2, 0, α3)`;
//! - dynamics, eq. 6: `k_X` with `(var, γ, lin, prec) = (β1, β2, β3, β4)`.
//!
//! `δ(x, x')` is the Kronecker delta on training indices (the noise term), so it appears on
//! the diagonal of a Gram matrix and never in a cross-covariance with a test point.

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
    /// Pose kernel `k_Y` of eq. 4 from `α = [α1, α2, α3]`.
    pub fn pose(alpha: [f64; 3]) -> Self {
        RbfLinear {
            var: alpha[0],
            gamma: alpha[1],
            lin: 0.0,
            prec: alpha[2],
        }
    }

    /// Dynamics kernel `k_X` of eq. 6 from `β = [β1, β2, β3, β4]`.
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
    pub fn gram(&self, x: MatRef<'_, f64>) -> Gram {
        let n = x.nrows();
        let d = x.ncols();
        if d == 0 {
            // No coordinates: every distance and dot product is 0.
            return self.gram(Mat::<f64>::zeros(n, 1).as_ref());
        }
        let rows: Vec<f64> = (0..n)
            .flat_map(|i| (0..d).map(move |c| x[(i, c)]))
            .collect();
        let mut rbf = Mat::<f64>::zeros(n, n);
        let mut k = Mat::<f64>::zeros(n, n);
        let half_gamma = -0.5 * self.gamma;
        let noise = 1.0 / self.prec;
        for j in 0..n {
            let xj = &rows[j * d..(j + 1) * d];
            let rcol = &mut rbf
                .col_mut(j)
                .try_as_col_major_mut()
                .expect("contiguous")
                .as_slice_mut()[j..];
            let kcol = &mut k
                .col_mut(j)
                .try_as_col_major_mut()
                .expect("contiguous")
                .as_slice_mut()[j..];
            // One pass: squared distance, RBF value and (optionally) the linear term.
            for ((r, kv), xi) in rcol
                .iter_mut()
                .zip(kcol.iter_mut())
                .zip(rows[j * d..].chunks_exact(d))
            {
                let (mut s, mut dot) = (0.0, 0.0);
                for (a, b) in xi.iter().zip(xj) {
                    s += (a - b) * (a - b);
                    dot += a * b;
                }
                let arg = half_gamma * s;
                // exp underflows below −745; returning 0 early avoids subnormal arithmetic.
                *r = if arg > -700.0 {
                    self.var * arg.exp()
                } else {
                    0.0
                };
                *kv = *r + self.lin * dot;
            }
            kcol[0] += noise;
        }
        Gram { k, rbf }
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
        let rows: Vec<f64> = (0..n)
            .flat_map(|i| (0..d).map(move |c| x[(i, c)]))
            .collect();
        let mut dx = vec![0.0; n * d];
        let (mut gv, mut gg, mut gl, mut tr) = (0.0, 0.0, 0.0, 0.0);
        let two_gamma = 2.0 * self.gamma;
        for j in 0..n {
            let gcol = &g.col(j).try_as_col_major().expect("contiguous").as_slice()[j..];
            let rcol = &gram
                .rbf
                .col(j)
                .try_as_col_major()
                .expect("contiguous")
                .as_slice()[j..];
            let gjj = gcol[0];
            tr += gjj;
            gv += gjj * rcol[0];
            let xj = &rows[j * d..(j + 1) * d];
            let (lo, hi) = dx.split_at_mut((j + 1) * d);
            let dxj = &mut lo[j * d..];
            for (((gij, r), xi), dxi) in gcol[1..]
                .iter()
                .zip(&rcol[1..])
                .zip(rows[(j + 1) * d..].chunks_exact(d))
                .zip(hi.chunks_exact_mut(d))
            {
                let (mut s, mut dot) = (0.0, 0.0);
                for (a, b) in xi.iter().zip(xj) {
                    s += (a - b) * (a - b);
                    dot += a * b;
                }
                // Off-diagonal pairs count twice (G and K symmetric).
                gv += 2.0 * gij * r;
                gg -= gij * r * s;
                gl += 2.0 * gij * dot;
                let p = two_gamma * gij * r;
                let l = 2.0 * self.lin * gij;
                for c in 0..d {
                    let (a, b) = (xi[c], xj[c]);
                    dxi[c] += -p * (a - b) + l * b;
                    dxj[c] += -p * (b - a) + l * a;
                }
            }
            // Diagonal: K_jj = var + lin ‖x_j‖² + 1/prec.
            let mut dot = 0.0;
            for c in 0..d {
                let a = rows[j * d + c];
                dot += a * a;
                dx[j * d + c] += 2.0 * self.lin * gjj * a;
            }
            gl += gjj * dot;
        }
        let dxm = Mat::from_fn(n, d, |i, c| dx[i * d + c]);
        ([gv / self.var, gg, gl, -tr / (self.prec * self.prec)], dxm)
    }
}

/// A Gram matrix with the pieces its gradient needs.
#[derive(Clone, Debug)]
pub struct Gram {
    /// Full kernel matrix including the noise diagonal.
    pub k: Mat<f64>,
    /// RBF part `var · exp(-γ/2 ‖x_i − x_j‖²)`.
    pub rbf: Mat<f64>,
}
