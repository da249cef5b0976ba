//! Hybrid Monte Carlo over whole latent trajectories (paper §6, "Latent sampling").
//!
//! The sampled density is the trajectory likelihood of the learned dynamics, 3DV eqs. 8-10,
//! given the first point: `p(x_2..x_T | x_1) = ∏_t N(x_{t+1}; μ_X(x_t), σ²_X(x_t) I)`, i.e. the
//! energy `E = Σ_t ‖x_{t+1} − μ_X(x_t)‖² / (2σ²_X(x_t)) + d/2 ln σ²_X(x_t)`. Each factor is
//! the GP predictive conditioned on the training dynamics only (Markov form), so `K_X` is
//! factorised once per model and every energy evaluation costs one batched triangular solve.
//!
//! Leapfrog with unit mass, step size adapted during burn-in toward a target acceptance rate
//! (dual averaging, Hoffman & Gelman 2014 alg. 5, then a Robbins-Monro refinement with Polyak
//! averaging; see [`sample`]), then frozen;
//! ±10 % step jitter per iteration; thinning; ChaCha8 RNG seeded by the caller.

use crate::error::{invalid, Result};
use crate::predict::Predictor;
use crate::vexp::exp_fast;
use faer::Mat;
use nalgebra::DMatrix;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

/// A differentiable energy (negative log density up to a constant).
pub trait Energy {
    /// Number of free coordinates.
    fn dim(&self) -> usize;
    /// Energy at `q`, writing `∂E/∂q` into `grad`; `None` when not finite.
    fn energy_grad(&self, q: &[f64], grad: &mut [f64]) -> Option<f64>;
}

/// Where a trajectory chain starts.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ChainStart {
    /// The mean prediction from the first point (3DV eq. 8; the paper's initialisation, §6).
    /// It is the mode-like centre of the density, not a typical draw: the energy of the chain
    /// has to rise to the stationary level during burn-in. Where the mean prediction leaves the
    /// learned data ([`leaves_the_data`]) the chain starts at the given trajectory instead (the
    /// sequence's learned one: §1's "initialized with a latent motion trajectory").
    #[default]
    #[serde(rename = "mean")]
    MeanPrediction,
    /// One exact draw of the sampled density itself (`crate::ancestral`, seeded from the
    /// chain's seed). HMC leaves its target invariant, so a chain started at a draw of it is
    /// stationary from the first iteration; burn-in then only has to adapt the step size.
    Ancestral,
    /// The given trajectory itself (the sequence's learned one: §1's "initialized with a
    /// latent motion trajectory to generate variants of this latter").
    Learned,
}

/// Sampler options.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct HmcOptions {
    /// Samples kept.
    pub n_samples: usize,
    /// Adaptation iterations discarded before sampling.
    pub burn_in: usize,
    /// Keep one iteration in `thin`.
    pub thin: usize,
    /// Leapfrog steps per iteration.
    pub leapfrog_steps: usize,
    /// Starting step size (refined by a doubling/halving search, then adapted).
    pub initial_step: f64,
    /// Target acceptance probability during burn-in.
    pub target_accept: f64,
    /// RNG seed: same seed, same samples.
    pub seed: u64,
    /// Where [`sample_trajectories`] starts its chains (the paper's mean prediction by
    /// default; [`sample`] itself starts at the point it is given).
    #[serde(default)]
    pub start: ChainStart,
}

impl Default for HmcOptions {
    fn default() -> Self {
        HmcOptions {
            n_samples: 100,
            burn_in: 200,
            thin: 2,
            leapfrog_steps: 20,
            initial_step: 0.01,
            target_accept: 0.7,
            seed: 0,
            start: ChainStart::MeanPrediction,
        }
    }
}

/// Output of a chain.
#[derive(Clone, Debug, PartialEq)]
pub struct HmcResult {
    /// Kept samples, in order.
    pub samples: Vec<Vec<f64>>,
    /// Acceptance rate after burn-in (fraction of accepted proposals).
    pub accept_rate: f64,
    /// Acceptance rate during burn-in.
    pub burn_in_accept_rate: f64,
    /// Step size used after burn-in.
    pub step_size: f64,
    /// Energy/gradient evaluations.
    pub evaluations: usize,
    /// The chain started at the given trajectory because the mean prediction left the learned
    /// data ([`leaves_the_data`]).
    pub started_at_template: bool,
}

