//! Gaussian Process Dynamical Model (Boukhayma & Boyer, 3DV 2017, after Wang et al. 2008)
//! and Hybrid Monte Carlo sampling of latent trajectories.
//!
//! Data flow: poses `Y` → [`model::Gpdm::new`] (PCA start) → [`optim::train`] (eq. 7 MAP) →
//! [`predict::Predictor`] (eqs. 8-13) → [`hmc`] (trajectory variations) → [`blend`] (§7).
//! All numerics are f64; kernel matrices are factorised by Cholesky with logged jitter
//! retries and never inverted explicitly.

pub mod blend;
pub mod error;
pub mod hmc;
pub mod kernel;
pub mod linalg;
pub mod model;
pub mod optim;
pub mod predict;

pub use error::{GpdmError, Result};
pub use model::{Gpdm, GpdmConfig};
