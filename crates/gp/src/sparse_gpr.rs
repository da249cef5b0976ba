//! Sparse GP regression: Titsias' (2009) collapsed variational bound with `M` inducing inputs
//! `Z`, for training sets too large for the exact GP of CVPR eqs. 8-13 (whose cost is cubic in
//! the number of pairs `F`).
//!
//! With `K = K_uu` (`M x M`), `Φ = K_fu` (`F x M`), `Q_ff = Φ K⁻¹ Φᵀ`, `s = σn²` and `m` output
//! columns sharing the kernel (as in CVPR eq. 8), the bound on the log marginal likelihood is
//! ```text
//! F(θ) = Σ_i log N(Y_i | 0, Q_ff + s I) - m/(2s) tr(K_ff - Q_ff)
//!      = -½ m log|B| - ½ F m log(2π s) - |Y|²/(2s) + ½ |c|² - m/(2s) (tr K_ff - tr(L⁻¹ T L⁻ᵀ))
//! T = Φᵀ Φ,  K = L Lᵀ,  B = I + L⁻¹ T L⁻ᵀ / s = L_B L_Bᵀ,  c = L_B⁻¹ L⁻¹ Φᵀ Y / s
//! ```
//! (matrix determinant lemma and Woodbury, with `P = K + T/s = L B Lᵀ`). Only `M x M` and
//! `M x F` matrices appear, never an `F x F` one: a value costs one `M x F` kernel block, the
//! whitened features `A = L⁻¹ Φᵀ` (a triangular solve, `F M²`) and `S = A Aᵀ = L⁻¹ T L⁻ᵀ`
//! (`F M²/2`); the code works with `S` rather than `T` (see `SparseFactored`).
//!
//! Gradient, through `K`, `Φ` and `diag K_ff` (each kernel's `∂/∂log σf` is twice itself):
//! ```text
//! β = P⁻¹ Φᵀ Y,   G_P = -½ m P⁻¹ - ββᵀ/(2s²)
//! G_K = G_P + ½ m K⁻¹ - m/(2s) K⁻¹ T K⁻¹,    G_T = G_P / s + m/(2s) K⁻¹
//! ∂F/∂θ = <G_K, ∂K> + 2 <G_T, Φᵀ ∂Φ> + <β, ∂Φᵀ Y>/s² - m/(2s) tr ∂K_ff
//! ∂F/∂s = -<G_P, T>/s² - F m/(2s) + |Y|²/(2s²) - <β, ΦᵀY>/s³ + m/(2s²)(tr K_ff - tr(K⁻¹T))
//! ```
//! (`<·,·>` the Frobenius product); computed whitened (`SparseFactored::gradient`), it adds
//! one `M x M` by `M x F` product (`2 F M²`) contracted with the kernel derivative, and the
//! elements of `B⁻¹` (`M x M`, needed for the trace terms, as in the exact GP's gradient). The inducing inputs are fixed during optimisation
//! ([`crate::inducing::greedy_variance`] at the starting hyperparameters). The kernel
//! hyperparameters are optimised with `σf²` profiled out (the bound is concave in it and its
//! pieces scale with it: `Parts::profile_signal_variance`), leaving a search over `log l`
//! alone ([`crate::optim::minimize_scalar`]); with a learned `σn²`, all three by the exact GP's
//! conjugate gradients.
//!
//! Prediction (Titsias eq. 6, the optimal `q(u)`): mean `K_*u β / s`, latent variance
//! `k_** - |L⁻¹ k_u*|² + |L_P⁻¹ k_u*|²` with `L_P = L L_B` (the factor of `P`). At `Z = X` the
//! bound, mean and variance equal the exact GP's (`Q_ff = K_ff`, `K⁻¹ - P⁻¹ = (K + sI)⁻¹`).
//!
//! Cross-check: `scripts/compare/sgpr_gpy.py` against GPy's `SparseGPRegression` with the
//! same inducing inputs.

use crate::likelihood::warm_start;
pub use crate::training::{Sparsity, AUTO_INDUCING};
use crate::training::{check_xy, initial_kernel, maximise, summarise_notes, GprOptions, TrainReport};
use crate::inducing::greedy_variance;
use crate::kernel::Kernel;
use crate::optim::{minimize_scalar, CgOptions, ExitState};
use crate::linalg::{
    add_mul_tr_rows, blocks, lower_solve_in_place, lower_tr_solve_in_place, mul, mul_columns_into, mul_tr, Cholesky,
};
use crate::{check_finite, invalid, Result};
use nalgebra::{DMatrix, DVector};
use serde::{Deserialize, Serialize};

