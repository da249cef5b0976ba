//! Times sparse GP training (Titsias' bound) of the 12 transfer models (5 parts x 20-D +
//! 6-D displacement, both directions) on synthetic pairs: wall and CPU time, peak memory, the
//! bound per model; with `--exact` also the exact GP on the same problems, its likelihood and
//! the difference of the two posterior means at the training inputs. `--dump DIR` writes every problem, its inducing inputs and our
//! optimum for `scripts/compare/sgpr_gpy.py`.
//!
//! With `--dump`, every model is also trained again on this thread alone from the data-driven
//! start with the dumped inducing inputs (the problem GPy is given), `--repeat R` times
//! (default 3): the fastest wall and thread-CPU time are recorded.
//!
//! e.g.: `OPENBLAS_NUM_THREADS=1 cargo run --release -p studies --bin sgpr_compare -- --pairs 10000 --inducing 256`
use studies::synthetic_pairs;
use studies::gp_support as support;

use gp::gpr::{initial_kernel, train_many, Gpr, GprOptions, TrainReport};
use gp::kernel::Kernel;
use gp::sparse_gpr::Sparsity;
use nalgebra::DMatrix;
use std::time::Instant;
use support::{cpu_seconds, l_sf, peak_rss_mib, thread_cpu_seconds, write_csv};

/// RMS difference of two models' posterior means at `x`, relative to the RMS of `y`.
fn relative_difference(a: &Gpr, b: &Gpr, x: &nalgebra::DMatrix<f64>, y: &nalgebra::DMatrix<f64>) -> f64 {
    (a.predict_mean(x).unwrap() - b.predict_mean(x).unwrap()).norm() / y.norm()
}

/// Times sparse GP training of the 12 transfer models on synthetic pairs; --dump writes
/// every problem for scripts/compare/sgpr_gpy.py.
#[derive(clap::Parser)]
struct Cli {
    /// Training pairs per model.
    #[arg(long, default_value_t = 1000)]
    pairs: usize,
    /// Inducing inputs.
    #[arg(long, default_value_t = 256)]
    inducing: usize,
    /// Also train the exact GP on the same problems and compare.
    #[arg(long)]
    exact: bool,
    /// Write every problem, its inducing inputs and our optimum here.
    #[arg(long)]
    dump: Option<std::path::PathBuf>,
    /// How many of the 12 models to train.
    #[arg(long, default_value_t = 12)]
    models: usize,
    /// Single-thread retrainings timed per model with --dump (the fastest is kept).
    #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u64).range(1..))]
    repeat: u64,
    #[command(flatten)]
    cg: support::CgArgs,
}

fn main() {
    let cli = <Cli as clap::Parser>::parse();
    let kernel = Kernel::neural_network(1.0, 1.0);
    let mut opts = GprOptions { sparse: Sparsity::Inducing(cli.inducing), ..Default::default() };
    cli.cg.apply(&mut opts.cg);
    let mut problems = synthetic_pairs::both_directions(cli.pairs, 7);
    problems.truncate(cli.models);
    let trained = train_sparse(kernel, &problems, &opts, cli.pairs, cli.inducing);
    if cli.exact {
        compare_exact(kernel, &problems, &trained.models);
    }
    if let Some(dir) = &cli.dump {
        dump(dir, kernel, &problems, &opts, &trained, &cli);
    }
}

/// The sparse models trained side by side, with the wall and CPU seconds they took.
struct Trained {
    models: Vec<(Gpr, TrainReport)>,
    train_s: f64,
    train_cpu: f64,
}

/// Trains the sparse GP of every problem side by side (`n` pairs, `m` inducing inputs) and
/// prints the time, the peak memory and each model's bound.
fn train_sparse(kernel: Kernel, problems: &[(DMatrix<f64>, DMatrix<f64>)], opts: &GprOptions, n: usize, m: usize) -> Trained {
    let (t0, c0) = (Instant::now(), cpu_seconds());
    let models: Vec<(Gpr, _)> = train_many(kernel, problems, opts).into_iter().map(|r| r.expect("training")).collect();
    let (train_s, train_cpu) = (t0.elapsed().as_secs_f64(), cpu_seconds() - c0);
    println!(
        "pairs {n}, M = {m}: trained {} sparse models in {train_s:.3} s wall, {train_cpu:.2} s CPU ({} threads), peak RSS {:.0} MiB",
        models.len(),
        rayon::current_num_threads(),
        peak_rss_mib()
    );
    for (i, (model, rep)) in models.iter().enumerate() {
        println!(
            "  model {i:2}: bound {:14.4} (start {:14.4}) exit {:?} iters {} evals {} grads {} (l, sf) = {:?}",
            rep.lml, rep.initial_lml, rep.exit, rep.iterations, rep.evaluations, rep.gradient_evaluations, l_sf(&model.kernel)
        );
        for note in &rep.notes {
            println!("    note: {note}");
        }
    }
    Trained { models, train_s, train_cpu }
}

