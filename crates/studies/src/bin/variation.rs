//! Variation vs plausibility of HMC samples as a function of the dynamics-noise floor:
//! trains on one noise-free synthetic cycle (120 frames, D = 300), samples 20 trajectories
//! of 120 frames, and reports acceptance, the RMS pose distance of samples to the
//! time-aligned source (variation) and to the nearest training pose (plausibility).
//!
//! Usage: variation

use clap::Parser;
use studies::synthetic;

use gpdm::hmc::{sample_trajectories, HmcOptions};
use gpdm::optim::{train, TrainOptions};
use gpdm::predict::Predictor;
use gpdm::{Gpdm, GpdmConfig};

/// Variation vs plausibility of HMC samples as a function of the dynamics-noise floor.
#[derive(Parser)]
struct Cli {
}

fn main() {
    Cli::parse();
    let data: Vec<_> = synthetic::synthetic(300, 0.0).into_iter().take(1).collect();
    let y = &data[0];
    let rms = |a: nalgebra::DMatrixView<f64>, b: nalgebra::DMatrixView<f64>| {
        (a - b).map(|v| v * v).mean().sqrt()
    };
    for dyn_floor in [None, Some(1e-4), Some(1e-3), Some(1e-2)] {
        let config = GpdmConfig {
            dyn_noise_floor: dyn_floor,
            ..Default::default()
        };
        let mut m = Gpdm::new(&data, config).unwrap();
        let r = train(&mut m, &TrainOptions::default()).unwrap();
        let pred = Predictor::new(&m).unwrap();
        let template = m.sequence_latent(0).unwrap();
        let opts = HmcOptions {
            n_samples: 20,
            burn_in: 200,
            thin: 5,
            leapfrog_steps: 20,
            seed: 1,
            ..Default::default()
        };
        let (trajs, res) = sample_trajectories(&pred, &template, &opts).unwrap();
        let x1: Vec<f64> = template.row(0).iter().copied().collect();
        let mean_pose = pred
            .pose_mean(&pred.mean_trajectory(&x1, 120).unwrap())
            .unwrap();
        let (mut to_src, mut to_near, mut between) = (0.0, 0.0, 0.0);
        let mut prev: Option<nalgebra::DMatrix<f64>> = None;
        for t in &trajs {
            let p = pred.pose_mean(t).unwrap();
            to_src += rms(p.as_view(), y.as_view());
            let near: f64 = p
                .row_iter()
                .map(|q| {
                    y.row_iter()
                        .map(|s| (q - s).norm_squared())
                        .fold(f64::INFINITY, f64::min)
                })
                .sum::<f64>()
                / (p.nrows() * p.ncols()) as f64;
            to_near += near.sqrt();
            if let Some(pp) = &prev {
                between += rms(p.as_view(), pp.as_view());
            }
            prev = Some(p);
        }
        let k = trajs.len() as f64;
        println!(
            "dyn floor {dyn_floor:?}: 1/β4 {:.1e}, f {:.0}; HMC acceptance {:.2}, step {:.1e}; mean-prediction RMS to source {:.4}; \
             samples: RMS to source {:.4}, between consecutive samples {:.4}, to nearest training pose {:.4} (data RMS {:.3})",
            1.0 / m.beta[3], r.final_value, res.accept_rate, res.step_size,
            rms(mean_pose.as_view(), y.as_view()), to_src / k, between / (k - 1.0), to_near / k,
            y.map(|v| v * v).mean().sqrt()
        );
    }
}
