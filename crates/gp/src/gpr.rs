//! Multi-output Gaussian-process regression, CVPR eqs. 8-13.
//!
//! Each output column `Y_i` (a target PCA coefficient, or one of the 6 rigid-displacement
//! values) is an independent GP over the same inputs with the **same kernel** (CVPR eq. 8), so one
//! Cholesky factorisation of `K + σn² I` serves all outputs and the log marginal likelihood is
//! the sum over outputs:
//! ```text
//! log p(Y | X) = -½ Σ_i Y_iᵀ (K + σn² I)⁻¹ Y_i - (m/2) log|K + σn² I| - (m F / 2) log 2π
//! ∂/∂θ        =  ½ tr( (α αᵀ - m (K + σn² I)⁻¹) ∂K/∂θ ),     α = (K + σn² I)⁻¹ Y
//! ```
//! (Rasmussen & Williams eqs. 2.30 and 5.9, summed over the `m` outputs.) The noise variance is
//! fixed at the paper's `σn² = 0.1` by default and can optionally be learnt (in log space).
//! Hyperparameters are found by maximising the log marginal likelihood with
//! [`crate::optim::minimize`] (Polak-Ribière+ CG) on log hyperparameters (for the NN kernel in
//! the rotated coordinates `(log l, log σf/l)`, see `to_search`), starting from a data-driven
//! guess ([`initial_kernel`]).
//!
//! Cost: a likelihood value is one kernel matrix, one Cholesky and one solve; its gradient
//! adds a `potri`-style inverse of the `F x F` matrix (the trace term needs the inverse's
//! elements), `∂K/∂log l` and one fused pass over the lower triangles (`W` is never formed).
//! The optimiser asks for gradients lazily ([`crate::optim::minimize_lazy`]): rejected
//! line-search trials cost only the value, and the factorisation is reused when the
//! gradient follows at the same point. Large problems start from the optimum on a subset
//! ([`GprOptions::warm_start_pairs`]).
//!
//! Cross-check (scripts/compare/gpr_gpy.py): GPy's `GPRegression` adds 1e-8 to the noise
//! variance internally, so its likelihood at identical hyperparameters is lower than ours by
//! about `1e-8 · ½ tr(W)` (~3e-4 on the 350-pair benchmark).
//!
//! Prediction is the posterior mean of CVPR eq. 13, `K_* α`, for many inputs at once (one kernel
//! evaluation and one matrix product), and optionally the latent variance of CVPR eq. 12,
//! `K_** - K_* (K + σn² I)⁻¹ K_*ᵀ` (add `noise_var` for the variance of a noisy observation).

use crate::kernel::Kernel;
use crate::linalg::Cholesky;
use crate::optim::{minimize_lazy, CgOptions, ExitState};
use crate::sparse_gpr::{train_sparse, SparsePosterior, Sparsity};
use crate::{check_finite, invalid, Result};
use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// The paper's fixed observation-noise variance (after CVPR eq. 8).
pub const PAPER_NOISE_VAR: f64 = 0.1;

/// Training settings.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct GprOptions {
    /// Observation-noise variance `σn²` (the starting value when `learn_noise`).
    pub noise_var: f64,
    /// Also optimise `log σn²` (off by default: the paper fixes `σn² = 0.1`).
    pub learn_noise: bool,
    /// Optimise the kernel hyperparameters (otherwise the given kernel is used as is).
    pub optimise: bool,
    /// Start the optimiser from [`initial_kernel`] instead of the given hyperparameters.
    pub data_init: bool,
    /// Conjugate-gradient settings.
    pub cg: CgOptions,
    /// Warm start: first maximise the likelihood on `min(warm_start_pairs, F / 3)` evenly
    /// spaced training pairs (cheap: the cost is cubic in the count; skipped below 32 pairs)
    /// and start the full optimisation from there. 0 disables it. The full-data optimisation
    /// then runs to the same tolerance, so only the path to the optimum changes. Measured on
    /// the 12 benchmark models: 1100 pairs, 256 -> 167 to 90-139 full-size evaluations.
    #[serde(default)]
    pub warm_start_pairs: usize,
    /// Exact GP or Titsias' sparse bound ([`crate::sparse_gpr`]); exact by default.
    #[serde(default)]
    pub sparse: Sparsity,
}

