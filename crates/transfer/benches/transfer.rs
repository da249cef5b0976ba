//! Speed goals (docs/PERFORMANCE.md), on synthetic data of the
//! demo set's shape: 5 parts x 20 PCA coefficients plus the 6-vector
//! displacement.
//! - `gpr-train`: all parts plus displacement, one direction, with about 350
//!   and 1100 dense pairs (goal: both directions in <= 1 s and <= 5 s);
//! - `gpr-predict`: GP prediction of 1000 frames without decoding or
//!   stitching (goal: >= 5000 frames/s).
//!
//! Run: `OPENBLAS_NUM_THREADS=1 cargo bench -p transfer --bench transfer`.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use gp::gpr::GprOptions;
use nalgebra::DMatrix;
use transfer::gpr_model::{train, MeanFunction, Method, PairData, MEAN_RIDGE};
use transfer::predict::{displacement_matrix, predict};

const PARTS: usize = 5;
const M: usize = 20;

/// Smooth, correlated coefficient trajectories (a few latent sinusoids mixed).
fn coeffs(frames: usize, seed: f64) -> DMatrix<f64> {
    DMatrix::from_fn(frames, M, |i, c| {
        let t = i as f64 * 0.05;
        let k = c as f64;
        (2.0 / (1.0 + k)) * ((1.0 + 0.3 * k) * t + seed + k).sin()
            + 0.3 * (0.7 * t * (1.0 + 0.1 * k) + 2.0 * seed).cos()
    })
}

fn pair_data(n: usize) -> PairData {
    let disp: Vec<[f64; 6]> = (0..n)
        .map(|i| {
            let t = i as f64 * 0.05;
            [
                0.03 * t.sin(),
                0.005 * (2.0 * t).cos(),
                0.04 + 0.01 * t.cos(),
                0.01 * t.sin(),
                0.05 * (0.5 * t).sin(),
                0.005,
            ]
        })
        .collect();
    PairData {
        source_coeffs: (0..PARTS).map(|p| coeffs(n, p as f64)).collect(),
        target_coeffs: (0..PARTS)
            .map(|p| coeffs(n, p as f64 + 0.2).map(|v| 1.2 * v + 0.1 * v * v))
            .collect(),
        source_disp: disp.clone(),
        target_disp: disp,
        pairs: (0..n).map(|i| [i, i]).collect(),
        keyposes: (0..n).step_by(n / 5).map(|i| [i, i]).collect(),
    }
}

fn bench(c: &mut Criterion) {
    faer::set_global_parallelism(faer::Par::Seq);
    let names: Vec<String> = (0..PARTS).map(|p| format!("part{p}")).collect();
    let opts = GprOptions::default();
    let mut g = c.benchmark_group("gpr-train");
    g.sample_size(10);
    for n in [350, 1100] {
        let data = pair_data(n);
        g.bench_function(
            format!("{n} pairs, 5 parts + displacement, one direction"),
            |b| {
                b.iter(|| {
                    train(
                        Method::GprNn,
                        false,
                        MeanFunction::default(),
                        MEAN_RIDGE, None,
                        &names,
                        std::slice::from_ref(&data),
                        1.0,
                        false,
                        &opts,
                    )
                    .unwrap()
                })
            },
        );
    }
    g.finish();
    let model = train(
        Method::GprNn,
        false,
        MeanFunction::default(),
        MEAN_RIDGE, None,
        &names,
        &[pair_data(1100)],
        1.0,
        false,
        &opts,
    )
    .unwrap();
    let test = pair_data(1000);
    let xd = displacement_matrix(&test.source_disp);
    let mut g = c.benchmark_group("gpr-predict");
    g.throughput(Throughput::Elements(1000));
    g.bench_function("1000 frames, model of 1100 pairs", |b| {
        b.iter(|| predict(&model, &test.source_coeffs, &xd, false).unwrap())
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