/// Trains the exact GP of every problem and prints its likelihood against the sparse `models`'
/// bound, and how far the two posterior means lie apart at the training inputs.
fn compare_exact(kernel: Kernel, problems: &[(DMatrix<f64>, DMatrix<f64>)], models: &[(Gpr, TrainReport)]) {
    let t1 = Instant::now();
    let exact: Vec<(Gpr, _)> =
        train_many(kernel, problems, &GprOptions::default()).into_iter().map(|r| r.expect("training")).collect();
    println!("exact: trained in {:.3} s wall, peak RSS {:.0} MiB", t1.elapsed().as_secs_f64(), peak_rss_mib());
    for (i, (((ms, rs), (me, re)), (x, y))) in models.iter().zip(&exact).zip(problems).enumerate() {
        println!(
            "  model {i:2}: bound {:.4}, exact lml {:.4}, mean difference / RMS target {:.2e}",
            rs.lml,
            re.lml,
            relative_difference(ms, me, x, y)
        );
    }
}

/// Writes every problem, its inducing inputs and our optimum into `dir` with `rust.json`, after
/// timing each model's training again on this thread alone (`--repeat` times, the fastest
/// kept) from the data-driven start with the same inducing inputs.
fn dump(dir: &std::path::Path, kernel: Kernel, problems: &[(DMatrix<f64>, DMatrix<f64>)], opts: &GprOptions, trained: &Trained, cli: &Cli) {
    let (n, m, repeat) = (cli.pairs, cli.inducing, cli.repeat as usize);
    let (train_s, train_cpu) = (trained.train_s, trained.train_cpu);
    std::fs::create_dir_all(dir).unwrap();
    let mut items = Vec::new();
    let (mut seq_total, mut seq_cpu_total) = (0.0, 0.0);
    for (i, ((x, y), (model, rep))) in problems.iter().zip(&trained.models).enumerate() {
        let z = model.sparse().expect("sparse model").inducing();
        write_csv(&dir.join(format!("problem_{i:02}_x.csv")), x).unwrap();
        write_csv(&dir.join(format!("problem_{i:02}_y.csv")), y).unwrap();
        write_csv(&dir.join(format!("problem_{i:02}_z.csv")), z).unwrap();
        // Single-thread optimisation of the bound alone with these inducing inputs, for a
        // like-for-like time against GPy (which is given the same Z and start).
        let start = initial_kernel(&kernel, x, y);
        let (mut secs, mut cpu) = (f64::INFINITY, f64::INFINITY);
        let mut seq = None;
        // Per evaluation: its bound, and the thread-CPU seconds (since the start) at which
        // the *next* evaluation's bound was known, or the end: by then this bound and its
        // gradient, if one was taken, were known (conservative for us by one evaluation).
        let mut trace: Vec<(f64, f64)> = Vec::new();
        for _ in 0..repeat {
            let mut run: Vec<(f64, f64)> = Vec::new();
            let (t, c) = (Instant::now(), thread_cpu_seconds());
            let r = gp::sparse_gpr::train_sparse_observed(start, x, y, z, opts, &mut |v| {
                run.push((thread_cpu_seconds() - c, v));
            })
            .unwrap()
            .1;
            let this_cpu = thread_cpu_seconds() - c;
            if this_cpu < cpu {
                let ends: Vec<f64> = run.iter().skip(1).map(|e| e.0).chain([this_cpu]).collect();
                trace = run.iter().zip(ends).map(|(e, end)| (end, e.1)).collect();
                cpu = this_cpu;
            }
            secs = secs.min(t.elapsed().as_secs_f64());
            seq = Some(r);
        }
        let seq = seq.unwrap();
        seq_total += secs;
        seq_cpu_total += cpu;
        let (l0, sf0) = l_sf(&start);
        let (l, sf) = l_sf(&model.kernel);
        items.push(format!(
            "{{\"index\": {i}, \"bound\": {:.12e}, \"l\": {l:.15e}, \"sigma_f\": {sf:.15e}, \"l0\": {l0:.15e}, \"sigma_f0\": {sf0:.15e}, \"train_s\": {secs:.6}, \"train_cpu_s\": {cpu:.6}, \"train_bound\": {:.12e}, \"evaluations\": {}, \"gradients\": {}, \"exit\": \"{:?}\", \"trace\": [{}]}}",
            rep.lml, seq.lml, seq.evaluations, seq.gradient_evaluations, seq.exit,
            trace.iter().map(|(t, v)| format!("[{t:.6}, {v:.12e}]")).collect::<Vec<_>>().join(", ")
        ));
    }
    let json = format!(
        "{{\"pairs\": {n}, \"inducing\": {m}, \"kernel\": \"{}\", \"noise_var\": {}, \"parallel_train_s\": {train_s:.6}, \"parallel_train_cpu_s\": {train_cpu:.6}, \"threads\": {}, \"sequential_train_s\": {seq_total:.6}, \"sequential_train_cpu_s\": {seq_cpu_total:.6}, \"repeat\": {repeat}, \"models\": [\n  {}\n]}}\n",
        kernel.name(), opts.noise_var, rayon::current_num_threads(), items.join(",\n  ")
    );
    std::fs::write(dir.join("rust.json"), json).unwrap();
    println!(
        "dumped {} problems to {}; one thread, same Z, from the data-driven start: {seq_total:.3} s wall, {seq_cpu_total:.3} s CPU (fastest of {repeat})",
        problems.len(),
        dir.display()
    );
}