/// Jitter added to `K_uu`, relative to the mean of its diagonal: `K_uu + ε mean(diag K_uu) I`
/// (a differentiable function of the hyperparameters, included in the gradient). The NN kernel
/// tends to a rank-`D+1` linear kernel as `l` grows, so with more inducing inputs than that
/// `K_uu` becomes singular during the optimisation; GPy and GPflow add a fixed absolute `1e-6`
/// for the same reason (relative here because the NN kernel's prior variance falls as
/// `σf² / (2 l²)` in that limit, where an absolute or `σf²`-relative jitter would dominate). Training uses this value; the lower-level functions take it as an argument (0
/// gives the bound exactly as written, e.g. to compare with the exact GP at `Z = X`).
pub const KUU_JITTER: f64 = 1e-6;

/// What a sparse regressor (`gpr::Gpr`) keeps for prediction: the inducing inputs and two `M x M` lower
/// factors (`L` of `K_uu` and `L_P` of `K_uu + K_uf K_fu / s`); the model's `alpha` is `β / s`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SparsePosterior {
    pub(crate) inducing: DMatrix<f64>,
    pub(crate) l_uu: DMatrix<f64>,
    pub(crate) l_p: DMatrix<f64>,
}

impl SparsePosterior {
    /// The inducing inputs `Z` (`M x D`).
    pub fn inducing(&self) -> &DMatrix<f64> {
        &self.inducing
    }

    /// Latent variance `k_** - |L⁻¹ k_u*|² + |L_P⁻¹ k_u*|²` for each row of `ks_t` (`K_u*` as
    /// `M x N`) with prior variances `prior`.
    pub(crate) fn variance(&self, ku_star: &DMatrix<f64>, prior: &DVector<f64>) -> DVector<f64> {
        let a = lower_solve(&self.l_uu, ku_star);
        let b = lower_solve(&self.l_p, ku_star);
        DVector::from_iterator(
            prior.len(),
            (0..prior.len()).map(|i| {
                (prior[i] - a.column(i).norm_squared() + b.column(i).norm_squared()).max(0.0)
            }),
        )
    }
}

fn lower_solve(l: &DMatrix<f64>, b: &DMatrix<f64>) -> DMatrix<f64> {
    let mut x = b.clone();
    lower_solve_in_place(l, &mut x);
    x
}

/// `L⁻ᵀ B` for the lower-triangular `l`.
fn upper_solve(l: &DMatrix<f64>, b: &DMatrix<f64>) -> DMatrix<f64> {
    let mut x = b.clone();
    lower_tr_solve_in_place(l, &mut x);
    x
}

/// `D += ε mean(diag D) I` (linear in `D`, so the derivative of the jittered `K_uu` is the
/// jittered derivative).
fn add_relative_jitter(d: &mut DMatrix<f64>, eps: f64) {
    let n = d.nrows();
    let add = eps * d.trace() / n.max(1) as f64;
    for i in 0..n {
        d[(i, i)] += add;
    }
}

fn check_noise(s: f64) -> Result<()> {
    if s > 0.0 && s.is_finite() {
        Ok(())
    } else {
        invalid(format!("sparse GP: noise variance must be > 0, got {s}"))
    }
}

fn check_inducing(z: &DMatrix<f64>, x: &DMatrix<f64>) -> Result<()> {
    if z.nrows() == 0 || z.ncols() != x.ncols() {
        return invalid(format!(
            "sparse GP: {} inducing inputs of dimension {} for inputs of dimension {}",
            z.nrows(),
            z.ncols(),
            x.ncols()
        ));
    }
    check_finite("inducing inputs", z)
}

