//! Ancestral sampling of the one-step-predictive trajectory density, checked against the
//! predictive itself and against the HMC sampler, which targets the same density.

mod common;

use gpdm::ancestral::sample_trajectories_ancestral;
use gpdm::hmc::{sample_trajectories_scaled, HmcOptions};
use gpdm::predict::Predictor;
use nalgebra::DMatrix;

/// Per coordinate (mean, variance) of row `t` over the trajectories.
fn moments(trajs: &[DMatrix<f64>], t: usize) -> Vec<(f64, f64)> {
    let n = trajs.len() as f64;
    (0..trajs[0].ncols())
        .map(|c| {
            let mean = trajs.iter().map(|x| x[(t, c)]).sum::<f64>() / n;
            let var = trajs
                .iter()
                .map(|x| (x[(t, c)] - mean).powi(2))
                .sum::<f64>()
                / (n - 1.0);
            (mean, var)
        })
        .collect()
}

#[test]
fn first_step_follows_the_one_step_predictive() {
    let (m, _, _) = common::rotation_model();
    let pred = Predictor::new(&m).unwrap();
    let x1: Vec<f64> = m
        .sequence_latent(0)
        .unwrap()
        .row(5)
        .iter()
        .copied()
        .collect();
    let (mu, var1) = pred.dynamics(&x1);
    let n = 4000;
    for kappa in [1.0, 0.5] {
        let var = kappa * var1;
        let trajs = sample_trajectories_ancestral(&pred, &x1, 2, n, 11, kappa).unwrap();
        for t in &trajs {
            assert_eq!(t.row(0).iter().copied().collect::<Vec<_>>(), x1);
        }
        let se = (var / n as f64).sqrt();
        for (c, (mean, v)) in moments(&trajs, 1).into_iter().enumerate() {
            assert!(
                (mean - mu[c]).abs() < 4.0 * se,
                "mean {mean} vs {} (se {se})",
                mu[c]
            );
            // Sample variance of n normal draws: relative sd sqrt(2/n) = 2.2 %.
            assert!(
                (v / var - 1.0).abs() < 0.09,
                "κ = {kappa}: variance {v} vs {var}"
            );
        }
    }
}

#[test]
fn hmc_and_ancestral_sampling_agree_on_the_trajectory_density() {
    let (m, _, _) = common::rotation_model();
    let pred = Predictor::new(&m).unwrap();
    let template = m.sequence_latent(0).unwrap().rows(0, 6).into_owned();
    let x1: Vec<f64> = template.row(0).iter().copied().collect();
    for kappa in [1.0, 0.3] {
        let exact = sample_trajectories_ancestral(&pred, &x1, 6, 4000, 5, kappa).unwrap();
        let opts = HmcOptions {
            n_samples: 2000,
            burn_in: 300,
            thin: 5,
            leapfrog_steps: 10,
            seed: 9,
            ..Default::default()
        };
        let (chain, res) = sample_trajectories_scaled(&pred, &template, &opts, kappa).unwrap();
        assert!(res.accept_rate > 0.3, "acceptance {}", res.accept_rate);
        // The spread grows along the trajectory; compare the last point, where the two
        // samplers would differ most if the HMC energy and the ancestral draws disagreed.
        let (a, b) = (moments(&exact, 5), moments(&chain, 5));
        for ((ma, va), (mb, vb)) in a.iter().zip(&b) {
            let sd = va.sqrt();
            eprintln!(
                "κ = {kappa}, last point: ancestral {ma:.4} ± {sd:.4}, HMC {mb:.4} ± {:.4}",
                vb.sqrt()
            );
            assert!((ma - mb).abs() < 0.15 * sd, "means {ma} vs {mb} (sd {sd})");
            assert!((vb / va - 1.0).abs() < 0.25, "variances {va} vs {vb}");
        }
    }
}

#[test]
fn same_seed_same_trajectories_on_any_number_of_threads() {
    let (m, _, _) = common::rotation_model();
    let pred = Predictor::new(&m).unwrap();
    let x1: Vec<f64> = m
        .sequence_latent(1)
        .unwrap()
        .row(0)
        .iter()
        .copied()
        .collect();
    let run = |threads: usize, seed: u64| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| sample_trajectories_ancestral(&pred, &x1, 30, 8, seed, 1.0).unwrap())
    };
    let one = run(1, 3);
    assert_eq!(one, run(2, 3));
    assert_ne!(one, run(2, 4));
    assert!(one.windows(2).all(|w| w[0] != w[1]), "trajectories repeat");
    assert!(sample_trajectories_ancestral(&pred, &x1, 1, 8, 3, 1.0).is_err());
    assert!(sample_trajectories_ancestral(&pred, &x1[..1], 30, 8, 3, 1.0).is_err());
    assert!(sample_trajectories_ancestral(&pred, &x1, 30, 8, 3, -1.0).is_err());
}

