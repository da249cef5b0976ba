//! The conjugate-gradient optimiser on functions with known minima, and its exit states.
use gp::optim::{minimize, minimize_lazy, minimize_scalar, CgOptions, ExitState};

fn rosenbrock(x: &[f64]) -> (f64, Vec<f64>) {
    let (a, b) = (x[0], x[1]);
    let f = (1.0 - a).powi(2) + 100.0 * (b - a * a).powi(2);
    let g = vec![
        -2.0 * (1.0 - a) - 400.0 * a * (b - a * a),
        200.0 * (b - a * a),
    ];
    (f, g)
}

#[test]
fn rosenbrock_reaches_the_minimum() {
    let opts = CgOptions {
        max_iter: 2000,
        grad_tol: 1e-10,
        max_step: 10.0,
        ..Default::default()
    };
    let r = minimize(rosenbrock, &[-1.2, 1.0], &opts);
    assert_eq!(r.exit, ExitState::Converged, "{r:?}");
    assert!(
        (r.x[0] - 1.0).abs() < 1e-6 && (r.x[1] - 1.0).abs() < 1e-6,
        "{r:?}"
    );
}

#[test]
fn ill_conditioned_quadratic() {
    // f = ½ Σ c_i (x_i - t_i)², minimum at t.
    let c = [1.0, 10.0, 100.0, 1000.0, 3.0];
    let t = [1.0, -2.0, 0.5, 3.0, -1.0];
    let f = |x: &[f64]| {
        let v = (0..5).map(|i| 0.5 * c[i] * (x[i] - t[i]).powi(2)).sum();
        (v, (0..5).map(|i| c[i] * (x[i] - t[i])).collect())
    };
    let opts = CgOptions {
        max_iter: 500,
        grad_tol: 1e-10,
        max_step: 10.0,
        ..Default::default()
    };
    let r = minimize(f, &[0.0; 5], &opts);
    assert_eq!(r.exit, ExitState::Converged, "{r:?}");
    for i in 0..5 {
        assert!((r.x[i] - t[i]).abs() < 1e-8, "{r:?}");
    }
}

#[test]
fn max_iterations_is_reported_with_best_point() {
    let opts = CgOptions {
        max_iter: 3,
        ..Default::default()
    };
    let r = minimize(rosenbrock, &[-1.2, 1.0], &opts);
    assert_eq!(r.exit, ExitState::MaxIterations);
    assert!(
        r.f < rosenbrock(&[-1.2, 1.0]).0,
        "best point must improve on the start"
    );
    assert_eq!(r.f, rosenbrock(&r.x).0);
}

#[test]
fn wrong_gradient_gives_line_search_failure_not_a_silent_result() {
    // The gradient has the wrong sign: no step along -g decreases f.
    let f = |x: &[f64]| (x[0] * x[0] + 1.0, vec![-2.0 * x[0]]);
    let r = minimize(f, &[1.0], &CgOptions::default());
    assert_eq!(r.exit, ExitState::LineSearchFailed);
    assert_eq!(r.x, vec![1.0], "the best point is the start");
}

#[test]
fn non_finite_start_and_infinite_regions() {
    let r = minimize(
        |_x: &[f64]| (f64::NAN, vec![0.0]),
        &[0.0],
        &CgOptions::default(),
    );
    assert_eq!(r.exit, ExitState::NonFiniteStart);
    // f = (x - 2)² for x < 3, +inf beyond: the line search must back off from infinity.
    let f = |x: &[f64]| {
        if x[0] < 3.0 {
            ((x[0] - 2.0).powi(2), vec![2.0 * (x[0] - 2.0)])
        } else {
            (f64::INFINITY, vec![0.0])
        }
    };
    let opts = CgOptions {
        max_step: 100.0,
        grad_tol: 1e-10,
        ..Default::default()
    };
    let r = minimize(f, &[-50.0], &opts);
    assert_eq!(r.exit, ExitState::Converged, "{r:?}");
    assert!((r.x[0] - 2.0).abs() < 1e-8);
}