/// The bound at one hyperparameter setting, factorised so that the gradient can follow
/// without recomputing the value's products (as the exact GP's `Factored`). Everything is
/// kept whitened by `L` (`A = L⁻¹ Φᵀ`, `S = A Aᵀ = L⁻¹ T L⁻ᵀ`): `K_uu` is close to singular
/// whenever the inducing inputs outnumber what the kernel can tell apart, and the whitened
/// quantities stay well scaled where `K⁻¹ T K⁻¹` does not.
struct SparseFactored {
    kernel: Kernel,
    noise_var: f64,
    /// `K_uu + ε mean(diag K_uu) I` ([`KUU_JITTER`]) and the lower factor of it plus any
    /// jitter retry.
    kuu: DMatrix<f64>,
    kuu_jitter: f64,
    l_uu: DMatrix<f64>,
    jitter: f64,
    /// `A = L⁻¹ K_uf` (`M x F`), `S = A Aᵀ`, `A Y`.
    a: DMatrix<f64>,
    s_mat: DMatrix<f64>,
    a_y: DMatrix<f64>,
    l_b: DMatrix<f64>,
    /// `tr K_ff`, `tr S = tr(K⁻¹ T)`, `|Y|²`.
    trace_kff: f64,
    trace_qff: f64,
    yy: f64,
    /// `γ = B⁻¹ A Y`, so that `β = P⁻¹ Φᵀ Y = L⁻ᵀ γ`.
    gamma: DMatrix<f64>,
    value: f64,
}

/// The kernel-dependent pieces of [`SparseFactored`], before the noise enters: `K_uu` (with
/// the relative jitter) and its factor, `A = L⁻¹ K_uf`, `S = A Aᵀ`, `A Y` and the traces. Every
/// kernel here is `σf²` times a unit kernel, so the pieces at `σf² = v` are those at `σf = 1`
/// scaled ([`Parts::scale`]): the signal variance can be optimised without new kernel blocks
/// ([`Parts::profile_signal_variance`]).
struct Parts {
    kuu: DMatrix<f64>,
    l_uu: DMatrix<f64>,
    /// Jitter retry of `K_uu`'s factorisation (0 when none was needed).
    jitter: f64,
    a: DMatrix<f64>,
    s_mat: DMatrix<f64>,
    a_y: DMatrix<f64>,
    trace_kff: f64,
    trace_qff: f64,
    yy: f64,
}

impl Parts {
    /// The pieces of `kernel`, with `A` written into `a_buffer`'s storage when its shape is
    /// `M x F` (the previous evaluation's `A`, so that a training loop allocates it once).
    fn new(
        kernel: &Kernel,
        z: &DMatrix<f64>,
        x: &DMatrix<f64>,
        y: &DMatrix<f64>,
        kuu_jitter: f64,
        a_buffer: DMatrix<f64>,
        notes: &mut Vec<String>,
    ) -> Result<Self> {
        let mut kuu = kernel.gram(z);
        add_relative_jitter(&mut kuu, kuu_jitter);
        let chol = Cholesky::new(&kuu, "K_uu", notes)?;
        let (l_uu, jitter) = (chol.lower(), chol.jitter);
        let mut a = a_buffer;
        kernel.cross_fast_into(z, x, &mut a);
        lower_solve_in_place(&l_uu, &mut a);
        let s_mat = mul_tr(&a, &a, true);
        let a_y = mul(&a, y);
        let trace_qff = s_mat.trace();
        Ok(Self { kuu, l_uu, jitter, a, s_mat, a_y, trace_kff: kernel.diag(x).sum(), trace_qff, yy: y.norm_squared() })
    }

    /// The pieces of the kernel times `v` (`K -> v K`: `L -> √v L`, `A -> √v A`, `S -> v S`).
    fn scale(&mut self, v: f64) {
        let r = v.sqrt();
        self.kuu *= v;
        self.l_uu *= r;
        self.jitter *= v;
        self.a *= r;
        self.s_mat *= v;
        self.a_y *= r;
        self.trace_kff *= v;
        self.trace_qff *= v;
    }

