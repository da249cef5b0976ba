//! Learning a GPDM on a linear dynamical system, prediction, optimiser and serialisation.

mod common;

use gpdm::hmc::{sample_trajectories, HmcOptions};
use gpdm::optim::{lbfgs, lbfgs_blocks, train, Exit, LbfgsOptions, Schedule, TrainOptions};
use gpdm::predict::Predictor;
use gpdm::{Gpdm, GpdmConfig};
use nalgebra::DMatrix;

#[test]
fn lbfgs_minimises_rosenbrock() {
    let f = |x: &[f64], g: &mut [f64]| {
        let (a, b) = (x[0], x[1]);
        g[0] = -2.0 * (1.0 - a) - 400.0 * a * (b - a * a);
        g[1] = 200.0 * (b - a * a);
        Some((1.0 - a).powi(2) + 100.0 * (b - a * a).powi(2))
    };
    let r = lbfgs(
        f,
        &[-1.2, 1.0],
        &LbfgsOptions {
            value_tol: 0.0,
            ..Default::default()
        },
    );
    assert_eq!(r.exit, Exit::GradientTolerance, "{r:?}");
    assert!(
        (r.x[0] - 1.0).abs() < 1e-5 && (r.x[1] - 1.0).abs() < 1e-5,
        "{:?}",
        r.x
    );
}

#[test]
fn block_scaling_solves_a_badly_scaled_quadratic_sooner() {
    // f = ½ Σ h_i x_i² with curvatures 1..2 on the first block and 1e-6..2e-6 on the second:
    // one scalar γ makes the second block crawl; a γ per block does not.
    let n = 20;
    let h: Vec<f64> = (0..n)
        .map(|i| (1.0 + i as f64 % 10.0 / 9.0) * if i < 10 { 1.0 } else { 1e-6 })
        .collect();
    let f = |x: &[f64], g: &mut [f64]| {
        for i in 0..n {
            g[i] = h[i] * x[i];
        }
        Some(0.5 * (0..n).map(|i| h[i] * x[i] * x[i]).sum::<f64>())
    };
    let x0: Vec<f64> = (0..n).map(|i| if i < 10 { 1.0 } else { 1000.0 }).collect();
    let o = LbfgsOptions {
        memory: 3,
        grad_tol: 1e-8,
        value_tol: 0.0,
        ..Default::default()
    };
    let scalar = lbfgs_blocks(f, &x0, &o, &[0..n]);
    let blocks = lbfgs_blocks(f, &x0, &o, &[0..10, 10..n]);
    assert_eq!(blocks.exit, Exit::GradientTolerance, "{blocks:?}");
    assert!(blocks.x.iter().all(|v| v.abs() < 1e-2), "{:?}", blocks.x);
    assert!(
        blocks.evaluations * 2 < scalar.evaluations,
        "blocks {} vs scalar {} evaluations",
        blocks.evaluations,
        scalar.evaluations
    );
}

#[test]
fn value_window_does_not_stop_on_one_short_step() {
    // Rosenbrock from the standard start has iterations with tiny decrease before the valley
    // floor is reached; a 10-iteration window still reaches the minimum.
    let f = |x: &[f64], g: &mut [f64]| {
        let (a, b) = (x[0], x[1]);
        g[0] = -2.0 * (1.0 - a) - 400.0 * a * (b - a * a);
        g[1] = 200.0 * (b - a * a);
        Some((1.0 - a).powi(2) + 100.0 * (b - a * a).powi(2))
    };
    let o = LbfgsOptions {
        value_tol: 3e-3,
        value_window: 1,
        grad_tol: 1e-12,
        ..Default::default()
    };
    let short = lbfgs(f, &[-1.2, 1.0], &o);
    assert_eq!(short.exit, Exit::ValueTolerance, "{short:?}");
    assert!(
        (short.x[0] - 1.0).abs() > 0.5,
        "window 1 stops early: {:?}",
        short.x
    );
    let o = LbfgsOptions {
        value_window: 10,
        ..o
    };
    let r = lbfgs(f, &[-1.2, 1.0], &o);
    assert_eq!(r.exit, Exit::ValueTolerance, "{r:?}");
    assert!(
        (r.x[0] - 1.0).abs() < 1e-3 && (r.x[1] - 1.0).abs() < 1e-3,
        "{:?}",
        r.x
    );
}

#[test]
fn lbfgs_reports_unevaluable_start() {
    let r = lbfgs(
        |_: &[f64], _: &mut [f64]| None,
        &[0.0],
        &LbfgsOptions::default(),
    );
    assert_eq!(r.exit, Exit::StartFailed);
}

