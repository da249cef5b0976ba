//! L-BFGS on quadratics with known minimisers (independent truth: a Cholesky solve).

use gpdm::optim::{lbfgs, Exit, LbfgsOptions};
use nalgebra::{DMatrix, DVector};

/// f = ½ xᵀAx − bᵀx with SPD A = Q diag(λ) Qᵀ with λ from 1 to `cond` (Q from the QR of a fixed pseudo-random
/// matrix) and b; n = 41 is not a multiple of the dot product's 4-way unrolling.
fn quadratic(n: usize, cond: f64) -> (DMatrix<f64>, DVector<f64>) {
    let m = DMatrix::from_fn(n, n, |i, j| {
        ((i * 31 + j * 17 + 7) % 23) as f64 / 23.0 - 0.5
    });
    let q = m.qr().q();
    let lam = DVector::from_fn(n, |i, _| cond.powf(i as f64 / (n - 1) as f64));
    let a = &q * DMatrix::from_diagonal(&lam) * q.transpose();
    let b = DVector::from_fn(n, |i, _| (i as f64 * 0.37).sin());
    (a, b)
}

fn run(a: &DMatrix<f64>, b: &DVector<f64>, memory: usize) -> gpdm::optim::LbfgsResult {
    let f = |x: &[f64], g: &mut [f64]| {
        let xv = DVector::from_column_slice(x);
        let ax = a * &xv;
        g.copy_from_slice((&ax - b).as_slice());
        Some(0.5 * xv.dot(&ax) - b.dot(&xv))
    };
    let o = LbfgsOptions {
        memory,
        max_iter: 5000,
        max_evals: 20000,
        grad_tol: 1e-6,
        value_tol: -1.0, // never stop on the value test
        ..Default::default()
    };
    lbfgs(f, &vec![0.0; b.len()], &o)
}

#[test]
fn lbfgs_reaches_the_solution_of_the_linear_system() {
    let (a, b) = quadratic(41, 1e3);
    let truth = a.clone().cholesky().unwrap().solve(&b);
    let mut iterations = vec![];
    for memory in [3, 100] {
        let r = run(&a, &b, memory);
        eprintln!(
            "memory {memory}: {:?} after {} iterations, {} evaluations",
            r.exit, r.iterations, r.evaluations
        );
        assert_eq!(
            r.exit,
            Exit::GradientTolerance,
            "memory {memory}: {:?}",
            r.exit
        );
        // ‖x − x*‖ ≤ ‖∇f‖₂ / λ_min ≤ √n · 1e-6 with λ_min = 1.
        let err = (DVector::from_vec(r.x.clone()) - &truth).norm();
        assert!(err <= (41f64).sqrt() * 1e-6, "memory {memory}: error {err}");
        iterations.push(r.iterations);
    }
    // Curvature pairs kept from all iterations (memory ≥ n) resolve the spectrum that three
    // pairs cannot: markedly fewer iterations.
    assert!(
        2 * iterations[1] < iterations[0],
        "memory 3: {} iterations, memory 100: {}",
        iterations[0],
        iterations[1]
    );
}

#[test]
fn memory_zero_is_scaled_steepest_descent() {
    // No correction pairs may be stored (this used to panic); on a well-conditioned quadratic
    // steepest descent with γ = 1/‖∇f‖∞ steps still converges.
    let (a, b) = quadratic(41, 2.0);
    let truth = a.clone().cholesky().unwrap().solve(&b);
    let r = run(&a, &b, 0);
    assert_eq!(r.exit, Exit::GradientTolerance, "{:?}", r.exit);
    let err = (DVector::from_vec(r.x) - &truth).norm();
    assert!(err <= (41f64).sqrt() * 1e-6, "error {err}");
}
