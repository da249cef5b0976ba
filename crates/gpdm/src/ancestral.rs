//! Exact sampling of the trajectory density that the HMC sampler targets.
//!
//! [`crate::hmc::TrajectoryEnergy`] is the negative log of a product of one-step GP
//! predictives (3DV eqs. 8-10) with the first point fixed:
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

use faer::Mat;
use nalgebra::DMatrix;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::error::{invalid, Result};
use crate::linalg::mul;
use crate::predict::Predictor;

/// `n` independent trajectories of `len` points (each `len × d`, first row `x1`) drawn from
/// the product of one-step predictives. The trajectories advance in lockstep, so each step is
/// one kernel evaluation and one triangular solve with `n` right-hand sides (3DV eqs. 9-10 for all
/// of them at once). Trajectory `k` draws its noise from its own ChaCha8 stream `k` of `seed`,
/// so the result does not depend on threads, nor on `n`'s batching beyond the rounding of the
/// batched products. `variance_scale` κ scales every one-step variance as in
/// [`crate::hmc::TrajectoryEnergy::with_variance_scale`] (1: the model's density).
pub fn sample_trajectories_ancestral(
    pred: &Predictor,
    x1: &[f64],
    len: usize,
    n: usize,
    seed: u64,
    variance_scale: f64,
) -> Result<Vec<DMatrix<f64>>> {
    Ok(sample_trajectories_on_data(pred, x1, len, n, seed, variance_scale, f64::INFINITY)?.0)
}

/// Redraws allowed per point of [`sample_trajectories_on_data`] before it keeps the candidate
/// nearest the data.
pub const MAX_REDRAWS: usize = 20;

/// The threshold `hmc-sample --sampler ancestral` gives [`sample_trajectories_on_data`]: a
/// point whose pose variance passes this share of the prior's is redrawn. Far below
/// [`crate::hmc::OFF_DATA_VARIANCE`], which says where a point has left the data: a draw kept
/// up to half the prior's variance already decodes to torn and spinning bodies (four capture
/// sets, seeds 0-2: 129 torn and 193 spinning frames at 0.5, none and 49 at 0.02;
/// docs/studies/45-ancestral-redraw-threshold.md).
pub const REDRAW_VARIANCE: f64 = 0.02;

/// [`sample_trajectories_ancestral`] restricted to the learned data: a drawn point whose pose
/// variance (3DV eq. 13) passes `off_data` of the prior's (`Predictor::pose_variance_ratio`;
/// `hmc-sample` uses [`REDRAW_VARIANCE`]) is redrawn from the same one-step
/// predictive, up to [`MAX_REDRAWS`] times, after which the candidate with the smallest ratio
/// is kept. Each accepted point is a draw of the one-step predictive truncated to the points
/// on the data, so a trajectory cannot run away from the data into the prior's mean pose.
/// Returns the trajectories and, per trajectory, the points kept off the data. Redraws come
/// from the trajectory's own stream, so batching and threads change the result no more than
/// they change [`sample_trajectories_ancestral`]'s, and with a threshold no point reaches the
/// trajectories are [`sample_trajectories_ancestral`]'s (`f64::INFINITY`: no ratio is
/// computed).
pub fn sample_trajectories_on_data(
    pred: &Predictor,
    x1: &[f64],
    len: usize,
    n: usize,
    seed: u64,
    variance_scale: f64,
    off_data: f64,
) -> Result<(Vec<DMatrix<f64>>, Vec<usize>)> {
    if !(off_data > 0.0) {
        return invalid(format!("off-data threshold {off_data} must be positive"));
    }
    if !(variance_scale > 0.0 && variance_scale.is_finite()) {
        return invalid(format!("variance scale {variance_scale} must be positive"));
    }
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
    let mut rngs: Vec<ChaCha8Rng> = (0..n)
        .map(|k| {
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            rng.set_stream(k as u64);
            rng
        })
        .collect();
    let mut trajs = vec![DMatrix::zeros(len, d); n];
    let mut off = vec![0usize; n];
    // Current points, one row per trajectory.
    let mut x = Mat::from_fn(n, d, |_, c| x1[c]);
    for traj in trajs.iter_mut() {
        for (c, &v) in x1.iter().enumerate() {
            traj[(0, c)] = v;
        }
    }
    let (kx, x_in) = (pred.dynamics_kernel(), pred.dynamics_inputs());
    for t in 1..len {
        let kstar = kx.cross(x_in, x.as_ref()); // M × n
        let mu = mul(pred.dynamics_weights().transpose(), kstar.as_ref()); // d × n
        let mut v = kstar;
        pred.dynamics_cholesky().half_solve_in_place(v.as_mut());
        for (k, (rng, traj)) in rngs.iter_mut().zip(trajs.iter_mut()).enumerate() {
            let xk: Vec<f64> = (0..d).map(|c| x[(k, c)]).collect();
            let var = variance_scale * (kx.self_cov(&xk) - v.col(k).squared_norm_l2());
            if !(var.is_finite() && var > 0.0) {
                return invalid(format!(
                    "one-step predictive variance {var:e} at frame {t} is not positive"
                ));
            }
            let sd = var.sqrt();
            let mut next = DMatrix::<f64>::zeros(1, d);
            let mut best: Option<(f64, DMatrix<f64>)> = None;
            for _ in 0..=MAX_REDRAWS {
                for c in 0..d {
                    let z: f64 = rng.sample(rand_distr::StandardNormal);
                    next[(0, c)] = mu[(c, k)] + sd * z;
                }
                if off_data == f64::INFINITY {
                    break;
                }
                let ratio = pred.pose_variance_ratio(&next)?[0];
                if ratio <= off_data {
                    best = None;
                    break;
                }
                if best.as_ref().is_none_or(|b| ratio < b.0) {
                    best = Some((ratio, next.clone()));
                }
            }
            if let Some((_, kept)) = best {
                next = kept;
                off[k] += 1;
            }
            for c in 0..d {
                x[(k, c)] = next[(0, c)];
                traj[(t, c)] = next[(0, c)];
            }
        }
    }
    Ok((trajs, off))
}