/// A chain started at an exact draw (`ChainStart::Ancestral`) is stationary from its first
/// iteration: after a burn-in of only 10 iterations, one sample from each of 400 chains has
/// the moments of the exact draws. The same seed gives the same chain.
#[test]
fn chains_started_at_an_exact_draw_need_no_burn_in() {
    use gpdm::hmc::ChainStart;
    let (m, _, _) = common::rotation_model();
    let pred = Predictor::new(&m).unwrap();
    let template = m.sequence_latent(0).unwrap().rows(0, 6).into_owned();
    let x1: Vec<f64> = template.row(0).iter().copied().collect();
    let kappa = 0.3;
    let exact = sample_trajectories_ancestral(&pred, &x1, 6, 4000, 5, kappa).unwrap();
    let chain = |seed: u64| {
        let opts = HmcOptions {
            n_samples: 1,
            burn_in: 10,
            thin: 1,
            leapfrog_steps: 10,
            seed,
            start: ChainStart::Ancestral,
            ..Default::default()
        };
        sample_trajectories_scaled(&pred, &template, &opts, kappa).unwrap().0.remove(0)
    };
    let draws: Vec<DMatrix<f64>> = (0..400).map(chain).collect();
    assert_eq!(draws[7], chain(7));
    assert_ne!(draws[7], draws[8]);
    let (a, b) = (moments(&exact, 5), moments(&draws, 5));
    for ((ma, va), (mb, vb)) in a.iter().zip(&b) {
        let sd = va.sqrt();
        // 400 draws: standard error of the mean 0.05 sd, relative sd of the variance 7 %.
        assert!((ma - mb).abs() < 0.2 * sd, "means {ma} vs {mb} (sd {sd})");
        assert!((vb / va - 1.0).abs() < 0.25, "variances {va} vs {vb}");
    }
}

#[test]
fn on_data_draws_redraw_exactly_the_points_off_the_data() {
    use gpdm::ancestral::sample_trajectories_on_data;
    let (m, _, _) = common::rotation_model();
    let pred = Predictor::new(&m).unwrap();
    let x1: Vec<f64> = m.sequence_latent(0).unwrap().row(0).iter().copied().collect();
    // A wide density (κ = 4) and a threshold at the free draws' 90th percentile ratio (this
    // noise-free model's ratios are all small), so that free draws leave "the data".
    let (len, n, kappa) = (60, 12, 4.0);
    let free = sample_trajectories_ancestral(&pred, &x1, len, n, 5, kappa).unwrap();
    let mut ratios: Vec<f64> =
        free.iter().flat_map(|x| pred.pose_variance_ratio(x).unwrap()).collect();
    ratios.sort_by(f64::total_cmp);
    let limit = ratios[ratios.len() * 9 / 10];
    assert!(pred.pose_variance_ratio(&DMatrix::from_row_slice(1, x1.len(), &x1)).unwrap()[0] <= limit);
    // Drawn points (the first is given) off the data.
    let off = |x: &DMatrix<f64>| {
        pred.pose_variance_ratio(x).unwrap().into_iter().skip(1).filter(|&r| r > limit).count()
    };
    let free_off: usize = free.iter().map(off).sum();
    assert!(free_off > 0, "the free draws must leave the data for this test to mean anything");
    let (kept, counts) = sample_trajectories_on_data(&pred, &x1, len, n, 5, kappa, limit).unwrap();
    for (x, &c) in kept.iter().zip(&counts) {
        assert_eq!(x.row(0).iter().copied().collect::<Vec<_>>(), x1);
        // Every point off the data is one the redraws could not avoid, and is counted.
        assert_eq!(off(x), c);
    }
    let kept_off: usize = counts.iter().sum();
    // Redraws avoid the excursions of the noise; where the mean itself drifts off (this model,
    // far from its data at κ = 4) they cannot avoid every point.
    assert!(kept_off < free_off, "{kept_off} points kept off the data, {free_off} free");
    // A threshold no ratio reaches (the posterior variance never exceeds the prior's) redraws
    // nothing: the free draws, bit for bit.
    let (same, none) = sample_trajectories_on_data(&pred, &x1, len, n, 5, kappa, 1.5).unwrap();
    assert_eq!(same, free);
    assert!(none.iter().all(|&c| c == 0));
    // Each trajectory has its own stream: batching changes it only by the rounding of the
    // batched products.
    let (one, _) = sample_trajectories_on_data(&pred, &x1, len, 1, 5, kappa, limit).unwrap();
    assert!((&one[0] - &kept[0]).abs().max() < 1e-9);
    assert!(sample_trajectories_on_data(&pred, &x1, len, n, 5, kappa, 0.0).is_err());
}
