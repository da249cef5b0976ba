//! The GPDM negative log posterior, 3DV eqs. 3-7, with analytic gradients.
//!
//! With `Y` the centred poses (N × D, sequences stacked), `X` the latent points (N × d),
//! `X_in`/`X_out` the latent points that have a successor/predecessor in the same sequence
//! (M = N − #sequences rows each), the minimised objective is (constants dropped)
//!
//! ```text
//! L = D/2 ln|K_Y| + 1/2 tr(K_Y⁻¹ Y Yᵀ)                      3DV eq. 3 (N × N form, Y Yᵀ precomputed)
//!   + d/2 ln|K_X| + 1/2 tr(K_X⁻¹ X_out X_outᵀ)              3DV eq. 5, K_X = k_X(X_in, X_in)
//!   + Σ_seq ‖x_first‖² / (2 σ0²)                            isotropic prior on each first point
//!   + Σ_k ln α_k + Σ_k ln β_k                               priors P(α) = ∏ 1/α_k, P(β) = ∏ 1/β_k
//!   + Σ_{k=1..3} (ln β_k)² / (2 s²)                          weak log-normal factor (deviation)
//! ```
//!
//! Well-posedness (a deviation from 3DV eq. 7 as printed, docs/DEVIATIONS.md): with `∏ 1/β` alone the objective
//! has no minimum whenever the data do not need a dynamics-kernel component: `ln β1`, `ln β2`
//! (RBF part) or `ln β3` (linear part) then fall without bound (β → 5e-324 in the demo fits)
//! and an optimiser stops only at its iteration limit. [`GpdmConfig::beta_log_sd`] multiplies
//! `1/β_k` (k = 1..3) by a log-normal `N(ln β_k; 0, s²)` (centred on the paper's start β = 1,
//! latents start at unit variance): a proper prior, so the minimum exists; an unused component
//! settles at `β_k = e^{−s²}` (1.2e-4 for s = 3, below the dynamics-noise floor 1e-3), and a
//! component the data determine moves by `ln β_k / s²` in gradient, i.e. negligibly. With the
//! noise floors on `1/α3` and `1/β4` (the latter needed to stop the latent scale from collapsing)
//! every term is bounded below in the directions the optimiser can reach.
//!
//! Latent scale (a deviation, docs/DEVIATIONS.md): the pose term is exactly invariant under
//! `X → cX, α2 → α2/c²`, so the scale of X is set only by the dynamics term and the priors, and
//! with an absolute dynamics-noise floor they favour `X → 0` (dynamics reduced to noise: on the
//! synthetic N = 446 problem an optimiser that follows this valley reaches α2 = 6e4, 728 nats
//! below where plain L-BFGS stalls after 2000 iterations). With
//! [`GpdmConfig::fixed_latent_scale`] the optimisation coordinates hold `X̃` and the model uses
//! `X = √(N d) X̃ / ‖X̃‖_F` (unit mean square, the PCA start's scale, the scale the floors are
//! stated in): one gauge direction removed, every other minimum of 3DV eq. 7 kept.
//!
//! Optimisation coordinates `θ` (see [`Gpdm::theta`]): X column-major, then `ln α1, ln α2,
//! ln(1/α3 − floor_Y)`, then `ln β1, ln β2, ln β3, ln(1/β4 − floor_X)`. The noise-variance floor
//! (`1/α3 ≥ floor`) is built into the parametrisation, so the objective stays bounded below
//! when the data are noise-free. The MAP point in (X, α, β) is unchanged by the
//! reparametrisation (no Jacobian term: this is optimisation, not a density change).

use crate::error::{invalid, Result};
use crate::kernel::RbfLinear;
use crate::linalg::{
    lower_wwt_scaled_only, lower_zzt_scaled_only, mul_abt, recycle, view, Cholesky, CholeskyProducts,
    PivotedCholesky, Split,
};
use faer::{Mat, MatRef};
use nalgebra::{DMatrix, DVector};
use serde::{Deserialize, Serialize};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::OnceLock;
use std::time::{Duration, Instant};

