//! The reduced-flop objective (pivoted Cholesky of Y Yᵀ, trapezoidal solves, lower-triangle
//! sandwiches) against the dense reference evaluation and against plain dense algebra.

mod common;
#[path = "common/synthetic.rs"]
mod synthetic;

use faer::Mat;
use gpdm::kernel::RbfLinear;
use gpdm::linalg::{lower_zzt, mul_abt, Cholesky, CholeskyProducts, PivotedCholesky};
use gpdm::{Gpdm, GpdmConfig};
use nalgebra::DMatrix;

/// Builds a model, moves it off the PCA start, and compares value and gradient of
/// `eval` with `eval_reference` (value 1e-12 relative, gradient 1e-9 relative to its max-norm).
fn compare(seqs: &[DMatrix<f64>], expect_rank: Option<usize>) {
    let mut m = Gpdm::new(seqs, GpdmConfig::default()).unwrap();
    let n = m.x.nrows();
    m.x += common::randn(n, m.x.ncols(), 11) * 0.2;
    m.alpha = [1.3, 0.7, 40.0];
    m.beta = [0.8, 1.2, 0.3, 20.0];
    let obj = m.objective().unwrap();
    if let Some(r) = expect_rank {
        assert_eq!(obj.s_rank(), r, "numerical rank of Y Yᵀ");
    }
    let th = m.theta();
    let (mut g, mut gr) = (vec![0.0; th.len()], vec![0.0; th.len()]);
    let e = obj.eval(&th, Some(&mut g)).unwrap();
    let er = obj.eval_reference(&th, Some(&mut gr)).unwrap();
    let rel = |a: f64, b: f64| (a - b).abs() / b.abs().max(1e-300);
    eprintln!(
        "N {n} rank {}: value {} vs {} (rel {:e}), pose rel {:e}",
        obj.s_rank(),
        e.value,
        er.value,
        rel(e.value, er.value),
        rel(e.pose, er.pose)
    );
    assert!(rel(e.pose, er.pose) < 1e-12);
    assert!(rel(e.dynamics, er.dynamics) < 1e-12);
    assert!(rel(e.value, er.value) < 1e-12);
    let gmax = gr.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    let worst = g
        .iter()
        .zip(&gr)
        .fold(0.0f64, |a, (u, v)| a.max((u - v).abs()));
    eprintln!("gradient: max |g| {gmax:e}, max difference {worst:e}");
    assert!(gmax > 0.0 && worst < 1e-9 * gmax);
    // Value-only path agrees with the gradient path.
    assert_eq!(obj.eval(&th, None).unwrap().value, e.value);
}

#[test]
fn fast_objective_matches_dense_on_synthetic_and_full_rank_y() {
    // The synthetic capture, N = 446 frames, D = 600 (its structured "noise" leaves
    // S = Y Yᵀ of numerical rank ~150).
    compare(&synthetic::synthetic(600, 1e-3), None);
    // Gaussian Y, D = 300 > N = 150: rank N − 1 (centring removes the direction 1).
    let seqs = vec![common::randn(80, 300, 8), common::randn(70, 300, 9)];
    compare(&seqs, Some(149));
}

#[test]
fn fast_objective_matches_dense_when_d_below_n() {
    // D = 40 < N = 90: rank(S) = 40 (centring only removes the direction 1 of the frames).
    let seqs = vec![common::randn(50, 40, 1), common::randn(40, 40, 2)];
    compare(&seqs, Some(40));
}

#[test]
fn fast_objective_matches_dense_on_noise_free_low_rank_y() {
    // Y = A B exactly of rank 4 (noise-free), D = 200, N = 120.
    let b = common::randn(4, 200, 5);
    let seqs = vec![&common::randn(70, 4, 3) * &b, &common::randn(50, 4, 4) * &b];
    compare(&seqs, None);
    // The noise-free smooth synthetic capture (fast-decaying spectrum), D = 300 < N.
    compare(&synthetic::synthetic(300, 0.0), None);
}

fn rand_mat(r: usize, c: usize, seed: u64) -> Mat<f64> {
    let m = common::randn(r, c, seed);
    Mat::from_fn(r, c, |i, j| m[(i, j)])
}

