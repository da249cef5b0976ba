//! Fits the GPDM (gpdm-train's model: pose-noise floor 1e-6, dynamics-noise floor 1e-3, weak
//! log-normal factor on β1..β3) with several optimiser settings, each stopping by convergence
//! (value or gradient tolerance), and prints objective, iterations, evaluations, time and
//! hyperparameters; optionally exports the problem and the traces for
//! `scripts/compare/gpdm_scipy.py`.
//!
//! Usage: fit_compare [D=2000 | PROBLEM_DIR] [EXPORT_DIR] [--runs ...] [--memory K]
//! [--targets F1,F2] [--overhead] [--in-pool] (`--help` lists them).
//! PROBLEM_DIR holds y.f64 (row-major N × D little-endian f64) and meta.json with "n", "d_obs"
//! and "seq_lens" (e.g. a body part written by the `export_part` binary).
//! e.g.: OPENBLAS_NUM_THREADS=1 target/release/fit_compare 15000 /tmp/gpdm_problem

use clap::Parser;
use gpdm::optim::{train, LbfgsOptions, Scaling, Schedule, TrainOptions};
use gpdm::{Gpdm, GpdmConfig};
use std::time::Instant;

use studies::gpdm_problem as problem;
use studies::synthetic;
use problem::load_problem;

/// Fits the GPDM with several optimiser settings and prints objective, iterations, evaluations,
/// time and hyperparameters of each.
#[derive(Parser)]
struct Cli {
    /// The synthetic capture's dimension D, or a problem directory (y.f64 and meta.json).
    #[arg(default_value = "2000")]
    problem: String,
    /// Writes the problem, θ0 and each run's trace here (for scripts/compare/gpdm_scipy.py).
    export_dir: Option<std::path::PathBuf>,
    /// The runs, comma-separated, of joint, joint-m10, joint-per-hyper, alternate.
    #[arg(long, value_delimiter = ',', default_value = "joint,joint-m10")]
    runs: Vec<String>,
    /// L-BFGS memory of every run [default: each run's own: 100 for joint and joint-per-hyper,
    /// 10 for joint-m10 and alternate].
    #[arg(long)]
    memory: Option<usize>,
    /// Objective values, comma-separated: prints the evaluation at which each was first reached
    /// and how many iterations needed more than one evaluation [default: none].
    #[arg(long, value_delimiter = ',')]
    targets: Option<Vec<f64>>,
    /// Also times the optimiser's own work per L-BFGS iteration.
    #[arg(long)]
    overhead: bool,
    /// Trains from inside a rayon worker (as gpdm-train's per-part par_iter does).
    #[arg(long)]
    in_pool: bool,
}

/// Convergence tolerances shared with scipy (written to meta.json).
const VALUE_TOL: f64 = 1e-10;
const GRAD_TOL: f64 = 1e-3;
/// gpdm-train's dynamics-noise floor (variation::train::DYN_NOISE_FLOOR).
const DYN_NOISE_FLOOR: f64 = 1e-3;

fn write_f64(path: &std::path::Path, v: &[f64]) {
    let bytes: Vec<u8> = v.iter().flat_map(|x| x.to_le_bytes()).collect();
    std::fs::write(path, bytes).unwrap();
}

/// Prints the evaluation at which the objective first reached each of `targets`
/// (deterministic, unlike times), and how many iterations needed more than one evaluation.
fn report_targets(name: &str, r: &gpdm::optim::TrainReport, targets: &[f64]) {
    for &t in targets {
        match r.trace.iter().position(|&(_, f)| f <= t) {
            Some(i) => println!(
                "  {name}: reached {t} at evaluation {} ({:.3} s)",
                i + 1,
                r.trace[i].0
            ),
            None => println!("  {name}: never reached {t}"),
        }
    }
    let multi = r.history.windows(2).filter(|w| w[1].0 - w[0].0 > 1).count();
    println!(
        "  {name}: {multi} of {} iterations needed more than one evaluation",
        r.history.len() - 1
    );
}

/// Time per L-BFGS iteration spent outside the objective (two-loop recursion,
/// line-search bookkeeping) for `n` parameters, on a quadratic that costs O(n) to evaluate.
fn optimiser_overhead(n: usize) {
    let h: Vec<f64> = (0..n)
        .map(|i| 1.0 + 1e4 * (i as f64 / n as f64).powi(4))
        .collect();
    let f = |x: &[f64], g: &mut [f64]| {
        let mut v = 0.0;
        for i in 0..n {
            g[i] = h[i] * x[i];
            v += 0.5 * h[i] * x[i] * x[i];
        }
        Some(v)
    };
    let x0 = vec![1.0; n];
    for memory in [10, 100, 200, 400] {
        let o = LbfgsOptions {
            memory,
            max_iter: 1000,
            max_evals: 100000,
            grad_tol: 0.0,
            value_tol: 0.0,
            ..Default::default()
        };
        let t = Instant::now();
        let r = gpdm::optim::lbfgs(f, &x0, &o);
        println!(
            "optimiser overhead, n = {n}, memory {memory}: {:.1} µs per iteration ({} iterations)",
            t.elapsed().as_secs_f64() * 1e6 / r.iterations.max(1) as f64,
            r.iterations
        );
    }
}