impl Default for GprOptions {
    fn default() -> Self {
        Self {
            noise_var: PAPER_NOISE_VAR,
            learn_noise: false,
            optimise: true,
            data_init: true,
            cg: CgOptions::default(),
            warm_start_pairs: 256,
            sparse: Sparsity::Exact,
        }
    }
}

/// What training did: optimiser exit state, likelihoods, numerical notes (jitter retries).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TrainReport {
    /// `None` when hyperparameters were not optimised.
    pub exit: Option<ExitState>,
    pub iterations: usize,
    /// Likelihood evaluations (one Cholesky each).
    pub evaluations: usize,
    /// Gradient evaluations (the inverse's elements each); fewer than `evaluations` because
    /// rejected line-search trials need only the value.
    #[serde(default)]
    pub gradient_evaluations: usize,
    /// Log marginal likelihood at the starting hyperparameters.
    pub initial_lml: f64,
    /// Log marginal likelihood of the returned model.
    pub lml: f64,
    /// One line per numerical event (jitter added), to be logged by the caller.
    pub notes: Vec<String>,
}

/// A trained GP regressor: hyperparameters, training inputs and `α = (K + σn² I)⁻¹ Y`; or,
/// trained sparse ([`crate::sparse_gpr`]), the training inputs, `α = β / σn²` over the
/// inducing inputs and the factors of the sparse posterior. Both predict through the same
/// methods.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Gpr {
    pub kernel: Kernel,
    pub noise_var: f64,
    /// Jitter that had to be added to `K + σn² I` (sparse: to `K_uu`; 0 normally).
    pub jitter: f64,
    x: DMatrix<f64>,
    alpha: DMatrix<f64>,
    sparse: Option<SparsePosterior>,
}

pub(crate) fn check_xy(x: &DMatrix<f64>, y: &DMatrix<f64>) -> Result<()> {
    if x.nrows() == 0 {
        return invalid("GP regression needs at least one training pair");
    }
    if x.nrows() != y.nrows() {
        return invalid(format!(
            "GP regression: {} input rows but {} output rows",
            x.nrows(),
            y.nrows()
        ));
    }
    check_finite("GP inputs", x)?;
    check_finite("GP outputs", y)
}

fn noisy_gram(mut ky: DMatrix<f64>, noise_var: f64) -> DMatrix<f64> {
    for i in 0..ky.nrows() {
        ky[(i, i)] += noise_var;
    }
    ky
}

fn lml_value(chol: &Cholesky, y: &DMatrix<f64>, alpha: &DMatrix<f64>) -> f64 {
    let (f, m) = (y.nrows() as f64, y.ncols() as f64);
    -0.5 * y.dot(alpha) - 0.5 * m * chol.log_det() - 0.5 * m * f * (2.0 * std::f64::consts::PI).ln()
}

/// Log marginal likelihood of `Y` given `X` summed over the output columns.
pub fn log_marginal_likelihood(
    kernel: &Kernel,
    noise_var: f64,
    x: &DMatrix<f64>,
    y: &DMatrix<f64>,
    notes: &mut Vec<String>,
) -> Result<f64> {
    check_xy(x, y)?;
    let chol = Cholesky::new(
        &noisy_gram(kernel.gram_lower(x, false).0, noise_var),
        "K + noise",
        notes,
    )?;
    let alpha = chol.solve(y);
    Ok(lml_value(&chol, y, &alpha))
}

/// The marginal likelihood at one hyperparameter setting, factorised: enough to return the
/// value at once and the gradient later ([`Factored::gradient`]) without refactorising, so
/// the optimiser's rejected line-search trials cost one Cholesky ([`crate::optim::minimize_lazy`]).
struct Factored {
    kernel: Kernel,
    noise_var: f64,
    /// Lower triangle of `K + σn² I`.
    ky: DMatrix<f64>,
    chol: Cholesky,
    alpha: DMatrix<f64>,
    value: f64,
}

