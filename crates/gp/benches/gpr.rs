//! Speed goals for the GP numerics (docs/PERFORMANCE.md) (run with `OPENBLAS_NUM_THREADS=1 cargo bench -p gp`):
//! - training all 5 parts (20-D -> 20-D) plus the displacement (6-D -> 6-D), both directions
//!   (12 models, rayon over models on the machine's cores): <= 1 s with 350 dense pairs,
//!   <= 5 s with 1100;
//! - prediction (CVPR eq. 13, 5 parts + displacement): >= 5000 frames/s.
//! - one log-marginal-likelihood + gradient evaluation, and one value alone (the optimiser's
//!   units of work: rejected line-search trials need only the value).
use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use gp::gpr::{log_marginal_likelihood, log_marginal_likelihood_grad, train_many, GprOptions};
use gp::kernel::Kernel;
use rayon::prelude::*;
use std::time::Duration;

#[path = "synthetic_pairs.rs"]
mod synthetic_pairs;

fn train(c: &mut Criterion) {
    let mut g = c.benchmark_group("gpr_train_all_parts_both_directions");
    g.sample_size(10)
        .measurement_time(Duration::from_secs(20))
        .warm_up_time(Duration::from_secs(1));
    for n in [350usize, 1100] {
        let problems = synthetic_pairs::both_directions(n, 7);
        g.bench_with_input(BenchmarkId::from_parameter(n), &problems, |b, p| {
            b.iter(|| train_many(Kernel::neural_network(1.0, 1.0), p, &GprOptions::default()))
        });
    }
    g.finish();
}

fn lml_grad(c: &mut Criterion) {
    let mut g = c.benchmark_group("lml_and_gradient_one_model");
    for n in [350usize, 1100] {
        let p = synthetic_pairs::pairs(n, 7);
        let (x, y) = &p[0];
        let k = Kernel::neural_network(3.0, 1.5);
        g.bench_function(BenchmarkId::from_parameter(n), |b| {
            b.iter(|| log_marginal_likelihood_grad(&k, 0.1, false, x, y, &mut Vec::new()).unwrap())
        });
    }
    g.finish();
    let mut g = c.benchmark_group("lml_value_one_model");
    for n in [350usize, 1100] {
        let p = synthetic_pairs::pairs(n, 7);
        let (x, y) = &p[0];
        let k = Kernel::neural_network(3.0, 1.5);
        g.bench_function(BenchmarkId::from_parameter(n), |b| {
            b.iter(|| log_marginal_likelihood(&k, 0.1, x, y, &mut Vec::new()).unwrap())
        });
    }
    g.finish();
}

fn predict(c: &mut Criterion) {
    let mut g = c.benchmark_group("gpr_predict_5_parts_and_displacement");
    let frames = 2000;
    for n in [350usize, 1100] {
        let models: Vec<_> = train_many(
            Kernel::neural_network(1.0, 1.0),
            &synthetic_pairs::pairs(n, 7),
            &GprOptions::default(),
        )
        .into_iter()
        .map(|r| r.unwrap().0)
        .collect();
        let test = synthetic_pairs::pairs(frames, 99);
        g.throughput(Throughput::Elements(frames as u64));
        g.bench_function(BenchmarkId::from_parameter(n), |b| {
            b.iter(|| {
                models
                    .par_iter()
                    .zip(&test)
                    .map(|(m, (x, _))| m.predict_mean(x).unwrap())
                    .collect::<Vec<_>>()
            })
        });
    }
    g.finish();
}

/// The sparse GP (targets: 12 models <= 10 s at 10⁴ pairs, <= 100 s at 10⁵; the 10⁵
/// run is `sgpr_compare --pairs 100000` (crates/studies), too long for criterion's samples):
/// one bound + gradient evaluation at 10³ and 10⁴ pairs, and training the 12 models at 10³.
fn sparse(c: &mut Criterion) {
    use gp::sparse_gpr::{sparse_bound_grad, Sparsity, KUU_JITTER};
    let mut g = c.benchmark_group("sparse_bound_and_gradient_one_model_m256");
    g.sample_size(10);
    for n in [1000usize, 10_000] {
        let p = synthetic_pairs::pairs(n, 7);
        let (x, y) = &p[0];
        let k = Kernel::neural_network(3.0, 1.5);
        let z = x.select_rows(gp::inducing::greedy_variance(&k, x, 256).iter());
        g.bench_function(BenchmarkId::from_parameter(n), |b| {
            b.iter(|| sparse_bound_grad(&k, 0.1, false, &z, x, y, KUU_JITTER, &mut Vec::new()).unwrap())
        });
    }
    g.finish();
    let mut g = c.benchmark_group("sparse_train_all_parts_both_directions_m256");
    g.sample_size(10).measurement_time(Duration::from_secs(30));
    let problems = synthetic_pairs::both_directions(1000, 7);
    let opts = GprOptions { sparse: Sparsity::Inducing(256), ..Default::default() };
    g.bench_function(BenchmarkId::from_parameter(1000), |b| {
        b.iter(|| train_many(Kernel::neural_network(1.0, 1.0), &problems, &opts))
    });
    g.finish();
}

criterion_group!(benches, lml_grad, predict, train, sparse);
criterion_main!(benches);
