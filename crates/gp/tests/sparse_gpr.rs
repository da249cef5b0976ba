//! The sparse GP (Titsias' bound) against the exact GP at `Z = X`, a closed form of the sparse
//! posterior written independently with dense LU solves, finite-difference gradients, the
//! bound's defining inequalities, and training through `Gpr::train`.
mod common;
use common::Rng;
use gp::gpr::{log_marginal_likelihood, Gpr, GprOptions};
use gp::inducing::greedy_variance;
use gp::kernel::Kernel;
use gp::sparse_gpr::{fit_sparse, sparse_bound, sparse_bound_grad, Sparsity};
use nalgebra::DMatrix;

fn kernels() -> [Kernel; 4] {
    [
        Kernel::neural_network(1.3, 0.9),
        Kernel::NeuralNetwork { l: 0.8, sigma_f: 1.2, bias: true },
        Kernel::SquaredExponential { l: 1.1, sigma_f: 0.7 },
        Kernel::Linear { sigma_f: 0.6 },
    ]
}

fn data(n: usize, seed: u64) -> (DMatrix<f64>, DMatrix<f64>) {
    let mut rng = Rng::new(seed);
    let x = rng.matrix(n, 3, 1.0);
    let y = DMatrix::from_fn(n, 2, |r, c| (x[(r, 0)] * (c + 1) as f64).sin() + 0.3 * x[(r, 1)] * x[(r, 2)])
        + rng.matrix(n, 2, 0.1);
    (x, y)
}

/// At `Z = X` the bound is the exact log marginal likelihood and the sparse posterior (mean and
/// latent variance) is the exact one, to 1e-8.
#[test]
fn inducing_at_every_input_equals_the_exact_gp() {
    let (x, y) = data(25, 1);
    let xs = Rng::new(2).matrix(7, 3, 1.2);
    for k in kernels() {
        // The linear kernel's Gram has rank 3: only an SE/NN K_uu is invertible at Z = X.
        if matches!(k, Kernel::Linear { .. }) {
            continue;
        }
        let mut notes = Vec::new();
        let exact = log_marginal_likelihood(&k, 0.1, &x, &y, &mut notes).unwrap();
        let bound = sparse_bound(&k, 0.1, &x, &x, &y, 0.0, &mut notes).unwrap();
        assert!(notes.is_empty(), "{k:?}: {notes:?}");
        assert!((exact - bound).abs() < 1e-8, "{k:?}: exact {exact} bound {bound}");
        let e = Gpr::fit(k, 0.1, &x, &y, &mut notes).unwrap();
        let s = Gpr::from_sparse(fit_sparse(k, 0.1, &x, &x, &y, 0.0, &mut notes).unwrap(), &x);
        let (me, ve) = e.predict_with_variance(&xs, &mut notes).unwrap();
        let (ms, vs) = s.predict_with_variance(&xs, &mut notes).unwrap();
        assert!((&me - &ms).amax() < 1e-8, "{k:?}: mean {}", (&me - &ms).amax());
        assert!((&ve - &vs).amax() < 1e-8, "{k:?}: variance {}", (&ve - &vs).amax());
        assert!((s.predict_mean(&xs).unwrap() - &ms).amax() < 1e-14);
    }
}

