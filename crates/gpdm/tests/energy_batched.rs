//! The HMC trajectory energy (`TrajectoryEnergy::energy_grad`, whose sums over the training
//! transitions run several steps side by side) against the step-by-step computation: the same
//! bits, for every trajectory length around the batch size and for scaled variances.

mod common;

use faer::Mat;
use gpdm::hmc::{Energy, TrajectoryEnergy};
use gpdm::predict::Predictor;
use gpdm::vexp::exp_fast;

/// Energy and gradient computed one step at a time, every sum over i in index order.
fn step_by_step(pred: &Predictor, x1: &[f64], kappa: f64, q: &[f64]) -> (f64, Vec<f64>) {
    let d = x1.len();
    let steps = q.len() / d;
    let k = pred.dynamics_kernel();
    let xin_m = pred.dynamics_inputs();
    let a_m = pred.dynamics_weights();
    let m = xin_m.nrows();
    let xin: Vec<Vec<f64>> = (0..d).map(|c| (0..m).map(|i| xin_m[(i, c)]).collect()).collect();
    let a: Vec<Vec<f64>> = (0..d).map(|c| (0..m).map(|i| a_m[(i, c)]).collect()).collect();
    let mut p = x1.to_vec();
    p.extend_from_slice(&q[..(steps - 1) * d]);
    let ln_var = k.var.ln();
    let mut rbf = vec![0.0; m * steps];
    let mut kst = Mat::<f64>::zeros(m, steps);
    let mut mu = vec![0.0; steps * d];
    for t in 0..steps {
        let xt = &p[t * d..(t + 1) * d];
        for i in 0..m {
            let (mut s, mut dp) = (0.0, 0.0);
            for c in 0..d {
                let diff = xt[c] - xin[c][i];
                s += diff * diff;
                dp += xt[c] * xin[c][i];
            }
            rbf[t * m + i] = exp_fast(-0.5 * k.gamma * s + ln_var);
            kst[(i, t)] = rbf[t * m + i] + k.lin * dp;
        }
        for c in 0..d {
            mu[t * d + c] = (0..m).map(|i| kst[(i, t)] * a[c][i]).sum();
        }
    }
    let chol = pred.dynamics_cholesky();
    let mut v = kst;
    chol.half_solve_in_place(v.as_mut());
    let kvk: Vec<f64> = (0..steps).map(|t| v.col(t).squared_norm_l2()).collect();
    chol.half_solve_t_in_place(v.as_mut());
    let mut grad = vec![0.0; q.len()];
    let mut energy = 0.0;
    for t in 0..steps {
        let xt = &p[t * d..(t + 1) * d];
        let s = kappa * (k.self_cov(xt) - kvk[t]);
        let e: Vec<f64> = (0..d).map(|c| q[t * d + c] - mu[t * d + c]).collect();
        let e2: f64 = e.iter().map(|v| v * v).sum();
        energy += 0.5 * e2 / s + 0.5 * d as f64 * s.ln();
        for c in 0..d {
            grad[t * d + c] += e[c] / s;
        }
        if t == 0 {
            continue;
        }
        let cs = (-0.5 * e2 / (s * s) + 0.5 * d as f64 / s) * kappa;
        let mut w: Vec<f64> = (0..m).map(|i| -2.0 * cs * v[(i, t)]).collect();
        for c in 0..d {
            let f = -e[c] / s;
            for i in 0..m {
                w[i] += f * a[c][i];
            }
        }
        let mut sum_wr = 0.0;
        let mut wr = vec![0.0; m];
        for i in 0..m {
            wr[i] = -k.gamma * w[i] * rbf[t * m + i];
            sum_wr += wr[i];
        }
        for c in 0..d {
            let (mut wr_x, mut w_x) = (0.0, 0.0);
            for i in 0..m {
                wr_x += wr[i] * xin[c][i];
                w_x += w[i] * xin[c][i];
            }
            grad[(t - 1) * d + c] +=
                sum_wr * xt[c] - wr_x + k.lin * w_x + 2.0 * cs * k.lin * xt[c];
        }
    }
    (energy, grad)
}

#[test]
fn batched_energy_has_the_bits_of_the_step_by_step_sum() {
    let (model, _, _) = common::rotation_model();
    let pred = Predictor::new(&model).unwrap();
    let x = model.sequence_latent(0).unwrap();
    let x1: Vec<f64> = x.row(3).iter().copied().collect();
    for len in [2, 3, 4, 5, 6, 9, 13, 40] {
        for kappa in [1.0, 0.3] {
            let energy = TrajectoryEnergy::new(&pred, &x1, len)
                .unwrap()
                .with_variance_scale(kappa)
                .unwrap();
            // The mean trajectory moved off itself, so that every term is non-trivial.
            let mean = pred.mean_trajectory(&x1, len).unwrap();
            let q: Vec<f64> = energy
                .free_coords(&mean)
                .iter()
                .enumerate()
                .map(|(i, v)| v + 0.05 * ((i as f64) * 0.7).sin())
                .collect();
            let mut g = vec![f64::NAN; q.len()];
            let e = energy.energy_grad(&q, &mut g).unwrap();
            let (e_ref, g_ref) = step_by_step(&pred, &x1, kappa, &q);
            assert_eq!(e.to_bits(), e_ref.to_bits(), "T = {len}, κ = {kappa}: {e} vs {e_ref}");
            for (i, (a, b)) in g.iter().zip(&g_ref).enumerate() {
                assert_eq!(a.to_bits(), b.to_bits(), "T = {len}, κ = {kappa}, ∂{i}: {a} vs {b}");
            }
            assert!(g.iter().any(|v| v.abs() > 1e-6));
        }
    }
}
