//! The GPDM speed goal (docs/PERFORMANCE.md): 100 variations of a 100-frame motion, decoded to poses, within 1 s on
//! 2 cores. Trains once on the synthetic 446-frame problem (D = 15000, 200 L-BFGS iterations),
//! then for each HMC setting times the sampler (`sample_trajectories_parallel`, 2 chains on a
//! 2-thread pool) and, for pose dimensions D ∈ {3000, 6000, 15000} (a body part's share; the
//! model's poses cut to their first D columns), decoding all 10,000 frames with
//! `Predictor::pose_means`, exactly and through a pose basis (`with_pose_basis`).
//!
//! Then the budget of docs/PERFORMANCE.md end to end at its reference size (one whole-body model, N = 446,
//! D = 15000): 100 ancestral draws of 100 frames (`gpdm::ancestral`, exact for the HMC's
//! density) and their 10,000 frames decoded by one kernel-basis GEMM per trajectory
//! (`Predictor::with_kernel_basis`, bound 1e-4 = 0.1 mm in metres), on the 2-thread pool.
//!
//! Usage: variations_budget [rel_tol=1e-6]
//! e.g.: OPENBLAS_NUM_THREADS=1 target/release/variations_budget

use clap::Parser;
use studies::synthetic;

use gpdm::ancestral::sample_trajectories_ancestral;
use gpdm::hmc::{sample_trajectories_parallel, HmcOptions};
use gpdm::optim::{train, LbfgsOptions, TrainOptions};
use gpdm::predict::Predictor;
use gpdm::{Gpdm, GpdmConfig};
use rayon::prelude::*;
use std::time::Instant;

/// 100 variations of a 100-frame motion, sampled and decoded to poses, on the synthetic capture.
#[derive(Parser)]
struct Cli {
    /// The pose basis's relative tolerance (`Predictor::with_pose_basis`).
    #[arg(default_value_t = 1e-6)]
    rel_tol: f64,
}