/// The sparse posterior against Titsias (2009) eq. 6 written out with dense LU solves:
/// `Σ = (K_uu + K_uf K_fu / s)⁻¹`, mean `K_*u Σ K_uf y / s`,
/// variance `k_** - K_*u K_uu⁻¹ K_u* + K_*u Σ K_u*`; and the bound against eq. 9 written with
/// an `F x F` matrix `Q_ff + s I` (only possible at this small size).
#[test]
fn sparse_posterior_and_bound_match_dense_closed_forms() {
    let (x, y) = data(30, 3);
    let z = Rng::new(4).matrix(6, 3, 1.0);
    let xs = Rng::new(5).matrix(4, 3, 1.0);
    let s = 0.05;
    for k in kernels() {
        let z = if matches!(k, Kernel::Linear { .. }) { z.rows(0, 3).into_owned() } else { z.clone() };
        let (kuu, kuf, ksu) = (k.gram(&z), k.cross(&z, &x), k.cross(&xs, &z));
        let sigma_inv = &kuu + &kuf * kuf.transpose() / s;
        let lu = sigma_inv.clone().lu();
        let mean = &ksu * lu.solve(&(&kuf * &y)).unwrap() / s;
        let kuu_lu = kuu.clone().lu();
        let m = Gpr::from_sparse(fit_sparse(k, s, &z, &x, &y, 0.0, &mut Vec::new()).unwrap(), &x);
        let (got_mean, got_var) = m.predict_with_variance(&xs, &mut Vec::new()).unwrap();
        assert!((&got_mean - &mean).amax() < 1e-9, "{k:?}: {}", (&got_mean - &mean).amax());
        for i in 0..xs.nrows() {
            let ku = ksu.row(i).transpose();
            let prior = k.diag(&xs.rows(i, 1).into_owned())[0];
            let v = prior - ku.dot(&kuu_lu.solve(&ku).unwrap()) + ku.dot(&lu.solve(&ku).unwrap());
            assert!((got_var[i] - v).abs() < 1e-9, "{k:?} {i}: {} vs {v}", got_var[i]);
        }
        // Eq. 9 of Titsias (2009), summed over the two outputs.
        let qff = kuf.transpose() * kuu_lu.solve(&kuf).unwrap();
        let mut c = qff.clone();
        for i in 0..c.nrows() {
            c[(i, i)] += s;
        }
        let (n, p) = (x.nrows() as f64, y.ncols() as f64);
        let c_lu = c.clone().lu();
        let quad = (0..y.ncols()).map(|j| y.column(j).dot(&c_lu.solve(&y.column(j).into_owned()).unwrap())).sum::<f64>();
        let log_det = c_lu.determinant().ln();
        let trace = k.gram(&x).trace() - qff.trace();
        let want = -0.5 * quad - 0.5 * p * log_det - 0.5 * p * n * (2.0 * std::f64::consts::PI).ln() - 0.5 * p * trace / s;
        let got = sparse_bound(&k, s, &z, &x, &y, 0.0, &mut Vec::new()).unwrap();
        assert!((got - want).abs() < 1e-8 * want.abs().max(1.0), "{k:?}: {got} vs {want}");
    }
}

/// Analytic gradient of the bound against central differences, every kernel, noise included,
/// with a `K_uu` jitter large enough to matter.
#[test]
fn bound_gradient_matches_finite_differences() {
    let (x, y) = data(40, 6);
    let z = x.select_rows([0usize, 5, 11, 17, 23, 31, 38].iter());
    for k in kernels() {
        let z = if matches!(k, Kernel::Linear { .. }) { z.rows(0, 3).into_owned() } else { z.clone() };
        let noise = 0.07;
        let (_, g) = sparse_bound_grad(&k, noise, true, &z, &x, &y, 1e-3, &mut Vec::new()).unwrap();
        let mut theta = k.log_params();
        theta.push(noise.ln());
        let f = |t: &[f64]| {
            let nk = t.len() - 1;
            sparse_bound(&k.with_log_params(&t[..nk]), t[nk].exp(), &z, &x, &y, 1e-3, &mut Vec::new()).unwrap()
        };
        let h = 1e-5;
        for i in 0..theta.len() {
            let (mut tp, mut tm) = (theta.clone(), theta.clone());
            tp[i] += h;
            tm[i] -= h;
            let fd = (f(&tp) - f(&tm)) / (2.0 * h);
            assert!((fd - g[i]).abs() < 1e-6 * fd.abs().max(1.0), "{k:?} {i}: fd {fd} vs {}", g[i]);
        }
    }
}

/// The bound never exceeds the exact log marginal likelihood, and adding inducing inputs
/// (greedy selection is nested) never lowers it.
#[test]
fn bound_is_below_the_exact_likelihood_and_rises_with_more_inducing_inputs() {
    let (x, y) = data(80, 7);
    let k = Kernel::NeuralNetwork { l: 1.0, sigma_f: 1.0, bias: true };
    let exact = log_marginal_likelihood(&k, 0.1, &x, &y, &mut Vec::new()).unwrap();
    let order = greedy_variance(&k, &x, 80);
    let mut prev = f64::NEG_INFINITY;
    for m in [2, 5, 10, 20, 40] {
        let z = x.select_rows(order[..m].iter());
        let b = sparse_bound(&k, 0.1, &z, &x, &y, 0.0, &mut Vec::new()).unwrap();
        assert!(b <= exact + 1e-9, "M = {m}: bound {b} above exact {exact}");
        assert!(b >= prev - 1e-9, "M = {m}: bound {b} fell from {prev}");
        prev = b;
    }
    assert!(exact - prev < 1.0, "40 inducing inputs: bound {prev}, exact {exact}");
}