    /// The signal variance `v` maximising the bound of the kernel `v k` (these pieces being
    /// `k`'s) at noise `s`, the bound there, and the bound at `v0`. With `S = U Λ Uᵀ` and `w_i = |(Uᵀ A Y)_i|²`
    /// the bound is, up to terms free of `v`,
    /// ```text
    /// h(v) = -½ m Σ log(1 + v λ_i/s) + v/(2s²) Σ w_i/(1 + v λ_i/s) - m v (tr K_ff - tr S)/(2s)
    /// ```
    /// concave in `v` (each term is), so `h'` falls monotonically and its root is found by
    /// Newton's method in `log v`, kept inside a bracket of sign changes (bisection when a step
    /// leaves it), from `v0`; `O(M)` per step after the eigenvalues and `Uᵀ A Y`
    /// ([`crate::linalg::symmetric_eigen_projected`], no eigenvectors formed). The root
    /// is searched within `e^±50` of `v0` (the bound's limit there otherwise).
    fn profile_signal_variance(&self, s: f64, f: f64, m: f64, v0: f64) -> Result<(f64, f64, f64)> {
        let (values, w_mat) = crate::linalg::symmetric_eigen_projected(&self.s_mat, &self.a_y)?;
        let lam: Vec<f64> = values.iter().map(|l| l.max(0.0) / s).collect();
        let w: Vec<f64> = w_mat.row_iter().map(|r| r.norm_squared() / (s * s)).collect();
        let c = 0.5 * m / s * (self.trace_kff - self.trace_qff);
        // h'(v) and v h''(v), the derivative of h' in log v.
        let slope = |v: f64| {
            let (mut d1, mut d2) = (-c, 0.0);
            for (l, wi) in lam.iter().zip(&w) {
                let r = 1.0 / (1.0 + v * l);
                d1 += -0.5 * m * l * r + 0.5 * wi * r * r;
                d2 += 0.5 * m * l * l * r * r - wi * l * r * r * r;
            }
            (d1, v * d2)
        };
        let t0 = v0.max(f64::MIN_POSITIVE).ln();
        let (mut lo, mut hi) = (t0 - 50.0, t0 + 50.0);
        let mut t = t0;
        for _ in 0..200 {
            let (d, dd) = slope(t.exp());
            if d > 0.0 {
                lo = t;
            } else if d < 0.0 {
                hi = t;
            } else {
                break;
            }
            let newton = t - d / dd;
            let next = if dd < 0.0 && newton > lo && newton < hi { newton } else { 0.5 * (lo + hi) };
            if (next - t).abs() <= 1e-14 * t.abs().max(1.0) || hi - lo <= 1e-14 * t.abs().max(1.0) {
                t = next;
                break;
            }
            t = next;
        }
        let bound = |v: f64| {
            lam.iter().zip(&w).map(|(l, wi)| -0.5 * m * (1.0 + v * l).ln() + 0.5 * v * wi / (1.0 + v * l)).sum::<f64>()
                - c * v
                - 0.5 * f * m * (2.0 * std::f64::consts::PI * s).ln()
                - 0.5 * self.yy / s
        };
        // Where the data hold no signal the root runs off toward v = 0 call after call; the
        // smallest normal number keeps the kernel valid (a model that predicts its mean).
        let v = t.exp().max(f64::MIN_POSITIVE);
        Ok((v, bound(v), bound(v0)))
    }

}

impl SparseFactored {
    #[allow(clippy::too_many_arguments)]
    fn new(
        kernel: &Kernel,
        noise_var: f64,
        z: &DMatrix<f64>,
        x: &DMatrix<f64>,
        y: &DMatrix<f64>,
        kuu_jitter: f64,
        notes: &mut Vec<String>,
    ) -> Result<Self> {
        check_xy(x, y)?;
        check_inducing(z, x)?;
        check_noise(noise_var)?;
        let parts = Parts::new(kernel, z, x, y, kuu_jitter, DMatrix::zeros(0, 0), notes)?;
        Self::assemble(kernel, noise_var, parts, x.nrows(), kuu_jitter, notes)
    }

    /// The factorisation from `kernel`'s pieces: `B`, its factor, `γ` and the bound.
    fn assemble(
        kernel: &Kernel,
        noise_var: f64,
        parts: Parts,
        rows: usize,
        kuu_jitter: f64,
        notes: &mut Vec<String>,
    ) -> Result<Self> {
        let Parts { kuu, l_uu, jitter, a, s_mat, a_y, trace_kff, trace_qff, yy } = parts;
        let (f, m) = (rows as f64, a_y.ncols() as f64);
        let s = noise_var;
        let mut bmat = &s_mat / s;
        for i in 0..bmat.nrows() {
            bmat[(i, i)] += 1.0;
        }
        let l_b = Cholesky::new(&bmat, "I + L⁻¹ K_uf K_fu L⁻ᵀ / noise", notes)?.lower();
        let c = lower_solve(&l_b, &a_y) / s;
        let gamma = upper_solve(&l_b, &c) * s;
        let log_det_b = 2.0 * l_b.diagonal().iter().map(|v| v.ln()).sum::<f64>();
        let value = -0.5 * m * log_det_b
            - 0.5 * f * m * (2.0 * std::f64::consts::PI * s).ln()
            - 0.5 * yy / s
            + 0.5 * c.norm_squared()
            - 0.5 * m / s * (trace_kff - trace_qff);
        Ok(Self {
            kernel: *kernel,
            noise_var,
            kuu,
            kuu_jitter,
            l_uu,
            jitter,
            a,
            s_mat,
            a_y,
            l_b,
            trace_kff,
            trace_qff,
            yy,
            gamma,
            value,
        })
    }

