//! Splits the cost of one HMC energy+gradient evaluation (100-frame trajectory, M = 442
//! training transitions) into its two triangular solves and the rest; averages of 200 runs.
//!
//! Usage: profile_energy

use clap::Parser;
use studies::synthetic;

use faer::Mat;
use gpdm::hmc::{Energy, TrajectoryEnergy};
use gpdm::optim::{train, LbfgsOptions, TrainOptions};
use gpdm::predict::Predictor;
use gpdm::{Gpdm, GpdmConfig};
use std::time::Instant;

/// Splits the cost of one HMC energy+gradient evaluation into its two triangular solves and the
/// rest.
#[derive(Parser)]
struct Cli {
    /// `gemm`: the GEMM throughput of the bulk decoder's shape instead.
    mode: Option<String>,
}

fn main() {
    if Cli::parse().mode.as_deref() == Some("gemm") {
        gemm_shapes();
        return;
    }
    let mut m = Gpdm::new(&synthetic::synthetic(30, 1e-3), GpdmConfig::default()).unwrap();
    let opts = TrainOptions {
        lbfgs: LbfgsOptions {
            max_iter: 100,
            ..Default::default()
        },
        ..Default::default()
    };
    train(&mut m, &opts).unwrap();
    let pred = Predictor::new(&m).unwrap();
    let template = m.sequence_latent(0).unwrap().rows(0, 100).into_owned();
    let x1: Vec<f64> = template.row(0).iter().copied().collect();
    let e = TrajectoryEnergy::new(&pred, &x1, 100).unwrap();
    let q = e.free_coords(&template);
    let mut g = vec![0.0; q.len()];
    let reps = 200;
    let t = Instant::now();
    for _ in 0..reps {
        std::hint::black_box(e.energy_grad(&q, &mut g));
    }
    let total = t.elapsed().as_secs_f64() * 1e3 / reps as f64;
    let chol = pred.dynamics_cholesky();
    let mmat = pred.dynamics_inputs().nrows();
    let rhs = Mat::from_fn(mmat, 99, |i, j| ((i * 7 + j * 3) as f64).sin());
    let t = Instant::now();
    for _ in 0..reps {
        let mut v = rhs.clone();
        chol.half_solve_in_place(v.as_mut());
        chol.half_solve_t_in_place(v.as_mut());
        std::hint::black_box(&v);
    }
    let solves = t.elapsed().as_secs_f64() * 1e3 / reps as f64;
    println!(
        "energy+gradient {total:.3} ms; of which two triangular solves ({mmat} x {mmat}, 99 rhs) {solves:.3} ms, rest {:.3} ms",
        total - solves
    );
}

/// GEMM throughput of the bulk decoder's shape: (D × R) · (R × T), D = 19282, R = 113, T = 100,
/// sequential, with the basis column-major (as stored) and row-major (transposed view).
#[allow(dead_code)]
fn gemm_shapes() {
    use faer::linalg::matmul::matmul;
    use faer::{Accum, Par};
    let (d, r, t) = (19282usize, 113usize, 100usize);
    let b = Mat::from_fn(d, r, |i, j| ((i * 3 + j * 7) as f64).sin());
    let bt = Mat::from_fn(r, d, |j, i| b[(i, j)]);
    let c = Mat::from_fn(r, t, |i, j| ((i + 2 * j) as f64).cos());
    let mut out = Mat::<f64>::zeros(d, t);
    let flops = 2.0 * (d * r * t) as f64;
    for (name, lhs) in [
        ("col-major", b.as_ref()),
        ("row-major view", bt.as_ref().transpose()),
    ] {
        let reps = 20;
        let st = Instant::now();
        for _ in 0..reps {
            matmul(out.as_mut(), Accum::Replace, lhs, c.as_ref(), 1.0, Par::Seq);
        }
        let s = st.elapsed().as_secs_f64() / reps as f64;
        println!(
            "GEMM {d}x{r} * {r}x{t} ({name}): {:.1} ms, {:.1} GFLOPS",
            s * 1e3,
            flops / s / 1e9
        );
    }
}
