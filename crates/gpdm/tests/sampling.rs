//! HMC on a known Gaussian, reproducibility, and §7 blending.

mod common;

use gpdm::blend::{blend_pair, BlendSet};
use gpdm::hmc::{sample, Energy, HmcOptions};
use nalgebra::DMatrix;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

/// N(m, Σ) with Σ = [[2, 0.8, 0], [0.8, 1, 0], [0, 0, 0.25]]; energy ½ (q−m)ᵀ Σ⁻¹ (q−m)
/// with the precision written out analytically.
struct Gauss;
const MEAN: [f64; 3] = [1.0, -2.0, 0.5];
const COV: [[f64; 3]; 3] = [[2.0, 0.8, 0.0], [0.8, 1.0, 0.0], [0.0, 0.0, 0.25]];

impl Energy for Gauss {
    fn dim(&self) -> usize {
        3
    }
    fn energy_grad(&self, q: &[f64], g: &mut [f64]) -> Option<f64> {
        let det = 2.0 * 1.0 - 0.8 * 0.8;
        let p = [
            [1.0 / det, -0.8 / det, 0.0],
            [-0.8 / det, 2.0 / det, 0.0],
            [0.0, 0.0, 4.0],
        ];
        let r: Vec<f64> = (0..3).map(|i| q[i] - MEAN[i]).collect();
        let mut e = 0.0;
        for i in 0..3 {
            g[i] = (0..3).map(|j| p[i][j] * r[j]).sum();
            e += 0.5 * r[i] * g[i];
        }
        Some(e)
    }
}

fn gauss_opts(seed: u64) -> HmcOptions {
    HmcOptions {
        n_samples: 4000,
        burn_in: 500,
        thin: 1,
        leapfrog_steps: 10,
        initial_step: 0.1,
        target_accept: 0.7,
        seed,
        ..Default::default()
    }
}

#[test]
fn hmc_recovers_gaussian_mean_and_covariance() {
    let res = sample(&Gauss, &[5.0, 5.0, 5.0], &gauss_opts(11)).unwrap();
    assert_eq!(res.samples.len(), 4000);
    let n = res.samples.len() as f64;
    let mean: Vec<f64> = (0..3)
        .map(|i| res.samples.iter().map(|s| s[i]).sum::<f64>() / n)
        .collect();
    for i in 0..3 {
        // Monte-Carlo standard error for independent draws is sqrt(Σ_ii / n) ≤ 0.023;
        // allow 5 standard errors (HMC draws are close to independent here).
        let se = (COV[i][i] / n).sqrt();
        assert!(
            (mean[i] - MEAN[i]).abs() < 5.0 * se,
            "mean[{i}] = {} vs {}",
            mean[i],
            MEAN[i]
        );
    }
    for i in 0..3 {
        for j in 0..3 {
            let c = res
                .samples
                .iter()
                .map(|s| (s[i] - mean[i]) * (s[j] - mean[j]))
                .sum::<f64>()
                / (n - 1.0);
            // Standard error of a sample covariance: sqrt((Σ_ii Σ_jj + Σ_ij²) / n).
            let se = ((COV[i][i] * COV[j][j] + COV[i][j] * COV[i][j]) / n).sqrt();
            assert!(
                (c - COV[i][j]).abs() < 5.0 * se,
                "cov[{i}][{j}] = {c} vs {}",
                COV[i][j]
            );
        }
    }
    eprintln!(
        "acceptance {} (burn-in {}), step {}",
        res.accept_rate, res.burn_in_accept_rate, res.step_size
    );
    // Adaptation reaches the target acceptance (0.7) in the sampling phase, not only in burn-in.
    assert!(
        (res.accept_rate - 0.7).abs() < 0.07,
        "acceptance {}",
        res.accept_rate
    );
}

#[test]
fn same_seed_same_samples_other_seed_other_samples() {
    let mut o = gauss_opts(5);
    o.n_samples = 50;
    o.burn_in = 50;
    let a = sample(&Gauss, &[0.0; 3], &o).unwrap();
    let b = sample(&Gauss, &[0.0; 3], &o).unwrap();
    assert_eq!(a.samples, b.samples);
    assert_eq!(a.step_size.to_bits(), b.step_size.to_bits());
    o.seed = 6;
    let c = sample(&Gauss, &[0.0; 3], &o).unwrap();
    assert_ne!(a.samples, c.samples);
}

#[test]
fn sampler_rejects_bad_options() {
    let mut o = gauss_opts(0);
    o.thin = 0;
    assert!(sample(&Gauss, &[0.0; 3], &o).is_err());
    assert!(sample(&Gauss, &[0.0; 2], &gauss_opts(0)).is_err());
}

fn set() -> (BlendSet, DMatrix<f64>, DMatrix<f64>, DMatrix<f64>) {
    let x0 = common::randn(20, 3, 1);
    let xh = common::randn(20, 3, 2);
    let x1 = common::randn(20, 3, 3);
    let s = BlendSet::new(vec![
        (1.0, vec![x1.clone()]),
        (0.0, vec![x0.clone()]),
        (0.5, vec![xh.clone()]),
    ])
    .unwrap();
    (s, x0, xh, x1)
}

#[test]
fn blend_at_endpoints_returns_endpoint_trajectories() {
    let (s, x0, _, x1) = set();
    let mut rng = ChaCha8Rng::seed_from_u64(0);
    assert_eq!(s.sample(0.0, &mut rng).unwrap(), x0);
    assert_eq!(s.sample(1.0, &mut rng).unwrap(), x1);
    // The interpolation formula itself also reproduces its endpoints.
    assert!((blend_pair(&x0, 0.0, &x1, 1.0, 0.0) - &x0).abs().max() < 1e-15);
    assert!((blend_pair(&x0, 0.0, &x1, 1.0, 1.0) - &x1).abs().max() < 1e-15);
}

#[test]
fn blend_uses_nearest_learned_trajectories() {
    let (s, x0, xh, x1) = set();
    assert_eq!(s.bounding(0.25).unwrap(), (0, 1));
    assert_eq!(s.bounding(0.75).unwrap(), (1, 2));
    assert_eq!(s.bounding(0.5).unwrap(), (1, 1));
    let mut rng = ChaCha8Rng::seed_from_u64(0);
    let b = s.sample(0.25, &mut rng).unwrap();
    // Halfway between X_0 and X_0.5, independent of X_1.
    assert!((b - (&x0 + &xh) * 0.5).abs().max() < 1e-12);
    let b = s.sample(0.9, &mut rng).unwrap();
    assert!((b - (&xh * 0.2 + &x1 * 0.8)).abs().max() < 1e-12);
    assert!(s.sample(1.5, &mut rng).is_err());
}

#[test]
fn blend_set_validates_input() {
    let a = common::randn(20, 3, 1);
    assert!(BlendSet::new(vec![(0.0, vec![a.clone()])]).is_err());
    assert!(BlendSet::new(vec![(0.0, vec![a.clone()]), (1.0, vec![])]).is_err());
    assert!(BlendSet::new(vec![
        (0.0, vec![a.clone()]),
        (1.0, vec![common::randn(19, 3, 2)])
    ])
    .is_err());
}
