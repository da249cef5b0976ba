//! Predictions of a trained GPDM: latent dynamics (3DV eqs. 8-10) and pose reconstruction
//! (3DV eqs. 11-13). `K_X` and `K_Y` are factorised once when the predictor is built, and
//! `K_X⁻¹ X_out` and `K_Y⁻¹ Y` are formed by triangular solves.

use crate::error::{invalid, Result};
use crate::kernel::RbfLinear;
use crate::linalg::{mul, to_na, view, Cholesky};
use crate::model::Gpdm;
use crate::vexp::exp_fast;
use faer::linalg::matmul::matmul;
use faer::reborrow::ReborrowMut;
use faer::{Accum, Mat, MatMut, MatRef, Par};
use nalgebra::{DMatrix, DVector};
use rand::RngExt;

/// A trained model ready for prediction.
#[derive(Clone, Debug)]
pub struct Predictor {
    kx: RbfLinear,
    ky: RbfLinear,
    /// Dynamics inputs X_in (M × d).
    x_in: Mat<f64>,
    chol_x: Cholesky,
    /// K_X⁻¹ X_out (M × d).
    a_x: Mat<f64>,
    /// Training latents X (N × d).
    x: Mat<f64>,
    chol_y: Cholesky,
    /// K_Y⁻¹ Y (N × D), Y centred; or K_Y⁻¹ U_r Λ_r^½ (N × r) with a pose basis; or the
    /// eigenvectors Q_R (N × R) of K_Y with a kernel basis.
    a_y: Mat<f64>,
    /// Optional basis B with the mean appended, `[B | ȳ]` stored D × (r+1) (column-major, the
    /// layout the bulk GEMM of [`Predictor::pose_mean_cols`] reads), so that
    /// μ_Y = ȳ + B (a_yᵀ k_Y): B is the pose basis V_r, or `(K_Y⁻¹ Y)ᵀ Q_R` for a kernel basis.
    basis: Option<Mat<f64>>,
    /// With a kernel basis ([`Predictor::with_kernel_basis`]): `max_j ‖(K_Y⁻¹ Y)_j‖`.
    basis_amax: Option<f64>,
    y_mean: DVector<f64>,
    /// Jitter notes from the factorisations (empty when none was needed); callers log these.
    pub notes: Vec<String>,
}

impl Predictor {
    /// Factorises the kernel matrices of `model`.
    pub fn new(model: &Gpdm) -> Result<Self> {
        let mut p = Self::factorised(model)?;
        solve_cols_par(&p.chol_y, p.a_y.as_mut());
        Ok(p)
    }

    /// [`Predictor::new`] with `a_y` still the centred Y (not yet solved with `K_Y`).
    fn factorised(model: &Gpdm) -> Result<Self> {
        let layout = model.layout();
        let d = model.config.latent_dim;
        let x = view(&model.x).to_owned();
        let x_in = Mat::from_fn(layout.x_in.len(), d, |i, j| x[(layout.x_in[i], j)]);
        let x_out = Mat::from_fn(layout.x_out.len(), d, |i, j| x[(layout.x_out[i], j)]);
        let kx = RbfLinear::dynamics(model.beta);
        let ky = RbfLinear::pose(model.alpha);
        let chol_x = Cholesky::factor(kx.gram(x_in.as_ref()).k.as_ref(), "K_X")?;
        let chol_y = Cholesky::factor(ky.gram(x.as_ref()).k.as_ref(), "K_Y")?;
        let mut notes = vec![];
        for (name, c) in [("K_X", &chol_x), ("K_Y", &chol_y)] {
            if c.jitter > 0.0 {
                notes.push(format!("{name}: Cholesky needed jitter {:e}", c.jitter));
            }
        }
        let a_x = chol_x.solve_mat(x_out.as_ref());
        let a_y = view(&model.y).to_owned();
        Ok(Predictor {
            kx,
            ky,
            x_in,
            chol_x,
            a_x,
            x,
            chol_y,
            a_y,
            basis: None,
            basis_amax: None,
            y_mean: model.y_mean.clone(),
            notes,
        })
    }

