//! Times GP training (5 parts x 20-D + 6-D displacement, both directions = 12 models) and
//! prediction on synthetic pairs, and optionally dumps every problem as CSV with our results
//! for `scripts/compare/gpr_gpy.py`.
//!
//! Usage: `gpr_compare [--pairs N] [--kernel nn|se|linear] [--dump DIR] [--grad-tol X] [--c2 X] [--max-step X] [--warm-start N]`
//! e.g.: `OPENBLAS_NUM_THREADS=1 cargo run --release -p studies --bin gpr_compare -- --pairs 1100 --dump /tmp/gpr1100`
use studies::synthetic_pairs;
use studies::gp_support as support;

use gp::gpr::{initial_kernel, train_many, Gpr, GprOptions};
use gp::kernel::Kernel;
use support::{cpu_seconds, l_sf, write_csv};
use rayon::prelude::*;
use std::time::Instant;

/// `--help`: what the program does and its arguments.
const USAGE: &str = "\
Times GP training and prediction of the 12 transfer models on synthetic pairs; --dump
writes every problem for scripts/compare/gpr_gpy.py.

Usage: gpr_compare [--pairs N] [--kernel nn|se|linear] [--dump DIR] [--grad-tol X] [--c2 X]
                   [--max-step X] [--warm-start N]
  defaults: --pairs 350 --kernel nn";

fn main() {
    studies::usage_on_help(USAGE);
    let args: Vec<String> = std::env::args().collect();
    let get = |flag: &str| {
        args.iter()
            .position(|a| a == flag)
            .and_then(|i| args.get(i + 1))
            .cloned()
    };
    let n: usize = get("--pairs").map_or(350, |s| s.parse().expect("--pairs N"));
    let kernel = match get("--kernel").as_deref().unwrap_or("nn") {
        "se" => Kernel::SquaredExponential {
            l: 1.0,
            sigma_f: 1.0,
        },
        "linear" => Kernel::Linear { sigma_f: 1.0 },
        _ => Kernel::neural_network(1.0, 1.0),
    };
    let mut opts = GprOptions::default();
    if let Some(v) = get("--grad-tol") {
        opts.cg.grad_tol = v.parse().expect("--grad-tol X");
    }
    if let Some(v) = get("--c2") {
        opts.cg.c2 = v.parse().expect("--c2 X");
    }
    if let Some(v) = get("--warm-start") {
        opts.warm_start_pairs = v.parse().expect("--warm-start N");
    }
    if let Some(v) = get("--max-step") {
        opts.cg.max_step = v.parse().expect("--max-step X");
    }
    let problems = synthetic_pairs::both_directions(n, 7);
    let (t0, c0) = (Instant::now(), cpu_seconds());
    let models = train_many(kernel, &problems, &opts);
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
    // Prediction throughput: one direction (5 parts + displacement), many frames at once.
    let frames = 5000;
    let test = synthetic_pairs::pairs(frames, 99);
    let t1 = Instant::now();
    let preds: Vec<_> = trained[..6]
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
    if let Some(dir) = get("--dump") {
        let dir = std::path::PathBuf::from(dir);
        std::fs::create_dir_all(&dir).unwrap();
        // Sequential single-thread timing per model, for a like-for-like ratio with GPy.
        let mut items = Vec::new();
        let mut seq_total = 0.0;
        for (i, ((x, y), (rep, k))) in problems.iter().zip(&records).enumerate() {
            write_csv(&dir.join(format!("problem_{i:02}_x.csv")), x).unwrap();
            write_csv(&dir.join(format!("problem_{i:02}_y.csv")), y).unwrap();
            let t = Instant::now();
            let _ = Gpr::train(kernel, x, y, &opts).unwrap();
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
            kernel.name(), opts.noise_var, frames as f64 / pred_s, items.join(",\n  ")
        );
        std::fs::write(dir.join("rust.json"), json).unwrap();
        println!(
            "dumped {} problems to {} (sequential total {seq_total:.3} s)",
            problems.len(),
            dir.display()
        );
    }
}