/// Model options.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GpdmConfig {
    /// Latent dimension d (paper: 3).
    pub latent_dim: usize,
    /// Lower bound on the pose-noise variance 1/α3, in squared units of Y (default 1e-6 m²).
    pub pose_noise_floor: Option<f64>,
    /// Lower bound on the dynamics-noise variance 1/β4, in squared latent units (default none,
    /// the paper's unbounded β4). On clean data 1/β4 collapses to ~1e-9 and HMC returns copies
    /// of the source; the PCA start scales the latents to unit mean variance, so a floor of
    /// 1e-4..1e-3 keeps the one-step noise at ≥ 1-3 % of the latent spread (measured with
    /// the `variation` study binary: none → 0 mm variation, 1e-4 → 3 mm, 1e-3 → 12 mm with the mean
    /// prediction within 0.3 mm, 1e-2 → 29 mm and 12 mm off the training poses). Not the
    /// default: on the 2-D rotation test model a 1e-4 floor already lets samples leave the
    /// data (tests/learning.rs), so callers choose it per data set.
    pub dyn_noise_floor: Option<f64>,
    /// Variance σ0² of the isotropic Gaussian prior on each sequence's first latent point.
    pub first_point_var: f64,
    /// Standard deviation `s` of the weak log-normal factor on β1, β2, β3 (see the module
    /// doc; default 3, `None` = the paper's improper `∏ 1/β` as printed, which has no minimum).
    /// Not stored in model files (the payload layout predates it; prediction does not use it).
    #[serde(skip, default = "default_beta_log_sd")]
    pub beta_log_sd: Option<f64>,
    /// Keep the latent positions at unit mean square (see the module doc; default true).
    /// Not stored in model files, like `beta_log_sd`.
    #[serde(skip, default = "default_true")]
    pub fixed_latent_scale: bool,
    /// Weight of the dynamics term (3DV eq. 5 with the first-point priors) in the objective
    /// (see [`DynamicsWeight`]). Not stored in model files, like `beta_log_sd`.
    #[serde(skip)]
    pub dynamics_weight: DynamicsWeight,
}

/// The weight λ of the dynamics term in the minimised objective `L = L_pose + λ L_dyn + priors`.
///
/// With `D` pose dimensions and `d` latent ones the pose term of 3DV eq. 3 counts `D/2 ln|K_Y|`
/// against the dynamics term's `d/2 ln|K_X|`: for a body part (`D` in the thousands, `d = 3`)
/// the latent positions are placed for the poses alone and the dynamics learned on them is weak;
/// its mean prediction settles toward a point within a few frames. The *balanced* GPDM (Wang,
/// Fleet and Hertzmann, "Gaussian Process Dynamical Models for Human Motion", PAMI 2008, §3.3)
/// raises the dynamics density to the power `D/d`, which gives both terms equal say.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "kebab-case")]
pub enum DynamicsWeight {
    /// λ = 1: 3DV eq. 7 as printed.
    #[default]
    Paper,
    /// λ = D/d: the balanced GPDM.
    Balanced,
}

impl DynamicsWeight {
    /// λ for `d_obs` pose and `latent_dim` latent dimensions.
    pub fn lambda(self, d_obs: usize, latent_dim: usize) -> f64 {
        match self {
            DynamicsWeight::Paper => 1.0,
            DynamicsWeight::Balanced => d_obs as f64 / latent_dim.max(1) as f64,
        }
    }
}

fn default_true() -> bool {
    true
}

/// Default of [`GpdmConfig::beta_log_sd`].
pub const BETA_LOG_SD: f64 = 3.0;

fn default_beta_log_sd() -> Option<f64> {
    Some(BETA_LOG_SD)
}

impl Default for GpdmConfig {
    fn default() -> Self {
        GpdmConfig {
            latent_dim: 3,
            pose_noise_floor: Some(1e-6),
            dyn_noise_floor: None,
            first_point_var: 1.0,
            beta_log_sd: default_beta_log_sd(),
            fixed_latent_scale: true,
            dynamics_weight: DynamicsWeight::default(),
        }
    }
}

/// Which rows of X enter the dynamics: no transition crosses a sequence boundary.
#[derive(Clone, Debug, PartialEq)]
pub struct Layout {
    /// Sequence lengths (each ≥ 2), in stacking order.
    pub seq_lens: Vec<usize>,
    /// Rows with a successor in the same sequence (`X_in`, the dynamics inputs).
    pub x_in: Vec<usize>,
    /// Their successors (`X_out` = the paper's X').
    pub x_out: Vec<usize>,
    /// First row of each sequence.
    pub firsts: Vec<usize>,
}

impl Layout {
    /// Builds the layout; every sequence needs at least two frames.
    pub fn new(seq_lens: &[usize]) -> Result<Self> {
        if seq_lens.is_empty() {
            return invalid("no sequences");
        }
        let (mut x_in, mut x_out, mut firsts) = (vec![], vec![], vec![]);
        let mut start = 0;
        for (s, &len) in seq_lens.iter().enumerate() {
            if len < 2 {
                return invalid(format!(
                    "sequence {s} has {len} frame(s); at least 2 needed"
                ));
            }
            firsts.push(start);
            for t in start..start + len - 1 {
                x_in.push(t);
                x_out.push(t + 1);
            }
            start += len;
        }
        Ok(Layout {
            seq_lens: seq_lens.to_vec(),
            x_in,
            x_out,
            firsts,
        })
    }

