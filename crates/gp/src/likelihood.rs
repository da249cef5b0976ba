//! The exact GP's log marginal likelihood (the training outputs' density under CVPR eq. 11's
//! prior, `N(0, K + σn² I)`, summed over the output columns) and its gradient, factorised once
//! per hyperparameter setting ([`Factored`]); its maximisation ([`fit_exact`]) and the warm start
//! of both trainings, that maximisation on a subset of the pairs ([`warm_start`]). The formulas
//! are in the documentation of the module `gpr`, the regressor built on them.

use crate::kernel::Kernel;
use crate::linalg::Cholesky;
use crate::optim::ExitState;
use crate::training::{check_xy, maximise, GprOptions, Sparsity};
use crate::Result;
use nalgebra::DMatrix;

pub(crate) fn noisy_gram(mut ky: DMatrix<f64>, noise_var: f64) -> DMatrix<f64> {
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
    let chol = noisy_cholesky(kernel, noise_var, x, notes)?;
    let alpha = chol.solve(y);
    Ok(lml_value(&chol, y, &alpha))
}

/// The Cholesky factorisation of `K + σn² I` at the inputs `x`.
pub(crate) fn noisy_cholesky(
    kernel: &Kernel,
    noise_var: f64,
    x: &DMatrix<f64>,
    notes: &mut Vec<String>,
) -> Result<Cholesky> {
    Cholesky::new(&noisy_gram(kernel.gram_lower(x, false).0, noise_var), "K + noise", notes)
}

/// The marginal likelihood at one hyperparameter setting, factorised: enough to return the
/// value at once and the gradient later ([`Factored::gradient`]) without refactorising, so
/// the optimiser's rejected line-search trials cost one Cholesky ([`crate::optim::minimize_lazy`]).
pub(crate) struct Factored {
    kernel: Kernel,
    noise_var: f64,
    /// Lower triangle of `K + σn² I`.
    ky: DMatrix<f64>,
    pub(crate) chol: Cholesky,
    /// `(K + σn² I)⁻¹ Y`.
    pub(crate) alpha: DMatrix<f64>,
    /// The log marginal likelihood.
    pub(crate) value: f64,
}

impl Factored {
    pub(crate) fn new(
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
    pub(crate) fn gradient(&self, x: &DMatrix<f64>, with_noise: bool) -> Vec<f64> {
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
    if !(sub.noise_var >= 0.0 && sub.noise_var.is_finite()) {
        return start;
    }
    match fit_exact(start, &xs, &ys, &sub, &mut Vec::new()) {
        Ok(fit) if fit.fitted.value.is_finite() => fit.kernel,
        _ => start,
    }
}

/// What [`fit_exact`] found: the hyperparameters, the factorisation there, and how.
pub(crate) struct ExactFit {
    pub kernel: Kernel,
    pub noise_var: f64,
    pub fitted: Factored,
    /// The likelihood at the start.
    pub initial_lml: f64,
    /// `None` when `opts.optimise` is off.
    pub exit: Option<ExitState>,
    pub iterations: usize,
    pub evaluations: usize,
    pub gradient_evaluations: usize,
}

/// The exact likelihood maximised from `start` (kept as is without `opts.optimise`), then the
/// factorisation at the hyperparameters found.
pub(crate) fn fit_exact(
    start: Kernel,
    x: &DMatrix<f64>,
    y: &DMatrix<f64>,
    opts: &GprOptions,
    notes: &mut Vec<String>,
) -> Result<ExactFit> {
    let first = Factored::new(&start, opts.noise_var, x, y, notes)?;
    let initial_lml = first.value;
    if !opts.optimise {
        return Ok(ExactFit {
            kernel: start,
            noise_var: opts.noise_var,
            fitted: first,
            initial_lml,
            exit: None,
            iterations: 0,
            evaluations: 0,
            gradient_evaluations: 0,
        });
    }
    // Seeded with the starting point, where the optimiser begins (not with a learnt noise,
    // whose start exp(ln σn²) may differ from σn² in the last bit).
    let seed = if opts.learn_noise { None } else { Some(first) };
    let r = maximise(
        start,
        opts,
        seed,
        |kern, noise| Factored::new(kern, noise, x, y, notes),
        |f| f.value,
        |f| f.gradient(x, opts.learn_noise),
    );
    // Condition on the data with the hyperparameters found (one more factorisation).
    let fitted = Factored::new(&r.kernel, r.noise_var, x, y, notes)?;
    Ok(ExactFit {
        kernel: r.kernel,
        noise_var: r.noise_var,
        fitted,
        initial_lml,
        exit: Some(r.exit),
        iterations: r.iterations,
        evaluations: r.evaluations,
        gradient_evaluations: r.gradient_evaluations,
    })
}
