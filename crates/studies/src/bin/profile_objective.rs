//! Times the pieces of one objective+gradient evaluation at N = 446 (D irrelevant after Y Yᵀ),
//! each averaged over 20 repetitions; then compares faer with the system OpenBLAS (single
//! thread, `openblas_set_num_threads(1)`) on the pose term's dense sequence at N = 192 and 446:
//! `potrf`, `L⁻¹ S L⁻ᵀ` (two `trsm`, N right-hand sides), the sandwich `L⁻ᵀ Q L⁻¹` (two
//! more `trsm`), and an N×N `gemm` for reference. Interleaved repetitions, medians.
//! Last, the whole objective+gradient (synthetic N = 446, D = 15000) on a rayon pool of 1
//! and of 2 threads, interleaved (the pose and dynamics terms are `rayon::join`ed).
//!
//! Then the reduced-flop pieces of the pose term against the dense ones, and the whole
//! objective+gradient `eval` against `eval_reference` (the dense algebra), interleaved,
//! on 1- and 2-thread pools.
//!
//! The pieces also time `RbfLinear::gram`/`gradients` against copies of their earlier
//! versions (`gram_h23`, `gradients_h23`: row-major, libm `exp`, scalar pair loops).
//!
//! `target/release/profile_objective [objective-only | old-new [PROBLEM_DIR...]]`
//! (built by `cargo build --release -p studies`; `objective-only` runs just the 1-vs-2-thread
//! part, longer, e.g. under `perf record`; `old-new` just the old-vs-new comparison on the
//! synthetic problem, or with directories only on those exported problems, e.g. /tmp/problems/leg_l,
//! see `fit_compare`).
use studies::gpdm_problem as problem;
use studies::synthetic;

use faer::{Mat, MatRef};
use gpdm::kernel::{Gram, RbfLinear};
use gpdm::linalg::{Cholesky, CholeskyProducts};
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

/// `eval` vs `eval_reference` (dense algebra), objective+gradient at the PCA start,
/// interleaved on 1- and 2-thread pools; medians.
fn old_new(name: &str, seqs: &[nalgebra::DMatrix<f64>], reps: usize) {
    let config = GpdmConfig {
        dyn_noise_floor: Some(1e-3),
        ..GpdmConfig::default()
    };
    let m = Gpdm::new(seqs, config).unwrap();
    let obj = m.objective().unwrap();
    let th = m.theta();
    let mut g = vec![0.0; th.len()];
    let pools = one_and_two_thread_pools();
    let mut times = vec![Vec::new(); 4];
    for _ in 0..reps {
        for (p, pool) in pools.iter().enumerate() {
            let t = Instant::now();
            pool.install(|| obj.eval_reference(&th, Some(&mut g)).unwrap());
            times[2 * p].push(t.elapsed().as_secs_f64());
            let t = Instant::now();
            pool.install(|| obj.eval(&th, Some(&mut g)).unwrap());
            times[2 * p + 1].push(t.elapsed().as_secs_f64());
        }
    }

    let t: Vec<f64> = times.into_iter().map(median).collect();
    let e = obj.eval(&th, None).unwrap();
    println!(
        "{name}: N = {} D = {} rank(YYᵀ) = {} jitter K_Y {:e} K_X {:e} ({reps} interleaved, medians)\n  \
         1 thread: old {:.3} ms new {:.3} ms (old/new {:.2})   \
         2 threads: old {:.3} ms new {:.3} ms (old/new {:.2})",
        m.x.nrows(),
        m.y.ncols(),
        obj.s_rank(),
        e.jitter_y,
        e.jitter_x,
        t[0] * 1e3,
        t[1] * 1e3,
        t[0] / t[1],
        t[2] * 1e3,
        t[3] * 1e3,
        t[2] / t[3]
    );
}