    /// Total number of frames N.
    pub fn n(&self) -> usize {
        self.seq_lens.iter().sum()
    }
}

/// `α` from optimisation coordinates: `[e^θ0, e^θ1, 1/(floor + e^θ2)]`.
pub fn alpha_from_theta(t: &[f64], floor: Option<f64>) -> [f64; 3] {
    [
        t[0].exp(),
        t[1].exp(),
        1.0 / (floor.unwrap_or(0.0) + t[2].exp()),
    ]
}

/// `β` from optimisation coordinates: `[e^θ0, e^θ1, e^θ2, 1/(floor + e^θ3)]`.
pub fn beta_from_theta(t: &[f64], floor: Option<f64>) -> [f64; 4] {
    [
        t[0].exp(),
        t[1].exp(),
        t[2].exp(),
        1.0 / (floor.unwrap_or(0.0) + t[3].exp()),
    ]
}

/// Inverse of the noise transform: `ln(1/prec − floor)`, clamped when `1/prec ≤ floor`.
fn noise_theta(prec: f64, floor: Option<f64>) -> f64 {
    let f = floor.unwrap_or(0.0);
    // Clamp at rounding level: 1/prec − f cancels when the variance sits on the floor.
    (1.0 / prec - f).max((1e-15 * f).max(1e-300)).ln()
}

/// Value of the objective split into its terms, plus any Cholesky jitter that was needed.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Eval {
    /// Total negative log posterior (constants dropped).
    pub value: f64,
    /// Pose term, 3DV eq. 3.
    pub pose: f64,
    /// Dynamics term, 3DV eq. 5 (including the first-point priors).
    pub dynamics: f64,
    /// Hyperparameter priors.
    pub prior: f64,
    /// Jitter added to K_Y (0 if none).
    pub jitter_y: f64,
    /// Jitter added to K_X (0 if none).
    pub jitter_x: f64,
}

/// The negative log posterior of 3DV eq. 7 for fixed data; `S = Y Yᵀ` and its pivoted Cholesky
/// factor `Pᵀ S P = R Rᵀ` are formed once here.
#[derive(Clone, Debug)]
pub struct Objective {
    /// `S = Y Yᵀ`, kept for [`Objective::eval_reference`].
    yyt: Mat<f64>,
    /// `Pᵀ S P = R Rᵀ`; the pose term is evaluated on the frames in pivot order.
    s_factor: PivotedCholesky,
    d_obs: usize,
    latent_dim: usize,
    layout: Layout,
    config: GpdmConfig,
}

impl Objective {
    /// Prepares the objective for centred poses `y` (N × D).
    pub fn new(y: MatRef<'_, f64>, layout: Layout, config: GpdmConfig) -> Result<Self> {
        if y.nrows() != layout.n() {
            return invalid(format!(
                "Y has {} rows but the sequences total {}",
                y.nrows(),
                layout.n()
            ));
        }
        let yyt = mul_abt(y, y);
        Ok(Objective {
            s_factor: PivotedCholesky::factor(yyt.as_ref()),
            yyt,
            d_obs: y.ncols(),
            latent_dim: config.latent_dim,
            layout,
            config,
        })
    }

    /// Length of the optimisation vector θ.
    pub fn n_params(&self) -> usize {
        self.layout.n() * self.latent_dim + 7
    }

    /// Numerical rank r of `S = Y Yᵀ` kept by the pivoted Cholesky factor.
    pub fn s_rank(&self) -> usize {
        self.s_factor.r.ncols()
    }

    /// Evaluates `L(θ)`; writes `∂L/∂θ` into `grad` when given. The pose and dynamics terms
    /// are computed concurrently: on a rayon worker by `rayon::join` (on one thread when the
    /// pool has one); from outside a pool the pose term runs on the calling thread and the
    /// dynamics term on the objective's own worker thread, which spins for up to 0.5 ms
    /// afterwards waiting for the next evaluation.
    pub fn eval(&self, theta: &[f64], grad: Option<&mut [f64]>) -> Result<Eval> {
        self.eval_with(theta, grad, false)
    }

    /// [`Objective::eval`] by the straightforward dense algebra (the algebra before the reduced-flop pose term: two full
    /// solves for `L⁻¹ S L⁻ᵀ`, full sandwiches). Same values up to rounding; for tests and
    /// benchmarks only.
    #[doc(hidden)]
    pub fn eval_reference(&self, theta: &[f64], grad: Option<&mut [f64]>) -> Result<Eval> {
        self.eval_with(theta, grad, true)
    }