    /// `L⁻¹ D L⁻ᵀ` for a symmetric `D`.
    fn whiten(&self, d: &DMatrix<f64>) -> DMatrix<f64> {
        let half = lower_solve(&self.l_uu, d);
        lower_solve(&self.l_uu, &half.transpose())
    }

    /// Gradient with respect to the kernel's log hyperparameters, then `∂/∂ log σn²` when
    /// `with_noise`: the module documentation's formulas with `G_X = L⁻ᵀ H_X L⁻¹`,
    /// ```text
    /// H_P = -½ m B⁻¹ - γγᵀ/(2s²),  H_K = H_P + ½ m I - m/(2s) S,  H_T = H_P / s + m/(2s) I
    /// ∂F/∂θ = <H_K, L⁻¹ ∂K L⁻ᵀ> + 2 <H_T, A ∂Aᵀ> + <γ, ∂A Y>/s² - m/(2s) tr ∂K_ff,  ∂A = L⁻¹ ∂K_uf
    /// ```
    /// The middle terms are evaluated as `<2 (L⁻ᵀ H_T) A + L⁻ᵀγ Yᵀ/s², ∂K_uf>` (`2 F M² + M³`
    /// flops instead of the `3 F M²` of forming `∂A` and `A ∂Aᵀ`), a block of columns at a
    /// time ([`crate::linalg::blocks`]): no `M x F` matrix besides `A` is formed.
    fn gradient(&self, z: &DMatrix<f64>, x: &DMatrix<f64>, y: &DMatrix<f64>, with_noise: bool) -> Vec<f64> {
        let (f, m, s) = (x.nrows() as f64, y.ncols() as f64, self.noise_var);
        let mm = self.kuu.nrows();
        let eye = DMatrix::<f64>::identity(mm, mm);
        let lb_inv = lower_solve(&self.l_b, &eye);
        let b_inv = mul_tr(&lb_inv.transpose(), &lb_inv.transpose(), true);
        let h_p = &b_inv * (-0.5 * m) - &self.gamma * self.gamma.transpose() * (0.5 / (s * s));
        let h_k = &h_p + &eye * (0.5 * m) - &self.s_mat * (0.5 * m / s);
        let h_t = &h_p / s + &eye * (0.5 * m / s);
        let gamma_ay = self.gamma.dot(&self.a_y);
        let mut grad = Vec::with_capacity(3);
        if self.kernel.param_names().len() == 2 {
            // 2 <H_T, A ∂Aᵀ> + <γ, ∂A Y>/s² = <G, ∂K_uf> with G = 2 (L⁻ᵀ H_T) A + β Yᵀ / s²
            // (β = L⁻ᵀ γ): one M x M triangular solve and one M x M by M x F product, then the
            // kernel derivative contracted entry by entry (never stored, no arcsines).
            let lt_ht = upper_solve(&self.l_uu, &h_t) * 2.0;
            let beta = upper_solve(&self.l_uu, &self.gamma) / (s * s);
            let mut contraction = 0.0;
            let mut g = DMatrix::zeros(0, 0);
            for cols in blocks(x.nrows()) {
                mul_columns_into(&mut g, &lt_ht, &self.a, cols.clone());
                add_mul_tr_rows(&mut g, &beta, y, cols.clone());
                self.kernel.cross_dlog_l_contract(z, x, cols, &g, &mut contraction);
            }
            let mut dkuu = self.kernel.gram_with_grads(z).1.swap_remove(0);
            add_relative_jitter(&mut dkuu, self.kuu_jitter);
            let (_, dkff) = self.kernel.diag_with_dlog_l(x);
            grad.push(
                h_k.dot(&self.whiten(&dkuu)) + contraction - 0.5 * m / s * dkff.sum(),
            );
        }
        // L⁻¹ K_uu L⁻ᵀ = I unless the factorisation needed a jitter retry.
        let h_k_kuu = if self.jitter == 0.0 { h_k.trace() } else { h_k.dot(&self.whiten(&self.kuu)) };
        grad.push(2.0 * h_k_kuu + 4.0 * h_t.dot(&self.s_mat) + 2.0 * gamma_ay / (s * s) - m / s * self.trace_kff);
        if with_noise {
            let d_s = -h_p.dot(&self.s_mat) / (s * s) - 0.5 * f * m / s + 0.5 * self.yy / (s * s)
                - gamma_ay / (s * s * s)
                + 0.5 * m / (s * s) * (self.trace_kff - self.trace_qff);
            grad.push(s * d_s);
        }
        grad
    }