/// Share of the pose prior's variance ([`Predictor::pose_variance_ratio`]) above which a latent
/// point is off the learned data. On the demo and holdout models a mean prediction reaches at
/// most 0.02 where its poses are sound and 0.88-0.99 where it has run away from the data (a
/// torso or an arm decoded to a crumpled mean pose;
/// docs/studies/17-mean-predictions-off-data.md).
pub const OFF_DATA_VARIANCE: f64 = 0.5;

/// Whether any point of the latent trajectory `x` is off the learned data
/// ([`OFF_DATA_VARIANCE`]).
pub fn leaves_the_data(pred: &Predictor, x: &DMatrix<f64>) -> Result<bool> {
    Ok(pred.pose_variance_ratio(x)?.into_iter().any(|r| r > OFF_DATA_VARIANCE))
}

struct State {
    q: Vec<f64>,
    e: f64,
    g: Vec<f64>,
}

/// One leapfrog trajectory from `s` with momentum `p`; returns the end state and ΔH.
fn leapfrog<E: Energy + ?Sized>(
    energy: &E,
    s: &State,
    p0: &[f64],
    eps: f64,
    steps: usize,
    evals: &mut usize,
) -> Option<(State, f64)> {
    let n = s.q.len();
    let mut q = s.q.clone();
    let mut p = p0.to_vec();
    let mut g = s.g.clone();
    let mut e = s.e;
    for _ in 0..steps {
        for i in 0..n {
            p[i] -= 0.5 * eps * g[i];
            q[i] += eps * p[i];
        }
        *evals += 1;
        e = energy.energy_grad(&q, &mut g)?;
        if !e.is_finite() || g.iter().any(|v| !v.is_finite()) {
            return None;
        }
        for i in 0..n {
            p[i] -= 0.5 * eps * g[i];
        }
    }
    let k0: f64 = 0.5 * p0.iter().map(|v| v * v).sum::<f64>();
    let k1: f64 = 0.5 * p.iter().map(|v| v * v).sum::<f64>();
    let dh = (e + k1) - (s.e + k0);
    Some((State { q, e, g }, dh))
}

fn momentum(rng: &mut ChaCha8Rng, n: usize) -> Vec<f64> {
    (0..n)
        .map(|_| rng.sample(rand_distr::StandardNormal))
        .collect()
}