    /// Like [`Predictor::new`], but decodes poses through the top-r principal directions of
    /// the centred training poses, `Y ≈ U_r Λ_r^½ V_rᵀ` (from the N × N eigenproblem of Y Yᵀ),
    /// with r the smallest rank whose discarded energy `Σ_{k>r} λ_k` is at most
    /// `rel_tol · Σ_k λ_k`. Eq. 12 then costs `T·N·r + T·r·D` instead of `T·N·D`; with
    /// `rel_tol = 0` only exactly-zero directions are dropped and the mean is unchanged.
    /// Returns the kept rank and the RMS reconstruction error of the training poses.
    pub fn with_pose_basis(model: &Gpdm, rel_tol: f64) -> Result<(Self, usize, f64)> {
        if !(rel_tol >= 0.0 && rel_tol < 1.0) {
            return invalid(format!("relative tolerance {rel_tol} outside [0, 1)"));
        }
        let mut p = Predictor::new(model)?;
        let n = model.y.nrows();
        let s = to_na(crate::linalg::mul_abt(view(&model.y), view(&model.y)).as_ref());
        let eig = nalgebra::SymmetricEigen::new(s);
        let mut order: Vec<usize> = (0..n).collect();
        order.sort_by(|&a, &b| eig.eigenvalues[b].total_cmp(&eig.eigenvalues[a]));
        let lam: Vec<f64> = order.iter().map(|&k| eig.eigenvalues[k].max(0.0)).collect();
        let total: f64 = lam.iter().sum();
        let floor = lam.first().copied().unwrap_or(0.0) * 1e-14;
        let mut r = 0;
        let mut rest = total;
        while r < n && lam[r] > floor && rest > rel_tol * total {
            rest -= lam[r];
            r += 1;
        }
        let r = r.max(1);
        let discarded: f64 = lam[r..].iter().sum();
        // U_r Λ_r^½ (N × r) and V_rᵀ = Λ_r^-½ U_rᵀ Y (r × D).
        let us = Mat::from_fn(n, r, |i, c| eig.eigenvectors[(i, order[c])] * lam[c].sqrt());
        let ut = Mat::from_fn(r, n, |c, i| eig.eigenvectors[(i, order[c])] / lam[c].sqrt());
        p.basis = Some(with_mean_col(
            mul(ut.as_ref(), view(&model.y)).transpose(),
            &model.y_mean,
        ));
        p.a_y = p.chol_y.solve_mat(us.as_ref());
        let rms = (discarded.max(0.0) / (n * model.y.ncols()) as f64).sqrt();
        Ok((p, r, rms))
    }