impl Factored {
    fn new(
        kernel: &Kernel,
        noise_var: f64,
        x: &DMatrix<f64>,
        y: &DMatrix<f64>,
        notes: &mut Vec<String>,
    ) -> Result<Self> {
        // Lower triangles only: the Cholesky reads the lower triangle and the contractions
        // of the gradient are over symmetric products.
        let ky = noisy_gram(kernel.gram_lower(x, false).0, noise_var);
        let chol = Cholesky::new(&ky, "K + noise", notes)?;
        let alpha = chol.solve(y);
        let value = lml_value(&chol, y, &alpha);
        Ok(Self {
            kernel: *kernel,
            noise_var,
            ky,
            chol,
            alpha,
            value,
        })
    }

    /// Gradient of the log marginal likelihood with respect to the kernel's log
    /// hyperparameters, then `∂/∂ log σn²` when `with_noise` (R&W eq. 5.9 summed over outputs).
    ///
    /// `W = α αᵀ - m (K + σn² I)⁻¹` is never formed: one pass over the lower triangles of
    /// `α αᵀ`, the inverse, `∂K/∂log l` and `K + σn² I` accumulates `tr(W ∂K/∂log l)`,
    /// `tr(W (K + σn² I))` and `tr W` (with `∂K/∂log σf = 2K = 2(K + σn² I) - 2σn² I`: every
    /// kernel's σf is a prefactor σf²). The inverse's elements are needed for the trace term.
    fn gradient(&self, x: &DMatrix<f64>, with_noise: bool) -> Vec<f64> {
        let n = self.ky.nrows();
        let m = self.alpha.ncols() as f64;
        let inv = self.chol.inverse_lower();
        let aa = &self.alpha * self.alpha.transpose();
        let dl = self.kernel.dgram_dlog_l_lower(x);
        let (mut t_l, mut t_ky, mut t_w) = (0.0, 0.0, 0.0);
        for j in 0..n {
            let (ic, ac) = (inv.col_as_slice(j), &aa.as_slice()[j * n..(j + 1) * n]);
            let kc = &self.ky.as_slice()[j * n..(j + 1) * n];
            let wjj = ac[j] - m * ic[j];
            t_w += wjj;
            t_ky += wjj * kc[j];
            let (mut off_ky, mut off_l) = (0.0, 0.0);
            match &dl {
                Some(dl) => {
                    let dc = &dl.as_slice()[j * n..(j + 1) * n];
                    t_l += wjj * dc[j];
                    for i in j + 1..n {
                        let w = ac[i] - m * ic[i];
                        off_ky += w * kc[i];
                        off_l += w * dc[i];
                    }
                }
                None => {
                    for i in j + 1..n {
                        off_ky += (ac[i] - m * ic[i]) * kc[i];
                    }
                }
            }
            t_ky += 2.0 * off_ky;
            t_l += 2.0 * off_l;
        }
        let mut grad = Vec::with_capacity(3);
        if dl.is_some() {
            grad.push(0.5 * t_l);
        }
        grad.push(t_ky - self.noise_var * t_w);
        if with_noise {
            grad.push(0.5 * self.noise_var * t_w);
        }
        grad
    }
}

/// Log marginal likelihood and its gradient with respect to the kernel's log
/// hyperparameters ([`Kernel::log_params`] order), followed by `∂/∂ log σn²` when
/// `with_noise`.
pub fn log_marginal_likelihood_grad(
    kernel: &Kernel,
    noise_var: f64,
    with_noise: bool,
    x: &DMatrix<f64>,
    y: &DMatrix<f64>,
    notes: &mut Vec<String>,
) -> Result<(f64, Vec<f64>)> {
    check_xy(x, y)?;
    let f = Factored::new(kernel, noise_var, x, y, notes)?;
    Ok((f.value, f.gradient(x, with_noise)))
}

