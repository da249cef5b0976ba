//! Gaussian Process Dynamical Model (Boukhayma & Boyer, 3DV 2017, after Wang et al. 2008)
//! and Hybrid Monte Carlo sampling of latent trajectories.
//!
//! Data flow: poses `Y` → [`model::Gpdm::new`] (PCA start) → [`optim::train`] (3DV eq. 7 MAP) →
//! [`predict::Predictor`] (3DV eqs. 8-13) → [`hmc`] (trajectory variations) → [`blend`] (§7).
//! All numerics are f64; kernel matrices are factorised by Cholesky with logged jitter
//! retries and never inverted explicitly.
//!
//! Choices and deviations from the paper (documented where implemented):
//! - Y is centred (the GP of 3DV eq. 3 has zero mean); the mean is added back in eq. 12.
//! - Noise-variance floors: `1/α3 ≥ pose_noise_floor` (default 1e-6, squared units of Y) and
//!   optionally `1/β4 ≥ dyn_noise_floor` (recommended 1e-4..1e-3 latent units² on clean
//!   data, see [`model::GpdmConfig`]), built into the parametrisation ([`model`]).
//! - Hyperparameters optimised in log coordinates, jointly with X by default ([`optim`]).
//! - PCA scores scaled to unit variance before training; each sequence's first latent point
//!   has an N(0, σ0² I) prior (σ0² = 1).
//! - HMC energy: product of one-step GP predictives (3DV eqs. 8-10) given the training dynamics
//!   ([`hmc`]); k(x, x) in 3DV eqs. 10 and 13 includes the noise term.
//! - No per-dimension output scaling W (the paper does not use it).

pub mod ancestral;
pub mod blend;
pub mod error;
pub mod hmc;
pub mod kernel;
pub mod linalg;
pub mod model;
pub mod optim;
pub mod pca;
pub mod predict;
pub mod vexp;

pub use error::{GpdmError, Result};
pub use model::{DynamicsWeight, Gpdm, GpdmConfig};