    /// Decoding through the leading eigenvectors of `K_Y` instead of the pose basis: 3DV eq. 12,
    /// `μ_Y(x) = ȳ + (K_Y⁻¹ Y)ᵀ k_Y(x)`, with `k_Y(x)` replaced by its projection `Q_R Q_Rᵀ
    /// k_Y(x)` onto the top-R eigenvectors `Q_R` of `K_Y` (N × N; a factorisation, no inverse
    /// is formed: `Q_Rᵀ K_Y⁻¹ Y` comes from the Cholesky solution). The error of coordinate j is
    /// `a_jᵀ (I − Q_R Q_Rᵀ) k_Y(x)` with `a_j` column j of `K_Y⁻¹ Y`, at most
    /// `max_j ‖a_j‖ · ‖(I − Q_R Q_Rᵀ) k_Y(x)‖` (Cauchy-Schwarz). R is the smallest rank for
    /// which this bound is at most `max_abs` at every training latent point (where `k_Y(x_i)`
    /// is column i of the noise-free Gram matrix, so the residual has the closed form
    /// `Σ_{l>R} (λ_l − σ²)² q_{l,i}²`); [`Predictor::basis_error_bound`] evaluates it for new
    /// points. Unlike a basis of Y it does not have to reproduce the training poses' noise,
    /// which the GP mean smooths. Cost of 3DV eq. 12: `T·N·R + T·R·D` instead of `T·N·D`.
    /// Returns the predictor, R and the bound at the training points.
    pub fn with_kernel_basis(model: &Gpdm, max_abs: f64) -> Result<(Self, usize, f64)> {
        if !(max_abs >= 0.0) {
            return invalid(format!("error bound {max_abs} must be non-negative"));
        }
        let mut p = Predictor::factorised(model)?;
        let n = p.x.nrows();
        let g = p.ky.gram(p.x.as_ref()).k; // lower triangle filled
        let full = DMatrix::from_fn(n, n, |i, j| if i >= j { g[(i, j)] } else { g[(j, i)] });
        let eig = nalgebra::SymmetricEigen::new(full);
        let mut order: Vec<usize> = (0..n).collect();
        order.sort_by(|&a, &b| eig.eigenvalues[b].total_cmp(&eig.eigenvalues[a]));
        let noise = 1.0 / p.ky.prec + p.chol_y.jitter;
        let mu: Vec<f64> = order
            .iter()
            .map(|&l| (eig.eigenvalues[l] - noise).max(0.0))
            .collect();
        // The factorised K_Y is `Q diag(λ + jitter) Qᵀ`, so `K_Y⁻¹ Y = Q diag(1 / (λ + jitter)) Cᵀ`
        // with `C = Yᵀ Q` (D × N, one GEMM, columns in `order`): the columns of K_Y⁻¹ Y have the
        // norms of C's scaled rows, and the basis `(K_Y⁻¹ Y)ᵀ Q_R` is C's first R scaled columns.
        let q_all = Mat::from_fn(n, n, |i, c| eig.eigenvectors[(i, order[c])]);
        let mut c = Mat::<f64>::zeros(p.a_y.ncols(), n);
        let yt = p.a_y.as_ref().transpose();
        matmul(c.as_mut(), Accum::Replace, yt, q_all.as_ref(), 1.0, Par::rayon(0));
        let mut norms = vec![0.0; c.nrows()];
        for (col, &l) in order.iter().enumerate() {
            let inv = 1.0 / (eig.eigenvalues[l] + p.chol_y.jitter);
            for (v, norm) in c.col_mut(col).iter_mut().zip(&mut norms) {
                *v *= inv;
                *norm += *v * *v;
            }
        }
        let amax = norms.iter().fold(0.0f64, |m, &v| m.max(v)).sqrt();
        // tail[i] = Σ_{l ≥ R} μ_l² q_{l,i}², from R = N downwards.
        let mut tail = vec![0.0; n];
        let mut r = n;
        let mut bound = 0.0;
        while r > 0 {
            let l = order[r - 1];
            let next: Vec<f64> = (0..n)
                .map(|i| tail[i] + (mu[r - 1] * eig.eigenvectors[(i, l)]).powi(2))
                .collect();
            let b = amax * next.iter().fold(0.0f64, |m, &v| m.max(v)).sqrt();
            if b > max_abs {
                break;
            }
            tail = next;
            bound = b;
            r -= 1;
        }
        let r = r.max(1);
        p.basis = Some(with_mean_col(c.as_ref().subcols(0, r), &p.y_mean));
        p.a_y = q_all.as_ref().subcols(0, r).to_owned();
        p.basis_amax = Some(amax);
        Ok((p, r, bound))
    }

    /// For a predictor from [`Predictor::with_kernel_basis`]: the largest certified bound on
    /// `|μ_Y − μ_Y,exact|` over the coordinates and the rows of `xs`; `None` otherwise.
    pub fn basis_error_bound(&self, xs: &DMatrix<f64>) -> Option<f64> {
        let amax = self.basis_amax?;
        let kstar = self.ky.cross(self.x.as_ref(), view(xs)); // N × T
        let proj = mul(self.a_y.as_ref().transpose(), kstar.as_ref()); // R × T
        let worst = (0..xs.nrows())
            .map(|t| (kstar.col(t).squared_norm_l2() - proj.col(t).squared_norm_l2()).max(0.0))
            .fold(0.0f64, f64::max);
        Some(amax * worst.sqrt())
    }

    /// Rank of the pose basis, if any.
    pub fn basis_rank(&self) -> Option<usize> {
        self.basis.as_ref().map(|b| b.ncols() - 1)
    }

    /// Eq. 12 factored as `μ_Y(x_t) = [B | ȳ] [c(x_t); 1]`: the coefficients `[c(x_t); 1]`
    /// ((R+1) × T) of the rows of `xs`, `c = a_yᵀ k_Y(X, x_t)` with a basis and `c = k_Y(X, x_t)`
    /// (R = N) for the exact predictor. With [`Predictor::pose_basis`], callers that need only
    /// some pose coordinates (a block of vertices) multiply only those rows.
    pub fn pose_coefficients(&self, xs: &DMatrix<f64>) -> Result<Mat<f64>> {
        self.check_latent(xs)?;
        let kstar = self.pose_cross(xs); // N × T
        let t = xs.nrows();
        let r = if self.basis.is_some() {
            self.a_y.ncols()
        } else {
            kstar.nrows()
        };
        let mut coef = Mat::<f64>::zeros(r + 1, t);
        if self.basis.is_some() {
            matmul(
                coef.as_mut().subrows_mut(0, r),
                Accum::Replace,
                self.a_y.as_ref().transpose(),
                kstar.as_ref(),
                1.0,
                Par::Seq,
            );
        } else {
            coef.as_mut().subrows_mut(0, r).copy_from(kstar.as_ref());
        }
        coef.as_mut().row_mut(r).fill(1.0);
        Ok(coef)
    }