/// A data-driven starting point: `l` = root-mean-square input norm (NN) or RMS distance to
/// the input mean (SE), and `σf` such that the mean prior variance `mean k(x, x)` equals
/// the mean squared output (the outputs are modelled with zero mean, as in the paper).
pub fn initial_kernel(kernel: &Kernel, x: &DMatrix<f64>, y: &DMatrix<f64>) -> Kernel {
    let f = x.nrows().max(1) as f64;
    let rms_norm = (x.iter().map(|v| v * v).sum::<f64>() / f).sqrt().max(1e-3);
    let mean = x.row_mean();
    let rms_spread = (x
        .row_iter()
        .map(|r| (r - &mean).norm_squared())
        .sum::<f64>()
        / f)
        .sqrt()
        .max(1e-3);
    let y2 = (y.iter().map(|v| v * v).sum::<f64>() / (y.len().max(1) as f64)).max(1e-6);
    let unit = match *kernel {
        Kernel::NeuralNetwork { bias, .. } => Kernel::NeuralNetwork {
            l: rms_norm,
            sigma_f: 1.0,
            bias,
        },
        Kernel::SquaredExponential { .. } => Kernel::SquaredExponential {
            l: rms_spread,
            sigma_f: 1.0,
        },
        Kernel::Linear { .. } => Kernel::Linear { sigma_f: 1.0 },
    };
    let prior = unit.diag(x).mean().max(1e-12);
    let sf = (y2 / prior).sqrt();
    let mut p = unit.log_params();
    *p.last_mut().unwrap() = sf.ln();
    unit.with_log_params(&p)
}

/// Search coordinates of the optimiser. For the NN kernel, `(log l, log σf - log l)`: when
/// the data are nearly linear the likelihood rises slowly along a valley `l, σf -> ∞` with
/// `σf / l` fixed (CVPR eq. 10 tends to the linear kernel `σf²/(2l²) xᵀx'`); in these coordinates
/// the valley is aligned with an axis and conjugate gradients need fewer steps. The optimum
/// is the same (an invertible linear change of variables).
pub(crate) fn to_search(theta: &[f64], valley: bool) -> Vec<f64> {
    if valley {
        vec![theta[0], theta[1] - theta[0]]
    } else {
        theta.to_vec()
    }
}

pub(crate) fn from_search(phi: &[f64], valley: bool) -> Vec<f64> {
    if valley {
        vec![phi[0], phi[1] + phi[0]]
    } else {
        phi.to_vec()
    }
}

/// The kernel hyperparameters maximising the likelihood on `opts.warm_start_pairs` evenly
/// spaced training pairs (see [`GprOptions::warm_start_pairs`]), or `start` unchanged when
/// the option is off, the data are small, or that fit fails.
pub(crate) fn warm_start(start: Kernel, x: &DMatrix<f64>, y: &DMatrix<f64>, opts: &GprOptions) -> Kernel {
    let n = x.nrows();
    let s = opts.warm_start_pairs.min(n / 3);
    if !opts.optimise || s < 32 {
        return start;
    }
    let rows: Vec<usize> = (0..s).map(|i| i * n / s).collect();
    let (xs, ys) = (x.select_rows(rows.iter()), y.select_rows(rows.iter()));
    let sub = GprOptions {
        learn_noise: false,
        data_init: false,
        warm_start_pairs: 0,
        sparse: Sparsity::Exact,
        ..*opts
    };
    match Gpr::train(start, &xs, &ys, &sub) {
        Ok((m, rep)) if rep.lml.is_finite() => m.kernel,
        _ => start,
    }
}

pub(crate) fn summarise_notes(mut notes: Vec<String>) -> Vec<String> {
    const KEEP: usize = 5;
    if notes.len() > KEEP {
        let extra = notes.len() - KEEP;
        notes.truncate(KEEP);
        notes.push(format!("... and {extra} more jitter retries"));
    }
    notes
}

