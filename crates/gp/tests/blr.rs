//! Bayesian linear regression (CVPR eqs. 1-6) against hand-computed ridge regression.
mod common;
use common::Rng;
use gp::blr::{cost_matrix, Blr, PartFrames, PAPER_SIGMA2};
use nalgebra::DMatrix;

#[test]
fn mean_equals_ridge_regression_and_variance_matches_eq4() {
    let mut rng = Rng::new(40);
    // L = 5 key-poses, m_s = 4, m_t = 3 (paper layout: columns are key-poses).
    let (xk, yk) = (rng.matrix(5, 4, 1.0), rng.matrix(5, 3, 1.0));
    let s2 = PAPER_SIGMA2;
    let (xp, yp) = (xk.transpose(), yk.transpose());
    // Ridge: M = Y Xᵀ (X Xᵀ + σ² I)⁻¹ (= Y Xᵀ A⁻¹ / σ²).
    let ridge = &yp
        * xp.transpose()
        * (&xp * xp.transpose() + DMatrix::identity(4, 4) * s2)
            .try_inverse()
            .unwrap();
    let a_inv = (&xp * xp.transpose() / s2 + DMatrix::identity(4, 4))
        .try_inverse()
        .unwrap();
    let model = Blr::fit(&xk, &yk, s2).unwrap();
    let xs = rng.matrix(6, 4, 1.0);
    let (mu, var) = model.predict(&xs).unwrap();
    for i in 0..6 {
        let x = xs.row(i).transpose();
        let expect = &ridge * &x;
        assert!((mu.row(i).transpose() - expect).amax() < 1e-10);
        let v = (x.transpose() * &a_inv * &x)[(0, 0)];
        assert!((var[i] - v).abs() < 1e-12 * v.max(1.0));
    }
    // Eq. 5 for one entry.
    let ys = rng.matrix(4, 3, 1.0);
    let c = model.neg_log_cost(&xs, &ys).unwrap();
    let d2 = (ys.row(2) - mu.row(1)).norm_squared();
    assert!((c[(1, 2)] - 0.5 * d2 / var[1]).abs() < 1e-9 * c[(1, 2)].max(1.0));
}

#[test]
fn whole_body_cost_is_the_sum_over_parts_and_zero_free_at_exact_linear_keys() {
    let mut rng = Rng::new(41);
    let keys = [(0, 0), (3, 2), (7, 6)];
    let (s1, t1) = (rng.matrix(8, 3, 1.0), rng.matrix(7, 2, 1.0));
    let (s2, t2) = (rng.matrix(8, 4, 1.0), rng.matrix(7, 4, 1.0));
    let parts = [
        PartFrames {
            source: &s1,
            target: &t1,
        },
        PartFrames {
            source: &s2,
            target: &t2,
        },
    ];
    let total = cost_matrix(&parts, &keys, 0.01).unwrap();
    let fit = |s: &DMatrix<f64>, t: &DMatrix<f64>| {
        let xk = DMatrix::from_fn(3, s.ncols(), |r, c| s[(keys[r].0, c)]);
        let yk = DMatrix::from_fn(3, t.ncols(), |r, c| t[(keys[r].1, c)]);
        Blr::fit(&xk, &yk, 0.01)
            .unwrap()
            .neg_log_cost(s, t)
            .unwrap()
    };
    assert!((total - fit(&s1, &t1) - fit(&s2, &t2)).amax() < 1e-9);
    assert!(cost_matrix(&parts, &[(8, 0)], 0.01).is_err());
}

#[test]
fn a_true_linear_relation_makes_the_matching_frame_the_cheapest() {
    let mut rng = Rng::new(42);
    let m = rng.matrix(3, 3, 1.0);
    let src = rng.matrix(30, 3, 1.0);
    let tgt = &src * m.transpose();
    let keys: Vec<_> = [0usize, 7, 15, 22, 29].iter().map(|&i| (i, i)).collect();
    let c = cost_matrix(
        &[PartFrames {
            source: &src,
            target: &tgt,
        }],
        &keys,
        0.01,
    )
    .unwrap();
    for i in 0..30 {
        let (jmin, _) = c.row(i).transpose().argmin();
        assert_eq!(jmin, i, "row {i}");
    }
}