    /// `[B | ȳ]` (D × (R+1), column-major) of [`Predictor::pose_coefficients`]: the stored basis,
    /// or `[(K_Y⁻¹ Y)ᵀ | ȳ]` for the exact predictor (built here: call once, not per frame).
    pub fn pose_basis(&self) -> Mat<f64> {
        match &self.basis {
            Some(b) => b.clone(),
            None => {
                let n = self.a_y.nrows();
                Mat::from_fn(self.a_y.ncols(), n + 1, |i, j| {
                    if j < n {
                        self.a_y[(j, i)]
                    } else {
                        self.y_mean[i]
                    }
                })
            }
        }
    }

    /// Eq. 12 for the rows of `xs` (T × d) written as the columns of `out` (D × T column-major,
    /// one frame per column, so that each frame's coordinates are contiguous): `out = ȳ 1ᵀ + (K_Y⁻¹ Y)ᵀ
    /// k_Y(X, X_*)`, or `ȳ 1ᵀ + V_r (k_Y(X_*, X) a_y)ᵀ` with a pose basis. One sequential
    /// GEMM (callers parallelise over trajectories).
    pub fn pose_mean_cols(&self, xs: &DMatrix<f64>, out: &mut [f64]) -> Result<()> {
        self.check_latent(xs)?;
        let t = xs.nrows();
        if out.len() != self.pose_dim() * t {
            return invalid(format!(
                "output has {} values, expected {} x {t}",
                out.len(),
                self.pose_dim()
            ));
        }
        let mut out = MatMut::from_column_major_slice_mut(out, self.pose_dim(), t);
        if let Some(b) = &self.basis {
            // [B | ȳ] · [coef; 1ᵀ]: the mean rides in the GEMM, so the D × T output is written
            // once (the separate fill pass cost as much as the GEMM: the output is memory-bound).
            let coef = self.pose_coefficients(xs)?;
            matmul(
                out,
                Accum::Replace,
                b.as_ref(),
                coef.as_ref(),
                1.0,
                Par::Seq,
            );
            return Ok(());
        }
        let kstar = self.pose_cross(xs); // N × T
        for j in 0..t {
            for (o, &m) in out.rb_mut().col_mut(j).iter_mut().zip(self.y_mean.iter()) {
                *o = m;
            }
        }
        matmul(
            out,
            Accum::Add,
            self.a_y.as_ref().transpose(),
            kstar.as_ref(),
            1.0,
            Par::Seq,
        );
        Ok(())
    }

    /// `k_Y(X, X_*)` (N × T) for the rows of `xs`, as `RbfLinear::cross` but with the
    /// vectorised [`exp_fast`] on per-coordinate arrays, `var·e^a` as `e^(a + ln var)` and 0
    /// below `e^-700` (no subnormal products).
    fn pose_cross(&self, xs: &DMatrix<f64>) -> Mat<f64> {
        let (n, t, d) = (self.x.nrows(), xs.nrows(), xs.ncols());
        let cols: Vec<Vec<f64>> = (0..d)
            .map(|c| (0..n).map(|i| self.x[(i, c)]).collect())
            .collect();
        let ln_var = if self.ky.var > 0.0 {
            self.ky.var.ln()
        } else {
            f64::NEG_INFINITY
        };
        let half_gamma = -0.5 * self.ky.gamma;
        let mut out = Mat::<f64>::zeros(n, t);
        let mut dist = vec![0.0; n];
        let mut dot = vec![0.0; n];
        for j in 0..t {
            dist.fill(0.0);
            dot.fill(0.0);
            for (c, xc) in cols.iter().enumerate() {
                let v = xs[(j, c)];
                for ((s, dp), &xi) in dist.iter_mut().zip(dot.iter_mut()).zip(xc) {
                    *s += (v - xi) * (v - xi);
                    *dp += v * xi;
                }
            }
            let col = out
                .col_mut(j)
                .try_as_col_major_mut()
                .expect("contiguous")
                .as_slice_mut();
            for ((o, &s), &dp) in col.iter_mut().zip(&dist).zip(&dot) {
                *o = exp_fast(half_gamma * s + ln_var) + self.ky.lin * dp;
            }
        }
        out
    }