/// Where [`maximise`] ended: the hyperparameters, how, and the factorisation at that point
/// when the optimiser's last request was there.
pub(crate) struct Maximised<F> {
    pub kernel: Kernel,
    pub noise_var: f64,
    pub exit: ExitState,
    pub iterations: usize,
    pub evaluations: usize,
    pub gradient_evaluations: usize,
    pub at_optimum: Option<F>,
}

/// Maximises a likelihood (exact, or the sparse bound) over the kernel's log hyperparameters
/// (and `log σn²` with `opts.learn_noise`) in the search coordinates of [`to_search`], with the
/// lazy-gradient CG. `factor` factorises at one setting (`Err`: treated as `-∞`), `value` and
/// `gradient` read a factorisation; the last one is kept, so the gradient that follows a value
/// at the same point reuses it. `seed` is the factorisation at `start`, if already made.
pub(crate) fn maximise<F>(
    start: Kernel,
    opts: &GprOptions,
    seed: Option<F>,
    mut factor: impl FnMut(&Kernel, f64) -> Result<F>,
    value: impl Fn(&F) -> f64,
    gradient: impl Fn(&F) -> Vec<f64>,
) -> Maximised<F> {
    let nk = start.param_names().len();
    let valley = matches!(start, Kernel::NeuralNetwork { .. });
    let mut phi0 = to_search(&start.log_params(), valley);
    if opts.learn_noise {
        phi0.push(opts.noise_var.ln());
    }
    let at = |phi: &[f64]| {
        let kern = start.with_log_params(&from_search(&phi[..nk], valley));
        let noise = if opts.learn_noise { phi[nk].exp() } else { opts.noise_var };
        (kern, noise)
    };
    let mut last: Option<(Vec<f64>, Result<F>)> = seed.map(|f| (phi0.clone(), Ok(f)));
    let r = minimize_lazy(
        |phi: &[f64], need_grad: bool| {
            if last.as_ref().is_none_or(|(p, _)| p.as_slice() != phi) {
                let (kern, noise) = at(phi);
                last = Some((phi.to_vec(), factor(&kern, noise)));
            }
            let Some((_, Ok(f))) = &last else {
                return (f64::INFINITY, None);
            };
            if !need_grad {
                return (-value(f), None);
            }
            let mut g = gradient(f);
            if valley {
                g[0] += g[1]; // chain rule for (log l, log σf) = (φ0, φ0 + φ1)
            }
            (-value(f), Some(g.into_iter().map(|d| -d).collect()))
        },
        &phi0,
        &opts.cg,
    );
    let (kernel, noise_var) = at(&r.x);
    let at_optimum = match last {
        Some((p, Ok(f))) if p == r.x => Some(f),
        _ => None,
    };
    Maximised {
        kernel,
        noise_var,
        exit: r.exit,
        iterations: r.iterations,
        evaluations: r.evaluations,
        gradient_evaluations: r.gradient_evaluations,
        at_optimum,
    }
}

impl Gpr {
    /// Conditions the GP on `(X, Y)` with fixed hyperparameters (no optimisation).
    pub fn fit(
        kernel: Kernel,
        noise_var: f64,
        x: &DMatrix<f64>,
        y: &DMatrix<f64>,
        notes: &mut Vec<String>,
    ) -> Result<Self> {
        check_xy(x, y)?;
        if !(noise_var >= 0.0 && noise_var.is_finite()) {
            return invalid(format!("noise variance must be >= 0, got {noise_var}"));
        }
        let chol = Cholesky::new(
            &noisy_gram(kernel.gram_lower(x, false).0, noise_var),
            "K + noise",
            notes,
        )?;
        let alpha = chol.solve(y);
        Ok(Self {
            kernel,
            noise_var,
            jitter: chol.jitter,
            x: x.clone(),
            alpha,
            sparse: None,
        })
    }

