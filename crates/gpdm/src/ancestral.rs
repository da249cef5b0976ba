//! Exact sampling of the trajectory density that the HMC sampler targets.
//!
//! [`crate::hmc::TrajectoryEnergy`] is the negative log of a product of one-step GP
//! predictives (eqs. 8-10) with the first point fixed:
//!
//! ```text
//! P(x_2, …, x_T | x_1) = ∏_{t=1}^{T-1} N(x_{t+1}; μ_X(x_t), σ²_X(x_t) I)
//! ```
//!
//! A Markov chain of this form is sampled exactly by drawing each point from its one-step
//! predictive given the point just drawn (ancestral sampling): every trajectory is an independent
//! draw of the same density, at the cost of one forward pass, with no burn-in, step size or
//! thinning. HMC (the paper's sampler, [`crate::hmc`]) targets the same density with correlated
//! draws; `hmc-sample --sampler` chooses between them.

use nalgebra::DMatrix;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

use crate::error::{invalid, Result};
use crate::predict::Predictor;

/// `n` independent trajectories of `len` points (each `len × d`, first row `x1`) drawn from
/// the product of one-step predictives. Trajectory `k` uses its own ChaCha8 stream `k` of
/// `seed`, so the result does not depend on the number of threads.
pub fn sample_trajectories_ancestral(
    pred: &Predictor,
    x1: &[f64],
    len: usize,
    n: usize,
    seed: u64,
) -> Result<Vec<DMatrix<f64>>> {
    let d = pred.latent_dim();
    if x1.len() != d {
        return invalid(format!(
            "first point has {} coordinates, the model's latent space {d}",
            x1.len()
        ));
    }
    if len < 2 {
        return invalid(format!("trajectory length {len}: at least 2 points needed"));
    }
    (0..n)
        .into_par_iter()
        .map(|k| {
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            rng.set_stream(k as u64);
            let mut traj = DMatrix::zeros(len, d);
            for (c, &v) in x1.iter().enumerate() {
                traj[(0, c)] = v;
            }
            let mut x = x1.to_vec();
            for t in 1..len {
                let (mu, var) = pred.dynamics(&x);
                if !(var.is_finite() && var > 0.0) {
                    return invalid(format!(
                        "one-step predictive variance {var:e} at frame {t} is not positive"
                    ));
                }
                let sd = var.sqrt();
                for c in 0..d {
                    let z: f64 = rng.sample(rand_distr::StandardNormal);
                    x[c] = mu[c] + sd * z;
                    traj[(t, c)] = x[c];
                }
            }
            Ok(traj)
        })
        .collect()
}
