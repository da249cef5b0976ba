//! Times the pieces of one objective+gradient evaluation at N = 446 (D irrelevant after Y Yᵀ),
//! each averaged over 20 repetitions; then compares faer with the system OpenBLAS (single
//! thread, `openblas_set_num_threads(1)`) on the pose term's dense sequence at N = 192 and 446:
//! `potrf`, `L⁻¹ S L⁻ᵀ` (two `trsm`, N right-hand sides), the sandwich `L⁻ᵀ Q L⁻¹` (two
//! more `trsm`), and an N×N `gemm` for reference. Interleaved repetitions, medians.
//! Last, the whole objective+gradient (synthetic N = 446, D = 15000) on a rayon pool of 1
//! and of 2 threads, interleaved (the pose and dynamics terms are `rayon::join`ed).
//!
//! `target/release/examples/profile_objective [objective-only]` (built by `cargo test --release
//! -p gpdm`; `objective-only` runs just the last part, longer, e.g. under `perf record`).
#[path = "common/synthetic.rs"]
mod synthetic;

use faer::Mat;
use gpdm::linalg::Cholesky;
use gpdm::{Gpdm, GpdmConfig};
use std::os::raw::{c_char, c_int};
use std::time::Instant;

#[link(name = "openblas")]
extern "C" {
    fn openblas_set_num_threads(n: c_int);
    fn dpotrf_(
        uplo: *const c_char,
        n: *const c_int,
        a: *mut f64,
        lda: *const c_int,
        info: *mut c_int,
    );
    #[allow(clippy::too_many_arguments)]
    fn dtrsm_(
        side: *const c_char,
        uplo: *const c_char,
        transa: *const c_char,
        diag: *const c_char,
        m: *const c_int,
        n: *const c_int,
        alpha: *const f64,
        a: *const f64,
        lda: *const c_int,
        b: *mut f64,
        ldb: *const c_int,
    );
    #[allow(clippy::too_many_arguments)]
    fn dgemm_(
        ta: *const c_char,
        tb: *const c_char,
        m: *const c_int,
        n: *const c_int,
        k: *const c_int,
        alpha: *const f64,
        a: *const f64,
        lda: *const c_int,
        b: *const f64,
        ldb: *const c_int,
        beta: *const f64,
        c: *mut f64,
        ldc: *const c_int,
    );
}

fn time<T>(name: &str, mut f: impl FnMut() -> T) -> T {
    let mut out = f();
    let t = Instant::now();
    for _ in 0..20 {
        out = f();
    }
    println!("{name:12} {:.2} ms", t.elapsed().as_secs_f64() * 1e3 / 20.0);
    out
}

/// Column-major n×n buffer (lda = n) copied from a faer matrix.
fn dense(m: &Mat<f64>) -> Vec<f64> {
    let n = m.nrows();
    let mut v = vec![0.0; n * m.ncols()];
    for j in 0..m.ncols() {
        for i in 0..n {
            v[i + j * n] = m[(i, j)];
        }
    }
    v
}

/// Which sub-step of the pose term to time.
#[derive(Clone, Copy)]
enum Step {
    Potrf,
    Cmat,
    Sandwich,
    Gemm,
    All,
}

fn faer_step(step: Step, k: &Mat<f64>, s: &Mat<f64>, ch: &Cholesky) -> f64 {
    match step {
        Step::Potrf => Cholesky::factor(k.as_ref(), "K").unwrap().l[(0, 0)],
        Step::Cmat => {
            let mut c = s.clone();
            ch.half_solve_in_place(c.as_mut());
            ch.half_solve_in_place(c.as_mut().transpose_mut());
            c[(0, 0)]
        }
        Step::Sandwich => ch.sandwich(s.as_ref())[(0, 0)],
        Step::Gemm => gpdm::linalg::mul(k.as_ref(), s.as_ref())[(0, 0)],
        Step::All => {
            let ch = Cholesky::factor(k.as_ref(), "K").unwrap();
            let mut c = s.clone();
            ch.half_solve_in_place(c.as_mut());
            ch.half_solve_in_place(c.as_mut().transpose_mut());
            ch.sandwich(c.as_ref())[(0, 0)]
        }
    }
}