#[test]
fn pivoted_cholesky_reconstructs_and_drops_only_rounding() {
    // Exactly rank 5, N = 60: r ≥ 5; the pivoted factor reproduces PᵀSP; tr(K⁻¹S) computed
    // from the kept columns equals the dense value to 1e-12 relative.
    let a = rand_mat(60, 5, 21);
    let s = mul_abt(a.as_ref(), a.as_ref());
    let pc = PivotedCholesky::factor(s.as_ref());
    let n = 60;
    let mut seen = pc.perm.clone();
    seen.sort();
    assert_eq!(seen, (0..n).collect::<Vec<_>>());
    let r = pc.r.ncols();
    assert!((5..=n).contains(&r), "rank {r}");
    for j in 0..r {
        for i in 0..j {
            assert_eq!(pc.r[(i, j)], 0.0);
        }
    }
    let rrt = mul_abt(pc.r.as_ref(), pc.r.as_ref());
    let smax = s.norm_max();
    for i in 0..n {
        for j in 0..n {
            let d = (rrt[(i, j)] - s[(pc.perm[i], pc.perm[j])]).abs();
            assert!(d < 1e-13 * smax, "({i},{j}): {d:e}");
        }
    }
    // Pivots are non-increasing (largest remaining diagonal first).
    for k in 1..r {
        assert!(pc.r[(k, k)] <= pc.r[(k - 1, k - 1)] * (1.0 + 1e-12));
    }
    // K with a small noise variance (1e-6, the default pose-noise floor) on permuted points.
    let x = rand_mat(n, 3, 22);
    let xp = Mat::from_fn(n, 3, |i, j| x[(pc.perm[i], j)]);
    let kern = RbfLinear::pose([1.0, 1.0, 1e6]);
    let ch = Cholesky::factor(kern.gram(x.as_ref()).k.as_ref(), "K").unwrap();
    let chp = Cholesky::factor(kern.gram(xp.as_ref()).k.as_ref(), "K").unwrap();
    let mut c = s.clone();
    ch.half_solve_in_place(c.as_mut());
    ch.half_solve_in_place(c.as_mut().transpose_mut());
    let tr_dense: f64 = (0..n).map(|i| c[(i, i)]).sum();
    let z = chp.half_solve_trapezoidal(pc.r.as_ref());
    let tr_fast: f64 = z.col_iter().map(|c| c.squared_norm_l2()).sum();
    assert!(
        (tr_fast - tr_dense).abs() < 1e-12 * tr_dense,
        "{tr_fast} vs {tr_dense}"
    );
    assert!((chp.log_det() - ch.log_det()).abs() < 1e-10 * ch.log_det().abs().max(1.0));
}

#[test]
fn blocked_triangular_kernels_match_dense_ones() {
    // Sizes straddling the block width (64): 1, 63, 64, 65, 200 columns.
    for (n, r) in [(1, 1), (63, 63), (64, 40), (65, 65), (200, 130), (200, 200)] {
        let x = rand_mat(n, 3, n as u64);
        let ch = Cholesky::factor(
            RbfLinear::pose([1.0, 0.5, 10.0])
                .gram(x.as_ref())
                .k
                .as_ref(),
            "K",
        )
        .unwrap();
        // Lower-trapezoidal R.
        let r_mat = Mat::from_fn(n, r, |i, j| {
            if i >= j {
                ((i * 7 + j * 3) as f64 * 0.31).sin() + if i == j { 2.0 } else { 0.0 }
            } else {
                0.0
            }
        });
        let z = ch.half_solve_trapezoidal(r_mat.as_ref());
        let mut zd = r_mat.clone();
        ch.half_solve_in_place(zd.as_mut());
        assert!((&z - &zd).norm_max() < 1e-12 * zd.norm_max(), "Z, n {n}");
        // lower(Z Zᵀ), strict upper zero.
        let q = lower_zzt(z.as_ref());
        let qd = mul_abt(z.as_ref(), z.as_ref());
        for j in 0..n {
            for i in 0..n {
                let want = if i >= j { qd[(i, j)] } else { 0.0 };
                assert!(
                    (q[(i, j)] - want).abs() < 1e-12 * qd.norm_max(),
                    "ZZᵀ n {n}"
                );
            }
        }
        // Lower-only sandwich of a symmetric Q whose upper triangle is garbage.
        let mut qs = Mat::from_fn(n, n, |i, j| ((i + j) as f64 * 0.7).cos());
        for i in 0..n {
            qs[(i, i)] += n as f64;
        }
        let full = ch.sandwich(qs.as_ref());
        let mut garbage = qs.clone();
        for j in 1..n {
            for i in 0..j {
                garbage[(i, j)] = f64::NAN;
            }
        }
        // Outside and inside a rayon pool (inside, the first solve runs in two joined halves).
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(2)
            .build()
            .unwrap();
        let lows = [
            ch.sandwich_lower(garbage.clone()),
            pool.install(|| ch.sandwich_lower(garbage)),
        ];
        for low in &lows {
            for j in 0..n {
                for i in j..n {
                    assert!(
                        (low[(i, j)] - full[(i, j)]).abs() < 1e-11 * full.norm_max(),
                        "sandwich n {n} ({i},{j})"
                    );
                }
            }
        }
    }
}
