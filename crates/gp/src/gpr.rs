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
use crate::likelihood::{fit_exact, noisy_cholesky, noisy_gram, warm_start};
use crate::linalg::Cholesky;
use crate::sparse_gpr::{train_sparse, SparseFit, SparsePosterior};
use crate::training::{check_xy, summarise_notes};
use crate::{check_finite, invalid, Result};
use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

pub use crate::likelihood::{log_marginal_likelihood, log_marginal_likelihood_grad};
pub use crate::training::{initial_kernel, GprOptions, TrainReport, PAPER_NOISE_VAR};

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
        let chol = noisy_cholesky(&kernel, noise_var, x, notes)?;
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
            return train_sparse(kernel, x, y, m, opts).map(|(fit, r)| (Self::from_sparse(fit, x), r));
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
        let fit = fit_exact(start, x, y, opts, &mut notes)?;
        let report = TrainReport {
            exit: fit.exit,
            iterations: fit.iterations,
            evaluations: fit.evaluations,
            gradient_evaluations: fit.gradient_evaluations,
            initial_lml: fit.initial_lml,
            lml: fit.fitted.value,
            notes: summarise_notes(notes),
        };
        let model = Self {
            kernel: fit.kernel,
            noise_var: fit.noise_var,
            jitter: fit.fitted.chol.jitter,
            x: x.clone(),
            alpha: fit.fitted.alpha,
            sparse: None,
        };
        Ok((model, report))
    }

    /// The regressor of a sparse GP conditioned on the training inputs `x`
    /// ([`crate::sparse_gpr`]): its `alpha` weights the inducing inputs.
    pub fn from_sparse(fit: SparseFit, x: &DMatrix<f64>) -> Self {
        let SparseFit { kernel, noise_var, jitter, alpha, posterior } = fit;
        Self { kernel, noise_var, jitter, x: x.clone(), alpha, sparse: Some(posterior) }
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
/// threading was measured slower than one job per core on 2 cores); run with `OPENBLAS_NUM_THREADS=1`.
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
