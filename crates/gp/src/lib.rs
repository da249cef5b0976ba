//! Numerics of "Surface Motion Capture Transfer with Gaussian Process Regression"
//! (Boukhayma, Franco, Boyer, CVPR 2017), sections 4-5, equations 1-13.
//!
//! Pure numerics, no meshes. Conventions used throughout the crate:
//! - data matrices hold **one sample per row** (`F x D`: frames x dimensions), as
//!   `nalgebra::DMatrix<f64>`; where the paper stacks samples as columns (CVPR eqs. 2-4) the
//!   doc comment says so;
//! - all model numerics are `f64`; linear systems are solved with Cholesky factorisations
//!   ([`linalg`]), with a jitter retry that is reported in a `notes` list, never an explicit
//!   inverse for solving;
//! - every model type is `serde`-serialisable so stage binaries can store it with bincode.
//!
//! Modules, in pipeline order:
//! - [`pca`]: per-part dimension reduction (section 4);
//! - [`blr`]: Bayesian linear regression association cost (CVPR eqs. 1-6);
//! - [`dtw`]: constrained least-cost path through the cost matrix (CVPR eq. 7);
//! - [`kernel`]: covariance functions, including the neural-network kernel (CVPR eq. 10);
//! - [`gpr`]: multi-output GP regression (CVPR eqs. 8-13), trained exact or sparse;
//!   [`likelihood`]: the exact GP's marginal likelihood and its maximisation; [`training`]:
//!   what the exact and sparse trainings share (options, report, start, optimiser loop);
//! - [`sparse_gpr`]: the same regression for large training sets, Titsias' (2009) bound with
//!   inducing inputs chosen by [`inducing`] (greedy variance selection);
//! - [`optim`]: non-linear conjugate gradients (Polak-Ribière+) with a strong-Wolfe line search;
//! - [`affine_keypose`]: the Semantic Deformation Transfer baseline (Baran et al. 2009);
//! - [`affine_mean`]: an explicit affine mean function, the GP then fitted on the residuals.

pub mod affine_keypose;
pub mod affine_mean;
pub mod band;
pub mod blr;
pub mod dtw;
pub mod gpr;
pub mod inducing;
pub mod kernel;
pub mod likelihood;
pub mod linalg;
pub mod optim;
pub mod pca;
pub mod sparse_gpr;
pub mod training;

/// Errors of the numerics: bad shapes/values passed in, or a matrix that stays
/// indefinite after the jitter retries.
#[derive(Debug, thiserror::Error)]
pub enum GpError {
    /// Input arrays with inconsistent shapes or non-finite values.
    #[error("invalid input: {0}")]
    Invalid(String),
    /// Cholesky failed even with the largest jitter tried.
    #[error("{what}: matrix not positive definite even with jitter {jitter:.3e}")]
    NotPositiveDefinite { what: String, jitter: f64 },
}

/// Result alias of this crate.
pub type Result<T> = std::result::Result<T, GpError>;

pub(crate) fn invalid<T>(msg: impl Into<String>) -> Result<T> {
    Err(GpError::Invalid(msg.into()))
}

/// Checks that every entry of a matrix is finite.
pub(crate) fn check_finite(name: &str, m: &nalgebra::DMatrix<f64>) -> Result<()> {
    if let Some(i) = m.iter().position(|v| !v.is_finite()) {
        return invalid(format!(
            "{name}: non-finite value at row {}, column {}",
            i % m.nrows().max(1),
            i / m.nrows().max(1)
        ));
    }
    Ok(())
}