    fn into_fit(self, z: &DMatrix<f64>) -> SparseFit {
        let l_p = &self.l_uu * &self.l_b;
        let alpha = upper_solve(&self.l_uu, &self.gamma) / self.noise_var;
        SparseFit {
            kernel: self.kernel,
            noise_var: self.noise_var,
            jitter: self.jitter,
            alpha,
            posterior: SparsePosterior {
                inducing: z.clone(),
                l_uu: self.l_uu,
                l_p,
            },
        }
    }
}

/// A sparse GP conditioned on its data, made a regressor by `gpr::Gpr::from_sparse`
/// with its training inputs.
#[derive(Clone, Debug, PartialEq)]
pub struct SparseFit {
    pub kernel: Kernel,
    pub noise_var: f64,
    /// Jitter added to `K_uu` beyond [`KUU_JITTER`] (0 normally).
    pub jitter: f64,
    /// `β / σn²`: the weights of the inducing inputs in the posterior mean.
    pub alpha: DMatrix<f64>,
    pub posterior: SparsePosterior,
}

/// Titsias' bound on the log marginal likelihood of `Y` given `X` with inducing inputs `Z`,
/// summed over the output columns, with `K_uu + kuu_jitter · mean(diag K_uu) I`.
pub fn sparse_bound(
    kernel: &Kernel,
    noise_var: f64,
    z: &DMatrix<f64>,
    x: &DMatrix<f64>,
    y: &DMatrix<f64>,
    kuu_jitter: f64,
    notes: &mut Vec<String>,
) -> Result<f64> {
    Ok(SparseFactored::new(kernel, noise_var, z, x, y, kuu_jitter, notes)?.value)
}

/// The bound and its gradient with respect to the kernel's log hyperparameters
/// ([`Kernel::log_params`] order), followed by `∂/∂ log σn²` when `with_noise`.
pub fn sparse_bound_grad(
    kernel: &Kernel,
    noise_var: f64,
    with_noise: bool,
    z: &DMatrix<f64>,
    x: &DMatrix<f64>,
    y: &DMatrix<f64>,
    kuu_jitter: f64,
    notes: &mut Vec<String>,
) -> Result<(f64, Vec<f64>)> {
    let f = SparseFactored::new(kernel, noise_var, z, x, y, kuu_jitter, notes)?;
    Ok((f.value, f.gradient(z, x, y, with_noise)))
}

/// Conditions the sparse GP on `(X, Y)` with fixed hyperparameters and inducing inputs `Z`.
pub fn fit_sparse(
    kernel: Kernel,
    noise_var: f64,
    z: &DMatrix<f64>,
    x: &DMatrix<f64>,
    y: &DMatrix<f64>,
    kuu_jitter: f64,
    notes: &mut Vec<String>,
) -> Result<SparseFit> {
    Ok(SparseFactored::new(&kernel, noise_var, z, x, y, kuu_jitter, notes)?.into_fit(z))
}

/// Trains the sparse GP with at most `m` inducing inputs: starting hyperparameters as the
/// exact GP's ([`initial_kernel`], then the warm start on a subset), inducing inputs by
/// [`greedy_variance`] at those hyperparameters, then the bound maximised over the kernel's
/// hyperparameters (and `σn²` if asked; see the module documentation). When the warm start's
/// point has no finite bound or gradient, selection and training start again from the
/// data-driven start.
pub fn train_sparse(
    kernel: Kernel,
    x: &DMatrix<f64>,
    y: &DMatrix<f64>,
    m: usize,
    opts: &GprOptions,
) -> Result<(SparseFit, TrainReport)> {
    check_xy(x, y)?;
    if m == 0 {
        return invalid("sparse GP: at least one inducing input is needed");
    }
    if !(opts.noise_var > 0.0 && opts.noise_var.is_finite()) {
        return invalid(format!("sparse GP: noise variance must be > 0, got {}", opts.noise_var));
    }
    let data_start = if opts.data_init { initial_kernel(&kernel, x, y) } else { kernel };
    let start = warm_start(data_start, x, y, opts);
    let z = x.select_rows(greedy_variance(&start, x, m).iter());
    let trained = train_sparse_with_inducing(start, x, y, &z, opts)?;
    if trained.1.exit != Some(ExitState::NonFiniteStart) || start == data_start {
        return Ok(trained);
    }
    // The warm start (the exact GP on a subset) can end where the bound on all pairs has no
    // finite gradient (the `long` preset's A->B displacement: l = 7e-9, every arcsine argument
    // at ±1): select and train again from the data-driven start.
    let z = x.select_rows(greedy_variance(&data_start, x, m).iter());
    let (model, mut report) = train_sparse_with_inducing(data_start, x, y, &z, opts)?;
    report.notes.push(format!("the warm start ({:?}) gave a non-finite bound or gradient: trained from the data-driven start", start));
    Ok((model, report))
}