#[test]
fn learned_dynamics_predict_the_next_state_of_a_rotation() {
    let (m, clean, rep) = common::rotation_model();
    eprintln!(
        "objective {} -> {} in {} evaluations, exits {:?}",
        rep.initial_value, rep.final_value, rep.evaluations, rep.exits
    );
    assert!(rep.final_value < rep.initial_value);
    let pred = Predictor::new(&m).unwrap();
    // One-step prediction in pose space: y_{t+1} ≈ μ_Y(μ_X(x_t)), against the clean truth,
    // compared with the persistence baseline y_{t+1} ≈ y_t.
    let (mut err, mut base, mut count) = (0.0, 0.0, 0.0);
    let mut row = 0;
    for c in &clean {
        for t in 0..c.nrows() - 1 {
            let xt: Vec<f64> = m.x.row(row + t).iter().copied().collect();
            let (next, _) = pred.dynamics(&xt);
            let y = pred
                .pose_mean(&DMatrix::from_row_slice(1, 2, &next))
                .unwrap();
            err += (y.row(0) - c.row(t + 1)).norm_squared();
            base += (c.row(t) - c.row(t + 1)).norm_squared();
            count += 1.0;
        }
        row += c.nrows();
    }
    let (err, base) = ((err / count).sqrt(), (base / count).sqrt());
    eprintln!("one-step RMS error {err:.4}, persistence baseline {base:.4}");
    assert!(
        err < 0.1 * base,
        "one-step error {err} vs persistence {base}"
    );

    // Mean prediction (3DV eq. 8) from the first latent point follows the cycle for 2 periods.
    let traj = pred
        .mean_trajectory(&m.x.row(0).iter().copied().collect::<Vec<_>>(), 32)
        .unwrap();
    let poses = pred.pose_mean(&traj).unwrap();
    let scale = clean[0].rows(0, 32).map(|v| v * v).mean().sqrt();
    let rms = (poses - clean[0].rows(0, 32)).map(|v| v * v).mean().sqrt();
    eprintln!("32-frame mean-prediction RMS error {rms:.4} (data RMS {scale:.3})");
    assert!(
        rms < 0.1 * scale,
        "rollout error {rms} vs data scale {scale}"
    );
}

#[test]
fn both_schedules_move_beta_and_lower_the_objective() {
    // Issue 6: with raw parameters a joint optimisation left β at its start. In log
    // coordinates both the joint and the alternating schedules must move β.
    let omega = std::f64::consts::TAU / 16.0;
    let (_, y1) = common::rotation_system(40, omega, 0.0, 0.01, 1);
    let config = GpdmConfig {
        latent_dim: 2,
        ..GpdmConfig::default()
    };
    let m0 = Gpdm::new(&[y1], config).unwrap();
    for schedule in [
        Schedule::Joint,
        Schedule::Alternate {
            rounds: 5,
            iters: 50,
        },
    ] {
        let mut m = m0.clone();
        let r = train(
            &mut m,
            &TrainOptions {
                schedule: schedule.clone(),
                ..Default::default()
            },
        )
        .unwrap();
        eprintln!(
            "{schedule:?}: {} -> {} ({} evals) beta {:?}",
            r.initial_value, r.final_value, r.evaluations, m.beta
        );
        assert!(r.final_value < r.initial_value - 1.0);
        let moved = m
            .beta
            .iter()
            .zip(m0.beta.iter())
            .filter(|(a, b)| (*a / *b).ln().abs() > 0.1)
            .count();
        assert!(
            moved >= 2,
            "{schedule:?} left β near its start: {:?}",
            m.beta
        );
        // The returned value is the objective at the stored parameters.
        let again = m.objective().unwrap().eval(&m.theta(), None).unwrap().value;
        assert!((again - r.final_value).abs() <= 1e-9 * again.abs().max(1.0));
    }
}

#[test]
fn pose_reconstruction_interpolates_training_poses() {
    let (m, _, _) = common::rotation_model();
    let pred = Predictor::new(&m).unwrap();
    let mean = pred.pose_mean(&m.x).unwrap();
    let mut y = m.y.clone();
    for mut r in y.row_iter_mut() {
        r += m.y_mean.transpose();
    }
    let rms = (&mean - &y).map(|v| v * v).mean().sqrt();
    // Noise std is 0.01: the GP mean at training inputs smooths to about that level.
    assert!(rms < 0.03, "reconstruction RMS {rms}");
    let var = pred.pose_variance(&m.x).unwrap();
    let far = pred
        .pose_variance(&DMatrix::from_row_slice(1, 2, &[1e3, 1e3]))
        .unwrap()[0];
    let prior = m.alpha[0] + 1.0 / m.alpha[2];
    assert!(
        (far - prior).abs() < 1e-9 * prior,
        "far variance {far} vs prior {prior}"
    );
    assert!(var.iter().all(|&v| v < 0.1 * prior));
}