    /// Trains on `X` (`F x D`) -> `Y` (`F x m`): maximises the log marginal likelihood over
    /// the kernel's hyperparameters (and `σn²` if asked), starting from `kernel` or from
    /// [`initial_kernel`], then conditions on the data with the best hyperparameters found.
    pub fn train(
        kernel: Kernel,
        x: &DMatrix<f64>,
        y: &DMatrix<f64>,
        opts: &GprOptions,
    ) -> Result<(Self, TrainReport)> {
        check_xy(x, y)?;
        if let Some(m) = opts.sparse.inducing_for(x.nrows()) {
            return train_sparse(kernel, x, y, m, opts);
        }
        let mut notes = Vec::new();
        let start = if opts.data_init {
            initial_kernel(&kernel, x, y)
        } else {
            kernel
        };
        if !(opts.noise_var >= 0.0 && opts.noise_var.is_finite()) {
            return invalid(format!(
                "noise variance must be >= 0, got {}",
                opts.noise_var
            ));
        }
        let start = warm_start(start, x, y, opts);
        let mut first = Some(Factored::new(&start, opts.noise_var, x, y, &mut notes)?);
        let initial_lml = first.as_ref().map_or(f64::NAN, |f| f.value);
        let (kernel, noise_var, exit, iterations, evaluations) = if opts.optimise {
            // Seeded with the starting point, where the optimiser begins (not with a learnt
            // noise, whose start exp(ln σn²) may differ from σn² in the last bit).
            let seed = if opts.learn_noise { None } else { first.take() };
            let r = maximise(
                start,
                opts,
                seed,
                |kern, noise| Factored::new(kern, noise, x, y, &mut notes),
                |f| f.value,
                |f| f.gradient(x, opts.learn_noise),
            );
            let counts = (r.evaluations, r.gradient_evaluations);
            (r.kernel, r.noise_var, Some(r.exit), r.iterations, counts)
        } else {
            (start, opts.noise_var, None, 0, (0, 0))
        };
        let (evaluations, gradient_evaluations) = evaluations;
        // Condition on the data with the hyperparameters found (one more factorisation).
        let fitted = match first {
            Some(f) if !opts.optimise => f,
            _ => Factored::new(&kernel, noise_var, x, y, &mut notes)?,
        };
        let lml = fitted.value;
        let model = Self {
            kernel,
            noise_var,
            jitter: fitted.chol.jitter,
            x: x.clone(),
            alpha: fitted.alpha,
            sparse: None,
        };
        let report = TrainReport {
            exit,
            iterations,
            evaluations,
            gradient_evaluations,
            initial_lml,
            lml,
            notes: summarise_notes(notes),
        };
        Ok((model, report))
    }

    /// A sparse model (built by [`crate::sparse_gpr`]): `alpha` weights the inducing inputs.
    pub(crate) fn from_sparse(
        kernel: Kernel,
        noise_var: f64,
        jitter: f64,
        x: DMatrix<f64>,
        alpha: DMatrix<f64>,
        sparse: SparsePosterior,
    ) -> Self {
        Self { kernel, noise_var, jitter, x, alpha, sparse: Some(sparse) }
    }

    /// The sparse posterior (inducing inputs), `None` for the exact GP.
    pub fn sparse(&self) -> Option<&SparsePosterior> {
        self.sparse.as_ref()
    }

