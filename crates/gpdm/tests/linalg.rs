//! Cholesky with jitter retries, solves and the kernel Gram matrix.

use faer::Mat;
use gpdm::kernel::RbfLinear;
use gpdm::linalg::Cholesky;

#[test]
fn cholesky_solves_and_log_determinant() {
    // SPD matrix with a known determinant: A = B Bᵀ + I, B lower bidiagonal.
    let n = 5;
    let b = Mat::from_fn(n, n, |i, j| {
        if i == j {
            2.0
        } else if i == j + 1 {
            1.0
        } else {
            0.0
        }
    });
    let a = &b * b.transpose();
    let c = Cholesky::factor(a.as_ref(), "A").unwrap();
    assert_eq!(c.jitter, 0.0);
    // det(B Bᵀ) = 2^(2n).
    assert!((c.log_det() - 2.0 * n as f64 * 2f64.ln()).abs() < 1e-12);
    let rhs = Mat::from_fn(n, 2, |i, j| (i + 3 * j) as f64);
    let x = c.solve_mat(rhs.as_ref());
    let back = &a * &x;
    assert!((back - rhs).norm_max() < 1e-12);
    // sandwich(Q) = L⁻ᵀ Q L⁻¹; with Q = L Lᵀ = A this is Lᵀ⁻¹ L Lᵀ L⁻¹, check via A·S·A = L Q Lᵀ... use Q = I:
    // L⁻ᵀ L⁻¹ = A⁻¹, so A · sandwich(I) = I.
    let s = c.sandwich(Mat::<f64>::identity(n, n).as_ref());
    assert!((&a * &s - Mat::<f64>::identity(n, n)).norm_max() < 1e-12);
}

#[test]
fn cholesky_adds_jitter_to_singular_and_rejects_indefinite() {
    // Rank-one PSD matrix: needs jitter, which is reported.
    let v = Mat::from_fn(4, 1, |i, _| 1.0 + i as f64);
    let a = &v * v.transpose();
    let c = Cholesky::factor(a.as_ref(), "rank one").unwrap();
    assert!(c.jitter > 0.0);
    // Clearly indefinite: fails with a named error.
    let m = Mat::from_fn(3, 3, |i, j| if i == j { -1.0 } else { 0.0 });
    match Cholesky::factor(m.as_ref(), "indefinite") {
        Err(gp::GpError::NotPositiveDefinite { what, .. }) => assert_eq!(what, "indefinite"),
        other => panic!("expected an error, got {other:?}"),
    }
    let nan = Mat::from_fn(2, 2, |_, _| f64::NAN);
    assert!(Cholesky::factor(nan.as_ref(), "nan").is_err());
}

#[test]
fn gram_matches_kernel_definition() {
    let x = Mat::from_fn(6, 3, |i, j| ((i * 3 + j) as f64).sin());
    let k = RbfLinear::dynamics([1.5, 0.7, 0.3, 20.0]);
    let g = k.gram(x.as_ref());
    let cross = k.cross(x.as_ref(), x.as_ref());
    for i in 0..6 {
        for j in 0..=i {
            let s: f64 = (0..3).map(|c| (x[(i, c)] - x[(j, c)]).powi(2)).sum();
            let dot: f64 = (0..3).map(|c| x[(i, c)] * x[(j, c)]).sum();
            let want = 1.5 * (-0.35 * s).exp() + 0.3 * dot + if i == j { 0.05 } else { 0.0 };
            assert!((g.k[(i, j)] - want).abs() < 1e-14);
            // The cross-covariance has no noise term.
            let noise = if i == j { 0.05 } else { 0.0 };
            assert!((cross[(i, j)] + noise - want).abs() < 1e-14);
        }
        let row: Vec<f64> = (0..3).map(|c| x[(i, c)]).collect();
        assert!((k.self_cov(&row) - g.k[(i, i)]).abs() < 1e-14);
    }
}