    fn eval_with(&self, theta: &[f64], grad: Option<&mut [f64]>, dense: bool) -> Result<Eval> {
        let n = self.layout.n();
        let d = self.latent_dim;
        if theta.len() != self.n_params() {
            return invalid(format!(
                "θ has {} entries, expected {}",
                theta.len(),
                self.n_params()
            ));
        }
        // Latent positions: θ's X block, rescaled to unit mean square when the scale is fixed.
        let x_raw = &theta[..n * d];
        let norm = x_raw.iter().map(|v| v * v).sum::<f64>().sqrt();
        let scale = if self.config.fixed_latent_scale {
            if !(norm > 0.0 && norm.is_finite()) {
                return invalid("latent positions are all zero or not finite");
            }
            ((n * d) as f64).sqrt() / norm
        } else {
            1.0
        };
        let x_scaled: Vec<f64>;
        let x = if scale == 1.0 {
            MatRef::from_column_major_slice(x_raw, n, d)
        } else {
            x_scaled = x_raw.iter().map(|v| v * scale).collect();
            MatRef::from_column_major_slice(&x_scaled, n, d)
        };
        let ta = &theta[n * d..n * d + 3];
        let tb = &theta[n * d + 3..];
        let alpha = alpha_from_theta(ta, self.config.pose_noise_floor);
        let beta = beta_from_theta(tb, self.config.dyn_noise_floor);
        let want = grad.is_some();
        let pose = |split| {
            if dense {
                self.pose_term_dense(x, alpha, want)
            } else {
                self.pose_term(x, alpha, want, split)
            }
        };
        let dynamics = |split| self.dynamics_term(x, beta, want, dense, split);
        let (py, px) = if rayon::current_thread_index().is_some() {
            rayon::join(|| pose(Split::Join), || dynamics(Split::Join))
        } else {
            // Called from outside a rayon pool (e.g. `gpdm-train`'s main thread): `join` would
            // inject both terms into the pool and put this thread to sleep (three wake-ups per
            // evaluation). Instead the pose term (the longer one) runs here and only the
            // dynamics term is handed to a pool worker (measured 8 % less time per evaluation on
            // leg_l). Neither splits its sandwich: this thread cannot run pool jobs, and a
            // split of the dynamics term would only wake a third thread on two cores.
            //
            // The worker is a dedicated one-thread pool kept spinning between evaluations
            // (see `eval_pool`): handing it the next dynamics term then needs no wake-up (measured
            // 6 % less time per leg_l fit, with the futex wake-up off this thread).
            let mut px = None;
            let gen = EVAL_GEN.fetch_add(1, Ordering::AcqRel) + 1;
            macro_rules! run_in {
                ($($scope:tt)+) => {
                    $($scope)+(|s| {
                        s.spawn(|_| {
                            px = Some(dynamics(Split::None));
                            rayon::spawn(move || keep_warm(gen));
                        });
                        pose(Split::None)
                    })
                };
            }
            let py = match eval_pool() {
                Some(pool) => run_in!(pool.in_place_scope),
                None => run_in!(rayon::in_place_scope),
            };
            (py, px.expect("scope waits for the dynamics term"))
        };
        let (py, mut px) = (py?, px?);
        let lambda = self.config.dynamics_weight.lambda(self.d_obs, d);
        if lambda != 1.0 {
            px.value *= lambda;
            px.dparams.iter_mut().for_each(|g| *g *= lambda);
            if let Some(dx) = px.dx.as_mut() {
                *dx *= faer::Scale(lambda);
            }
        }
        // Priors ∏ 1/α_k, ∏ 1/β_k → Σ ln α_k + Σ ln β_k, plus the log-normal factor on β1..β3
        // (in θ, ln β_k = θ_k for k = 1..3).
        let inv_s2 = self.config.beta_log_sd.map_or(0.0, |s| 1.0 / (s * s));
        let prior: f64 = alpha.iter().map(|a| a.ln()).sum::<f64>()
            + beta.iter().map(|b| b.ln()).sum::<f64>()
            + 0.5 * inv_s2 * tb[..3].iter().map(|t| t * t).sum::<f64>();
        let out = Eval {
            value: py.value + px.value + prior,
            pose: py.value,
            dynamics: px.value,
            prior,
            jitter_y: py.jitter,
            jitter_x: px.jitter,
        };
        let Some(grad) = grad else {
            return Ok(out);
        };
        let (gx_part, gh) = grad.split_at_mut(n * d);
        let (dxy, dxx) = (py.dx.expect("requested"), px.dx.expect("requested"));
        for j in 0..d {
            for i in 0..n {
                gx_part[i + j * n] = dxy[(i, j)] + dxx[(i, j)];
            }
        }
        if self.config.fixed_latent_scale {
            // X = s X̃ with s = √(Nd)/‖X̃‖: ∂L/∂X̃ = s (g − X̂ (X̂ · g)), X̂ = X̃/‖X̃‖.
            let radial: f64 = gx_part.iter().zip(x_raw).map(|(g, v)| g * v).sum::<f64>() / norm;
            for (g, v) in gx_part.iter_mut().zip(x_raw) {
                *g = scale * (*g - v / norm * radial);
            }
        }
        let (pa, pb) = (py.dparams, px.dparams);
        // Chain rule to θ, priors included (∂ ln α_k / ∂θ_k = 1 for the log-parametrised ones).
        gh[0] = alpha[0] * pa[0] + 1.0;
        gh[1] = alpha[1] * pa[1] + 1.0;
        gh[2] = (pa[3] + 1.0 / alpha[2]) * (-alpha[2] * alpha[2] * ta[2].exp());
        gh[3] = beta[0] * pb[0] + 1.0 + inv_s2 * tb[0];
        gh[4] = beta[1] * pb[1] + 1.0 + inv_s2 * tb[1];
        gh[5] = beta[2] * pb[2] + 1.0 + inv_s2 * tb[2];
        gh[6] = (pb[3] + 1.0 / beta[3]) * (-beta[3] * beta[3] * tb[3].exp());
        Ok(out)
    }