#[test]
fn hmc_variations_stay_near_the_cycle_and_differ() {
    let (m, clean, _) = common::rotation_model();
    let pred = Predictor::new(&m).unwrap();
    let template = m.sequence_latent(0).unwrap();
    let opts = HmcOptions {
        n_samples: 10,
        burn_in: 100,
        thin: 2,
        leapfrog_steps: 10,
        seed: 3,
        ..Default::default()
    };
    let (trajs, res) = sample_trajectories(&pred, &template, &opts).unwrap();
    eprintln!(
        "trajectory HMC acceptance {:.2}, step {:.2e}",
        res.accept_rate, res.step_size
    );
    assert_eq!(trajs.len(), 10);
    let scale = clean[0].map(|v| v * v).mean().sqrt();
    for t in &trajs {
        assert_eq!(t.row(0), template.row(0));
        let poses = pred.pose_mean(t).unwrap();
        // Plausible: every pose close to the data's circle in the 2-D latent truth means
        // a bounded distance from the nearest clean training pose.
        for r in poses.row_iter() {
            let nearest = clean
                .iter()
                .flat_map(|c| c.row_iter().map(|q| (q - r).norm()).collect::<Vec<_>>())
                .fold(f64::INFINITY, f64::min);
            assert!(
                nearest < 0.5 * scale * (10f64).sqrt(),
                "pose {nearest} from the data"
            );
        }
    }
    assert!(
        trajs.windows(2).any(|w| (&w[0] - &w[1]).abs().max() > 1e-6),
        "all samples identical"
    );
}

#[test]
fn model_serialises_round_trip_and_validates_input() {
    let (m, _, _) = {
        let (c, y) = common::rotation_system(10, 0.3, 0.0, 0.01, 1);
        (
            Gpdm::new(
                &[y],
                GpdmConfig {
                    latent_dim: 2,
                    ..Default::default()
                },
            )
            .unwrap(),
            c,
            (),
        )
    };
    let s = serde_json::to_string(&m).unwrap();
    let back: Gpdm = serde_json::from_str(&s).unwrap();
    assert_eq!(back, m);
    assert!(Gpdm::new(&[], GpdmConfig::default()).is_err());
    assert!(Gpdm::new(&[DMatrix::zeros(1, 4)], GpdmConfig::default()).is_err());
    assert!(Gpdm::new(
        &[DMatrix::zeros(5, 4), DMatrix::zeros(5, 3)],
        GpdmConfig::default()
    )
    .is_err());
    let mut bad = DMatrix::zeros(5, 4);
    bad[(0, 0)] = f64::NAN;
    assert!(Gpdm::new(&[bad], GpdmConfig::default()).is_err());
}

#[test]
fn pose_basis_decoder_matches_exact_decoder() {
    let (m, _, _) = common::rotation_model();
    let exact = Predictor::new(&m).unwrap();
    let xs = m.x.rows(0, 12).into_owned() * 1.1;
    let want = exact.pose_mean(&xs).unwrap();
    // Full rank: identical up to rounding.
    let (full, r, rms) = Predictor::with_pose_basis(&m, 0.0).unwrap();
    assert!(r <= 10 && rms < 1e-6, "rank {r}, rms {rms}");
    assert!((full.pose_mean(&xs).unwrap() - &want).abs().max() < 1e-9);
    // The data are rank 2 plus 0.01 noise in 10-D: keeping 99.9 % of the energy drops the
    // noise directions; the decoded poses move by at most about the noise level.
    let (low, r, rms) = Predictor::with_pose_basis(&m, 1e-3).unwrap();
    assert!(r < 10, "rank {r}");
    let diff = (low.pose_mean(&xs).unwrap() - &want)
        .map(|v| v * v)
        .mean()
        .sqrt();
    assert!(
        diff < 0.02 && rms < 0.02,
        "decoded difference {diff}, training rms {rms}"
    );
    assert!(Predictor::with_pose_basis(&m, 1.0).is_err());
}
