//! Known-answer comparisons against a reference library: LAPACK (OpenBLAS) through
//! ndarray-linalg. The GP numerics use faer; here the same problems are solved by LAPACK's
//! `dpotrf`/`dpotrs` (Cholesky), `dsyevd` (symmetric eigen) and the results must agree.

use gp::gpr::Gpr;
use gp::kernel::Kernel;
use gp::linalg::{symmetric_eigen, Cholesky};
use nalgebra::DMatrix;
use ndarray::Array2;
use ndarray_linalg::{Eigh, SolveC, UPLO};

/// A deterministic pseudo-random matrix (no RNG crate needed).
fn pseudo_random(r: usize, c: usize, seed: u64) -> DMatrix<f64> {
    let mut s = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
    DMatrix::from_fn(r, c, |_, _| {
        s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        ((s >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    })
}

fn to_nd(m: &DMatrix<f64>) -> Array2<f64> {
    Array2::from_shape_fn((m.nrows(), m.ncols()), |(i, j)| m[(i, j)])
}

#[test]
fn gp_posterior_mean_matches_lapack_cholesky_solve() {
    let x = pseudo_random(120, 5, 1);
    let y = pseudo_random(120, 3, 2);
    let kernel = Kernel::neural_network(1.3, 0.8);
    let noise = 0.1;
    let mut notes = Vec::new();
    let gpr = Gpr::fit(kernel.clone(), noise, &x, &y, &mut notes).unwrap();
    let xs = pseudo_random(7, 5, 3);
    let ours = gpr.predict_mean(&xs).unwrap();

    // Reference: (K + σn² I) α = Y by LAPACK Cholesky, then K_* α.
    let mut k = kernel.gram(&x);
    for i in 0..k.nrows() {
        k[(i, i)] += noise;
    }
    let k_nd = to_nd(&k);
    let ks = kernel.cross(&xs, &x);
    for out in 0..y.ncols() {
        let b = ndarray::Array1::from_iter(y.column(out).iter().copied());
        let alpha = k_nd.solvec(&b).unwrap();
        for r in 0..xs.nrows() {
            let reference: f64 = (0..x.nrows()).map(|c| ks[(r, c)] * alpha[c]).sum();
            let diff = (ours[(r, out)] - reference).abs();
            assert!(diff <= 1e-9 * (1.0 + reference.abs()), "row {r} output {out}: {} vs {reference}", ours[(r, out)]);
        }
    }
}

#[test]
fn cholesky_solve_and_log_det_match_lapack() {
    let a = pseudo_random(80, 80, 4);
    let spd = &a * a.transpose() + DMatrix::identity(80, 80) * 0.5;
    let b = pseudo_random(80, 4, 5);
    let mut notes = Vec::new();
    let chol = Cholesky::new(&spd, "test", &mut notes).unwrap();
    assert!(notes.is_empty(), "no jitter expected: {notes:?}");
    let x = chol.solve(&b);
    let spd_nd = to_nd(&spd);
    for c in 0..b.ncols() {
        let col = ndarray::Array1::from_iter(b.column(c).iter().copied());
        let reference = spd_nd.solvec(&col).unwrap();
        for r in 0..80 {
            assert!((x[(r, c)] - reference[r]).abs() < 1e-9 * (1.0 + reference[r].abs()));
        }
    }
    // log det from LAPACK's eigenvalues.
    let (w, _) = spd_nd.eigh(UPLO::Lower).unwrap();
    let reference: f64 = w.iter().map(|v| v.ln()).sum();
    assert!((chol.log_det() - reference).abs() < 1e-8 * reference.abs().max(1.0));
}

#[test]
fn symmetric_eigenvalues_match_lapack() {
    let a = pseudo_random(60, 40, 6);
    let gram = &a * a.transpose();
    let (ours, vectors) = symmetric_eigen(&gram).unwrap();
    let (mut reference, _) = to_nd(&gram).eigh(UPLO::Lower).unwrap().clone();
    let mut r: Vec<f64> = reference.iter_mut().map(|v| *v).collect();
    r.sort_by(|a, b| b.partial_cmp(a).unwrap());
    let scale = r[0];
    for (o, e) in ours.iter().zip(&r) {
        assert!((o - e).abs() < 1e-10 * scale, "{o} vs {e}");
    }
    // Eigenvectors: A v = λ v for the leading ones.
    for k in 0..5 {
        let v = vectors.column(k);
        let resid = (&gram * v - v * ours[k]).norm();
        assert!(resid < 1e-9 * scale);
    }
}