    /// Eq. 3 term `D/2 ln|K_Y| + 1/2 tr(K_Y⁻¹ S)`, `S = Y Yᵀ`, and its gradient
    /// `∂L/∂K_Y = 1/2 K⁻¹ (D I − S K⁻¹) = 1/2 L⁻ᵀ (D I − Z Zᵀ) L⁻¹`.
    ///
    /// The term is invariant under a simultaneous permutation of the frames of X and Y, so it
    /// is evaluated with the frames in the pivot order of `Pᵀ S P = R Rᵀ`: there
    /// `K_Y = L Lᵀ`, `Z = L⁻¹ R` (lower-trapezoidal, ~N³/6), `tr(K_Y⁻¹ S) = ‖Z‖²_F`,
    /// `Q = D I − Z Zᵀ` (lower triangle, ~N³/6) and the lower triangle of `L⁻ᵀ Q L⁻¹`
    /// (~2N³/3): with the Cholesky (N³/6) about 1.17 N³ multiply-adds instead of 2.17 N³.
    /// The rows of `∂L/∂X` are permuted back on the way out.
    fn pose_term(
        &self,
        x: MatRef<'_, f64>,
        alpha: [f64; 3],
        want: bool,
        split: Split,
    ) -> Result<Term> {
        let n = x.nrows();
        let d = x.ncols();
        let perm = &self.s_factor.perm;
        let xp = Mat::from_fn(n, d, |i, j| x[(perm[i], j)]);
        let ky = RbfLinear::pose(alpha);
        let mut gy = ky.gram_lower(xp.as_ref());
        // K_Y is factored in place; `gy` keeps the RBF part the gradient needs.
        let k = std::mem::replace(&mut gy.k, Mat::new());
        let cy = Cholesky::factor_owned(k, "K_Y", || ky.gram(xp.as_ref()).k)?;
        let z = cy.half_solve_trapezoidal(self.s_factor.r.as_ref());
        let tr_y: f64 = z.col_iter().map(|c| c.squared_norm_l2()).sum();
        let dd = self.d_obs as f64;
        let value = 0.5 * dd * cy.log_det() + 0.5 * tr_y;
        let mut term = Term::new(value, cy.jitter);
        if want {
            let mut q = lower_zzt_scaled_only(z.as_ref(), -0.5);
            for j in 0..n {
                q[(j, j)] += 0.5 * dd;
            }
            let g = cy.sandwich_lower_split(q, split);
            let (dp, dxp) = ky.gradients(&gy, xp.as_ref(), g.as_ref());
            recycle(g);
            let mut dx = Mat::<f64>::zeros(n, d);
            for j in 0..d {
                for (i, &pi) in perm.iter().enumerate() {
                    dx[(pi, j)] = dxp[(i, j)];
                }
            }
            term.dx = Some(dx);
            term.dparams = dp;
        }
        // The N × N buffers go back to the pool for the next evaluation.
        recycle(gy.rbf);
        recycle(cy.l);
        recycle(z);
        Ok(term)
    }

