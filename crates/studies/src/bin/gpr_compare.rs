//! Times GP training (5 parts x 20-D + 6-D displacement, both directions = 12 models) and
//! prediction on synthetic pairs, and optionally dumps every problem as CSV with our results
//! for `scripts/compare/gpr_gpy.py`.
//!
//! e.g.: `OPENBLAS_NUM_THREADS=1 cargo run --release -p studies --bin gpr_compare -- --pairs 1100 --dump /tmp/gpr1100`
use studies::synthetic_pairs;
use studies::gp_support as support;

use gp::gpr::{initial_kernel, train_many, Gpr, GprOptions, TrainReport};
use gp::kernel::Kernel;
use support::{cpu_seconds, l_sf, write_csv};
use rayon::prelude::*;
use nalgebra::DMatrix;
use std::time::Instant;

/// Times GP training and prediction of the 12 transfer models on synthetic pairs; --dump
/// writes every problem for scripts/compare/gpr_gpy.py.
#[derive(clap::Parser)]
struct Cli {
    /// Training pairs per model.
    #[arg(long, default_value_t = 350)]
    pairs: usize,
    /// The covariance function.
    #[arg(long, value_parser = ["nn", "se", "linear"], default_value = "nn")]
    kernel: String,
    /// Write every problem and our results here (CSV and rust.json).
    #[arg(long)]
    dump: Option<std::path::PathBuf>,
    /// Pairs of the warm start's sub-problem (`GprOptions::warm_start_pairs`).
    #[arg(long)]
    warm_start: Option<usize>,
    #[command(flatten)]
    cg: support::CgArgs,
}

fn main() {
    let cli = <Cli as clap::Parser>::parse();
    let kernel = match cli.kernel.as_str() {
        "se" => Kernel::SquaredExponential {
            l: 1.0,
            sigma_f: 1.0,
        },
        "linear" => Kernel::Linear { sigma_f: 1.0 },
        _ => Kernel::neural_network(1.0, 1.0),
    };
    let mut opts = GprOptions::default();
    cli.cg.apply(&mut opts.cg);
    if let Some(v) = cli.warm_start {
        opts.warm_start_pairs = v;
    }
    let problems = synthetic_pairs::both_directions(cli.pairs, 7);
    let trained = train(kernel, &problems, &opts, cli.pairs);
    let frames_per_s = time_prediction(&trained.models);
    if let Some(dir) = &cli.dump {
        dump(dir, kernel, &problems, &opts, &trained, frames_per_s, cli.pairs);
    }
}

/// The models trained side by side, their reports and the wall seconds they took.
struct Trained {
    models: Vec<Gpr>,
    reports: Vec<(TrainReport, Kernel)>,
    train_s: f64,
}

/// Trains the GP of every problem (`n` pairs) side by side and prints the time and each
/// model's likelihood, then the evaluations of all.
fn train(kernel: Kernel, problems: &[(DMatrix<f64>, DMatrix<f64>)], opts: &GprOptions, n: usize) -> Trained {
    let (t0, c0) = (Instant::now(), cpu_seconds());
    let models = train_many(kernel, problems, opts);
    let (train_s, train_cpu) = (t0.elapsed().as_secs_f64(), cpu_seconds() - c0);
    println!(
        "pairs {n}: trained {} models ({}) in {train_s:.3} s wall, {train_cpu:.2} s CPU (rayon, {} threads)",
        models.len(),
        kernel.name(),
        rayon::current_num_threads()
    );
    let (mut total_evals, mut total_grads) = (0, 0);
    let mut trained = Vec::new();
    let mut records = Vec::new();
    for (i, m) in models.into_iter().enumerate() {
        let (model, rep) = m.expect("training");
        println!(
            "  model {i:2}: lml {:12.4} (start {:12.4}) exit {:?} iters {} evals {} grads {} (l, sf) = {:?}",
            rep.lml,
            rep.initial_lml,
            rep.exit,
            rep.iterations,
            rep.evaluations,
            rep.gradient_evaluations,
            l_sf(&model.kernel)
        );
        total_evals += rep.evaluations;
        total_grads += rep.gradient_evaluations;
        for note in &rep.notes {
            println!("    note: {note}");
        }
        records.push((rep, model.kernel));
        trained.push(model);
    }
    println!("total evaluations {total_evals}, gradients {total_grads}");
    Trained { models: trained, reports: records, train_s }
}

/// Prints the prediction throughput of one direction's six models (5 parts + displacement),
/// many frames at once, and returns it in frames per second.
fn time_prediction(models: &[Gpr]) -> f64 {
    let frames = 5000;
    let test = synthetic_pairs::pairs(frames, 99);
    let t1 = Instant::now();
    let preds: Vec<_> = models[..6]
        .par_iter()
        .zip(&test)
        .map(|(m, (x, _))| m.predict_mean(x).unwrap())
        .collect();
    let pred_s = t1.elapsed().as_secs_f64();
    println!(
        "predict: {frames} frames (6 models) in {pred_s:.4} s = {:.0} frames/s",
        frames as f64 / pred_s
    );
    assert_eq!(preds.len(), 6);
    frames as f64 / pred_s
}

/// Writes every problem as CSV into `dir` with our results in `rust.json`, after timing each
/// model's training again on this thread alone (a like-for-like time against GPy).
fn dump(dir: &std::path::Path, kernel: Kernel, problems: &[(DMatrix<f64>, DMatrix<f64>)], opts: &GprOptions, trained: &Trained, frames_per_s: f64, n: usize) {
    let train_s = trained.train_s;
    std::fs::create_dir_all(dir).unwrap();
    let mut items = Vec::new();
    let mut seq_total = 0.0;
    for (i, ((x, y), (rep, k))) in problems.iter().zip(&trained.reports).enumerate() {
        write_csv(&dir.join(format!("problem_{i:02}_x.csv")), x).unwrap();
        write_csv(&dir.join(format!("problem_{i:02}_y.csv")), y).unwrap();
        let t = Instant::now();
        let _ = Gpr::train(kernel, x, y, opts).unwrap();
        let secs = t.elapsed().as_secs_f64();
        seq_total += secs;
        let (l0, sf0) = l_sf(&initial_kernel(&kernel, x, y));
        let (l, sf) = l_sf(k);
        items.push(format!(
            "{{\"index\": {i}, \"lml\": {:.10}, \"l\": {l:.10e}, \"sigma_f\": {sf:.10e}, \"l0\": {l0:.10e}, \"sigma_f0\": {sf0:.10e}, \"train_s\": {secs:.6}, \"exit\": \"{:?}\"}}",
            rep.lml, rep.exit
        ));
    }
    let json = format!(
        "{{\"pairs\": {n}, \"kernel\": \"{}\", \"noise_var\": {}, \"parallel_train_s\": {train_s:.6}, \"sequential_train_s\": {seq_total:.6}, \"predict_frames_per_s\": {:.1}, \"models\": [\n  {}\n]}}\n",
        kernel.name(), opts.noise_var, frames_per_s, items.join(",\n  ")
    );
    std::fs::write(dir.join("rust.json"), json).unwrap();
    println!(
        "dumped {} problems to {} (sequential total {seq_total:.3} s)",
        problems.len(),
        dir.display()
    );
}
