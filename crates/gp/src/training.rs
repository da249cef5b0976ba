//! What training a GP's hyperparameters needs, exact or sparse (the modules `gpr` and
//! `sparse_gpr` above this one): the options and the report, the input checks, the data-driven
//! start, the optimiser's search coordinates and the maximisation itself.

use crate::kernel::Kernel;
use crate::optim::{minimize_lazy, CgOptions, ExitState};
use crate::{check_finite, invalid, Result};
use nalgebra::DMatrix;
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
    /// Exact GP or Titsias' sparse bound (module `sparse_gpr`); exact by default.
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

/// Inducing-input count used by [`Sparsity::Auto`].
pub const AUTO_INDUCING: usize = 256;

/// Exact or sparse training.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum Sparsity {
    /// The exact GP (CVPR eqs. 8-13).
    #[default]
    Exact,
    /// Titsias' bound with at most this many inducing inputs (exact when `F` is not larger).
    Inducing(usize),
    /// Exact while it is faster than the sparse GP with [`AUTO_INDUCING`] inputs, sparse above
    /// (see [`Sparsity::inducing_for`]).
    Auto,
}

impl Sparsity {
    /// The inducing-input count to train `pairs` pairs with, `None` for the exact GP. For
    /// [`Sparsity::Auto`]: sparse when `F > 4 M`. Counting flops, an exact evaluation (`~F³`:
    /// Cholesky and the inverse's elements) costs more than a sparse one (`~4 F M²`: `ΦᵀΦ`,
    /// `Φᵀ∂Φ`, the kernel blocks) from `F ≈ 2 M`, but measured on the demo set (588 pairs,
    /// M = 256) the exact GP still trained faster (5.8 s against 8.5 s for the two directions);
    /// at 1100 pairs the sparse GP took half the exact time (docs/studies/08-sparse-gp.md).
    pub fn inducing_for(&self, pairs: usize) -> Option<usize> {
        match *self {
            Sparsity::Exact => None,
            Sparsity::Inducing(m) => (pairs > m).then_some(m),
            Sparsity::Auto => (pairs > 4 * AUTO_INDUCING).then_some(AUTO_INDUCING),
        }
    }
}

impl std::str::FromStr for Sparsity {
    type Err = String;

    /// `exact`, `auto`, or an inducing-input count `M >= 1` (the command-line syntax).
    fn from_str(s: &str) -> std::result::Result<Self, String> {
        match s {
            "exact" => Ok(Sparsity::Exact),
            "auto" => Ok(Sparsity::Auto),
            _ => match s.parse::<usize>() {
                Ok(m) if m >= 1 => Ok(Sparsity::Inducing(m)),
                _ => Err(format!("expected an inducing-input count >= 1, 'auto' or 'exact', got '{s}'")),
            },
        }
    }
}

impl std::fmt::Display for Sparsity {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Sparsity::Exact => write!(f, "exact"),
            Sparsity::Inducing(m) => write!(f, "{m}"),
            Sparsity::Auto => write!(f, "auto"),
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