    /// [`Objective::pose_term`] by dense algebra: `C = L⁻¹ S L⁻ᵀ` by two full solves,
    /// `tr(K_Y⁻¹ S) = tr C`, `∂L/∂K_Y = 1/2 L⁻ᵀ (D I − C) L⁻¹` by a full sandwich.
    fn pose_term_dense(&self, x: MatRef<'_, f64>, alpha: [f64; 3], want: bool) -> Result<Term> {
        let n = x.nrows();
        let ky = RbfLinear::pose(alpha);
        let gy = ky.gram(x);
        let cy = Cholesky::factor(gy.k.as_ref(), "K_Y")?;
        let mut c = self.yyt.clone();
        cy.half_solve_in_place(c.as_mut()); // B = L⁻¹ S
        cy.half_solve_in_place(c.as_mut().transpose_mut()); // C = L⁻¹ Bᵀ = L⁻¹ S L⁻ᵀ (Cᵀ stored; C symmetric)
        let tr_y: f64 = (0..n).map(|i| c[(i, i)]).sum();
        let dd = self.d_obs as f64;
        let value = 0.5 * dd * cy.log_det() + 0.5 * tr_y;
        let mut term = Term::new(value, cy.jitter);
        if want {
            let mut q = -c;
            for i in 0..n {
                q[(i, i)] += dd;
            }
            let g = cy.sandwich(q.as_ref()) * faer::Scale(0.5);
            let (dp, dx) = ky.gradients(&gy, x, g.as_ref());
            term.dx = Some(dx);
            term.dparams = dp;
        }
        Ok(term)
    }

    /// Eq. 5 term `d/2 ln|K_X| + 1/2 tr(K_X⁻¹ X_out X_outᵀ)` plus the first-point priors,
    /// with `∂L/∂K_X = 1/2 L⁻ᵀ (d I − W Wᵀ) L⁻¹`, `W = L⁻¹ X_out`, `∂L/∂X_out = L⁻ᵀ W`.
    /// `dense` selects the full sandwich (reference) instead of the lower-triangle one.
    fn dynamics_term(
        &self,
        x: MatRef<'_, f64>,
        beta: [f64; 4],
        want: bool,
        dense: bool,
        split: Split,
    ) -> Result<Term> {
        let n = x.nrows();
        let d = x.ncols();
        let kx = RbfLinear::dynamics(beta);
        let xin = Mat::from_fn(self.layout.x_in.len(), d, |i, j| {
            x[(self.layout.x_in[i], j)]
        });
        let xout = Mat::from_fn(self.layout.x_out.len(), d, |i, j| {
            x[(self.layout.x_out[i], j)]
        });
        let m = xin.nrows();
        let (gx, cx) = if dense {
            let gx = kx.gram(xin.as_ref());
            let cx = Cholesky::factor(gx.k.as_ref(), "K_X")?;
            (gx, cx)
        } else {
            let mut gx = kx.gram_lower(xin.as_ref());
            let k = std::mem::replace(&mut gx.k, Mat::new());
            let cx = Cholesky::factor_owned(k, "K_X", || kx.gram(xin.as_ref()).k)?;
            (gx, cx)
        };
        let mut w = xout;
        cx.half_solve_in_place(w.as_mut()); // W = L⁻¹ X_out
        let quad_x: f64 = w.col_iter().map(|col| col.squared_norm_l2()).sum();
        let sigma0 = self.config.first_point_var;
        let first: f64 = self
            .layout
            .firsts
            .iter()
            .map(|&f| (0..d).map(|j| x[(f, j)] * x[(f, j)]).sum::<f64>())
            .sum::<f64>()
            / (2.0 * sigma0);
        let value = 0.5 * d as f64 * cx.log_det() + 0.5 * quad_x + first;
        let mut term = Term::new(value, cx.jitter);
        if want {
            let g = if dense {
                let mut q = mul_abt(w.as_ref(), w.as_ref());
                q *= faer::Scale(-0.5);
                for i in 0..m {
                    q[(i, i)] += 0.5 * d as f64;
                }
                cx.sandwich(q.as_ref())
            } else {
                // Lower triangle of ½ (d I − W Wᵀ) only: sandwich_lower reads no more.
                let mut q = lower_wwt_scaled_only(w.as_ref(), -0.5);
                for i in 0..m {
                    q[(i, i)] += 0.5 * d as f64;
                }
                cx.sandwich_lower_split(q, split)
            };
            let (dp, dx_in) = kx.gradients(&gx, xin.as_ref(), g.as_ref());
            recycle(g);
            term.dparams = dp;
            let mut dx_out = w;
            cx.half_solve_t_in_place(dx_out.as_mut());
            let mut dx = Mat::<f64>::zeros(n, d);
            for j in 0..d {
                for r in 0..m {
                    dx[(self.layout.x_in[r], j)] += dx_in[(r, j)];
                    dx[(self.layout.x_out[r], j)] += dx_out[(r, j)];
                }
                for &f in &self.layout.firsts {
                    dx[(f, j)] += x[(f, j)] / sigma0;
                }
            }
            term.dx = Some(dx);
        }
        recycle(gx.rbf);
        recycle(cx.l);
        Ok(term)
    }
}