/// The earlier `RbfLinear::gram` (row-major coordinates, libm `exp`, one element at a time),
/// kept here as the "old" side of the piece timings.
fn gram_h23(kern: &RbfLinear, x: MatRef<'_, f64>) -> Gram {
    let n = x.nrows();
    let d = x.ncols();
    if d == 0 {
        // No coordinates: every distance and dot product is 0.
        return gram_h23(kern, Mat::<f64>::zeros(n, 1).as_ref());
    }
    let rows: Vec<f64> = (0..n)
        .flat_map(|i| (0..d).map(move |c| x[(i, c)]))
        .collect();
    let mut rbf = Mat::<f64>::zeros(n, n);
    let mut k = Mat::<f64>::zeros(n, n);
    let half_gamma = -0.5 * kern.gamma;
    let noise = 1.0 / kern.prec;
    for j in 0..n {
        let xj = &rows[j * d..(j + 1) * d];
        let rcol = &mut rbf
            .col_mut(j)
            .try_as_col_major_mut()
            .expect("contiguous")
            .as_slice_mut()[j..];
        let kcol = &mut k
            .col_mut(j)
            .try_as_col_major_mut()
            .expect("contiguous")
            .as_slice_mut()[j..];
        // One pass: squared distance, RBF value and (optionally) the linear term.
        for ((r, kv), xi) in rcol
            .iter_mut()
            .zip(kcol.iter_mut())
            .zip(rows[j * d..].chunks_exact(d))
        {
            let (mut s, mut dot) = (0.0, 0.0);
            for (a, b) in xi.iter().zip(xj) {
                s += (a - b) * (a - b);
                dot += a * b;
            }
            let arg = half_gamma * s;
            // exp underflows below −745; returning 0 early avoids subnormal arithmetic.
            *r = if arg > -700.0 {
                kern.var * arg.exp()
            } else {
                0.0
            };
            *kv = *r + kern.lin * dot;
        }
        kcol[0] += noise;
    }
    Gram { k, rbf }
}

/// The earlier `RbfLinear::gradients` (row-major, scalar pair loop).
fn gradients_h23(
    k: &RbfLinear,
    gram: &Gram,
    x: MatRef<'_, f64>,
    g: MatRef<'_, f64>,
) -> ([f64; 4], Mat<f64>) {
    let n = g.nrows();
    let d = x.ncols();
    if d == 0 {
        // No coordinates: same kernel as one all-zero coordinate; no X gradient.
        let (p, _) = gradients_h23(k, gram, Mat::<f64>::zeros(n, 1).as_ref(), g);
        return (p, Mat::zeros(n, 0));
    }
    let rows: Vec<f64> = (0..n)
        .flat_map(|i| (0..d).map(move |c| x[(i, c)]))
        .collect();
    let mut dx = vec![0.0; n * d];
    let (mut gv, mut gg, mut gl, mut tr) = (0.0, 0.0, 0.0, 0.0);
    let two_gamma = 2.0 * k.gamma;
    for j in 0..n {
        let gcol = &g.col(j).try_as_col_major().expect("contiguous").as_slice()[j..];
        let rcol = &gram
            .rbf
            .col(j)
            .try_as_col_major()
            .expect("contiguous")
            .as_slice()[j..];
        let gjj = gcol[0];
        tr += gjj;
        gv += gjj * rcol[0];
        let xj = &rows[j * d..(j + 1) * d];
        let (lo, hi) = dx.split_at_mut((j + 1) * d);
        let dxj = &mut lo[j * d..];
        for (((gij, r), xi), dxi) in gcol[1..]
            .iter()
            .zip(&rcol[1..])
            .zip(rows[(j + 1) * d..].chunks_exact(d))
            .zip(hi.chunks_exact_mut(d))
        {
            let (mut s, mut dot) = (0.0, 0.0);
            for (a, b) in xi.iter().zip(xj) {
                s += (a - b) * (a - b);
                dot += a * b;
            }
            // Off-diagonal pairs count twice (G and K symmetric).
            gv += 2.0 * gij * r;
            gg -= gij * r * s;
            gl += 2.0 * gij * dot;
            let p = two_gamma * gij * r;
            let l = 2.0 * k.lin * gij;
            for c in 0..d {
                let (a, b) = (xi[c], xj[c]);
                dxi[c] += -p * (a - b) + l * b;
                dxj[c] += -p * (b - a) + l * a;
            }
        }
        // Diagonal: K_jj = var + lin ‖x_j‖² + 1/prec.
        let mut dot = 0.0;
        for c in 0..d {
            let a = rows[j * d + c];
            dot += a * a;
            dx[j * d + c] += 2.0 * k.lin * gjj * a;
        }
        gl += gjj * dot;
    }
    let dxm = Mat::from_fn(n, d, |i, c| dx[i * d + c]);
    ([gv / k.var, gg, gl, -tr / (k.prec * k.prec)], dxm)
}