fn main() {
    let rel_tol = Cli::parse().rel_tol;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap();
    let mut m = Gpdm::new(&synthetic::synthetic(15000, 1e-3), GpdmConfig::default()).unwrap();
    let opts = TrainOptions {
        lbfgs: LbfgsOptions {
            max_iter: 200,
            ..Default::default()
        },
        ..Default::default()
    };
    train(&mut m, &opts).unwrap();
    let pred = Predictor::new(&m).unwrap();
    let template = m.sequence_latent(0).unwrap().rows(0, 100).into_owned();
    println!("1/beta4 = {:.2e}", 1.0 / m.beta[3]);
    let mut trajs = vec![];
    for (burn_in, leapfrog) in [(100, 10), (50, 5), (40, 4), (30, 3)] {
        let hopts = HmcOptions {
            n_samples: 100,
            burn_in,
            thin: 1,
            leapfrog_steps: leapfrog,
            seed: 7,
            ..Default::default()
        };
        let t = Instant::now();
        let (tr, stats) = pool
            .install(|| sample_trajectories_parallel(&pred, &template, &hopts, 2))
            .unwrap();
        let secs = t.elapsed().as_secs_f64();
        let evals: usize = stats.iter().map(|s| s.evaluations).sum();
        // Diversity: mean relative latent distance to the template and between consecutive
        // samples of a chain (a frozen chain gives 0).
        let rel = |a: &nalgebra::DMatrix<f64>, b: &nalgebra::DMatrix<f64>| {
            (a - b).norm() / template.norm()
        };
        let to_src = tr.iter().map(|x| rel(x, &template)).sum::<f64>() / tr.len() as f64;
        let consec = tr.windows(2).map(|w| rel(&w[0], &w[1])).sum::<f64>() / (tr.len() - 1) as f64;
        println!(
            "HMC burn-in {burn_in}, {leapfrog} leapfrog, 2 chains x 50 samples: {secs:.3} s ({evals} energy evals), acceptance {:?}, latent distance to source {to_src:.3}, between consecutive samples {consec:.3}",
            stats.iter().map(|s| (s.accept_rate * 100.0).round() / 100.0).collect::<Vec<_>>()
        );
        trajs = tr;
    }
    for d_part in [3000usize, 6000, 15000] {
        let mut mp = m.clone();
        mp.y = m.y.columns(0, d_part).into_owned();
        mp.y_mean = m.y_mean.rows(0, d_part).into_owned();
        let t = Instant::now();
        let exact = pool.install(|| Predictor::new(&mp)).unwrap();
        let setup = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let poses = pool.install(|| exact.pose_means(&trajs)).unwrap();
        let secs = t.elapsed().as_secs_f64();
        let frames: usize = poses.iter().map(|p| p.nrows()).sum();
        drop(poses);
        let t = Instant::now();
        let (fast, r, rms) = pool
            .install(|| Predictor::with_pose_basis(&mp, rel_tol))
            .unwrap();
        let setup_b = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let poses_b = pool.install(|| fast.pose_means(&trajs)).unwrap();
        let secs_b = t.elapsed().as_secs_f64();
        let check = exact.pose_mean(&trajs[0]).unwrap();
        let err = (&poses_b[0] - check).abs().max();
        println!(
            "decode {frames} frames, D = {d_part}: exact {secs:.3} s ({:.0} frames/s, setup {setup:.2} s); rank-{r} basis (tol {rel_tol:e}, training RMS {rms:.1e}, max dev from exact {err:.1e}) {secs_b:.3} s ({:.0} frames/s, setup {setup_b:.2} s)",
            frames as f64 / secs,
            frames as f64 / secs_b
        );
    }
    // The budget at its reference size: sampling + decoding, 2 threads. Two ways to
    // hold the result: streamed (each thread decodes one variation at a time into a reused
    // 100 x D buffer, as a writer or renderer consumes it) and all 10,000 frames in one fresh
    // buffer (1.2 GB at D = 15000, whose first-touch page faults are counted).
    let x1: Vec<f64> = template.row(0).iter().copied().collect();
    let dim = m.y.ncols();
    for (rep, tol) in [1e-4, 1e-6, 1e-8].into_iter().enumerate() {
        let (kb, r, bound) = pool
            .install(|| Predictor::with_kernel_basis(&m, tol))
            .unwrap();
        let t = Instant::now();
        let trajs = sample_trajectories_ancestral(&pred, &x1, 100, 100, rep as u64, 1.0).unwrap();
        let sampling = t.elapsed().as_secs_f64();
        // Streamed: the consumer here checks one value per variation.
        let t = Instant::now();
        let first: Vec<f64> = pool.install(|| {
            trajs
                .par_iter()
                .map_init(
                    || vec![0.0; 100 * dim],
                    |buf, x| {
                        kb.pose_mean_cols(x, buf).unwrap();
                        buf[0]
                    },
                )
                .collect()
        });
        let streamed = t.elapsed().as_secs_f64();
        std::hint::black_box(first);
        let t = Instant::now();
        let mut out = vec![0.0; 100 * 100 * dim];
        pool.install(|| {
            out.par_chunks_mut(100 * dim)
                .zip(&trajs)
                .for_each(|(buf, x)| kb.pose_mean_cols(x, buf).unwrap())
        });
        let in_memory = t.elapsed().as_secs_f64();
        let mut exact = vec![0.0; 100 * dim];
        pred.pose_mean_cols(&trajs[0], &mut exact).unwrap();
        let dev = exact
            .iter()
            .zip(&out[..100 * dim])
            .map(|(a, b)| (a - b).abs())
            .fold(0.0f64, f64::max);
        println!(
            "budget (N = {}, D = {dim}): 100 ancestral draws x 100 frames {sampling:.3} s; decoding 10,000 frames through a kernel basis (rank {r}, bound {bound:.1e} at the training points, {:.1e} at variation 0's, max dev from exact {dev:.1e}) streamed {streamed:.3} s, into one fresh buffer {in_memory:.3} s; total {:.3} s / {:.3} s",
            m.y.nrows(),
            kb.basis_error_bound(&trajs[0]).unwrap_or(f64::NAN),
            sampling + streamed,
            sampling + in_memory
        );
    }
}