/// Training through `Gpr::train` with `Sparsity::Inducing`: the bound rises, the model
/// survives a bincode round trip, and it predicts held-out targets about as well as the exact
/// GP; below `M` pairs the exact GP is trained.
#[test]
fn sparse_training_generalises_like_the_exact_gp_and_round_trips() {
    let (x, y) = data(400, 8);
    let (xt, yt) = data(100, 9);
    let k = Kernel::NeuralNetwork { l: 1.0, sigma_f: 1.0, bias: true };
    let sparse = GprOptions { sparse: Sparsity::Inducing(150), ..Default::default() };
    let (ms, rs) = Gpr::train(k, &x, &y, &sparse).unwrap();
    let (me, re) = Gpr::train(k, &x, &y, &GprOptions::default()).unwrap();
    assert_eq!(ms.sparse().map(|s| s.inducing().nrows()), Some(150));
    assert!(me.sparse().is_none());
    assert!(rs.lml >= rs.initial_lml && rs.lml <= re.lml + 1e-6, "{rs:?} {re:?}");
    let err = |m: &Gpr| (m.predict_mean(&xt).unwrap() - &yt).norm() / yt.norm();
    let (es, ee) = (err(&ms), err(&me));
    assert!(es < 1.1 * ee, "sparse {es} exact {ee}");
    let bytes = bincode::serde::encode_to_vec(&ms, bincode::config::standard()).unwrap();
    let (back, _): (Gpr, usize) = bincode::serde::decode_from_slice(&bytes, bincode::config::standard()).unwrap();
    assert_eq!(back, ms);
    let small = Gpr::train(k, &x.rows(0, 50).into_owned(), &y.rows(0, 50).into_owned(), &sparse).unwrap().0;
    assert!(small.sparse().is_none());
    let m = gp::sparse_gpr::AUTO_INDUCING;
    assert_eq!(Sparsity::Auto.inducing_for(4 * m), None);
    assert_eq!(Sparsity::Auto.inducing_for(4 * m + 1), Some(m));
    for (text, want) in [("auto", Sparsity::Auto), ("exact", Sparsity::Exact), ("64", Sparsity::Inducing(64))] {
        assert_eq!(text.parse::<Sparsity>(), Ok(want));
        assert_eq!(want.to_string(), text);
    }
    assert!("0".parse::<Sparsity>().is_err() && "many".parse::<Sparsity>().is_err());
}

/// Bad inducing inputs are an error, not a panic.
#[test]
fn bad_inducing_inputs_are_rejected() {
    let (x, y) = data(10, 10);
    let k = Kernel::neural_network(1.0, 1.0);
    assert!(sparse_bound(&k, 0.1, &DMatrix::zeros(0, 3), &x, &y, 0.0, &mut Vec::new()).is_err());
    assert!(sparse_bound(&k, 0.1, &DMatrix::zeros(2, 2), &x, &y, 0.0, &mut Vec::new()).is_err());
    let nan = DMatrix::from_element(2, 3, f64::NAN);
    assert!(sparse_bound(&k, 0.1, &nan, &x, &y, 0.0, &mut Vec::new()).is_err());
    assert!(sparse_bound(&k, 0.0, &x.rows(0, 2).into_owned(), &x, &y, 0.0, &mut Vec::new()).is_err());
}

/// Training maximises the bound over `(log l, log σf)` although it searches over `log l` alone
/// (`σf` profiled out in closed form): at the returned hyperparameters both partial
/// derivatives of the bound vanish to the optimiser's tolerance, and no nearby point of a
/// grid in both coordinates has a higher bound.
#[test]
fn profiled_training_reaches_a_stationary_maximum_in_both_hyperparameters() {
    let (x, y) = data(300, 10);
    for k in [Kernel::neural_network(1.0, 1.0), Kernel::SquaredExponential { l: 1.0, sigma_f: 1.0 }, Kernel::Linear { sigma_f: 1.0 }] {
        let opts = GprOptions { sparse: Sparsity::Inducing(40), warm_start_pairs: 0, ..Default::default() };
        let (model, rep) = Gpr::train(k, &x, &y, &opts).unwrap();
        assert_eq!(rep.exit, Some(gp::optim::ExitState::Converged), "{k:?}: {rep:?}");
        let z = model.sparse().unwrap().inducing().clone();
        let jitter = gp::sparse_gpr::KUU_JITTER;
        let (b, g) = sparse_bound_grad(&model.kernel, 0.1, false, &z, &x, &y, jitter, &mut Vec::new()).unwrap();
        assert!((b - rep.lml).abs() < 1e-9 * b.abs(), "{k:?}: {b} vs {}", rep.lml);
        for gi in &g {
            assert!(gi.abs() <= 1e-5 * b.abs(), "{k:?}: gradient {g:?} at bound {b}");
        }
        let theta = model.kernel.log_params();
        for d0 in [-0.05, 0.0, 0.05] {
            for d1 in [-0.05, 0.0, 0.05] {
                let mut t = theta.clone();
                t[0] += d0;
                if t.len() == 2 {
                    t[1] += d1;
                }
                let near = sparse_bound(&model.kernel.with_log_params(&t), 0.1, &z, &x, &y, jitter, &mut Vec::new()).unwrap();
                assert!(near <= b + 1e-9 * b.abs(), "{k:?}: {near} at {t:?} above {b}");
            }
        }
    }
}
