//! Finite-difference checks of the analytic gradients of 3DV eq. 7 and of the HMC energy.

mod common;

use gpdm::hmc::{Energy, TrajectoryEnergy};
use gpdm::predict::Predictor;
use gpdm::{Gpdm, GpdmConfig};
use nalgebra::DMatrix;

fn small_model(config: GpdmConfig) -> Gpdm {
    let seqs = vec![common::randn(7, 5, 1), common::randn(6, 5, 2)];
    let mut m = Gpdm::new(&seqs, config).unwrap();
    // Move away from the symmetric starting point so that every term is exercised.
    m.x += common::randn(13, m.x.ncols(), 3) * 0.3;
    m.alpha = [1.3, 0.7, 4.0];
    m.beta = [0.8, 1.2, 0.3, 20.0];
    m
}

/// Central differences, step h, compared component-wise with a relative tolerance.
fn check_fd(f: &dyn Fn(&[f64]) -> f64, theta: &[f64], grad: &[f64], h: f64, tol: f64) {
    let mut worst: f64 = 0.0;
    for i in 0..theta.len() {
        let mut tp = theta.to_vec();
        let mut tm = theta.to_vec();
        tp[i] += h;
        tm[i] -= h;
        let fd = (f(&tp) - f(&tm)) / (2.0 * h);
        let err = (fd - grad[i]).abs() / grad[i].abs().max(1.0);
        worst = worst.max(err);
        assert!(
            err < tol,
            "component {i}: analytic {} vs finite difference {fd}",
            grad[i]
        );
    }
    eprintln!(
        "worst relative gradient error {worst:e} over {} components",
        theta.len()
    );
}

fn check_objective(config: GpdmConfig) {
    let m = small_model(config);
    let obj = m.objective().unwrap();
    let theta = m.theta();
    let mut g = vec![0.0; theta.len()];
    let e = obj.eval(&theta, Some(&mut g)).unwrap();
    assert!(e.value.is_finite());
    assert_eq!(e.jitter_y, 0.0);
    assert_eq!(e.jitter_x, 0.0);
    assert!((e.pose + e.dynamics + e.prior - e.value).abs() < 1e-12 * e.value.abs().max(1.0));
    // All parameter blocks carry gradient.
    let nd = m.x.len();
    assert!(g[..nd].iter().any(|v| v.abs() > 1e-3));
    assert!(g[nd..nd + 3].iter().all(|v| v.abs() > 1e-6));
    assert!(g[nd + 3..].iter().all(|v| v.abs() > 1e-6));
    check_fd(
        &|t| obj.eval(t, None).unwrap().value,
        &theta,
        &g,
        1e-5,
        1e-6,
    );
}

#[test]
fn objective_gradient_matches_finite_differences() {
    check_objective(GpdmConfig::default());
}

#[test]
fn objective_gradient_with_active_noise_floors() {
    // Floors comparable to the noise variances, so the floor transform matters.
    check_objective(GpdmConfig {
        pose_noise_floor: Some(0.1),
        dyn_noise_floor: Some(0.02),
        ..GpdmConfig::default()
    });
}

#[test]
fn objective_gradient_without_floor_and_two_dimensional_latent() {
    check_objective(GpdmConfig {
        latent_dim: 2,
        pose_noise_floor: None,
        ..GpdmConfig::default()
    });
}

#[test]
fn objective_gradient_of_the_balanced_gpdm() {
    check_objective(GpdmConfig {
        dynamics_weight: gpdm::DynamicsWeight::Balanced,
        ..GpdmConfig::default()
    });
}

/// The balanced objective is the paper's with the dynamics term (and the first-point priors)
/// weighted by D/d, the pose term and the priors unchanged.
#[test]
fn the_balanced_objective_weights_the_dynamics_term_by_d_over_d() {
    let seqs = vec![common::randn(7, 5, 1), common::randn(6, 5, 2)];
    let paper = gpdm::Gpdm::new(&seqs, GpdmConfig::default()).unwrap();
    let balanced = gpdm::Gpdm::new(&seqs, GpdmConfig { dynamics_weight: gpdm::DynamicsWeight::Balanced, ..GpdmConfig::default() }).unwrap();
    let theta = paper.theta();
    let a = paper.objective().unwrap().eval(&theta, None).unwrap();
    let b = balanced.objective().unwrap().eval(&theta, None).unwrap();
    let lambda = paper.y.ncols() as f64 / paper.config.latent_dim as f64;
    assert!(lambda > 1.0);
    assert!((b.pose - a.pose).abs() <= 1e-12 * a.pose.abs() && (b.prior - a.prior).abs() <= 1e-12 * a.prior.abs().max(1.0));
    assert!((b.dynamics - lambda * a.dynamics).abs() <= 1e-10 * (lambda * a.dynamics).abs(), "{} vs {}", b.dynamics, lambda * a.dynamics);
}

/// Eq. 7 exactly as printed: no log-normal factor on β, latent scale free.
fn as_printed() -> GpdmConfig {
    GpdmConfig {
        beta_log_sd: None,
        fixed_latent_scale: false,
        ..GpdmConfig::default()
    }
}

#[test]
fn objective_gradient_as_printed() {
    check_objective(as_printed());
}

