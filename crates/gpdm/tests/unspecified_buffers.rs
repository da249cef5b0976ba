//! The objective's N × N work buffers come from the recycling pool without a zero fill
//! (`gram_lower`, `lower_zzt_scaled_only`, `lower_wwt_scaled_only`, the Z solve). Every entry
//! they read must be written first: with the pool filled with NaN buffers of every size the
//! objective uses, the results must be bit-identical to those from fresh zeroed buffers.
//! Also: evaluations from several threads at once (they share the objective's one-thread
//! dynamics pool) equal the sequential ones bit for bit.

mod common;

use faer::Mat;
use gpdm::kernel::RbfLinear;
use gpdm::linalg::{
    lower_wwt_scaled, lower_zzt, recycle, zeros_recycled, Cholesky, CholeskyProducts, PivotedCholesky,
};
use gpdm::{Gpdm, GpdmConfig};

/// Empties the pool of r × c buffers, then puts `count` NaN-filled ones into it.
fn poison(r: usize, c: usize, count: usize) {
    for _ in 0..64 {
        drop(zeros_recycled(r, c));
    }
    for _ in 0..count {
        recycle(Mat::from_fn(r, c, |_, _| f64::NAN));
    }
}

fn model(n1: usize, n2: usize, dim: usize, seed: u64) -> Gpdm {
    let seqs = vec![
        common::randn(n1, dim, seed),
        common::randn(n2, dim, seed + 1),
    ];
    let mut m = Gpdm::new(&seqs, GpdmConfig::default()).unwrap();
    let n = m.x.nrows();
    m.x += common::randn(n, m.x.ncols(), seed + 2) * 0.2;
    m.alpha = [1.3, 0.7, 40.0];
    m.beta = [0.8, 1.2, 0.3, 20.0];
    m
}

#[test]
fn objective_is_unchanged_by_nan_filled_recycled_buffers() {
    // N = 131 (M = 129), D = 80 < N: Y Yᵀ has rank 79, so Z is N × 79 (every buffer is
    // above the pool's 64 KiB minimum).
    let m = model(70, 61, 80, 41);
    let obj = m.objective().unwrap();
    let th = m.theta();
    let (n, mm, r) = (131, 129, obj.s_rank());
    assert!(r < n && n * r * 8 >= 64 << 10);
    // Fresh zeroed buffers first (the pool holds no buffer of these shapes yet).
    let mut g0 = vec![0.0; th.len()];
    let e0 = obj.eval(&th, Some(&mut g0)).unwrap();
    for _ in 0..3 {
        poison(n, n, 6);
        poison(mm, mm, 6);
        poison(n, r, 2);
        let mut g = vec![0.0; th.len()];
        let e = obj.eval(&th, Some(&mut g)).unwrap();
        assert!(e.value.is_finite());
        assert_eq!(e.value.to_bits(), e0.value.to_bits(), "value");
        assert_eq!(e.pose.to_bits(), e0.pose.to_bits(), "pose term");
        for (a, b) in g.iter().zip(&g0) {
            assert_eq!(a.to_bits(), b.to_bits(), "gradient");
        }
    }
}

#[test]
fn public_kernels_keep_zero_upper_triangles_with_nan_filled_buffers() {
    let n = 120; // n × n and the n × 70 Z are above the pool's 64 KiB minimum
    let x = common::randn(n, 3, 7);
    let x = Mat::from_fn(n, 3, |i, j| x[(i, j)]);
    let w = common::randn(n, 70, 8);
    let w = Mat::from_fn(n, 70, |i, j| w[(i, j)]);
    let kern = RbfLinear {
        var: 1.1,
        gamma: 0.6,
        lin: 0.4,
        prec: 30.0,
    };
    let g0 = kern.gram(x.as_ref());
    let ch = Cholesky::factor(g0.k.as_ref(), "K").unwrap();
    let s = gpdm::linalg::mul_abt(w.as_ref(), w.as_ref());
    let pc = PivotedCholesky::factor(s.as_ref());
    assert_eq!(pc.r.ncols(), 70);
    let z0 = ch.half_solve_trapezoidal(pc.r.as_ref());
    let zzt0 = lower_zzt(z0.as_ref());
    let wwt0 = lower_wwt_scaled(w.as_ref(), -0.5);
    poison(n, n, 8);
    poison(n, pc.r.ncols(), 2);
    let same = |a: &Mat<f64>, b: &Mat<f64>, what: &str| {
        for j in 0..a.ncols() {
            for i in 0..a.nrows() {
                assert_eq!(
                    a[(i, j)].to_bits(),
                    b[(i, j)].to_bits(),
                    "{what} ({i}, {j})"
                );
            }
        }
    };
    let g = kern.gram(x.as_ref());
    same(&g.k, &g0.k, "gram k");
    same(&g.rbf, &g0.rbf, "gram rbf");
    for j in 1..n {
        for i in 0..j {
            assert_eq!(g.k[(i, j)], 0.0);
            assert_eq!(g.rbf[(i, j)], 0.0);
        }
    }
    same(&ch.half_solve_trapezoidal(pc.r.as_ref()), &z0, "Z");
    same(&lower_zzt(z0.as_ref()), &zzt0, "lower Z Zᵀ");
    same(&lower_wwt_scaled(w.as_ref(), -0.5), &wwt0, "lower W Wᵀ");
}

#[test]
fn concurrent_evaluations_match_sequential_ones() {
    let models: Vec<Gpdm> = (0..4)
        .map(|k| model(40 + k, 35, 30, 100 + 10 * k as u64))
        .collect();
    let expect: Vec<(u64, Vec<f64>)> = models
        .iter()
        .map(|m| {
            let th = m.theta();
            let mut g = vec![0.0; th.len()];
            let e = m.objective().unwrap().eval(&th, Some(&mut g)).unwrap();
            (e.value.to_bits(), g)
        })
        .collect();
    std::thread::scope(|s| {
        for (m, (v, g0)) in models.iter().zip(&expect) {
            s.spawn(move || {
                let obj = m.objective().unwrap();
                let th = m.theta();
                for _ in 0..20 {
                    let mut g = vec![0.0; th.len()];
                    let e = obj.eval(&th, Some(&mut g)).unwrap();
                    assert_eq!(e.value.to_bits(), *v);
                    assert!(g.iter().zip(g0).all(|(a, b)| a.to_bits() == b.to_bits()));
                }
            });
        }
    });
}
