//! The column-wise `RbfLinear::gram`/`gradients` against the kernel's definition
//! (3DV eqs. 4 and 6) written out naively over all pairs (libm `exp`), against finite
//! differences, and `Cholesky::factor_owned` against `Cholesky::factor`.

use faer::Mat;
use gpdm::kernel::RbfLinear;
use gpdm::linalg::Cholesky;

/// Deterministic pseudo-random numbers in [-1, 1).
fn rnd(seed: usize) -> f64 {
    (((seed as f64 + 0.5) * 12.9898).sin() * 43758.5453).fract()
}

/// n × d latent points stored as the transpose of a d × n matrix when `strided`, so that the
/// columns are not contiguous (the kernels must copy).
fn points(n: usize, d: usize, seed: usize, strided: bool) -> Mat<f64> {
    let x = Mat::from_fn(n, d, |i, c| 1.5 * rnd(seed + 7 * i + 131 * c));
    if strided {
        let t = x.transpose().to_owned();
        t.transpose().to_owned()
    } else {
        x
    }
}

/// Symmetric G with NaN in the strict upper triangle (only the lower one may be read).
fn lower_g(n: usize, seed: usize) -> Mat<f64> {
    Mat::from_fn(n, n, |i, j| {
        if i >= j {
            rnd(seed + i * n + j)
        } else {
            f64::NAN
        }
    })
}

fn sym(g: &Mat<f64>, i: usize, j: usize) -> f64 {
    if i >= j {
        g[(i, j)]
    } else {
        g[(j, i)]
    }
}

fn kernels() -> [RbfLinear; 3] {
    [
        RbfLinear::pose([1.3, 0.7, 25.0]),
        RbfLinear::dynamics([0.8, 1.9, 0.3, 40.0]),
        // Wide RBF argument range, including exp underflow (γ s/2 > 700) for far pairs.
        RbfLinear::dynamics([2.0, 900.0, 1.1, 5.0]),
    ]
}

#[test]
fn gram_matches_naive_definition_with_zero_upper_triangle() {
    for kern in kernels() {
        for (n, d) in [(1, 1), (2, 3), (5, 1), (13, 3), (37, 4), (64, 2)] {
            for strided in [false, true] {
                let x = points(n, d, n + d, strided);
                let g = kern.gram(x.as_ref());
                for j in 0..n {
                    for i in 0..n {
                        if i < j {
                            assert_eq!(g.k[(i, j)], 0.0);
                            assert_eq!(g.rbf[(i, j)], 0.0);
                            continue;
                        }
                        let s: f64 = (0..d).map(|c| (x[(i, c)] - x[(j, c)]).powi(2)).sum();
                        let dot: f64 = (0..d).map(|c| x[(i, c)] * x[(j, c)]).sum();
                        let rbf = kern.var * (-0.5 * kern.gamma * s).exp();
                        let want =
                            rbf + kern.lin * dot + if i == j { 1.0 / kern.prec } else { 0.0 };
                        assert!(
                            (g.rbf[(i, j)] - rbf).abs() <= 1e-15 * rbf.abs() + 1e-300,
                            "rbf ({i},{j}) {} vs {rbf}",
                            g.rbf[(i, j)]
                        );
                        assert!(
                            (g.k[(i, j)] - want).abs() <= 1e-14 * want.abs().max(1.0),
                            "k ({i},{j}) {} vs {want}",
                            g.k[(i, j)]
                        );
                    }
                }
            }
        }
    }
}

/// `∂/∂(var, γ, lin, prec)` and `∂/∂X` of `Σ_ij G_ij K_ij`, summed over all ordered pairs.
fn naive_gradients(kern: &RbfLinear, x: &Mat<f64>, g: &Mat<f64>) -> ([f64; 4], Mat<f64>) {
    let (n, d) = (x.nrows(), x.ncols());
    let mut p = [0.0; 4];
    let mut dx = Mat::<f64>::zeros(n, d);
    for i in 0..n {
        for j in 0..n {
            let gij = sym(g, i, j);
            let s: f64 = (0..d).map(|c| (x[(i, c)] - x[(j, c)]).powi(2)).sum();
            let dot: f64 = (0..d).map(|c| x[(i, c)] * x[(j, c)]).sum();
            let r = kern.var * (-0.5 * kern.gamma * s).exp();
            p[0] += gij * r / kern.var;
            p[1] += gij * r * (-0.5 * s);
            p[2] += gij * dot;
            if i == j {
                p[3] += -gij / (kern.prec * kern.prec);
            }
            for c in 0..d {
                dx[(i, c)] +=
                    2.0 * gij * (-kern.gamma * r * (x[(i, c)] - x[(j, c)]) + kern.lin * x[(j, c)]);
            }
        }
    }
    (p, dx)
}

#[test]
fn gradients_match_naive_chain_rule() {
    for kern in kernels() {
        for (n, d) in [(1, 1), (2, 3), (5, 1), (13, 3), (37, 4), (64, 2)] {
            for strided in [false, true] {
                let x = points(n, d, 3 * n + d, strided);
                let g = lower_g(n, 11 * n + d);
                let gram = kern.gram(x.as_ref());
                let (p, dx) = kern.gradients(&gram, x.as_ref(), g.as_ref());
                let (pw, dxw) = naive_gradients(&kern, &x, &g);
                let scale = (0..n)
                    .flat_map(|i| (0..d).map(move |c| (i, c)))
                    .map(|(i, c)| dxw[(i, c)].abs())
                    .fold(1e-300, f64::max);
                for i in 0..n {
                    for c in 0..d {
                        assert!(
                            (dx[(i, c)] - dxw[(i, c)]).abs() <= 1e-12 * scale,
                            "n {n} d {d}: dx ({i},{c}) {} vs {}",
                            dx[(i, c)],
                            dxw[(i, c)]
                        );
                    }
                }
                for k in 0..4 {
                    assert!(
                        (p[k] - pw[k]).abs() <= 1e-12 * pw[k].abs().max(1.0),
                        "n {n} d {d}: param {k} {} vs {}",
                        p[k],
                        pw[k]
                    );
                }
            }
        }
    }
}