#[test]
fn well_posed_terms_match_their_definitions() {
    // Default model = 3DV eq. 7 as printed evaluated at X rescaled to unit mean square, plus
    // Σ_{k≤3} (ln β_k)² / (2 s²); and invariant to the scale of θ's X block.
    let m = small_model(GpdmConfig::default());
    let s = m.config.beta_log_sd.unwrap();
    let th = m.theta();
    let e = m.objective().unwrap().eval(&th, None).unwrap();
    let mut p = small_model(as_printed());
    let nd = p.x.len();
    p.x *= (nd as f64).sqrt() / p.x.norm();
    let ep = p.objective().unwrap().eval(&p.theta(), None).unwrap();
    let extra: f64 = m.beta[..3].iter().map(|b| b.ln().powi(2)).sum::<f64>() / (2.0 * s * s);
    assert!(extra > 0.05, "the test point must exercise the factor");
    assert!((e.pose - ep.pose).abs() < 1e-10 * ep.pose.abs().max(1.0));
    assert!((e.dynamics - ep.dynamics).abs() < 1e-10 * ep.dynamics.abs().max(1.0));
    assert!((e.prior - (ep.prior + extra)).abs() < 1e-12);
    let mut scaled = th.clone();
    scaled[..nd].iter_mut().for_each(|v| *v *= 3.7);
    let es = m.objective().unwrap().eval(&scaled, None).unwrap();
    assert!((es.value - e.value).abs() < 1e-10 * e.value.abs().max(1.0));
    // The stored model is what the objective saw.
    let mut m2 = m.clone();
    m2.set_theta(&scaled);
    assert!((m2.x.norm_squared() / nd as f64 - 1.0).abs() < 1e-12);
}

#[test]
fn objective_matches_direct_formula() {
    // Independent evaluation of 3DV eq. 7 with nalgebra (explicit determinants and solves).
    let m = small_model(as_printed());
    let e = m.objective().unwrap().eval(&m.theta(), None).unwrap();
    let x = &m.x;
    let n = x.nrows();
    let k = |a: &[f64], b: &[f64], p: [f64; 4], same: bool| {
        let s: f64 = a.iter().zip(b).map(|(u, v)| (u - v) * (u - v)).sum();
        let dot: f64 = a.iter().zip(b).map(|(u, v)| u * v).sum();
        p[0] * (-0.5 * p[1] * s).exp() + p[2] * dot + if same { 1.0 / p[3] } else { 0.0 }
    };
    let row = |i: usize| x.row(i).iter().copied().collect::<Vec<_>>();
    let pa = [m.alpha[0], m.alpha[1], 0.0, m.alpha[2]];
    let ky = DMatrix::from_fn(n, n, |i, j| k(&row(i), &row(j), pa, i == j));
    let yy = &m.y * m.y.transpose();
    let dy = m.y.ncols() as f64;
    let pose = 0.5 * dy * ky.determinant().ln() + 0.5 * ky.clone().lu().solve(&yy).unwrap().trace();
    let ins: Vec<usize> = (0..6).chain(7..12).collect();
    let outs: Vec<usize> = (1..7).chain(8..13).collect();
    let kx = DMatrix::from_fn(11, 11, |i, j| k(&row(ins[i]), &row(ins[j]), m.beta, i == j));
    let xo = DMatrix::from_fn(11, x.ncols(), |i, c| x[(outs[i], c)]);
    let d = x.ncols() as f64;
    let dynamics = 0.5 * d * kx.determinant().ln()
        + 0.5
            * kx.clone()
                .lu()
                .solve(&(&xo * xo.transpose()))
                .unwrap()
                .trace()
        + 0.5
            * (row(0).iter().map(|v| v * v).sum::<f64>()
                + row(7).iter().map(|v| v * v).sum::<f64>());
    let prior: f64 = m.alpha.iter().chain(m.beta.iter()).map(|v| v.ln()).sum();
    assert!(
        (e.pose - pose).abs() < 1e-9 * pose.abs().max(1.0),
        "{} vs {pose}",
        e.pose
    );
    assert!((e.dynamics - dynamics).abs() < 1e-9 * dynamics.abs().max(1.0));
    assert!((e.prior - prior).abs() < 1e-12);
}

#[test]
fn trajectory_energy_gradient_and_value() {
    let m = small_model(GpdmConfig::default());
    let pred = Predictor::new(&m).unwrap();
    let x1: Vec<f64> = m.x.row(0).iter().copied().collect();
    // κ = 1 is the model's density; κ = 0.4 scales every one-step variance.
    for kappa in [1.0, 0.4] {
        let energy = TrajectoryEnergy::new(&pred, &x1, 6)
            .unwrap()
            .with_variance_scale(kappa)
            .unwrap();
        let traj = m.x.rows(0, 6).into_owned() + common::randn(6, 3, 9) * 0.1;
        let q = energy.free_coords(&traj);
        let mut g = vec![0.0; q.len()];
        let e = energy.energy_grad(&q, &mut g).unwrap();
        // Value: sum of -log N(x_{t+1}; μ(x_t), κ σ²(x_t) I) (constants dropped), 3DV eqs. 9-10.
        let full = energy.trajectory(&q);
        let mut direct = 0.0;
        for t in 0..5 {
            let xt: Vec<f64> = full.row(t).iter().copied().collect();
            let (mu, s) = pred.dynamics(&xt);
            let s = kappa * s;
            let e2: f64 = (0..3).map(|c| (full[(t + 1, c)] - mu[c]).powi(2)).sum();
            direct += 0.5 * e2 / s + 1.5 * s.ln();
        }
        assert!(
            (e - direct).abs() < 1e-10 * direct.abs().max(1.0),
            "κ = {kappa}: {e} vs {direct}"
        );
        let scratch = vec![0.0; q.len()];
        check_fd(
            &|t| energy.energy_grad(t, &mut scratch.clone()).unwrap(),
            &q,
            &g,
            1e-6,
            1e-6,
        );
    }
    assert!(TrajectoryEnergy::new(&pred, &x1, 6)
        .unwrap()
        .with_variance_scale(0.0)
        .is_err());
}