fn blas_step(step: Step, n: usize, k: &[f64], s: &[f64], l: &[f64]) -> f64 {
    let ni = n as c_int;
    let one = 1.0f64;
    let zero = 0.0f64;
    let (cl, cr, cn, ct) = (
        b'L' as c_char,
        b'R' as c_char,
        b'N' as c_char,
        b'T' as c_char,
    );
    // SAFETY: all buffers are n×n column-major with lda = n, as the BLAS calls state.
    unsafe {
        let potrf = |a: &mut Vec<f64>| {
            let mut info = 0;
            dpotrf_(&cl, &ni, a.as_mut_ptr(), &ni, &mut info);
            assert_eq!(info, 0);
        };
        let trsm = |side, trans, a: &[f64], b: &mut Vec<f64>| {
            dtrsm_(
                &side,
                &cl,
                &trans,
                &cn,
                &ni,
                &ni,
                &one,
                a.as_ptr(),
                &ni,
                b.as_mut_ptr(),
                &ni,
            )
        };
        match step {
            Step::Potrf => {
                let mut a = k.to_vec();
                potrf(&mut a);
                a[0]
            }
            Step::Cmat => {
                let mut c = s.to_vec();
                trsm(cl, cn, l, &mut c); // L⁻¹ S
                trsm(cr, ct, l, &mut c); // (L⁻¹ S) L⁻ᵀ
                c[0]
            }
            Step::Sandwich => {
                let mut c = s.to_vec();
                trsm(cl, ct, l, &mut c); // L⁻ᵀ Q
                trsm(cr, cn, l, &mut c); // (L⁻ᵀ Q) L⁻¹
                c[0]
            }
            Step::Gemm => {
                let mut c = vec![0.0; n * n];
                dgemm_(
                    &cn,
                    &cn,
                    &ni,
                    &ni,
                    &ni,
                    &one,
                    k.as_ptr(),
                    &ni,
                    s.as_ptr(),
                    &ni,
                    &zero,
                    c.as_mut_ptr(),
                    &ni,
                );
                c[0]
            }
            Step::All => {
                let mut a = k.to_vec();
                potrf(&mut a);
                let mut c = s.to_vec();
                trsm(cl, cn, &a, &mut c);
                trsm(cr, ct, &a, &mut c);
                trsm(cl, ct, &a, &mut c);
                trsm(cr, cn, &a, &mut c);
                c[0]
            }
        }
    }
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(|a, b| a.total_cmp(b));
    v[v.len() / 2]
}

fn compare(n: usize, reps: usize) {
    let x = Mat::from_fn(n, 3, |i, j| ((i * 3 + j) as f64 * 0.37).sin() * 2.0);
    let kern = gpdm::kernel::RbfLinear::pose([1.0, 1.0, 10.0]);
    let k = kern.gram(x.as_ref()).k;
    // A dense symmetric right-hand side of full rank (S = Y Yᵀ with D > N in the objective).
    let y = Mat::from_fn(n, n + 7, |i, j| {
        (((i * 31 + j * 17) % 101) as f64 / 50.0 - 1.0) + 0.1 * ((i + j) as f64).cos()
    });
    let s = gpdm::linalg::mul_abt(y.as_ref(), y.as_ref());
    let ch = Cholesky::factor(k.as_ref(), "K").unwrap();
    let (kd, sd, ld) = (dense(&k), dense(&s), dense(&ch.l));
    let n3 = (n as f64).powi(3);
    println!("N = {n} ({reps} interleaved repetitions, medians; G = 1e9 multiply-adds/s)");
    for (name, step, madds) in [
        ("potrf", Step::Potrf, n3 / 6.0),
        ("L⁻¹SL⁻ᵀ", Step::Cmat, n3),
        ("sandwich", Step::Sandwich, n3),
        ("gemm NxN", Step::Gemm, n3),
        ("pose seq", Step::All, n3 * (2.0 + 1.0 / 6.0)),
    ] {
        let (mut tf, mut tb) = (Vec::new(), Vec::new());
        let mut sink = 0.0;
        for _ in 0..reps {
            let t = Instant::now();
            sink += faer_step(step, &k, &s, &ch);
            tf.push(t.elapsed().as_secs_f64());
            let t = Instant::now();
            sink += blas_step(step, n, &kd, &sd, &ld);
            tb.push(t.elapsed().as_secs_f64());
        }
        let (mf, mb) = (median(tf), median(tb));
        println!(
            "  {name:10} faer {:7.3} ms ({:5.1} G)   openblas {:7.3} ms ({:5.1} G)   faer/openblas {:.2}   [{}]",
            mf * 1e3,
            madds / mf / 1e9,
            mb * 1e3,
            madds / mb / 1e9,
            mf / mb,
            if sink.is_finite() { "ok" } else { "nan" }
        );
    }
}

fn main() {
    // SAFETY: plain FFI call; pins OpenBLAS to the calling thread's single core.
    unsafe { openblas_set_num_threads(1) };
    faer::set_global_parallelism(faer::Par::Seq);
    if std::env::args().nth(1).as_deref() == Some("objective-only") {
        // For `perf record`: only the interleaved objective timing.
        objective_threads(201);
        return;
    }
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
    println!();
    for n in [192, 446] {
        compare(n, if n < 300 { 101 } else { 41 });
    }
    objective_threads(41);
}

fn objective_threads(reps: usize) {
    let m = Gpdm::new(&synthetic::synthetic(15000, 1e-3), GpdmConfig::default()).unwrap();
    let obj = m.objective().unwrap();
    let th = m.theta();
    let mut g = vec![0.0; th.len()];
    let pools: Vec<_> = [1, 2]
        .map(|t| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(t)
                .build()
                .unwrap()
        })
        .into();
    let mut times = [Vec::new(), Vec::new()];
    for _ in 0..reps {
        for (p, pool) in pools.iter().enumerate() {
            let t = Instant::now();
            pool.install(|| obj.eval(&th, Some(&mut g)).unwrap());
            times[p].push(t.elapsed().as_secs_f64());
        }
    }
    let [t1, t2] = times.map(median);
    println!(
        "objective+gradient N=446 D=15000 ({reps} interleaved, medians): 1 thread {:.2} ms, 2 threads {:.2} ms",
        t1 * 1e3,
        t2 * 1e3
    );
}