#[test]
fn gradients_match_finite_differences() {
    let (n, d) = (23, 3);
    let x = points(n, d, 5, false);
    let g = lower_g(n, 9);
    // f(kernel, X) = Σ_ij G_ij K_ij (G symmetric), through the lower triangle of the Gram.
    let f = |kern: &RbfLinear, x: &Mat<f64>| -> f64 {
        let k = kern.gram(x.as_ref()).k;
        (0..n)
            .flat_map(|j| (j..n).map(move |i| (i, j)))
            .map(|(i, j)| (if i == j { 1.0 } else { 2.0 }) * g[(i, j)] * k[(i, j)])
            .sum()
    };
    for kern in [
        RbfLinear::pose([1.3, 0.7, 25.0]),
        RbfLinear::dynamics([0.8, 1.9, 0.3, 40.0]),
    ] {
        let (p, dx) = kern.gradients(&kern.gram(x.as_ref()), x.as_ref(), g.as_ref());
        let h = 1e-6;
        for i in 0..n {
            for c in 0..d {
                let (mut xp, mut xm) = (x.clone(), x.clone());
                xp[(i, c)] += h;
                xm[(i, c)] -= h;
                let fd = (f(&kern, &xp) - f(&kern, &xm)) / (2.0 * h);
                assert!((fd - dx[(i, c)]).abs() < 1e-7 * dx[(i, c)].abs().max(1.0));
            }
        }
        let bump = |k: usize, e: f64| {
            let mut q = kern;
            match k {
                0 => q.var += e,
                1 => q.gamma += e,
                2 => q.lin += e,
                _ => q.prec += e,
            }
            q
        };
        for (k, &pk) in p.iter().enumerate() {
            let fd = (f(&bump(k, h), &x) - f(&bump(k, -h), &x)) / (2.0 * h);
            assert!(
                (fd - pk).abs() < 1e-7 * pk.abs().max(1.0),
                "param {k}: {pk} vs {fd}"
            );
        }
    }
}

#[test]
fn factor_owned_equals_factor_and_keeps_upper_zero() {
    for kern in kernels() {
        for n in [1, 7, 40, 130] {
            let x = points(n, 3, n, false);
            let k = kern.gram(x.as_ref()).k;
            let a = Cholesky::factor(k.as_ref(), "K").unwrap();
            let b = Cholesky::factor_owned(k.clone(), "K", || unreachable!()).unwrap();
            assert_eq!(b.jitter, 0.0);
            for j in 0..n {
                for i in 0..n {
                    assert_eq!(a.l[(i, j)], b.l[(i, j)], "({i},{j})");
                }
            }
        }
    }
    // Duplicate points and no noise: the plain factorisation fails; `original` is used and
    // the jitter retries of `factor` apply.
    let kern = RbfLinear::pose([1.0, 1.0, 1e300]);
    let x = Mat::from_fn(6, 2, |i, c| (i / 2 + c) as f64);
    let k = kern.gram(x.as_ref()).k;
    let a = Cholesky::factor(k.as_ref(), "K").unwrap();
    let mut rebuilt = false;
    let b = Cholesky::factor_owned(k.clone(), "K", || {
        rebuilt = true;
        kern.gram(x.as_ref()).k
    })
    .unwrap();
    assert!(rebuilt && a.jitter > 0.0 && a.jitter == b.jitter);
    assert!((0..6).all(|j| (0..6).all(|i| a.l[(i, j)] == b.l[(i, j)])));
}

#[test]
fn lower_wwt_scaled_matches_dense_product() {
    for (n, d) in [(1, 1), (5, 3), (31, 3), (64, 4), (192, 3), (301, 5)] {
        let w = points(n, d, 2 * n + d, false);
        let got = gpdm::linalg::lower_wwt_scaled(w.as_ref(), -0.5);
        for j in 0..n {
            for i in 0..n {
                let want: f64 = -0.5 * (0..d).map(|c| w[(i, c)] * w[(j, c)]).sum::<f64>();
                if i < j {
                    assert_eq!(got[(i, j)], 0.0);
                } else {
                    assert!((got[(i, j)] - want).abs() < 1e-14, "n {n} ({i},{j})");
                }
            }
        }
    }
}

#[test]
fn recycled_buffers_come_back_zeroed_with_the_requested_shape() {
    use gpdm::linalg::{recycle, zeros_recycled};
    // Shapes no other test in this binary uses, so that the pool's content is ours.
    let (n, m) = (211, 173);
    recycle(Mat::from_fn(n, m, |i, j| (i + j) as f64 + 1.0));
    recycle(Mat::from_fn(m, n, |_, _| f64::NAN));
    for (r, c) in [(n, m), (m, n), (n, m), (7, 5)] {
        let z = zeros_recycled(r, c);
        assert_eq!((z.nrows(), z.ncols()), (r, c));
        assert!((0..c).all(|j| (0..r).all(|i| z[(i, j)] == 0.0)));
    }
}