/// Evaluations started from outside a rayon pool (see [`keep_warm`]).
static EVAL_GEN: AtomicU64 = AtomicU64::new(0);

/// How long the dynamics worker spins after its term, waiting for the next evaluation.
const KEEP_WARM: Duration = Duration::from_micros(500);

/// The one-thread pool that runs the dynamics term of an evaluation called from outside a
/// rayon pool. Its own pool, so that while its worker spins no other sleeping worker is woken
/// to take the next term (`None` if its thread could not be started: the global pool is
/// used).
fn eval_pool() -> Option<&'static rayon::ThreadPool> {
    static POOL: OnceLock<Option<rayon::ThreadPool>> = OnceLock::new();
    POOL.get_or_init(|| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .thread_name(|_| "gpdm-eval".into())
            .build()
            .ok()
    })
    .as_ref()
}

/// Spins until evaluation `gen` is superseded or [`KEEP_WARM`] has passed: between two
/// evaluations of an optimiser (~0.1 ms on leg_l) a sleeping worker would have to be woken
/// by a system call and takes ~50 µs to start.
fn keep_warm(gen: u64) {
    let t = Instant::now();
    while EVAL_GEN.load(Ordering::Acquire) == gen && t.elapsed() < KEEP_WARM {
        std::hint::spin_loop();
    }
}

/// One term of the objective with its gradient pieces.
struct Term {
    value: f64,
    jitter: f64,
    dx: Option<Mat<f64>>,
    /// Raw `∂/∂(var, γ, lin, prec)` of the kernel.
    dparams: [f64; 4],
}

impl Term {
    /// A term's value and jitter, its gradient pieces not (yet) computed.
    fn new(value: f64, jitter: f64) -> Self {
        Term {
            value,
            jitter,
            dx: None,
            dparams: [0.0; 4],
        }
    }
}

/// A (trained or initialised) GPDM: data, latent points and hyperparameters. Serialisable.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Gpdm {
    /// Model options.
    pub config: GpdmConfig,
    /// Lengths of the stacked training sequences.
    pub seq_lens: Vec<usize>,
    /// Mean pose subtracted from the data (the GP of 3DV eq. 3 has zero mean).
    pub y_mean: DVector<f64>,
    /// Centred training poses, N × D.
    pub y: DMatrix<f64>,
    /// Latent points, N × d.
    pub x: DMatrix<f64>,
    /// Pose-kernel hyperparameters (α1, α2, α3), 3DV eq. 4.
    pub alpha: [f64; 3],
    /// Dynamics-kernel hyperparameters (β1, β2, β3, β4), 3DV eq. 6.
    pub beta: [f64; 4],
}

impl Gpdm {
    /// Stacks the sequences (each T_j × D), centres them and sets the paper's starting point:
    /// X from PCA ([`crate::pca::pca_init`]), α_k = β_k = 1 and noise variances 0.1.
    pub fn new(sequences: &[DMatrix<f64>], config: GpdmConfig) -> Result<Self> {
        if sequences.is_empty() {
            return invalid("no training sequences");
        }
        let dim = sequences[0].ncols();
        if dim == 0 {
            return invalid("poses have dimension 0");
        }
        if let Some((i, s)) = sequences.iter().enumerate().find(|(_, s)| s.ncols() != dim) {
            return invalid(format!(
                "sequence {i} has pose dimension {}, expected {dim}",
                s.ncols()
            ));
        }
        if sequences.iter().any(|s| s.iter().any(|v| !v.is_finite())) {
            return invalid("training poses contain NaN or infinity");
        }
        if config.latent_dim == 0 {
            return invalid("latent dimension must be positive");
        }
        if !(config.first_point_var > 0.0 && config.first_point_var.is_finite()) {
            return invalid("first-point prior variance must be positive and finite");
        }
        for f in [config.pose_noise_floor, config.dyn_noise_floor]
            .into_iter()
            .flatten()
        {
            if !(f >= 0.0 && f.is_finite()) {
                return invalid(format!("noise floor {f} must be non-negative and finite"));
            }
        }
        if let Some(sd) = config.beta_log_sd {
            if !(sd > 0.0 && sd.is_finite()) {
                return invalid(format!("β log-prior sd {sd} must be positive and finite"));
            }
        }
        let seq_lens: Vec<usize> = sequences.iter().map(|s| s.nrows()).collect();
        Layout::new(&seq_lens)?;
        let n: usize = seq_lens.iter().sum();
        if config.latent_dim > n.min(dim) {
            return invalid(format!(
                "latent dimension {} exceeds min(frames {n}, pose dimension {dim})",
                config.latent_dim
            ));
        }
        let mut y = DMatrix::zeros(n, dim);
        let mut r = 0;
        for s in sequences {
            y.rows_mut(r, s.nrows()).copy_from(s);
            r += s.nrows();
        }
        let y_mean = y.row_mean().transpose();
        for mut row in y.row_iter_mut() {
            row -= y_mean.transpose();
        }
        let x = crate::pca::pca_init(&y, config.latent_dim)?;
        Ok(Gpdm {
            config,
            seq_lens,
            y_mean,
            y,
            x,
            alpha: [1.0, 1.0, 10.0],
            beta: [1.0, 1.0, 1.0, 10.0],
        })
    }

