//! Times GP training (all parts + displacement, both directions) and prediction on the
//! synthetic pairs, and optionally dumps one problem's arrays as CSV for
//! `scripts/compare/gpr_gpy.py`.
//!
//! Usage: `gpr_compare [--pairs N] [--dump DIR] [--kernel nn|se|linear]`
//! e.g.: `OPENBLAS_NUM_THREADS=1 cargo run --release -p gp --example gpr_compare -- --pairs 1100 --dump /tmp/gpr`
#[path = "../benches/synthetic_pairs.rs"]
mod synthetic_pairs;

use gp::gpr::{train_many, GprOptions};
use gp::kernel::Kernel;
use nalgebra::DMatrix;
use std::io::Write;
use std::time::Instant;

fn write_csv(path: &std::path::Path, m: &DMatrix<f64>) -> std::io::Result<()> {
    let mut f = std::io::BufWriter::new(std::fs::File::create(path)?);
    for r in m.row_iter() {
        let line: Vec<String> = r.iter().map(|v| format!("{v:.17e}")).collect();
        writeln!(f, "{}", line.join(","))?;
    }
    Ok(())
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let get = |flag: &str| args.iter().position(|a| a == flag).and_then(|i| args.get(i + 1)).cloned();
    let n: usize = get("--pairs").map_or(350, |s| s.parse().expect("--pairs N"));
    let kernel = match get("--kernel").as_deref().unwrap_or("nn") {
        "se" => Kernel::SquaredExponential { l: 1.0, sigma_f: 1.0 },
        "linear" => Kernel::Linear { sigma_f: 1.0 },
        _ => Kernel::neural_network(1.0, 1.0),
    };
    let problems = synthetic_pairs::both_directions(n, 7);
    let mut opts = GprOptions::default();
    if let Some(v) = get("--grad-tol") {
        opts.cg.grad_tol = v.parse().expect("--grad-tol X");
    }
    if let Some(v) = get("--max-step") {
        opts.cg.max_step = v.parse().expect("--max-step X");
    }
    if let Some(v) = get("--c2") {
        opts.cg.c2 = v.parse().expect("--c2 X");
    }
    let t0 = Instant::now();
    let models = train_many(kernel, &problems, &opts);
    let train_s = t0.elapsed().as_secs_f64();
    let mut total_evals = 0;
    println!("pairs {n}: trained {} models ({}) in {train_s:.3} s", models.len(), kernel.name());
    let mut trained = Vec::new();
    for (i, m) in models.into_iter().enumerate() {
        let (model, rep) = m.expect("training");
        println!(
            "  model {i:2}: lml {:12.4} (start {:12.4}) exit {:?} iters {} evals {} kernel {:?}",
            rep.lml, rep.initial_lml, rep.exit, rep.iterations, rep.evaluations, model.kernel
        );
        total_evals += rep.evaluations;
        for note in &rep.notes {
            println!("    note: {note}");
        }
        trained.push(model);
    }
    println!("total evaluations {total_evals}");
    // Prediction throughput: one direction (5 parts + displacement), many frames at once.
    let frames = 5000;
    let test = synthetic_pairs::pairs(frames, 99);
    let t1 = Instant::now();
    use rayon::prelude::*;
    let preds: Vec<_> =
        trained[..6].par_iter().zip(&test).map(|(m, (x, _))| m.predict_mean(x).unwrap()).collect();
    let pred_s = t1.elapsed().as_secs_f64();
    println!("predict: {frames} frames (6 models) in {pred_s:.4} s = {:.0} frames/s", frames as f64 / pred_s);
    assert_eq!(preds.len(), 6);
    if let Some(dir) = get("--dump") {
        let dir = std::path::PathBuf::from(dir);
        std::fs::create_dir_all(&dir).unwrap();
        let (x, y) = &problems[0];
        write_csv(&dir.join("x.csv"), x).unwrap();
        write_csv(&dir.join("y.csv"), y).unwrap();
        // Time of our training on this one problem, for the ratio against GPy.
        let t = Instant::now();
        let (m, rep) = gp::gpr::Gpr::train(kernel, x, y, &opts).unwrap();
        let one_s = t.elapsed().as_secs_f64();
        let (l, sf) = match m.kernel {
            Kernel::NeuralNetwork { l, sigma_f, .. } => (l, sigma_f),
            _ => (f64::NAN, f64::NAN),
        };
        let json = format!(
            "{{\"pairs\": {n}, \"noise_var\": {}, \"lml\": {:.10}, \"l\": {l:.10}, \"sigma_f\": {sf:.10}, \"train_s\": {one_s:.6}, \"all_models_both_directions_s\": {train_s:.6}, \"models\": {}, \"exit\": \"{:?}\"}}\n",
            opts.noise_var, rep.lml, problems.len(), rep.exit
        );
        std::fs::write(dir.join("rust.json"), json).unwrap();
        println!("dumped problem 0 to {}", dir.display());
    }
}
