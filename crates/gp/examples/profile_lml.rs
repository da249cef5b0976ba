#[path = "../benches/synthetic_pairs.rs"]
mod synthetic_pairs;
use gp::kernel::Kernel;
use gp::linalg::Cholesky;
use std::time::Instant;
fn main() {
    faer::set_global_parallelism(faer::Par::Seq);
    for n in [350usize, 1100] {
        let p = synthetic_pairs::pairs(n, 7);
        let (x, y) = &p[0];
        let k = Kernel::neural_network(3.0, 1.5);
        let reps = 20;
        let t = Instant::now();
        for _ in 0..reps { std::hint::black_box(k.gram_with_grads(x)); }
        let tg = t.elapsed().as_secs_f64() / reps as f64;
        let (kk, dk) = k.gram_with_grads(x);
        let mut ky = kk.clone();
        for i in 0..n { ky[(i, i)] += 0.1; }
        let t = Instant::now();
        for _ in 0..reps { std::hint::black_box(Cholesky::new(&ky, "k", &mut vec![]).unwrap()); }
        let tc = t.elapsed().as_secs_f64() / reps as f64;
        let ch = Cholesky::new(&ky, "k", &mut vec![]).unwrap();
        let t = Instant::now();
        for _ in 0..reps { std::hint::black_box(ch.inverse_elements()); }
        let ti = t.elapsed().as_secs_f64() / reps as f64;
        let t = Instant::now();
        for _ in 0..reps { std::hint::black_box(ch.solve(y)); }
        let ts = t.elapsed().as_secs_f64() / reps as f64;
        let alpha = ch.solve(y);
        let t = Instant::now();
        for _ in 0..reps {
            let mut w = ch.inverse_elements();
            w.gemm(1.0, &alpha, &alpha.transpose(), 1.0);
            std::hint::black_box(dk.iter().map(|d| w.dot(d)).sum::<f64>());
        }
        let tw = t.elapsed().as_secs_f64() / reps as f64 - ti;
        let t = Instant::now();
        for _ in 0..reps { std::hint::black_box(gp::gpr::log_marginal_likelihood_grad(&k, 0.1, false, x, y, &mut vec![]).unwrap()); }
        let tt = t.elapsed().as_secs_f64() / reps as f64;
        println!("n {n}: gram+grads {:.2} ms, chol {:.2} ms, inverse {:.2} ms, solve {:.2} ms, W+contract {:.2} ms, total lml_grad {:.2} ms",
            tg*1e3, tc*1e3, ti*1e3, ts*1e3, tw*1e3, tt*1e3);
    }
}