/// The pose term's dense steps vs the reduced ones, one thread, interleaved, medians.
fn pieces(n: usize, d_obs: usize, reps: usize) {
    let x = Mat::from_fn(n, 3, |i, j| ((i * 3 + j) as f64 * 0.37).sin() * 2.0);
    let kern = gpdm::kernel::RbfLinear::pose([1.0, 1.0, 10.0]);
    let gram = kern.gram(x.as_ref());
    let k = gram.k.clone();
    // Pseudo-random Y with D > N: S = Y Yᵀ of full rank, the worst case.
    let y = Mat::from_fn(n, d_obs, |i, j| {
        (((i * d_obs + j) as f64 * 12.9898).sin() * 43758.5453).fract()
    });
    let s = gpdm::linalg::mul_abt(y.as_ref(), y.as_ref());
    let t = Instant::now();
    let pc = gpdm::linalg::PivotedCholesky::factor(s.as_ref());
    let t_pc = t.elapsed().as_secs_f64();
    let ch = Cholesky::factor(k.as_ref(), "K").unwrap();
    let mut c = s.clone();
    ch.half_solve_in_place(c.as_mut());
    ch.half_solve_in_place(c.as_mut().transpose_mut());
    let z = ch.half_solve_trapezoidal(pc.r.as_ref());
    let mut sink = 0.0;
    let mut steps: Vec<(&str, Box<dyn FnMut() -> f64 + '_>)> = vec![
        (
            "old C=L⁻¹SL⁻ᵀ",
            Box::new(|| {
                let mut c = s.clone();
                ch.half_solve_in_place(c.as_mut());
                ch.half_solve_in_place(c.as_mut().transpose_mut());
                c[(0, 0)]
            }),
        ),
        (
            "new Z=L⁻¹R",
            Box::new(|| ch.half_solve_trapezoidal(pc.r.as_ref())[(0, 0)]),
        ),
        (
            "new Z, block 64",
            Box::new(|| ch.half_solve_trapezoidal_blocked(pc.r.as_ref(), 64)[(0, 0)]),
        ),
        (
            "new Z, block 96",
            Box::new(|| ch.half_solve_trapezoidal_blocked(pc.r.as_ref(), 96)[(0, 0)]),
        ),
        (
            "new Z, block 128",
            Box::new(|| ch.half_solve_trapezoidal_blocked(pc.r.as_ref(), 128)[(0, 0)]),
        ),
        (
            "new low(ZZᵀ)",
            Box::new(|| gpdm::linalg::lower_zzt(z.as_ref())[(n - 1, 0)]),
        ),
        ("old sandwich", Box::new(|| ch.sandwich(c.as_ref())[(0, 0)])),
        (
            "new sandwich_lower",
            Box::new(|| ch.sandwich_lower(c.clone())[(0, 0)]),
        ),
        // Non-GEMM per-term costs for scale: the Gram matrix (N²/2 scalar `exp`) and the
        // kernel chain rule, and N²/2 calls of libm `exp` vs the vectorisable `exp_fast`.
        ("gram", Box::new(|| kern.gram(x.as_ref()).k[(0, 0)])),
        (
            "gram pre-h24",
            Box::new(|| gram_h23(&kern, x.as_ref()).k[(0, 0)]),
        ),
        (
            "gradients",
            Box::new(|| kern.gradients(&gram, x.as_ref(), c.as_ref()).0[0]),
        ),
        (
            "gradients pre-h24",
            Box::new(|| gradients_h23(&kern, &gram, x.as_ref(), c.as_ref()).0[0]),
        ),
        (
            "2 Mat::zeros N×N",
            Box::new(|| {
                let (a, b) = (Mat::<f64>::zeros(n, n), Mat::<f64>::zeros(n, n));
                a[(n - 1, 0)] + b[(0, n - 1)]
            }),
        ),
        (
            "N²/2 libm exp",
            Box::new(|| {
                (0..n * (n + 1) / 2)
                    .map(|i| (-(i as f64) * 1e-5).exp())
                    .sum::<f64>()
            }),
        ),
        (
            "N²/2 exp_fast",
            Box::new(|| {
                (0..n * (n + 1) / 2)
                    .map(|i| gpdm::vexp::exp_fast(-(i as f64) * 1e-5))
                    .sum::<f64>()
            }),
        ),
    ];
    let mut times = vec![Vec::new(); steps.len()];
    for _ in 0..reps {
        for (i, (_, f)) in steps.iter_mut().enumerate() {
            let t = Instant::now();
            sink += f();
            times[i].push(t.elapsed().as_secs_f64());
        }
    }
    println!(
        "pose-term pieces, N = {n}, rank(S) = {} ({reps} interleaved, medians, one thread; \
         pivoted Cholesky of S, once per model: {:.2} ms):",
        pc.r.ncols(),
        t_pc * 1e3
    );
    for ((name, _), t) in steps.iter().zip(times) {
        println!("  {name:20} {:.3} ms", median(t) * 1e3);
    }
    assert!(sink.is_finite());
    drop(steps);
    let (old, new) = (gram_h23(&kern, x.as_ref()).k, kern.gram(x.as_ref()).k);
    let diff = (0..n)
        .flat_map(|j| (j..n).map(move |i| (i, j)))
        .map(|(i, j)| (old[(i, j)] - new[(i, j)]).abs())
        .fold(0.0, f64::max);
    assert!(
        diff < 1e-12,
        "gram differs from the pre-h24 one by {diff:e}"
    );
}