    /// The inputs the posterior mean is a kernel expansion over: the training inputs, or
    /// the inducing inputs of a sparse model.
    /// The invariants prediction relies on, for a model read from a file: positive finite
    /// kernel parameters, finite non-negative noise and jitter, finite training inputs and
    /// weights, one weight row per basis row (training or inducing input), inducing inputs of
    /// the training inputs' dimension and square factors of their count. The error is the
    /// problem.
    pub fn validate(&self) -> std::result::Result<(), String> {
        let positive = |v: f64| v.is_finite() && v > 0.0;
        let ok_kernel = match self.kernel {
            Kernel::NeuralNetwork { l, sigma_f, .. } | Kernel::SquaredExponential { l, sigma_f } => {
                positive(l) && positive(sigma_f)
            }
            Kernel::Linear { sigma_f } => positive(sigma_f),
        };
        if !ok_kernel {
            return Err(format!("kernel {:?} has a parameter that is not a finite positive number", self.kernel));
        }
        if !(self.noise_var.is_finite() && self.noise_var >= 0.0 && self.jitter.is_finite() && self.jitter >= 0.0) {
            return Err(format!("noise variance {} or jitter {} is not a finite number >= 0", self.noise_var, self.jitter));
        }
        if self.x.nrows() == 0 || self.x.ncols() == 0 {
            return Err(format!("{} x {} training inputs", self.x.nrows(), self.x.ncols()));
        }
        let basis = self.basis();
        if basis.ncols() != self.x.ncols() || self.alpha.nrows() != basis.nrows() || self.alpha.ncols() == 0 {
            return Err(format!(
                "weights of {} x {} for {} basis inputs of dimension {} (training inputs {} x {})",
                self.alpha.nrows(),
                self.alpha.ncols(),
                basis.nrows(),
                basis.ncols(),
                self.x.nrows(),
                self.x.ncols()
            ));
        }
        if let Some(s) = &self.sparse {
            let m = s.inducing.nrows();
            if s.l_uu.shape() != (m, m) || s.l_p.shape() != (m, m) {
                return Err(format!("sparse factors of {:?} and {:?} for {m} inducing inputs", s.l_uu.shape(), s.l_p.shape()));
            }
            if !s.l_uu.iter().chain(s.l_p.iter()).all(|v| v.is_finite()) {
                return Err("a sparse factor has a non-finite entry".into());
            }
        }
        if !self.x.iter().chain(self.alpha.iter()).chain(basis.iter()).all(|v| v.is_finite()) {
            return Err("training inputs or weights have a non-finite entry".into());
        }
        Ok(())
    }

    fn basis(&self) -> &DMatrix<f64> {
        self.sparse.as_ref().map_or(&self.x, |s| &s.inducing)
    }

    /// Number of training pairs `F`.
    pub fn n_train(&self) -> usize {
        self.x.nrows()
    }

    /// Input dimension `D`.
    pub fn input_dim(&self) -> usize {
        self.x.ncols()
    }

    /// The training inputs (`F x D`, one pair per row).
    pub fn inputs(&self) -> &DMatrix<f64> {
        &self.x
    }

    /// Output dimension `m`.
    pub fn output_dim(&self) -> usize {
        self.alpha.ncols()
    }

    fn check_inputs(&self, xs: &DMatrix<f64>) -> Result<()> {
        if xs.ncols() != self.input_dim() {
            return invalid(format!(
                "GP prediction: inputs have {} columns, the model expects {}",
                xs.ncols(),
                self.input_dim()
            ));
        }
        check_finite("GP prediction inputs", xs)
    }

    /// Posterior mean (CVPR eq. 13) for every row of `xs` (`N x D` -> `N x m`): `K_* α`.
    pub fn predict_mean(&self, xs: &DMatrix<f64>) -> Result<DMatrix<f64>> {
        self.check_inputs(xs)?;
        Ok(self.kernel.cross(xs, self.basis()) * &self.alpha)
    }

    /// Posterior mean (CVPR eq. 13) and latent variance (eq. 12, shared by all outputs) for every
    /// row of `xs`. The variance refactorises `K + σn² I` (the model does not store the
    /// `F x F` factor, to keep artifacts small): use [`Gpr::predict_mean`] when only the
    /// mean is needed.
    pub fn predict_with_variance(
        &self,
        xs: &DMatrix<f64>,
        notes: &mut Vec<String>,
    ) -> Result<(DMatrix<f64>, DVector<f64>)> {
        self.check_inputs(xs)?;
        let ks = self.kernel.cross(xs, self.basis());
        let mean = &ks * &self.alpha;
        if let Some(sp) = &self.sparse {
            return Ok((mean, sp.variance(&ks.transpose(), &self.kernel.diag(xs))));
        }
        let mut ky = noisy_gram(self.kernel.gram_lower(&self.x, false).0, self.noise_var);
        for i in 0..ky.nrows() {
            ky[(i, i)] += self.jitter;
        }
        let l = Cholesky::new(&ky, "K + noise", notes)?.lower();
        // v = L⁻¹ K_*ᵀ; variance = k(x*, x*) - |v|² per column.
        let v = l
            .solve_lower_triangular(&ks.transpose())
            .ok_or_else(|| crate::GpError::Invalid("singular Cholesky factor".into()))?;
        let prior = self.kernel.diag(xs);
        let var = DVector::from_iterator(
            xs.nrows(),
            v.column_iter()
                .zip(prior.iter())
                .map(|(c, p)| (p - c.norm_squared()).max(0.0)),
        );
        Ok((mean, var))
    }
}

