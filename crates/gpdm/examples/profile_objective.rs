//! Times the pieces of one objective+gradient evaluation at N = 446 (D irrelevant after Y Yᵀ),
//! each averaged over 20 repetitions.
use faer::Mat;
use gpdm::linalg::Cholesky;
use std::time::Instant;

fn time<T>(name: &str, mut f: impl FnMut() -> T) -> T {
    let mut out = f();
    let t = Instant::now();
    for _ in 0..20 {
        out = f();
    }
    println!("{name:12} {:.2} ms", t.elapsed().as_secs_f64() * 1e3 / 20.0);
    out
}

fn main() {
    let n = 446;
    let x = Mat::from_fn(n, 3, |i, j| ((i * 3 + j) as f64 * 0.37).sin() * 2.0);
    let k = gpdm::kernel::RbfLinear::pose([1.0, 1.0, 10.0]);
    let g = time("gram", || k.gram(x.as_ref()));
    let c = time("cholesky", || Cholesky::factor(g.k.as_ref(), "K").unwrap());
    let s = gpdm::linalg::mul_abt(x.as_ref(), x.as_ref());
    let b = time("trsm NxN", || {
        let mut b = s.clone();
        c.half_solve_in_place(b.as_mut());
        b
    });
    let q = time("sandwich", || c.sandwich(b.as_ref()));
    time("gradients", || k.gradients(&g, x.as_ref(), q.as_ref()));
    time("gemm NxN", || gpdm::linalg::mul(q.as_ref(), b.as_ref()));
}