/// Runs one HMC chain from `q0`.
pub fn sample<E: Energy + ?Sized>(energy: &E, q0: &[f64], opts: &HmcOptions) -> Result<HmcResult> {
    let n = energy.dim();
    if q0.len() != n {
        return invalid(format!(
            "start has {} coordinates, energy has {n}",
            q0.len()
        ));
    }
    if opts.thin == 0 || opts.leapfrog_steps == 0 || !(opts.initial_step > 0.0) {
        return invalid("thin, leapfrog_steps and initial_step must be positive");
    }
    if !(opts.target_accept > 0.0 && opts.target_accept < 1.0) {
        return invalid("target acceptance must lie in (0, 1)");
    }
    let mut rng = ChaCha8Rng::seed_from_u64(opts.seed);
    let mut evals = 1;
    let mut g = vec![0.0; n];
    let Some(e) = energy.energy_grad(q0, &mut g).filter(|e| e.is_finite()) else {
        return invalid("energy is not finite at the start point");
    };
    let mut s = State {
        q: q0.to_vec(),
        e,
        g,
    };

    // Reasonable first step: double or halve until one leapfrog step's acceptance crosses 1/2.
    let mut eps = opts.initial_step;
    {
        let p = momentum(&mut rng, n);
        let acc = |eps: f64, evals: &mut usize| -> f64 {
            leapfrog(energy, &s, &p, eps, 1, evals)
                .map(|(_, dh)| (-dh).exp().min(1.0))
                .unwrap_or(0.0)
        };
        let up = acc(eps, &mut evals) > 0.5;
        for _ in 0..50 {
            let a = acc(eps, &mut evals);
            if up && a <= 0.5 {
                eps *= 0.5;
                break;
            }
            if !up && a > 0.5 {
                break;
            }
            eps = if up { eps * 2.0 } else { eps * 0.5 };
        }
    }

    // Step-size adaptation in two halves of burn-in.
    // 1. Dual averaging (Hoffman & Gelman 2014, alg. 5): finds the scale quickly, but its
    //    iterates spread widely and the acceptance is concave in log ε near the stability
    //    limit, so the averaged step accepts more often than the target (0.82-0.88 measured
    //    for 0.7).
    // 2. Robbins-Monro on log ε with a small decreasing gain, started from the dual-averaged
    //    step, and Polyak averaging over its second half: low spread, acceptance on target.
    let (gamma, t0, kappa) = (0.05, 10.0, 0.75);
    let mu = (10.0 * eps).ln();
    let mut hbar = 0.0;
    let mut log_eps_bar = eps.ln();
    let phase2 = opts.burn_in / 2;
    let (mut log_sum, mut log_n) = (0.0, 0usize);
    let mut burn_acc = 0.0;
    let mut post_acc = 0usize;
    let mut post_n = 0usize;
    let total = opts.burn_in + opts.n_samples * opts.thin;
    let mut samples = Vec::with_capacity(opts.n_samples);
    for it in 0..total {
        let adapting = it < opts.burn_in;
        let base = if adapting { eps } else { log_eps_bar.exp() };
        let step = base * (0.9 + 0.2 * rng.random::<f64>());
        let p = momentum(&mut rng, n);
        let prop = leapfrog(energy, &s, &p, step, opts.leapfrog_steps, &mut evals);
        let a = prop
            .as_ref()
            .map(|(_, dh)| {
                if dh.is_nan() {
                    0.0
                } else {
                    (-dh).exp().min(1.0)
                }
            })
            .unwrap_or(0.0);
        let u: f64 = rng.random();
        let accepted = u < a;
        if accepted {
            s = prop.expect("accepted proposal exists").0;
        }
        if adapting {
            burn_acc += a;
            if it < phase2 {
                let m = (it + 1) as f64;
                hbar = (1.0 - 1.0 / (m + t0)) * hbar + (opts.target_accept - a) / (m + t0);
                eps = (mu - m.sqrt() / gamma * hbar).exp();
                let w = m.powf(-kappa);
                log_eps_bar = w * eps.ln() + (1.0 - w) * log_eps_bar;
                if it + 1 == phase2 {
                    eps = log_eps_bar.exp();
                }
            } else {
                let k = (it - phase2 + 1) as f64;
                eps *= (0.5 * (a - opts.target_accept) / (k + 10.0).powf(0.6)).exp();
                if 2 * (it - phase2) >= opts.burn_in - phase2 {
                    log_sum += eps.ln();
                    log_n += 1;
                }
                log_eps_bar = if log_n > 0 {
                    log_sum / log_n as f64
                } else {
                    eps.ln()
                };
            }
        } else {
            post_n += 1;
            post_acc += accepted as usize;
            if (it - opts.burn_in + 1) % opts.thin == 0 {
                samples.push(s.q.clone());
            }
        }
    }
    if opts.burn_in == 0 {
        log_eps_bar = eps.ln();
    }
    Ok(HmcResult {
        samples,
        accept_rate: post_acc as f64 / post_n.max(1) as f64,
        burn_in_accept_rate: burn_acc / opts.burn_in.max(1) as f64,
        step_size: log_eps_bar.exp(),
        evaluations: evals,
        started_at_template: false,
    })
}

/// Energy of a latent trajectory with its first point fixed (module doc); the free
/// coordinates are rows 2..T, row-major.
pub struct TrajectoryEnergy<'a> {
    pred: &'a Predictor,
    x1: Vec<f64>,
    len: usize,
    /// X_in by coordinate: `xin[c][i]` (d arrays of length M), so that the loops over the M
    /// training transitions run on contiguous arrays and vectorise.
    xin: Vec<Vec<f64>>,
    /// K_X⁻¹ X_out by coordinate (d × M).
    a: Vec<Vec<f64>>,
    /// κ: every one-step variance is κ σ²_X(x_t) (1: the model's; see
    /// [`TrajectoryEnergy::with_variance_scale`]).
    variance_scale: f64,
}