/// Maximises the bound with the inducing inputs `z` fixed, starting from `start` as given
/// (no data-driven start, no warm start), then conditions on the data.
pub fn train_sparse_with_inducing(
    start: Kernel,
    x: &DMatrix<f64>,
    y: &DMatrix<f64>,
    z: &DMatrix<f64>,
    opts: &GprOptions,
) -> Result<(SparseFit, TrainReport)> {
    train_sparse_observed(start, x, y, z, opts, &mut |_| {})
}

/// [`train_sparse_with_inducing`], calling `observe` with the bound of every evaluation in
/// order (the benchmark's record of when a bound was first reached).
pub fn train_sparse_observed(
    start: Kernel,
    x: &DMatrix<f64>,
    y: &DMatrix<f64>,
    z: &DMatrix<f64>,
    opts: &GprOptions,
    observe: &mut dyn FnMut(f64),
) -> Result<(SparseFit, TrainReport)> {
    check_xy(x, y)?;
    check_inducing(z, x)?;
    check_noise(opts.noise_var)?;
    let mut notes = Vec::new();
    if opts.optimise && !opts.learn_noise {
        let p = maximise_profiled(start, x, y, z, opts, observe, &mut notes)?;
        let report = TrainReport {
            exit: Some(p.exit),
            iterations: p.evaluations,
            evaluations: p.evaluations,
            gradient_evaluations: p.evaluations,
            initial_lml: p.initial_lml,
            lml: p.fitted.value,
            notes: summarise_notes(notes),
        };
        return Ok((p.fitted.into_fit(z), report));
    }
    let first = SparseFactored::new(&start, opts.noise_var, z, x, y, KUU_JITTER, &mut notes)?;
    observe(first.value);
    let initial_lml = first.value;
    let (fitted, exit, iterations, evaluations, gradient_evaluations) = if opts.optimise {
        let r = maximise(
            start,
            opts,
            None,
            |kern, noise| {
                let f = SparseFactored::new(kern, noise, z, x, y, KUU_JITTER, &mut notes);
                if let Ok(f) = &f {
                    observe(f.value);
                }
                f
            },
            |f| f.value,
            |f| f.gradient(z, x, y, opts.learn_noise),
        );
        let fitted = match r.at_optimum {
            Some(f) => f,
            None => SparseFactored::new(&r.kernel, r.noise_var, z, x, y, KUU_JITTER, &mut notes)?,
        };
        (fitted, Some(r.exit), r.iterations, r.evaluations, r.gradient_evaluations)
    } else {
        (first, None, 0, 0, 0)
    };
    let lml = fitted.value;
    let report = TrainReport {
        exit,
        iterations,
        evaluations,
        gradient_evaluations,
        initial_lml,
        lml,
        notes: summarise_notes(notes),
    };
    Ok((fitted.into_fit(z), report))
}

/// First step of the profiled search in `log l` (then secant steps). On the 12 benchmark
/// models (1100 pairs, data-driven start) the optimum lies 0.04-0.4 from the start on the
/// forward and displacement models: 0.5 brackets it at once, and took 4-6 points per model
/// where 0.25 took 4-5 but more time to GPy's bound.
const PROFILE_FIRST_STEP: f64 = 0.5;

/// What [`maximise_profiled`] found.
struct Profiled {
    fitted: SparseFactored,
    initial_lml: f64,
    exit: ExitState,
    evaluations: usize,
}