#[test]
fn lazy_gradients_reach_the_same_minimum_with_fewer_gradients() {
    // Rosenbrock through the lazy protocol: the gradient may only be asked at the point of
    // the previous (value-only) call, which is what lets the GP reuse its factorisation.
    let opts = CgOptions {
        max_iter: 2000,
        grad_tol: 1e-10,
        max_step: 10.0,
        ..Default::default()
    };
    let (mut values, mut grads) = (0usize, 0usize);
    let mut last: Option<Vec<f64>> = None;
    let r = minimize_lazy(
        |x: &[f64], need_grad: bool| {
            let (f, g) = rosenbrock(x);
            if need_grad {
                if last.as_deref() != Some(x) {
                    values += 1;
                }
                grads += 1;
                last = Some(x.to_vec());
                (f, Some(g))
            } else {
                values += 1;
                last = Some(x.to_vec());
                (f, None)
            }
        },
        &[-1.2, 1.0],
        &opts,
    );
    assert_eq!(r.exit, ExitState::Converged, "{r:?}");
    assert!(
        (r.x[0] - 1.0).abs() < 1e-6 && (r.x[1] - 1.0).abs() < 1e-6,
        "{r:?}"
    );
    // The report counts what the objective saw, and some trials were rejected on value alone.
    assert_eq!(r.evaluations, values, "{r:?}");
    assert_eq!(r.gradient_evaluations, grads, "{r:?}");
    assert!(grads < values, "{grads} gradients for {values} values");
    // The returned gradient is the true gradient at the returned point.
    assert_eq!(r.grad, rosenbrock(&r.x).1);
    // The eager wrapper computes a gradient with every value.
    let e = minimize(rosenbrock, &[-1.2, 1.0], &opts);
    assert_eq!(e.exit, ExitState::Converged);
    assert_eq!(e.evaluations, e.gradient_evaluations);
}

#[test]
fn lazy_objective_failing_its_gradient_is_treated_as_too_far() {
    // f = (x - 2)², but the gradient is unavailable (None) beyond x = 3: the search must back
    // off to the region where it exists and still converge.
    let opts = CgOptions {
        max_step: 100.0,
        grad_tol: 1e-10,
        ..Default::default()
    };
    let r = minimize_lazy(
        |x: &[f64], need_grad: bool| {
            let f = (x[0] - 2.0).powi(2);
            let g = (need_grad && x[0] < 3.0).then(|| vec![2.0 * (x[0] - 2.0)]);
            (f, g)
        },
        &[-50.0],
        &opts,
    );
    assert_eq!(r.exit, ExitState::Converged, "{r:?}");
    assert!((r.x[0] - 2.0).abs() < 1e-8, "{r:?}");
}

/// The scalar search reaches the minimiser of smooth functions on either side of the start,
/// near or far, to the gradient tolerance, in few evaluations (secant steps converge
/// superlinearly once bracketed).
#[test]
fn scalar_search_finds_minimisers_near_and_far() {
    let opts = CgOptions { max_step: 0.5, grad_tol: 1e-10, ..Default::default() };
    // f = cosh(x - t) - 1 + 3 (x - t)²: minimum 0 at t, curvature 7.
    for t in [-30.0, -1.7, -0.2, 0.0, 0.05, 0.4, 2.5, 40.0] {
        let f = |x: f64| ((x - t).cosh() - 1.0 + 3.0 * (x - t).powi(2), (x - t).sinh() + 6.0 * (x - t));
        let r = minimize_scalar(f, 0.0, &opts);
        assert_eq!(r.exit, ExitState::Converged, "t = {t}: {r:?}");
        assert!((r.x[0] - t).abs() < 1e-9, "t = {t}: {r:?}");
        assert!(r.evaluations <= 30, "t = {t}: {} evaluations", r.evaluations);
    }
}

/// A function decreasing toward an infimum at +∞ (as the NN kernel's bound toward its linear
/// limit): steps grow geometrically, and the search stops by the tolerance close to the
/// infimum instead of creeping.
#[test]
fn scalar_search_follows_an_asymptote() {
    let f = |x: f64| (100.0 * (-2.0 * x).exp() - 1000.0, -200.0 * (-2.0 * x).exp());
    let opts = CgOptions { max_step: 0.5, grad_tol: 1e-5, ..Default::default() };
    let r = minimize_scalar(f, 0.0, &opts);
    assert_eq!(r.exit, ExitState::Converged, "{r:?}");
    // |f'| <= 1e-5 |f| = 0.01 means f within 0.005 of the infimum.
    assert!(r.f + 1000.0 <= 0.005, "{r:?}");
    assert!(r.evaluations <= 12, "{r:?}");
}

/// Non-finite values (a failed factorisation) bound the search like higher values; a
/// non-finite start is reported as such.
#[test]
fn scalar_search_treats_non_finite_values_as_too_far() {
    // Minimum at 0.8; undefined beyond 1.
    let f = |x: f64| if x < 1.0 { ((x - 0.8).powi(2) - (1.0 - x).ln() * 1e-3, 2.0 * (x - 0.8) + 1e-3 / (1.0 - x)) } else { (f64::NAN, f64::NAN) };
    let opts = CgOptions { max_step: 4.0, grad_tol: 1e-9, ..Default::default() };
    let r = minimize_scalar(f, -3.0, &opts);
    assert_eq!(r.exit, ExitState::Converged, "{r:?}");
    assert!(r.x[0] < 1.0 && f(r.x[0]).1.abs() <= 1e-9 * r.f.abs().max(1.0), "{r:?}");
    let r = minimize_scalar(f, 2.0, &opts);
    assert_eq!(r.exit, ExitState::NonFiniteStart);
}