impl<'a> TrajectoryEnergy<'a> {
    /// Trajectories of `len` ≥ 2 frames starting at `x1`.
    pub fn new(pred: &'a Predictor, x1: &[f64], len: usize) -> Result<Self> {
        if x1.len() != pred.latent_dim() || len < 2 {
            return invalid("trajectory needs a start point of latent dimension and ≥ 2 frames");
        }
        let by_coord = |mat: faer::MatRef<'_, f64>| -> Vec<Vec<f64>> {
            (0..mat.ncols())
                .map(|c| (0..mat.nrows()).map(|i| mat[(i, c)]).collect())
                .collect()
        };
        Ok(TrajectoryEnergy {
            pred,
            x1: x1.to_vec(),
            len,
            xin: by_coord(pred.dynamics_inputs()),
            a: by_coord(pred.dynamics_weights()),
            variance_scale: 1.0,
        })
    }

    /// The same density with every one-step variance scaled by `kappa > 0` (κ < 1: trajectories
    /// that keep closer to the learned dynamics, with less frame-to-frame jitter; κ = 1: the model).
    pub fn with_variance_scale(mut self, kappa: f64) -> Result<Self> {
        if !(kappa > 0.0 && kappa.is_finite()) {
            return invalid(format!("variance scale {kappa} must be positive"));
        }
        self.variance_scale = kappa;
        Ok(self)
    }

    /// Free coordinates of a full trajectory (T × d).
    pub fn free_coords(&self, traj: &DMatrix<f64>) -> Vec<f64> {
        let d = self.x1.len();
        (1..traj.nrows())
            .flat_map(|t| (0..d).map(move |c| traj[(t, c)]))
            .collect()
    }

    /// Full trajectory (T × d) from free coordinates.
    pub fn trajectory(&self, q: &[f64]) -> DMatrix<f64> {
        let d = self.x1.len();
        DMatrix::from_fn(self.len, d, |t, c| {
            if t == 0 {
                self.x1[c]
            } else {
                q[(t - 1) * d + c]
            }
        })
    }
}

impl Energy for TrajectoryEnergy<'_> {
    fn dim(&self) -> usize {
        (self.len - 1) * self.x1.len()
    }

    /// Kernel columns `k_X(x_t, X_in)` for the T−1 inputs, then one batched pair of
    /// triangular solves (`L⁻¹ K*` for the variances, `K_X⁻¹ K*` for their gradients); the
    /// loops over the M training transitions run on per-coordinate arrays (see
    /// [`TrajectoryEnergy`]) and vectorise. Compiled a second time for AVX2 and picked at run
    /// time (no FMA contraction: both copies give the same bits).
    fn energy_grad(&self, q: &[f64], grad: &mut [f64]) -> Option<f64> {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the CPU supports AVX2 (checked just above).
            return unsafe { self.energy_grad_avx2(q, grad) };
        }
        self.energy_grad_impl(q, grad)
    }
}

/// Steps whose sums over the M training transitions are accumulated side by side: each step
/// keeps its own accumulator, added in the same order as one step alone (same bits), and the
/// independent chains of additions overlap instead of waiting on one another.
const STEP_BATCH: usize = 4;