    /// Latent dimension d.
    pub fn latent_dim(&self) -> usize {
        self.x.ncols()
    }

    /// Pose dimension D.
    pub fn pose_dim(&self) -> usize {
        self.y_mean.len()
    }

    /// Dynamics kernel.
    pub fn dynamics_kernel(&self) -> RbfLinear {
        self.kx
    }

    /// Dynamics inputs X_in (M × d).
    pub fn dynamics_inputs(&self) -> MatRef<'_, f64> {
        self.x_in.as_ref()
    }

    /// K_X⁻¹ X_out (M × d).
    pub fn dynamics_weights(&self) -> MatRef<'_, f64> {
        self.a_x.as_ref()
    }

    /// Cholesky factor of K_X.
    pub fn dynamics_cholesky(&self) -> &Cholesky {
        &self.chol_x
    }

    /// Eqs. 9 and 10: mean `μ_X(x) = X_outᵀ K_X⁻¹ k_X(x)` and variance
    /// `σ²_X(x) = k_X(x, x) − k_X(x)ᵀ K_X⁻¹ k_X(x)` of the next latent point (k_X(x, x)
    /// includes the noise 1/β4: the next point is a noisy observation of the mapping).
    pub fn dynamics(&self, x: &[f64]) -> (Vec<f64>, f64) {
        let d = self.latent_dim();
        let q = MatRef::from_row_major_slice(x, 1, d);
        let kstar = self.kx.cross(self.x_in.as_ref(), q); // M × 1
        let mu = mul(self.a_x.as_ref().transpose(), kstar.as_ref());
        let mut v = kstar.clone();
        self.chol_x.half_solve_in_place(v.as_mut());
        let var = self.kx.self_cov(x) - v.col(0).squared_norm_l2();
        ((0..d).map(|c| mu[(c, 0)]).collect(), var)
    }

    /// Eq. 8 by mean prediction: `x̂_1 = x1`, `x̂_{t+1} = μ_X(x̂_t)`; returns `len × d`.
    pub fn mean_trajectory(&self, x1: &[f64], len: usize) -> Result<DMatrix<f64>> {
        let d = self.latent_dim();
        if x1.len() != d {
            return invalid(format!(
                "start point has {} coordinates, expected {d}",
                x1.len()
            ));
        }
        let mut out = DMatrix::zeros(len, d);
        if len == 0 {
            return Ok(out);
        }
        let mut cur = x1.to_vec();
        for t in 0..len {
            for c in 0..d {
                out[(t, c)] = cur[c];
            }
            cur = self.dynamics(&cur).0;
        }
        Ok(out)
    }

    fn check_latent(&self, xs: &DMatrix<f64>) -> Result<()> {
        if xs.ncols() != self.latent_dim() {
            return invalid(format!(
                "latent points have {} coordinates, expected {}",
                xs.ncols(),
                self.latent_dim()
            ));
        }
        Ok(())
    }

    /// Eq. 12 for each row of `xs` (T × d): `μ_Y(x) = Yᵀ K_Y⁻¹ k_Y(x)` plus the data mean.
    ///
    /// One GEMM `k_Y(X_*, X) · (K_Y⁻¹ Y)` (T × N × D, or T × N × r then T × r × D with a pose
    /// basis) accumulated straight into the mean-initialised output; the output columns are
    /// split across rayon threads (each column block computed identically whatever the thread
    /// count, so results do not depend on it).
    pub fn pose_mean(&self, xs: &DMatrix<f64>) -> Result<DMatrix<f64>> {
        self.check_latent(xs)?;
        let t = xs.nrows();
        let kstar = self.ky.cross(view(xs), self.x.as_ref()); // T × N
        let mut m = DMatrix::<f64>::zeros(t, self.pose_dim());
        if t > 0 {
            for (col, &mu) in m.as_mut_slice().chunks_exact_mut(t).zip(self.y_mean.iter()) {
                col.fill(mu);
            }
        }
        let out = MatMut::from_column_major_slice_mut(m.as_mut_slice(), t, self.pose_dim());
        match &self.basis {
            Some(b) => {
                let coef = mul(kstar.as_ref(), self.a_y.as_ref()); // T × r
                let r = b.ncols() - 1;
                gemm_add_cols(out, coef.as_ref(), b.as_ref().subcols(0, r).transpose());
            }
            None => gemm_add_cols(out, kstar.as_ref(), self.a_y.as_ref()),
        }
        Ok(m)
    }

    /// [`Predictor::pose_mean`] for many trajectories, decoded in parallel (rayon, one
    /// trajectory per task); the output is identical for any number of threads.
    pub fn pose_means(&self, trajs: &[DMatrix<f64>]) -> Result<Vec<DMatrix<f64>>> {
        use rayon::prelude::*;
        trajs.par_iter().map(|t| self.pose_mean(t)).collect()
    }

    /// Eq. 13 for each row of `xs`: `σ²_Y(x) = k_Y(x, x) − k_Y(x)ᵀ K_Y⁻¹ k_Y(x)`, with
    /// k_Y(x, x) = α1 + 1/α3 (a new noisy pose).
    pub fn pose_variance(&self, xs: &DMatrix<f64>) -> Result<Vec<f64>> {
        self.check_latent(xs)?;
        let mut v = self.ky.cross(self.x.as_ref(), view(xs)); // N × T
        self.chol_y.half_solve_in_place(v.as_mut());
        Ok((0..xs.nrows())
            .map(|t| {
                let row: Vec<f64> = xs.row(t).iter().copied().collect();
                (self.ky.self_cov(&row) - v.col(t).squared_norm_l2()).max(0.0)
            })
            .collect())
    }

    /// [`Predictor::pose_variance`] over the prior's `k_Y(x, x)` for each row of `xs`: near 0
    /// on the learned latent points, 1 where the training poses say nothing about the pose (the
    /// mean of eq. 12 there falls back to the data mean, whatever the motion).
    pub fn pose_variance_ratio(&self, xs: &DMatrix<f64>) -> Result<Vec<f64>> {
        Ok(self
            .pose_variance(xs)?
            .into_iter()
            .zip(xs.row_iter())
            .map(|(v, x)| v / self.ky.self_cov(&x.iter().copied().collect::<Vec<_>>()))
            .collect())
    }

    /// Eq. 11: poses for the latent rows of `xs`; the mean (3DV eq. 12) when `rng` is `None`,
    /// otherwise a draw `ỹ ~ N(μ_Y(x), σ²_Y(x) I)`.
    pub fn reconstruct<R: rand::Rng + ?Sized>(
        &self,
        xs: &DMatrix<f64>,
        rng: Option<&mut R>,
    ) -> Result<DMatrix<f64>> {
        let mut m = self.pose_mean(xs)?;
        if let Some(rng) = rng {
            let var = self.pose_variance(xs)?;
            for (t, v) in var.iter().enumerate() {
                let s = v.sqrt();
                for c in 0..m.ncols() {
                    let z: f64 = rng.sample(rand_distr::StandardNormal);
                    m[(t, c)] += s * z;
                }
            }
        }
        Ok(m)
    }
}

