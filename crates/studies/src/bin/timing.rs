//! Wall-clock timings of the GPDM speed goals (docs/PERFORMANCE.md) without criterion (which
//! `cargo bench -p gpdm` runs): objective+gradient at N = 446, D = 15000, and HMC for 100 samples of a
//! 100-frame trajectory, plus decoding them to poses (3DV eq. 12).
//!
//! Usage: timing [D=15000]

use clap::Parser;
use studies::synthetic;

use gpdm::hmc::{sample_trajectories, HmcOptions};
use gpdm::optim::{train, LbfgsOptions, TrainOptions};
use gpdm::predict::Predictor;
use gpdm::{Gpdm, GpdmConfig};
use std::time::Instant;

/// Wall-clock timings of the GPDM speed goals without criterion.
#[derive(Parser)]
struct Cli {
    /// The synthetic capture's dimension D.
    #[arg(default_value_t = 15000)]
    d: usize,
}

fn main() {
    let d_obs = Cli::parse().d;
    let m = Gpdm::new(&synthetic::synthetic(d_obs, 1e-3), GpdmConfig::default()).unwrap();
    let obj = m.objective().unwrap();
    let th = m.theta();
    let mut g = vec![0.0; th.len()];
    for threads in [1, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let t = Instant::now();
        let reps = 20;
        pool.install(|| {
            for _ in 0..reps {
                obj.eval(&th, Some(&mut g)).unwrap();
            }
        });
        println!(
            "objective+gradient N=446 D={d_obs}: {:.1} ms ({threads} thread(s))",
            t.elapsed().as_secs_f64() * 1e3 / reps as f64
        );
    }
    let mut m = m;
    let opts = TrainOptions {
        lbfgs: LbfgsOptions {
            max_iter: 200,
            ..Default::default()
        },
        ..Default::default()
    };
    train(&mut m, &opts).unwrap();
    let t = Instant::now();
    let pred = Predictor::new(&m).unwrap();
    println!(
        "predictor (factorisations, K_Y⁻¹Y): {:.1} ms",
        t.elapsed().as_secs_f64() * 1e3
    );
    let template = m.sequence_latent(0).unwrap().rows(0, 100).into_owned();
    let hopts = HmcOptions {
        n_samples: 100,
        burn_in: 100,
        thin: 1,
        leapfrog_steps: 10,
        ..Default::default()
    };
    let t = Instant::now();
    let (trajs, res) = sample_trajectories(&pred, &template, &hopts).unwrap();
    let secs = t.elapsed().as_secs_f64();
    println!(
        "HMC 100 samples x 100 frames (burn-in 100, 10 leapfrog): {secs:.2} s, {} energy evals ({:.2} ms each), acceptance {:.2}, step {:.2e}, 1/beta4 {:.2e}",
        res.evaluations, secs * 1e3 / res.evaluations as f64, res.accept_rate, res.step_size, 1.0 / m.beta[3]
    );
    for chains in [2usize] {
        let t = Instant::now();
        let (_, stats) =
            gpdm::hmc::sample_trajectories_parallel(&pred, &template, &hopts, chains).unwrap();
        println!(
            "HMC same work in {chains} parallel chains (each with its own burn-in): {:.2} s, acceptance {:?}",
            t.elapsed().as_secs_f64(),
            stats.iter().map(|s| (s.accept_rate * 100.0).round() / 100.0).collect::<Vec<_>>()
        );
    }
    let t = Instant::now();
    let mut frames = 0;
    for tr in &trajs {
        frames += pred.pose_mean(tr).unwrap().nrows();
    }
    println!(
        "decoding {frames} frames to D={d_obs} poses: {:.2} s",
        t.elapsed().as_secs_f64()
    );
    let t = Instant::now();
    let (fast, r, rms) = Predictor::with_pose_basis(&m, 1e-8).unwrap();
    let prep = t.elapsed().as_secs_f64();
    let t = Instant::now();
    for tr in &trajs {
        std::hint::black_box(fast.pose_mean(tr).unwrap());
    }
    println!(
        "decoding {frames} frames through a rank-{r} pose basis (rel. energy tol 1e-8, training RMS error {rms:.1e}): {:.2} s (+{prep:.2} s setup)",
        t.elapsed().as_secs_f64()
    );
    let a = fast.pose_mean(&trajs[0]).unwrap();
    let b = pred.pose_mean(&trajs[0]).unwrap();
    println!(
        "  max |basis − exact| on one trajectory: {:.1e}",
        (a - b).abs().max()
    );
    let spread = trajs
        .iter()
        .map(|tr| (tr - &template).norm() / template.norm())
        .sum::<f64>()
        / trajs.len() as f64;
    println!("mean relative latent distance of samples from the training trajectory: {spread:.3}");
}