fn main() {
    let cli = Cli::parse();
    let first = cli.problem.clone();
    let seqs = if std::path::Path::new(&first).is_dir() {
        load_problem(std::path::Path::new(&first))
    } else {
        synthetic::synthetic(first.parse().expect("D or a problem directory"), 1e-3)
    };
    let config = GpdmConfig {
        dyn_noise_floor: Some(DYN_NOISE_FLOOR),
        ..GpdmConfig::default()
    };
    let m0 = Gpdm::new(&seqs, config).unwrap();
    let d_obs = m0.y.ncols();
    if let Some(dir) = &cli.export_dir {
        std::fs::create_dir_all(dir).unwrap();
        // Y row-major (N × D), θ0 as in Gpdm::theta (X column-major, then 3 + 4).
        let yt = m0.y.transpose();
        write_f64(&dir.join("y.f64"), yt.as_slice());
        write_f64(&dir.join("theta0.f64"), &m0.theta());
        let c = &m0.config;
        let meta = serde_json::json!({
            "n": m0.y.nrows(), "d_obs": d_obs, "latent_dim": c.latent_dim,
            "seq_lens": m0.seq_lens, "pose_noise_floor": c.pose_noise_floor.unwrap_or(0.0),
            "dyn_noise_floor": c.dyn_noise_floor.unwrap_or(0.0),
            "beta_log_sd": c.beta_log_sd.unwrap_or(0.0),
            "fixed_latent_scale": c.fixed_latent_scale,
            "first_point_var": c.first_point_var, "value_tol": VALUE_TOL, "grad_tol": GRAD_TOL,
        });
        std::fs::write(dir.join("meta.json"), meta.to_string()).unwrap();
    }
    let obj = m0.objective().unwrap();
    let th = m0.theta();
    let mut g = vec![0.0; th.len()];
    let t = Instant::now();
    let reps = 10;
    for _ in 0..reps {
        obj.eval(&th, Some(&mut g)).unwrap();
    }
    println!(
        "objective+gradient: {:.2} ms (N = {}, D = {d_obs})",
        t.elapsed().as_secs_f64() * 1e3 / reps as f64,
        m0.y.nrows()
    );
    if cli.overhead {
        optimiser_overhead(th.len());
    }
    let alternate = Schedule::Alternate {
        rounds: 10,
        iters: 200,
    };
    // (name, schedule, scaling, L-BFGS memory, value window). "joint" is gpdm-train's setting.
    let runs = [
        ("joint", Schedule::Joint, Scaling::Scalar, 100, 10),
        ("joint-m10", Schedule::Joint, Scaling::Scalar, 10, 1),
        (
            "joint-per-hyper",
            Schedule::Joint,
            Scaling::PerHyperparameter,
            100,
            10,
        ),
        ("alternate", alternate, Scaling::Scalar, 10, 1),
    ];
    for (name, schedule, scaling, memory, window) in runs {
        if !cli.runs.iter().any(|r| r == name) {
            continue;
        }
        let mut m = m0.clone();
        let t = Instant::now();
        let opts = TrainOptions {
            schedule,
            scaling,
            lbfgs: LbfgsOptions {
                max_iter: 10000,
                max_evals: 20000,
                grad_tol: GRAD_TOL,
                value_tol: VALUE_TOL,
                value_window: window,
                memory: cli.memory.unwrap_or(memory),
                ..Default::default()
            },
        };
        let r = if cli.in_pool {
            rayon::ThreadPoolBuilder::new()
                .build()
                .expect("pool")
                .install(|| train(&mut m, &opts))
                .unwrap()
        } else {
            train(&mut m, &opts).unwrap()
        };
        let secs = t.elapsed().as_secs_f64();
        let iters = r.history.len() - 1;
        if let Some(targets) = &cli.targets {
            report_targets(name, &r, targets);
        }
        println!(
            "{name}: {:.6} -> {:.6} in {iters} iterations, {} evals, {:.3} s; exits {:?}; alpha {:?} beta {:?}; jitter {:e}",
            r.initial_value, r.final_value, r.evaluations, secs, r.exits, m.alpha, m.beta, r.max_jitter
        );
        let mut gf = vec![0.0; th.len()];
        obj.eval(&m.theta(), Some(&mut gf)).unwrap();
        let nx = th.len() - 7;
        let gx = gf[..nx].iter().fold(0.0f64, |a, v| a.max(v.abs()));
        println!(
            "  final gradient: |X|inf {gx:.3e}, ln alpha {:?}, ln beta {:?}",
            &gf[nx..nx + 3],
            &gf[nx + 3..]
        );
        if let Some(dir) = &cli.export_dir {
            // Failed evaluations (non-finite) are left out: JSON has no infinity.
            let tr: Vec<String> = r
                .trace
                .iter()
                .filter(|(_, f)| f.is_finite())
                .map(|(t, f)| format!("[{t}, {f}]"))
                .collect();
            let path = dir.join(format!("rust_trace_{name}.json"));
            std::fs::write(path, format!("[{}]", tr.join(","))).unwrap();
        }
    }
}
