//! Times the pieces of one objective+gradient evaluation at N = 446 (D irrelevant after Y Yᵀ).
use faer::Mat;
use gpdm::linalg::Cholesky;
use std::time::Instant;

fn main() {
    let n = 446;
    let x = Mat::from_fn(n, 3, |i, j| ((i * 3 + j) as f64 * 0.37).sin() * 2.0);
    let k = gpdm::kernel::RbfLinear::pose([1.0, 1.0, 10.0]);
    let t = Instant::now();
    let g = k.gram(x.as_ref());
    println!("gram {:.2} ms", t.elapsed().as_secs_f64() * 1e3);
    let t = Instant::now();
    let c = Cholesky::factor(g.k.as_ref(), "K").unwrap();
    println!("chol {:.2} ms", t.elapsed().as_secs_f64() * 1e3);
    let s = gpdm::linalg::mul_abt(x.as_ref(), x.as_ref());
    let t = Instant::now();
    let mut b = s.clone();
    c.half_solve_in_place(b.as_mut());
    println!("trsm NxN {:.2} ms", t.elapsed().as_secs_f64() * 1e3);
    let t = Instant::now();
    let q = c.sandwich(b.as_ref());
    println!("sandwich {:.2} ms", t.elapsed().as_secs_f64() * 1e3);
    let t = Instant::now();
    let _ = k.x_grad(&g, x.as_ref(), q.as_ref());
    println!("x_grad {:.2} ms", t.elapsed().as_secs_f64() * 1e3);
    let t = Instant::now();
    let _ = k.param_grads(&g, x.as_ref(), q.as_ref());
    println!("param_grads {:.2} ms", t.elapsed().as_secs_f64() * 1e3);
    let t = Instant::now();
    let _ = gpdm::linalg::mul(q.as_ref(), b.as_ref());
    println!("gemm NxN {:.2} ms", t.elapsed().as_secs_f64() * 1e3);
}
