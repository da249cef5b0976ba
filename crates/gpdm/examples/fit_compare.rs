//! Fits the GPDM (gpdm-train's model: pose-noise floor 1e-6, dynamics-noise floor 1e-3, weak
//! log-normal factor on β1..β3) with several optimiser settings, each stopping by convergence
//! (value or gradient tolerance), and prints objective, iterations, evaluations, time and
//! hyperparameters; optionally exports the problem and the traces for
//! `scripts/compare/gpdm_scipy.py`.
//!
//! Usage: fit_compare [D=2000 | PROBLEM_DIR] [export_dir]
//! PROBLEM_DIR holds y.f64 (row-major N × D little-endian f64) and meta.json with "n", "d_obs"
//! and "seq_lens" (e.g. a body part exported by `variation`'s `export_part` example).
//! RUNS=joint,joint-m10,joint-per-hyper,alternate selects the runs (default joint,joint-m10);
//! MEMORY=k overrides their L-BFGS memory; TARGETS=f1,f2 prints the evaluation at which each
//! objective value was first reached; OVERHEAD=1 times the optimiser's own work per iteration.
//! e.g.: OPENBLAS_NUM_THREADS=1 target/release/examples/fit_compare 15000 /tmp/gpdm_problem

use gpdm::optim::{train, LbfgsOptions, Scaling, Schedule, TrainOptions};
use gpdm::{Gpdm, GpdmConfig};
use std::time::Instant;

#[path = "common/problem.rs"]
mod problem;
#[path = "common/synthetic.rs"]
mod synthetic;
use problem::load_problem;

/// Convergence tolerances shared with scipy (written to meta.json).
const VALUE_TOL: f64 = 1e-10;
const GRAD_TOL: f64 = 1e-3;
/// gpdm-train's dynamics-noise floor (variation::train::DYN_NOISE_FLOOR).
const DYN_NOISE_FLOOR: f64 = 1e-3;

fn write_f64(path: &std::path::Path, v: &[f64]) {
    let bytes: Vec<u8> = v.iter().flat_map(|x| x.to_le_bytes()).collect();
    std::fs::write(path, bytes).unwrap();
}

/// TARGETS=f1,f2,...: prints the evaluation at which the objective first reached each value
/// (deterministic, unlike times), and how many iterations needed more than one evaluation.
fn report_targets(name: &str, r: &gpdm::optim::TrainReport) {
    let Ok(targets) = std::env::var("TARGETS") else {
        return;
    };
    for t in targets
        .split(',')
        .map(|v| v.parse::<f64>().expect("TARGETS"))
    {
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

/// OVERHEAD=1: time per L-BFGS iteration spent outside the objective (two-loop recursion,
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
    let args: Vec<String> = std::env::args().collect();
    let first = args.get(1).cloned().unwrap_or_else(|| "2000".into());
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
    if let Some(dir) = args.get(2) {
        let dir = std::path::Path::new(dir);
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
    if std::env::var("OVERHEAD").is_ok() {
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
    let wanted = std::env::var("RUNS").unwrap_or_else(|_| "joint,joint-m10".into());
    for (name, schedule, scaling, memory, window) in runs {
        if !wanted.split(',').any(|r| r == name) {
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
                // MEMORY overrides the memory of every run (experiments).
                memory: std::env::var("MEMORY").map_or(memory, |v| v.parse().expect("MEMORY")),
                ..Default::default()
            },
        };
        // IN_POOL=1: train from inside a rayon worker (as gpdm-train's per-part par_iter does).
        let r = if std::env::var("IN_POOL").is_ok_and(|v| v == "1") {
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
        report_targets(name, &r);
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
        if let Some(dir) = args.get(2) {
            // Failed evaluations (non-finite) are left out: JSON has no infinity.
            let tr: Vec<String> = r
                .trace
                .iter()
                .filter(|(_, f)| f.is_finite())
                .map(|(t, f)| format!("[{t}, {f}]"))
                .collect();
            let path = std::path::Path::new(dir).join(format!("rust_trace_{name}.json"));
            std::fs::write(path, format!("[{}]", tr.join(","))).unwrap();
        }
    }
}