/// Times the pieces of one GPDM objective+gradient evaluation (all of them without a command).
#[derive(clap::Parser)]
struct Cli {
    #[command(subcommand)]
    only: Option<Only>,
}

#[derive(clap::Subcommand)]
enum Only {
    /// Just the 1-vs-2-thread objective timing, longer (e.g. under `perf record`).
    ObjectiveOnly,
    /// Just the old-vs-new comparison: on the synthetic problem, or on the exported problems
    /// given (see `fit_compare`).
    OldNew { problems: Vec<String> },
}

fn main() {
    let cli = <Cli as clap::Parser>::parse();
    // SAFETY: plain FFI call; pins OpenBLAS to the calling thread's single core.
    unsafe { openblas_set_num_threads(1) };
    faer::set_global_parallelism(faer::Par::Seq);
    match cli.only {
        Some(Only::ObjectiveOnly) => {
            objective_threads(201);
            return;
        }
        Some(Only::OldNew { problems }) => {
            if problems.is_empty() {
                for n in [192, 446] {
                    pieces(n, n + 7, if n < 300 { 101 } else { 41 });
                }
                old_new("synthetic", &synthetic::synthetic(15000, 1e-3), 41);
            }
            for dir in &problems {
                old_new(dir, &problem::load_problem(std::path::Path::new(dir)), 101);
            }
            return;
        }
        None => {}
    }
    objective_pieces(446);
    println!();
    for n in [192, 446] {
        compare(n, if n < 300 { 101 } else { 41 });
    }
    objective_threads(41);
    println!();
    for n in [192, 446] {
        pieces(n, n + 7, if n < 300 { 101 } else { 41 });
    }
    old_new("synthetic", &synthetic::synthetic(15000, 1e-3), 41);
}

/// Times the pieces of one objective+gradient evaluation at `n` latent points (the pose
/// kernel on a fixed 3-D latent layout): the Gram matrix, its Cholesky factor, `L⁻¹ S` for
/// `S = X Xᵀ`, the sandwich, the kernel's gradients, and an N×N `gemm` for reference.
fn objective_pieces(n: usize) {
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

fn objective_threads(reps: usize) {
    let m = Gpdm::new(&synthetic::synthetic(15000, 1e-3), GpdmConfig::default()).unwrap();
    let obj = m.objective().unwrap();
    let th = m.theta();
    let mut g = vec![0.0; th.len()];
    let pools = one_and_two_thread_pools();
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

/// Rayon pools of 1 and 2 threads (for interleaved thread-count comparisons).
fn one_and_two_thread_pools() -> [rayon::ThreadPool; 2] {
    [1, 2].map(|t| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(t)
            .build()
            .expect("thread pool")
    })
}
