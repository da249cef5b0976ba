//! Measures the pose-noise floor: trains on noise-free and on noisy synthetic
//! cyclic data with and without the 1e-6 floor on 1/α3, and reports the learned noise
//! variance, cond(K_Y), optimiser exit, and how well the mean prediction (3DV eq. 8) from the
//! first frame tracks the 120-frame training cycle (RMS pose error, 3DV eq. 12 decoding).
//!
//! Usage: noise_floor [D=300] [single]   (`single`: train on the first sequence only)

use clap::Parser;
use studies::synthetic;

use gpdm::kernel::RbfLinear;
use gpdm::optim::{train, LbfgsOptions, TrainOptions};
use gpdm::predict::Predictor;
use gpdm::{Gpdm, GpdmConfig};
use std::time::Instant;

/// Measures the pose-noise floor on noise-free and noisy synthetic cyclic data.
#[derive(Parser)]
struct Cli {
    /// The synthetic capture's dimension D.
    #[arg(default_value_t = 300)]
    d: usize,
    /// `single`: trains on the first sequence only.
    single: Option<String>,
}

fn main() {
    let cli = Cli::parse();
    let d_obs = cli.d;
    let single = cli.single.as_deref() == Some("single");
    let keep = if single { 1 } else { 4 };
    for noise in [0.0, 2e-3] {
        let clean = synthetic::synthetic(d_obs, 0.0);
        let data: Vec<_> = synthetic::synthetic(d_obs, noise)
            .into_iter()
            .take(keep)
            .collect();
        for floor in [None, Some(1e-6)] {
            let config = GpdmConfig {
                pose_noise_floor: floor,
                ..Default::default()
            };
            let mut m = Gpdm::new(&data, config).unwrap();
            let t = Instant::now();
            let opts = TrainOptions {
                lbfgs: LbfgsOptions {
                    max_iter: 1000,
                    max_evals: 3000,
                    ..Default::default()
                },
                ..Default::default()
            };
            let r = train(&mut m, &opts).unwrap();
            let secs = t.elapsed().as_secs_f64();
            let k = RbfLinear::pose(m.alpha).gram(gpdm::linalg::view(&m.x)).k;
            let k = gpdm::linalg::to_na(k.as_ref());
            let ev = nalgebra::SymmetricEigen::new(k).eigenvalues;
            let cond = ev.max() / ev.min();
            let pred = Predictor::new(&m).unwrap();
            let x1: Vec<f64> = m.x.row(0).iter().copied().collect();
            let traj = pred.mean_trajectory(&x1, 120).unwrap();
            let poses = pred.pose_mean(&traj).unwrap();
            let err = |a: usize, b: usize| {
                ((poses.rows(a, b - a) - clean[0].rows(a, b - a))
                    .map(|v| v * v)
                    .mean())
                .sqrt()
            };
            println!(
                "noise {noise:.0e} floor {floor:?}: 1/α3 = {:.2e}, 1/β4 = {:.2e}, cond(K_Y) = {cond:.1e}, exit {:?} after {} evals ({secs:.1} s), f = {:.1}; \
                 mean-prediction RMS frames 0-30 {:.4}, 30-60 {:.4}, 60-120 {:.4} (data RMS {:.3}); notes {:?}",
                1.0 / m.alpha[2], 1.0 / m.beta[3], r.exits.last().unwrap(), r.evaluations, r.final_value,
                err(0, 30), err(30, 60), err(60, 120), clean[0].map(|v| v * v).mean().sqrt(), pred.notes
            );
        }
    }
}
