//! Breakdown of one log-marginal-likelihood + gradient evaluation at `--pairs N` (default
//! 1100): kernel matrices, Cholesky (faer and LAPACK), the inverse's elements (faer and
//! LAPACK `dpotri`), value-only and value+gradient evaluations. Median of `--reps` runs.
//!
//! `OPENBLAS_NUM_THREADS=1 target/release/gpr_profile --pairs 1100`
use studies::synthetic_pairs;

use gp::gpr::{log_marginal_likelihood, log_marginal_likelihood_grad};
use gp::kernel::Kernel;
use gp::linalg::Cholesky;
use ndarray::{Array2, ShapeBuilder};
use ndarray_linalg::{CholeskyFactorized, InverseCInto, UPLO};
use std::time::Instant;

fn median_ms(reps: usize, mut f: impl FnMut()) -> f64 {
    let mut t: Vec<f64> = (0..reps)
        .map(|_| {
            let s = Instant::now();
            f();
            s.elapsed().as_secs_f64() * 1e3
        })
        .collect();
    t.sort_by(f64::total_cmp);
    t[reps / 2]
}

/// Breakdown of one log-marginal-likelihood + gradient evaluation.
#[derive(clap::Parser)]
struct Cli {
    /// Training pairs.
    #[arg(long, default_value_t = 1100)]
    pairs: usize,
    /// Runs per timing (the median is reported).
    #[arg(long, default_value_t = 9, value_parser = clap::value_parser!(u64).range(1..))]
    reps: u64,
}

fn main() {
    let cli = <Cli as clap::Parser>::parse();
    let (n, reps) = (cli.pairs, cli.reps as usize);
    faer::set_global_parallelism(faer::Par::Seq);
    let t = time_pieces(n, reps);
    println!(
        "pairs {n} (median of {reps}, ms): gram {:.2}, gram+grads(full) {:.2}, faer cholesky {:.2}, faer inverse {:.2}, lapack potrf {:.2}, lapack potri {:.2}, lml value {:.2}, lml+grad {:.2}",
        t.gram, t.grads, t.chol, t.inv, t.lapack_chol, t.lapack_inv, t.value, t.both
    );
}

/// Median milliseconds of each piece of one evaluation.
struct Timings {
    /// The kernel matrix.
    gram: f64,
    /// The kernel matrix with its gradients.
    grads: f64,
    /// faer's Cholesky factorisation of `K + σ² I`.
    chol: f64,
    /// The inverse's elements from faer's factor.
    inv: f64,
    /// LAPACK `potrf`.
    lapack_chol: f64,
    /// LAPACK `potri`.
    lapack_inv: f64,
    /// The log marginal likelihood alone.
    value: f64,
    /// The log marginal likelihood and its gradient.
    both: f64,
}

/// Times each piece of one evaluation on the first of the synthetic problems of `n` pairs
/// (NN kernel, noise variance 0.1), the median of `reps` runs.
fn time_pieces(n: usize, reps: usize) -> Timings {
    let p = synthetic_pairs::pairs(n, 7);
    let (x, y) = &p[0];
    let k = Kernel::neural_network(3.0, 1.5);
    let mut ky = k.gram(x);
    for i in 0..n {
        ky[(i, i)] += 0.1;
    }
    let gram = median_ms(reps, || {
        std::hint::black_box(k.gram(x));
    });
    let grads = median_ms(reps, || {
        std::hint::black_box(k.gram_with_grads(x));
    });
    let chol = median_ms(reps, || {
        std::hint::black_box(Cholesky::new(&ky, "K", &mut Vec::new()).unwrap());
    });
    let c = Cholesky::new(&ky, "K", &mut Vec::new()).unwrap();
    let inv = median_ms(reps, || {
        std::hint::black_box(c.inverse_elements());
    });
    let lapack_chol = median_ms(reps, || {
        let a = Array2::from_shape_vec((n, n).f(), ky.as_slice().to_vec()).unwrap();
        std::hint::black_box(ndarray_linalg::CholeskyInto::cholesky_into(a, UPLO::Lower).unwrap());
    });
    let l = c.lower();
    let lapack_inv = median_ms(reps, || {
        let f = CholeskyFactorized {
            factor: Array2::from_shape_vec((n, n).f(), l.as_slice().to_vec()).unwrap(),
            uplo: UPLO::Lower,
        };
        std::hint::black_box(f.invc_into().unwrap());
    });
    let value = median_ms(reps, || {
        std::hint::black_box(log_marginal_likelihood(&k, 0.1, x, y, &mut Vec::new()).unwrap());
    });
    let both = median_ms(reps, || {
        std::hint::black_box(
            log_marginal_likelihood_grad(&k, 0.1, false, x, y, &mut Vec::new()).unwrap(),
        );
    });
    Timings { gram, grads, chol, inv, lapack_chol, lapack_inv, value, both }
}