impl TrajectoryEnergy<'_> {
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn energy_grad_avx2(&self, q: &[f64], grad: &mut [f64]) -> Option<f64> {
        self.energy_grad_impl(q, grad)
    }

    #[inline(always)]
    fn energy_grad_impl(&self, q: &[f64], grad: &mut [f64]) -> Option<f64> {
        let d = self.x1.len();
        let steps = self.len - 1;
        let k = self.pred.dynamics_kernel();
        let m = self.xin.first().map_or(0, |v| v.len());
        // Inputs x_1..x_{T-1}, row-major (x_1 fixed, then the free coordinates).
        let mut p = Vec::with_capacity(steps * d);
        p.extend_from_slice(&self.x1);
        p.extend_from_slice(&q[..(steps - 1) * d]);
        // RBF part and full k_X(x_t, X_in), M × steps, column-major (one column per step).
        // var·exp(a) is computed as exp(a + ln var): a collapsed RBF variance (β1 ~ 1e-320 on
        // the demo arms) otherwise makes every product subnormal.
        let ln_var = if k.var > 0.0 {
            k.var.ln()
        } else {
            f64::NEG_INFINITY
        };
        let half_gamma = -0.5 * k.gamma;
        let mut rbf = vec![0.0; m * steps];
        let mut kst = Mat::<f64>::zeros(m, steps);
        let mut dist = vec![0.0; m];
        let mut dot = vec![0.0; m];
        for t in 0..steps {
            let xt = &p[t * d..(t + 1) * d];
            dist.fill(0.0);
            dot.fill(0.0);
            for c in 0..d {
                let xc = xt[c];
                for ((s, dp), &xi) in dist.iter_mut().zip(dot.iter_mut()).zip(&self.xin[c]) {
                    let diff = xc - xi;
                    *s += diff * diff;
                    *dp += xc * xi;
                }
            }
            let rcol = &mut rbf[t * m..(t + 1) * m];
            let kcol = kst
                .col_mut(t)
                .try_as_col_major_mut()
                .expect("contiguous")
                .as_slice_mut();
            for (((r, kv), &s), &dp) in rcol.iter_mut().zip(kcol.iter_mut()).zip(&dist).zip(&dot) {
                *r = exp_fast(half_gamma * s + ln_var);
                *kv = *r + k.lin * dp;
            }
        }
        // Mean (3DV eq. 9): μ_t = (K_X⁻¹ X_out)ᵀ k_t, each sum over i in order from -0.0 (as
        // `Iterator::sum`).
        let mut mu = vec![0.0; steps * d];
        let col = |t: usize| {
            kst.col(t)
                .try_as_col_major()
                .expect("contiguous")
                .as_slice()
        };
        for t0 in (0..steps).step_by(STEP_BATCH) {
            let nb = STEP_BATCH.min(steps - t0);
            let cols: [&[f64]; STEP_BATCH] = std::array::from_fn(|j| col(t0 + j.min(nb - 1)));
            for c in 0..d {
                let a = &self.a[c];
                let mut acc = [-0.0f64; STEP_BATCH];
                for i in 0..m {
                    for j in 0..STEP_BATCH {
                        acc[j] += cols[j][i] * a[i];
                    }
                }
                for j in 0..nb {
                    mu[(t0 + j) * d + c] = acc[j];
                }
            }
        }
        // U = L⁻¹ K* gives k*ᵀ K_X⁻¹ k* (3DV eq. 10); V = L⁻ᵀ U = K_X⁻¹ K* its gradient.
        let chol = self.pred.dynamics_cholesky();
        let mut v = kst;
        chol.half_solve_in_place(v.as_mut());
        let kvk: Vec<f64> = (0..steps).map(|t| v.col(t).squared_norm_l2()).collect();
        chol.half_solve_t_in_place(v.as_mut());

        // Energy and ∂/∂x_{t+1} of every step, in step order.
        grad.iter_mut().for_each(|g| *g = 0.0);
        let mut energy = 0.0;
        let mut err = vec![0.0; steps * d];
        let mut var = vec![0.0; steps];
        let mut dvar = vec![0.0; steps];
        for t in 0..steps {
            let xt = &p[t * d..(t + 1) * d];
            let s = self.variance_scale * (k.self_cov(xt) - kvk[t]);
            if !(s > 0.0) {
                return None;
            }
            let next = &q[t * d..(t + 1) * d];
            let e = &mut err[t * d..(t + 1) * d];
            for c in 0..d {
                e[c] = next[c] - mu[t * d + c];
            }
            let e2: f64 = e.iter().map(|v| v * v).sum();
            energy += 0.5 * e2 / s + 0.5 * d as f64 * s.ln();
            for c in 0..d {
                grad[t * d + c] += e[c] / s;
            }
            var[t] = s;
            // ∂E/∂s times ∂s/∂s_raw = κ (s = κ s_raw; the terms below differentiate s_raw).
            dvar[t] = (-0.5 * e2 / (s * s) + 0.5 * d as f64 / s) * self.variance_scale;
        }
        // ∂/∂x_t through μ_t and s_t (t ≥ 1: x_1 is fixed): Σ_i w_i ∂k_i/∂x_t with
        // w_i = −(A e)_i / s − 2 c_s (K_X⁻¹ k_t)_i and ∂k_i/∂x_t = −γ r_i (x_t − x_i) + lin x_i.
        // Batches of steps: w and w_i r_i interleaved by step (`w[i·B + j]` for step t0 + j).
        let mut w = vec![0.0; m * STEP_BATCH];
        let mut wr = vec![0.0; m * STEP_BATCH];
        for t0 in (1..steps).step_by(STEP_BATCH) {
            let nb = STEP_BATCH.min(steps - t0);
            for j in 0..STEP_BATCH {
                // Lanes past the last step repeat it (computed, not used).
                let t = t0 + j.min(nb - 1);
                let (s, cs) = (var[t], dvar[t]);
                let vcol = v.col(t).try_as_col_major().expect("contiguous").as_slice();
                let rcol = &rbf[t * m..(t + 1) * m];
                for (i, &vi) in vcol.iter().enumerate() {
                    w[i * STEP_BATCH + j] = -2.0 * cs * vi;
                }
                for c in 0..d {
                    let f = -err[t * d + c] / s;
                    for (i, &ai) in self.a[c].iter().enumerate() {
                        w[i * STEP_BATCH + j] += f * ai;
                    }
                }
                for (i, &ri) in rcol.iter().enumerate() {
                    wr[i * STEP_BATCH + j] = -k.gamma * w[i * STEP_BATCH + j] * ri;
                }
            }
            let mut sum_wr = [0.0f64; STEP_BATCH];
            for i in 0..m {
                for j in 0..STEP_BATCH {
                    sum_wr[j] += wr[i * STEP_BATCH + j];
                }
            }
            for c in 0..d {
                let xin = &self.xin[c];
                let (mut wr_x, mut w_x) = ([0.0f64; STEP_BATCH], [0.0f64; STEP_BATCH]);
                for (i, &xi) in xin.iter().enumerate() {
                    for j in 0..STEP_BATCH {
                        wr_x[j] += wr[i * STEP_BATCH + j] * xi;
                        w_x[j] += w[i * STEP_BATCH + j] * xi;
                    }
                }
                for j in 0..nb {
                    let t = t0 + j;
                    let xt = p[t * d + c];
                    grad[(t - 1) * d + c] += sum_wr[j] * xt - wr_x[j]
                        + k.lin * w_x[j]
                        + 2.0 * dvar[t] * k.lin * xt;
                }
            }
        }
        Some(energy)
    }
}