/// `out += a · b`, sequential GEMMs on column blocks of at least 256 columns, split
/// recursively with `rayon::join` (deterministic: every block is the same sequential GEMM).
fn gemm_add_cols(out: MatMut<'_, f64>, a: MatRef<'_, f64>, b: MatRef<'_, f64>) {
    let cols = out.ncols();
    if cols < 512 || out.nrows() * cols < 1 << 16 {
        matmul(out, Accum::Add, a, b, 1.0, Par::Seq);
        return;
    }
    let half = cols / 2;
    let (left, right) = out.split_at_col_mut(half);
    let (bl, br) = b.split_at_col(half);
    rayon::join(
        || gemm_add_cols(left, a, bl),
        || gemm_add_cols(right, a, br),
    );
}

/// `rhs ← K⁻¹ rhs` with the columns split across rayon threads (blocks of ≥ 256 columns).
fn solve_cols_par(chol: &Cholesky, rhs: MatMut<'_, f64>) {
    let cols = rhs.ncols();
    if cols < 512 {
        chol.solve_in_place(rhs);
        return;
    }
    let (left, right) = rhs.split_at_col_mut(cols / 2);
    rayon::join(
        || solve_cols_par(chol, left),
        || solve_cols_par(chol, right),
    );
}

/// `[b | mean]` (D × (r+1)), column-major.
fn with_mean_col(b: MatRef<'_, f64>, mean: &DVector<f64>) -> Mat<f64> {
    let r = b.ncols();
    Mat::from_fn(
        b.nrows(),
        r + 1,
        |i, j| if j < r { b[(i, j)] } else { mean[i] },
    )
}