/// Maximises the bound at fixed noise over the kernel's hyperparameters with the signal
/// variance profiled out: at each length scale the pieces of the unit kernel are computed once
/// and `σf²` is set to its maximiser in closed form up to a scalar root
/// ([`Parts::profile_signal_variance`]), which leaves a function of `log l` alone. Its
/// derivative is the bound's partial derivative in `log l` at that `σf` (the partial in `σf` is
/// zero there), so [`minimize_scalar`] maximises it with one kernel block, one value and one
/// gradient per point, to the same relative gradient tolerance as the two-parameter search.
/// Kernels without a length scale need the profile alone. `observe` receives the bound at the
/// starting hyperparameters (from the first point's pieces, no extra kernel block), then at
/// every point.
fn maximise_profiled(
    start: Kernel,
    x: &DMatrix<f64>,
    y: &DMatrix<f64>,
    z: &DMatrix<f64>,
    opts: &GprOptions,
    observe: &mut dyn FnMut(f64),
    notes: &mut Vec<String>,
) -> Result<Profiled> {
    let (s, f, m) = (opts.noise_var, x.nrows() as f64, y.ncols() as f64);
    let theta0 = start.log_params();
    let nk = theta0.len();
    let mut v_prev = (2.0 * theta0[nk - 1]).exp();
    let mut initial_lml = None;
    // The factorisation at `log l` (ignored without a length scale) with `σf²` profiled, its
    // `A` written into `a_buffer` (see `Parts::new`).
    let mut at = |log_l: f64, a_buffer: DMatrix<f64>, notes: &mut Vec<String>| -> Result<SparseFactored> {
        let mut theta = theta0.clone();
        if nk == 2 {
            theta[0] = log_l;
        }
        theta[nk - 1] = 0.0;
        let unit = start.with_log_params(&theta);
        let mut parts = Parts::new(&unit, z, x, y, KUU_JITTER, a_buffer, notes)?;
        let (v, _, at_v0) = parts.profile_signal_variance(s, f, m, v_prev)?;
        if initial_lml.is_none() {
            initial_lml = Some(at_v0);
            observe(at_v0);
        }
        v_prev = v;
        parts.scale(v);
        theta[nk - 1] = 0.5 * v.ln();
        let fac = SparseFactored::assemble(&start.with_log_params(&theta), s, parts, x.nrows(), KUU_JITTER, notes)?;
        observe(fac.value);
        Ok(fac)
    };
    if nk == 1 {
        let fitted = at(0.0, DMatrix::zeros(0, 0), notes)?;
        let initial_lml = initial_lml.unwrap_or(fitted.value);
        return Ok(Profiled { fitted, initial_lml, exit: ExitState::Converged, evaluations: 1 });
    }
    // The last point's factorisation; its `A`, no longer needed once the gradient is taken,
    // is the next point's buffer.
    let mut last: Option<(f64, SparseFactored)> = None;
    let take_a = |last: &mut Option<(f64, SparseFactored)>| match last {
        Some((_, fac)) => std::mem::replace(&mut fac.a, DMatrix::zeros(0, 0)),
        None => DMatrix::zeros(0, 0),
    };
    let r = minimize_scalar(
        |log_l| match at(log_l, take_a(&mut last), notes) {
            Ok(fac) => {
                let g = fac.gradient(z, x, y, false)[0];
                let v = fac.value;
                last = Some((log_l, fac));
                (-v, -g)
            }
            Err(_) => (f64::INFINITY, f64::NAN),
        },
        theta0[0],
        &CgOptions { max_step: opts.cg.max_step.min(PROFILE_FIRST_STEP), ..opts.cg },
    );
    let fitted = match last {
        Some((p, fac)) if p == r.x[0] => fac,
        _ => at(r.x[0], take_a(&mut last), notes)?,
    };
    let initial_lml = initial_lml.unwrap_or(fitted.value);
    Ok(Profiled { fitted, initial_lml, exit: r.exit, evaluations: r.evaluations })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Targets with no signal push the profiled signal variance down by up to `e^50` per
    /// evaluation; from a start already near the bottom of the range the root would underflow to
    /// 0, a kernel no reader accepts. It stays the smallest normal number, and the bound is finite.
    #[test]
    fn a_signal_variance_profiled_toward_zero_stays_positive() {
        let x = DMatrix::from_fn(40, 2, |i, j| ((i * 7 + j * 3) % 11) as f64 / 11.0 - 0.5);
        let y = DMatrix::zeros(40, 2);
        let z = x.rows(0, 8).into_owned();
        let kernel = Kernel::NeuralNetwork { l: 1.0, sigma_f: 1.0, bias: false };
        let parts = Parts::new(&kernel, &z, &x, &y, 1e-6, DMatrix::zeros(0, 0), &mut Vec::new()).unwrap();
        let (v, bound, _) = parts.profile_signal_variance(0.1, 40.0, 2.0, 1e-300).unwrap();
        assert_eq!(v, f64::MIN_POSITIVE);
        assert!(bound.is_finite(), "{bound}");
    }
}
