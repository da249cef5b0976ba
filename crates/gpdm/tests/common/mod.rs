//! Shared test data generators.
#![allow(dead_code)]

use nalgebra::DMatrix;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Deterministic standard-normal matrix.
pub fn randn(rows: usize, cols: usize, seed: u64) -> DMatrix<f64> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    DMatrix::from_fn(rows, cols, |_, _| rng.sample(rand_distr::StandardNormal))
}

/// Linear dynamical system: z_{t+1} = R(ω) z_t on the unit circle (2-D), observed through a
/// fixed random 10 × 2 map plus Gaussian noise of std `noise`. Returns (clean, noisy) poses.
pub fn rotation_system(
    len: usize,
    omega: f64,
    phase: f64,
    noise: f64,
    seed: u64,
) -> (DMatrix<f64>, DMatrix<f64>) {
    let c = randn(10, 2, 7);
    let z = DMatrix::from_fn(len, 2, |t, k| {
        let a = phase + omega * t as f64;
        if k == 0 {
            a.cos()
        } else {
            a.sin()
        }
    });
    let clean = &z * c.transpose();
    let noisy = &clean + randn(len, 10, seed) * noise;
    (clean, noisy)
}

/// A GPDM (latent dimension 2, default training) of two noisy rotation sequences (40 and 30
/// frames, 16 frames per turn); returns the model, the clean poses and the training report.
pub fn rotation_model() -> (gpdm::Gpdm, Vec<DMatrix<f64>>, gpdm::optim::TrainReport) {
    let omega = std::f64::consts::TAU / 16.0;
    let (c1, y1) = rotation_system(40, omega, 0.0, 0.01, 1);
    let (c2, y2) = rotation_system(30, omega, 1.0, 0.01, 2);
    let config = gpdm::GpdmConfig {
        latent_dim: 2,
        ..gpdm::GpdmConfig::default()
    };
    let mut m = gpdm::Gpdm::new(&[y1, y2], config).unwrap();
    let rep = gpdm::optim::train(&mut m, &gpdm::optim::TrainOptions::default()).unwrap();
    (m, vec![c1, c2], rep)
}
