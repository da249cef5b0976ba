//! Fits the GPDM on a synthetic 446-frame problem with both optimisation schedules, prints
//! objective, evaluations, time and hyperparameters; optionally exports the problem for
//! `scripts/compare/gpdm_scipy.py`.
//!
//! Usage: fit_compare [D=2000] [export_dir]
//! e.g.: OPENBLAS_NUM_THREADS=1 target/release/examples/fit_compare 15000 /tmp/gpdm_problem

use gpdm::optim::{train, LbfgsOptions, Schedule, TrainOptions};
use gpdm::{Gpdm, GpdmConfig};
use std::time::Instant;

#[path = "common/synthetic.rs"]
mod synthetic;

fn write_f64(path: &std::path::Path, v: &[f64]) {
    let bytes: Vec<u8> = v.iter().flat_map(|x| x.to_le_bytes()).collect();
    std::fs::write(path, bytes).unwrap();
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let d_obs: usize = args.get(1).map(|s| s.parse().expect("D")).unwrap_or(2000);
    let m0 = Gpdm::new(&synthetic::synthetic(d_obs, 1e-3), GpdmConfig::default()).unwrap();
    if let Some(dir) = args.get(2) {
        let dir = std::path::Path::new(dir);
        std::fs::create_dir_all(dir).unwrap();
        // Y row-major (N × D), θ0 as in Gpdm::theta (X column-major, then 3 + 4).
        let yt = m0.y.transpose();
        write_f64(&dir.join("y.f64"), yt.as_slice());
        write_f64(&dir.join("theta0.f64"), &m0.theta());
        let meta = format!(
            "{{\"n\": {}, \"d_obs\": {}, \"latent_dim\": {}, \"seq_lens\": {:?}, \"pose_noise_floor\": {}, \"first_point_var\": {}}}",
            m0.y.nrows(), d_obs, m0.config.latent_dim, m0.seq_lens,
            m0.config.pose_noise_floor.unwrap_or(0.0), m0.config.first_point_var
        );
        std::fs::write(dir.join("meta.json"), meta).unwrap();
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
    let schedules = [
        ("joint", Schedule::Joint),
        (
            "alternate",
            Schedule::Alternate {
                rounds: 10,
                iters: 50,
            },
        ),
    ];
    for (name, schedule) in schedules {
        let mut m = m0.clone();
        let t = Instant::now();
        let opts = TrainOptions {
            schedule,
            lbfgs: LbfgsOptions {
                max_iter: 1000,
                max_evals: 3000,
                ..Default::default()
            },
        };
        let r = train(&mut m, &opts).unwrap();
        let secs = t.elapsed().as_secs_f64();
        println!(
            "{name}: {:.6} -> {:.6} in {} evals, {:.2} s; exits {:?}; alpha {:?} beta {:?}; jitter {:e}",
            r.initial_value, r.final_value, r.evaluations, secs, r.exits.last().unwrap(), m.alpha, m.beta, r.max_jitter
        );
        // Time to reach within 1e-6 relative of the final value.
        let target = r.final_value + 1e-6 * r.final_value.abs();
        if let Some(&(e, _)) = r.history.iter().find(|h| h.1 <= target) {
            println!("  reached final value (1e-6 rel) after {e} evals");
        }
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