// NOTE(next): at 1100 pairs (loaded machine) a likelihood value costs ~25-35 ms (kernel
// matrix ~5-10 ms of libm asin, Cholesky ~10-15 ms) and a gradient another ~45-70 ms (the
// potri-style inverse ~36-48 ms dominates; faer and OpenBLAS dpotri measured alike). Training
// the 12 benchmark models takes ~140 values and ~70 gradients. Ideas not yet tried: a
// vectorisable asin (Cephes-style rational approximation) for the NN kernel, a first
// line-search step from a quadratic model after the warm start, and balancing the 12 models
// across threads by expected cost (the near-linear ones take more iterations).

/// Trains one GP per `(X, Y)` problem (body parts, displacement) in parallel with rayon,
/// all with the same kernel family and options. Sets faer to sequential mode (its own
/// threading is slower than one job per core; STACK.md); run with `OPENBLAS_NUM_THREADS=1`.
pub fn train_many(
    kernel: Kernel,
    problems: &[(DMatrix<f64>, DMatrix<f64>)],
    opts: &GprOptions,
) -> Vec<Result<(Gpr, TrainReport)>> {
    faer::set_global_parallelism(faer::Par::Seq);
    problems
        .par_iter()
        .map(|(x, y)| Gpr::train(kernel, x, y, opts))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fitted() -> Gpr {
        let x = DMatrix::from_fn(12, 2, |i, c| ((i * 3 + c) as f64 * 0.41).sin());
        let y = DMatrix::from_fn(12, 3, |i, c| x[(i, c % 2)] * (c + 1) as f64);
        let k = Kernel::NeuralNetwork { l: 1.2, sigma_f: 0.8, bias: false };
        Gpr::fit(k, 0.1, &x, &y, &mut Vec::new()).unwrap()
    }

    /// A GP as fitted is valid; each broken invariant prediction relies on is named.
    #[test]
    fn validate_names_each_broken_invariant() {
        let gp = fitted();
        assert_eq!(gp.validate(), Ok(()));
        let broken: Vec<(Box<dyn Fn(&mut Gpr)>, &str)> = vec![
            (Box::new(|g| g.alpha = g.alpha.rows(0, 11).into_owned()), "weights of 11 x 3"),
            (Box::new(|g| g.kernel = Kernel::NeuralNetwork { l: -1.0, sigma_f: 0.8, bias: false }), "kernel"),
            (Box::new(|g| g.noise_var = f64::NAN), "noise variance"),
            (Box::new(|g| g.alpha[(3, 1)] = f64::INFINITY), "non-finite"),
            (
                Box::new(|g| {
                    g.sparse = Some(SparsePosterior {
                        inducing: g.x.rows(0, 4).into_owned(),
                        l_uu: DMatrix::identity(4, 4),
                        l_p: DMatrix::identity(3, 3),
                    })
                }),
                "weights of 12 x 3 for 4 basis inputs",
            ),
        ];
        for (breaks, want) in broken {
            let mut g = gp.clone();
            breaks(&mut g);
            let e = g.validate().unwrap_err();
            assert!(e.contains(want), "{e} (wanted '{want}')");
        }
        let mut g = gp.clone();
        g.sparse = Some(SparsePosterior {
            inducing: g.x.rows(0, 4).into_owned(),
            l_uu: DMatrix::identity(4, 4),
            l_p: DMatrix::identity(3, 3),
        });
        g.alpha = g.alpha.rows(0, 4).into_owned();
        assert!(g.validate().unwrap_err().contains("sparse factors"));
    }
}