/// Variations of a latent trajectory: an HMC chain over `template`'s length with its first row
/// fixed, started at `opts.start` (the mean prediction, 3DV eq. 8, or an exact draw).
/// Returns the sampled trajectories (each T × d) and the chain statistics.
pub fn sample_trajectories(
    pred: &Predictor,
    template: &DMatrix<f64>,
    opts: &HmcOptions,
) -> Result<(Vec<DMatrix<f64>>, HmcResult)> {
    sample_trajectories_scaled(pred, template, opts, 1.0)
}

/// [`sample_trajectories`] with every one-step variance scaled by `variance_scale`
/// ([`TrajectoryEnergy::with_variance_scale`]).
pub fn sample_trajectories_scaled(
    pred: &Predictor,
    template: &DMatrix<f64>,
    opts: &HmcOptions,
    variance_scale: f64,
) -> Result<(Vec<DMatrix<f64>>, HmcResult)> {
    let x1: Vec<f64> = template.row(0).iter().copied().collect();
    let mut started_at_template = false;
    let start = match opts.start {
        ChainStart::MeanPrediction => {
            let mean = pred.mean_trajectory(&x1, template.nrows())?;
            started_at_template = leaves_the_data(pred, &mean)?;
            if started_at_template {
                template.clone()
            } else {
                mean
            }
        }
        ChainStart::Learned => template.clone(),
        ChainStart::Ancestral => crate::ancestral::sample_trajectories_ancestral(
            pred,
            &x1,
            template.nrows(),
            1,
            opts.seed ^ START_SEED,
            variance_scale,
        )?
        .remove(0),
    };
    let energy =
        TrajectoryEnergy::new(pred, &x1, template.nrows())?.with_variance_scale(variance_scale)?;
    let res = HmcResult { started_at_template, ..sample(&energy, &energy.free_coords(&start), opts)? };
    let trajs = res.samples.iter().map(|q| energy.trajectory(q)).collect();
    Ok((trajs, res))
}

/// Mixed into the chain's seed to draw an [`ChainStart::Ancestral`] start (a stream apart
/// from the momenta's).
const START_SEED: u64 = 0x5747_A47;

/// [`sample_trajectories`] with `chains` independent chains run in parallel (rayon), chain
/// `c` seeded with `opts.seed + c` and contributing `ceil(n_samples / chains)` samples, each
/// with its own burn-in. Output order is by chain, so the result is the same for any number
/// of threads. Returns the trajectories and the per-chain statistics.
pub fn sample_trajectories_parallel(
    pred: &Predictor,
    template: &DMatrix<f64>,
    opts: &HmcOptions,
    chains: usize,
) -> Result<(Vec<DMatrix<f64>>, Vec<HmcResult>)> {
    use rayon::prelude::*;
    if chains == 0 {
        return invalid("at least one chain is needed");
    }
    let per = opts.n_samples.div_ceil(chains);
    let runs: Vec<Result<(Vec<DMatrix<f64>>, HmcResult)>> = (0..chains)
        .into_par_iter()
        .map(|c| {
            let o = HmcOptions {
                n_samples: per,
                seed: opts.seed.wrapping_add(c as u64),
                ..opts.clone()
            };
            sample_trajectories(pred, template, &o)
        })
        .collect();
    let mut trajs = Vec::with_capacity(opts.n_samples);
    let mut stats = Vec::with_capacity(chains);
    for r in runs {
        let (t, s) = r?;
        trajs.extend(t);
        stats.push(s);
    }
    trajs.truncate(opts.n_samples);
    Ok((trajs, stats))
}
