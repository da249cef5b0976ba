//! 3DV eq. 11 pose sampling against the predictive distribution computed independently here
//! (3DV eqs. 4, 12 and 13 by nalgebra's dense Cholesky, not the crate's kernels or factors): the
//! sample moments of many draws `ỹ ~ N(μ_Y(x), σ²_Y(x) I)` must match μ_Y and σ²_Y within
//! their sampling error, and the coordinates of one draw must be uncorrelated.

mod common;

use gpdm::predict::Predictor;
use nalgebra::{DMatrix, DVector};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

/// Eq. 4 by hand.
fn k_y(a: &[f64], b: &[f64], alpha: [f64; 3]) -> f64 {
    let r2: f64 = a.iter().zip(b).map(|(p, q)| (p - q) * (p - q)).sum();
    alpha[0] * (-0.5 * alpha[1] * r2).exp()
}

/// Eqs. 12 and 13 at `x` from the model's data and hyperparameters, by dense algebra;
/// k_Y(x, x) includes the noise 1/α3 (a new noisy pose, as the crate documents).
fn predictive(m: &gpdm::Gpdm, x: &[f64]) -> (DVector<f64>, f64) {
    let n = m.x.nrows();
    let row = |i: usize| m.x.row(i).iter().copied().collect::<Vec<f64>>();
    let mut k = DMatrix::from_fn(n, n, |i, j| k_y(&row(i), &row(j), m.alpha));
    for i in 0..n {
        k[(i, i)] += 1.0 / m.alpha[2];
    }
    let chol = k.cholesky().expect("K_Y positive definite");
    let ks = DVector::from_fn(n, |i, _| k_y(&row(i), x, m.alpha));
    let w = chol.solve(&ks);
    let mean = m.y.transpose() * &w + &m.y_mean;
    let var = m.alpha[0] + 1.0 / m.alpha[2] - ks.dot(&w);
    (mean, var)
}

#[test]
fn eq11_draws_have_the_predictive_mean_and_variance() {
    let (m, _, _) = common::rotation_model();
    let pred = Predictor::new(&m).unwrap();
    // A point between training points (variance well above the noise) and one far away
    // (variance → α1 + 1/α3, mean → the data mean).
    let between: Vec<f64> =
        m.x.row(3)
            .iter()
            .zip(m.x.row(4).iter())
            .map(|(a, b)| 0.5 * (a + b) + 0.3)
            .collect();
    let far = vec![10.0, -10.0];
    for x in [between, far] {
        let (mu, var) = predictive(&m, &x);
        assert!(var > 0.0);
        let draws = 4000;
        let xs = DMatrix::from_fn(draws, 2, |_, c| x[c]);
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let y = pred.reconstruct(&xs, Some(&mut rng)).unwrap();
        let d = y.ncols();
        // The mean (3DV eq. 12) without a generator.
        let mean_only = pred
            .reconstruct::<ChaCha8Rng>(&xs.rows(0, 1).into_owned(), None)
            .unwrap();
        for c in 0..d {
            assert!((mean_only[(0, c)] - mu[c]).abs() < 1e-8 * (1.0 + mu[c].abs()));
        }
        // Sample mean per coordinate: within 4.5 standard errors (d = 10 coordinates).
        let se = (var / draws as f64).sqrt();
        for c in 0..d {
            let m_c = y.column(c).mean();
            assert!(
                (m_c - mu[c]).abs() < 4.5 * se,
                "coordinate {c}: mean {m_c} vs {}",
                mu[c]
            );
        }
        // Pooled sample variance around the true mean: relative sd √(2/(draws d)) ≈ 0.7 %.
        let s2: f64 = (0..d)
            .map(|c| y.column(c).iter().map(|v| (v - mu[c]).powi(2)).sum::<f64>())
            .sum::<f64>()
            / (draws * d) as f64;
        let rel_sd = (2.0 / (draws * d) as f64).sqrt();
        assert!(
            (s2 / var - 1.0).abs() < 4.5 * rel_sd,
            "variance {s2} vs σ²_Y {var}"
        );
        // Isotropic and independent across coordinates (3DV eq. 11's σ² I): the sample
        // correlation of two coordinates is within 4.5/√draws of 0.
        let z = |c: usize| {
            y.column(c)
                .iter()
                .zip(std::iter::repeat(mu[c]))
                .map(|(v, m)| v - m)
                .collect::<Vec<f64>>()
        };
        let (z0, z1) = (z(0), z(1));
        let corr = z0.iter().zip(&z1).map(|(a, b)| a * b).sum::<f64>() / (draws as f64 * var);
        assert!(
            corr.abs() < 4.5 / (draws as f64).sqrt(),
            "correlation {corr}"
        );
    }
}

#[test]
fn eq11_draws_at_training_points_stay_close_to_them() {
    // At a training latent point σ²_Y is at most about the noise variance 1/α3 (plus the
    // model's own reconstruction uncertainty), far below α1.
    let (m, _, _) = common::rotation_model();
    let x: Vec<f64> = m.x.row(10).iter().copied().collect();
    let (_, var) = predictive(&m, &x);
    assert!(
        var < 0.1 * m.alpha[0],
        "σ²_Y at a training point {var} vs α1 {}",
        m.alpha[0]
    );
    let pred = Predictor::new(&m).unwrap();
    let v = pred
        .pose_variance(&DMatrix::from_row_slice(1, 2, &x))
        .unwrap()[0];
    assert!((v - var).abs() < 1e-9 * (1.0 + var), "{v} vs {var}");
}
