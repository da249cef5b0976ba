//! Kernel values against independent formulas and analytic gradients against finite
//! differences, for every kernel and hyperparameter.
mod common;
use common::Rng;
use gp::kernel::Kernel;
use nalgebra::DMatrix;

fn kernels() -> Vec<Kernel> {
    vec![
        Kernel::neural_network(0.7, 1.3),
        Kernel::NeuralNetwork {
            l: 2.5,
            sigma_f: 0.4,
            bias: true,
        },
        Kernel::SquaredExponential {
            l: 1.1,
            sigma_f: 0.8,
        },
        Kernel::Linear { sigma_f: 0.6 },
    ]
}

/// Central differences of the Gram matrix in log-parameter space.
fn fd_check(k: &Kernel, x: &DMatrix<f64>) {
    let (_, grads) = k.gram_with_grads(x);
    let p0 = k.log_params();
    assert_eq!(grads.len(), p0.len());
    for (pi, g) in grads.iter().enumerate() {
        let h = 1e-5;
        let (mut pp, mut pm) = (p0.clone(), p0.clone());
        pp[pi] += h;
        pm[pi] -= h;
        let fd = (k.with_log_params(&pp).gram(x) - k.with_log_params(&pm).gram(x)) / (2.0 * h);
        let err = (&fd - g).amax();
        let scale = fd.amax().max(1e-3);
        assert!(
            err / scale < 1e-6,
            "{k:?} param {pi}: analytic vs FD rel err {}",
            err / scale
        );
    }
}

#[test]
fn gradients_match_finite_differences() {
    let mut rng = Rng::new(1);
    let x = rng.matrix(9, 4, 1.5);
    for k in kernels() {
        fd_check(&k, &x);
    }
}

#[test]
fn nn_gradients_stay_finite_near_unit_arcsine_argument() {
    // Huge inputs drive |u| -> 1 (the GPflow NaN report); the "1 +" terms keep it below 1.
    let mut rng = Rng::new(2);
    let x = rng.matrix(6, 3, 1e4);
    let k = Kernel::neural_network(0.05, 1.0);
    let (g, grads) = k.gram_with_grads(&x);
    assert!(g.iter().all(|v| v.is_finite()));
    assert!(grads.iter().all(|m| m.iter().all(|v| v.is_finite())));
}

#[test]
fn nn_matches_eq10_known_value() {
    // x = x' = (1), l = 1/sqrt(2) => a = 1: asin(1 / (1 + 1)) = asin(1/2) = pi/6.
    let k = Kernel::neural_network(1.0 / 2f64.sqrt(), 2.0);
    let v = k.eval(&[1.0], &[1.0]);
    assert!((v - 4.0 * std::f64::consts::PI / 6.0).abs() < 1e-14, "{v}");
    // Orthogonal inputs: zero covariance (no bias).
    assert_eq!(k.eval(&[1.0, 0.0], &[0.0, 3.0]), 0.0);
}

/// GPy's MLP kernel, written from its documentation.
fn gpy_mlp(var: f64, w: f64, b: f64, x: &[f64], y: &[f64]) -> f64 {
    let d = |a: &[f64], c: &[f64]| a.iter().zip(c).map(|(p, q)| p * q).sum::<f64>();
    let num = w * d(x, y) + b;
    let den = ((w * d(x, x) + b + 1.0) * (w * d(y, y) + b + 1.0)).sqrt();
    var * 2.0 / std::f64::consts::PI * (num / den).asin()
}

#[test]
fn nn_maps_to_gpy_mlp_parameters() {
    let mut rng = Rng::new(3);
    let (l, sf) = (1.7, 0.9);
    let w = 1.0 / (2.0 * l * l);
    let var = sf * sf * std::f64::consts::PI / 2.0;
    for bias in [false, true] {
        let k = Kernel::NeuralNetwork {
            l,
            sigma_f: sf,
            bias,
        };
        let b = if bias { w } else { 0.0 };
        for _ in 0..20 {
            let x: Vec<f64> = (0..5).map(|_| rng.normal()).collect();
            let y: Vec<f64> = (0..5).map(|_| rng.normal()).collect();
            let (ours, gpy) = (k.eval(&x, &y), gpy_mlp(var, w, b, &x, &y));
            assert!((ours - gpy).abs() < 1e-13, "bias {bias}: {ours} vs {gpy}");
        }
    }
}

#[test]
fn se_and_linear_known_values() {
    let se = Kernel::SquaredExponential {
        l: 2.0,
        sigma_f: 3.0,
    };
    // |x - x'|² = 4 => exp(-4 / 8)
    assert!((se.eval(&[0.0, 0.0], &[2.0, 0.0]) - 9.0 * (-0.5f64).exp()).abs() < 1e-14);
    let lin = Kernel::Linear { sigma_f: 2.0 };
    assert!((lin.eval(&[1.0, 2.0], &[3.0, -1.0]) - 4.0).abs() < 1e-14);
}

#[test]
fn gram_cross_and_diag_agree_with_pointwise_eval() {
    let mut rng = Rng::new(4);
    let (x, xs) = (rng.matrix(7, 3, 1.0), rng.matrix(4, 3, 1.0));
    for k in kernels() {
        let (g, c, d) = (k.gram(&x), k.cross(&xs, &x), k.diag(&xs));
        let row = |m: &DMatrix<f64>, i: usize| m.row(i).iter().copied().collect::<Vec<_>>();
        for i in 0..7 {
            for j in 0..7 {
                assert!((g[(i, j)] - k.eval(&row(&x, i), &row(&x, j))).abs() < 1e-12);
            }
        }
        for i in 0..4 {
            assert!((d[i] - k.eval(&row(&xs, i), &row(&xs, i))).abs() < 1e-12);
            for j in 0..7 {
                assert!((c[(i, j)] - k.eval(&row(&xs, i), &row(&x, j))).abs() < 1e-12);
            }
        }
        assert_eq!(
            k.with_log_params(&k.log_params()).log_params(),
            k.log_params()
        );
    }
}
