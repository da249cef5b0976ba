//! Speed of the GPDM numerics (targets in docs/PERFORMANCE.md, numpy reference in brackets):
//! - objective + gradient of 3DV eq. 7 for N = 446 frames, D = 15000 (numpy ~20 ms, one core);
//! - HMC: 100 samples of a 100-frame latent trajectory (numpy ~11 s);
//! - decoding 10,000 frames to D = 3000 poses (a body part), exact, via a pose basis, and
//!   through the bulk column-major path exactly and with a kernel basis.
//! Run with `OPENBLAS_NUM_THREADS=1 cargo bench -p gpdm`.

use criterion::{criterion_group, criterion_main, Criterion};
use gpdm::hmc::{sample_trajectories, HmcOptions};
use gpdm::predict::Predictor;
use gpdm::{Gpdm, GpdmConfig};
use nalgebra::DMatrix;
use std::hint::black_box;

// The same synthetic "capture" as the tests and the studies (four cyclic sequences, 446 frames).
#[path = "../tests/common/synthetic.rs"]
mod synthetic_capture;

/// The shared synthetic capture with 1 mm noise, at any dimension `d_obs`.
fn synthetic(d_obs: usize) -> Vec<DMatrix<f64>> {
    synthetic_capture::synthetic(d_obs, 1e-3)
}

fn objective(c: &mut Criterion) {
    let m = Gpdm::new(&synthetic(15000), GpdmConfig::default()).unwrap();
    let obj = m.objective().unwrap();
    let theta = m.theta();
    let mut g = vec![0.0; theta.len()];
    let mut group = c.benchmark_group("objective");
    group.sample_size(20);
    group.bench_function("value+gradient N=446 D=15000", |b| {
        b.iter(|| black_box(obj.eval(black_box(&theta), Some(&mut g)).unwrap()))
    });
    group.bench_function("value N=446 D=15000", |b| {
        b.iter(|| black_box(obj.eval(black_box(&theta), None).unwrap()))
    });
    group.finish();
}

fn hmc(c: &mut Criterion) {
    let mut m = Gpdm::new(&synthetic(30), GpdmConfig::default()).unwrap();
    // A short fit so that the dynamics are meaningful.
    let opts = gpdm::optim::TrainOptions {
        schedule: gpdm::optim::Schedule::Alternate {
            rounds: 3,
            iters: 20,
        },
        ..Default::default()
    };
    gpdm::optim::train(&mut m, &opts).unwrap();
    let pred = Predictor::new(&m).unwrap();
    let template = m.sequence_latent(0).unwrap().rows(0, 100).into_owned();
    let hopts = HmcOptions {
        n_samples: 100,
        burn_in: 100,
        thin: 1,
        leapfrog_steps: 10,
        ..Default::default()
    };
    let mut group = c.benchmark_group("hmc");
    group.sample_size(10);
    group.bench_function("100 samples x 100 frames (100 burn-in, 10 leapfrog)", |b| {
        b.iter(|| black_box(sample_trajectories(&pred, &template, &hopts).unwrap()))
    });
    group.finish();
}

/// Decoding 100 trajectories of 100 frames (3DV eq. 12) at a body part's pose dimension D = 3000,
/// exactly and through the rank-r pose basis (`Predictor::pose_means`, rayon over trajectories).
fn decode(c: &mut Criterion) {
    let m = Gpdm::new(&synthetic(3000), GpdmConfig::default()).unwrap();
    let exact = Predictor::new(&m).unwrap();
    let (basis, r, _) = Predictor::with_pose_basis(&m, 1e-6).unwrap();
    let template = m.sequence_latent(0).unwrap().rows(0, 100).into_owned();
    let trajs: Vec<DMatrix<f64>> = (0..100)
        .map(|k| &template * (1.0 + 1e-3 * k as f64))
        .collect();
    let mut group = c.benchmark_group("decode");
    group.sample_size(10);
    group.bench_function("10000 frames D=3000 exact", |b| {
        b.iter(|| black_box(exact.pose_means(&trajs).unwrap()))
    });
    group.bench_function(format!("10000 frames D=3000 rank-{r} basis"), |b| {
        b.iter(|| black_box(basis.pose_means(&trajs).unwrap()))
    });
    // Building the kernel basis (eigenvectors of K_Y, then one GEMM `Yᵀ Q`): part of every
    // hmc-sample call's fixed cost.
    group.bench_function("kernel basis build, D=3000", |b| {
        b.iter(|| black_box(Predictor::with_kernel_basis(&m, 1e-6).unwrap()))
    });
    // Bulk path of the body decoder: one column-major GEMM per trajectory into a reused
    // buffer, kernel basis with a 1 µm certified bound at the training points.
    let (kb, rk, _) = Predictor::with_kernel_basis(&m, 1e-6).unwrap();
    for (name, p) in [
        ("exact", &exact),
        (&*format!("rank-{rk} kernel basis"), &kb),
    ] {
        group.bench_function(format!("10000 frames D=3000 {name}, pose_mean_cols"), |b| {
            use rayon::prelude::*;
            b.iter(|| {
                trajs.par_iter().for_each_init(
                    || vec![0.0; 3000 * 100],
                    |buf, t| {
                        p.pose_mean_cols(t, buf).unwrap();
                        black_box(&buf);
                    },
                )
            })
        });
    }
    group.finish();
}

criterion_group!(benches, objective, hmc, decode);
criterion_main!(benches);