    /// What [`Gpdm::new`] and training guarantee, for a model read from a file: a valid
    /// sequence layout, `N x D` centred poses and `N x d` latents with `N` the summed lengths,
    /// a `D`-vector mean, finite positive hyperparameters, every number finite. The error is
    /// the problem.
    pub fn validate(&self) -> std::result::Result<(), String> {
        Layout::new(&self.seq_lens).map_err(|e| e.to_string())?;
        let n: usize = self.seq_lens.iter().sum();
        let d = self.config.latent_dim;
        if self.y.nrows() != n || self.x.nrows() != n || self.x.ncols() != d || d == 0 {
            return Err(format!(
                "poses {} x {} and latents {} x {} for {n} frames of latent dimension {d}",
                self.y.nrows(),
                self.y.ncols(),
                self.x.nrows(),
                self.x.ncols()
            ));
        }
        if self.y_mean.len() != self.y.ncols() || self.y.ncols() == 0 {
            return Err(format!("a mean pose of {} values for poses of {}", self.y_mean.len(), self.y.ncols()));
        }
        if !self.alpha.iter().chain(&self.beta).all(|v| v.is_finite() && *v > 0.0)
            || !(self.config.first_point_var.is_finite() && self.config.first_point_var > 0.0)
        {
            return Err(format!(
                "hyperparameters α {:?}, β {:?} or first-point variance {} not finite positive numbers",
                self.alpha, self.beta, self.config.first_point_var
            ));
        }
        if !self.y.iter().chain(self.x.iter()).chain(self.y_mean.iter()).all(|v| v.is_finite()) {
            return Err("poses or latents have a non-finite entry".into());
        }
        Ok(())
    }

    /// The sequence layout.
    pub fn layout(&self) -> Layout {
        Layout::new(&self.seq_lens).expect("layout validated at construction")
    }

    /// Builds the objective of 3DV eq. 7 (forms Y Yᵀ once).
    pub fn objective(&self) -> Result<Objective> {
        Objective::new(view(&self.y), self.layout(), self.config.clone())
    }

    /// Current parameters in optimisation coordinates.
    pub fn theta(&self) -> Vec<f64> {
        let mut t: Vec<f64> = self.x.as_slice().to_vec();
        t.push(self.alpha[0].ln());
        t.push(self.alpha[1].ln());
        t.push(noise_theta(self.alpha[2], self.config.pose_noise_floor));
        t.push(self.beta[0].ln());
        t.push(self.beta[1].ln());
        t.push(self.beta[2].ln());
        t.push(noise_theta(self.beta[3], self.config.dyn_noise_floor));
        t
    }

    /// Sets the parameters from optimisation coordinates (X rescaled to unit mean square when
    /// [`GpdmConfig::fixed_latent_scale`], as the objective sees it).
    pub fn set_theta(&mut self, theta: &[f64]) {
        let nd = self.x.len();
        self.x.as_mut_slice().copy_from_slice(&theta[..nd]);
        if self.config.fixed_latent_scale {
            let norm = self.x.norm();
            if norm > 0.0 && norm.is_finite() {
                self.x *= (nd as f64).sqrt() / norm;
            }
        }
        self.alpha = alpha_from_theta(&theta[nd..nd + 3], self.config.pose_noise_floor);
        self.beta = beta_from_theta(&theta[nd + 3..nd + 7], self.config.dyn_noise_floor);
    }

    /// Latent trajectory of training sequence `s` (T_s × d).
    pub fn sequence_latent(&self, s: usize) -> Option<DMatrix<f64>> {
        let start: usize = self.seq_lens.get(..s)?.iter().sum();
        let len = *self.seq_lens.get(s)?;
        Some(self.x.rows(start, len).into_owned())
    }
}
