//! Fitting the GPDM: an L-BFGS minimiser of 3DV eq. 7 (started from [`crate::pca`]).
//!
//! The hyperparameters are optimised in log coordinates (see [`crate::model`]); on top of
//! that, [`Schedule::Alternate`] interleaves (X, α) phases with β-only phases, because the
//! curvature along β is orders of magnitude smaller than along X (measured on the demo parts): a joint quasi-Newton
//! step barely moves β. Every phase keeps and returns its best point.

use crate::error::Result;
use crate::model::Gpdm;
use serde::{Deserialize, Serialize};

/// Why a minimisation stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Exit {
    /// Gradient infinity-norm below tolerance.
    GradientTolerance,
    /// Relative decrease of f below tolerance.
    ValueTolerance,
    /// Iteration limit reached.
    MaxIterations,
    /// Evaluation limit reached.
    MaxEvaluations,
    /// The line search found no acceptable step (best point returned).
    LineSearchFailed,
    /// The objective could not be evaluated at the start point.
    StartFailed,
}

/// L-BFGS options.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LbfgsOptions {
    /// Number of stored correction pairs.
    pub memory: usize,
    /// Maximum iterations.
    pub max_iter: usize,
    /// Maximum objective evaluations.
    pub max_evals: usize,
    /// Stop when ‖∇f‖∞ ≤ grad_tol.
    pub grad_tol: f64,
    /// Stop when (f_{k−w} − f_k) ≤ w · value_tol · max(|f_k|, 1), w = `value_window`
    /// iterations (w = 1: scipy's `ftol` test; a longer window does not stop on one short step).
    pub value_tol: f64,
    /// Window w of the value test (≥ 1).
    #[serde(default = "one")]
    pub value_window: usize,
    /// Largest coordinate change of the first trial step of a line search (`‖p‖∞`; the
    /// search may still expand it). `None`: no limit.
    #[serde(default)]
    pub max_step: Option<f64>,
}

impl Default for LbfgsOptions {
    fn default() -> Self {
        LbfgsOptions {
            memory: 10,
            max_iter: 500,
            max_evals: 2000,
            grad_tol: 1e-6,
            value_tol: 1e-10,
            value_window: 1,
            max_step: None,
        }
    }
}

/// Outcome of a minimisation: the best point seen and why it stopped.
#[derive(Clone, Debug, PartialEq)]
pub struct LbfgsResult {
    /// Best point.
    pub x: Vec<f64>,
    /// f at the best point.
    pub f: f64,
    /// ‖∇f‖∞ at the best point.
    pub grad_norm: f64,
    /// Iterations done.
    pub iterations: usize,
    /// Objective evaluations done.
    pub evaluations: usize,
    /// Stop reason.
    pub exit: Exit,
    /// (evaluations so far, best f) after each iteration.
    pub history: Vec<(usize, f64)>,
}

fn one() -> usize {
    1
}

/// aᵀb with four independent partial sums (a single running sum is one dependent add chain
/// the compiler may not reorder: 4x slower, and the two-loop recursion is mostly dots).
fn dot(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len().min(b.len());
    let (a4, b4) = (a[..n].chunks_exact(4), b[..n].chunks_exact(4));
    let tail: f64 = a4
        .remainder()
        .iter()
        .zip(b4.remainder())
        .map(|(x, y)| x * y)
        .sum();
    let mut acc = [0.0; 4];
    for (x, y) in a4.zip(b4) {
        for ((s, x), y) in acc.iter_mut().zip(x).zip(y) {
            *s += x * y;
        }
    }
    (acc[0] + acc[1]) + (acc[2] + acc[3]) + tail
}

/// `q ← q + c v`, then `nextᵀq` (0 when `next` is empty) with [`dot`]'s lanes and order, in
/// one pass over q. `q_j + c v_j` with `c = −a` equals `q_j − a v_j` exactly. (An AVX2 build
/// of this loop measured no faster: it streams the stored pairs, ~1.9 MB per iteration at
/// memory 100, and is bound by cache bandwidth.)
fn axpy_dot(q: &mut [f64], c: f64, v: &[f64], next: &[f64]) -> f64 {
    let n = q.len();
    let v = &v[..n];
    if next.is_empty() {
        for (qj, vj) in q.iter_mut().zip(v) {
            *qj += c * vj;
        }
        return 0.0;
    }
    let next = &next[..n];
    let m = n / 4 * 4;
    let mut acc = [0.0; 4];
    for ((qc, vc), nc) in q[..m]
        .chunks_exact_mut(4)
        .zip(v[..m].chunks_exact(4))
        .zip(next[..m].chunks_exact(4))
    {
        for l in 0..4 {
            qc[l] += c * vc[l];
            acc[l] += nc[l] * qc[l];
        }
    }
    for j in m..n {
        q[j] += c * v[j];
    }
    let tail: f64 = next[m..].iter().zip(&q[m..]).map(|(x, y)| x * y).sum();
    (acc[0] + acc[1]) + (acc[2] + acc[3]) + tail
}

/// `q ← q ∘ scale`, then `nextᵀq` (0 when `next` is empty) as [`axpy_dot`] does.
fn scale_dot(q: &mut [f64], scale: &[f64], next: &[f64]) -> f64 {
    for (v, c) in q.iter_mut().zip(scale) {
        *v *= c;
    }
    if next.is_empty() {
        0.0
    } else {
        dot(next, q)
    }
}

fn inf_norm(a: &[f64]) -> f64 {
    a.iter().fold(0.0, |m, v| m.max(v.abs()))
}

/// Minimises `f` by L-BFGS with a strong-Wolfe line search (Nocedal & Wright, alg. 7.4,
/// 3.5 and 3.6). `f(x, g)` returns the value and writes the gradient, or `None` when it cannot
/// be evaluated (treated as +∞: the step is shortened).
pub fn lbfgs<F>(f: F, x0: &[f64], opts: &LbfgsOptions) -> LbfgsResult
where
    F: FnMut(&[f64], &mut [f64]) -> Option<f64>,
{
    lbfgs_blocks(f, x0, opts, &[0..x0.len()])
}

/// [`lbfgs`] with a block-diagonal initial inverse Hessian: in the two-loop recursion each
/// block `b` of coordinates is scaled by its own secant estimate `γ_b = s_bᵀy_b / y_bᵀy_b`
/// from the latest correction pair (the global `sᵀy / yᵀy` when `s_bᵀy_b ≤ 0`), instead of one
/// scalar for all coordinates. For the GPDM the latent positions, α and β have curvatures 1e3 to
/// 1e13 apart: one scalar sized for X makes every β step tiny. Blocks must be
/// disjoint; coordinates outside every block use the global scalar.
pub fn lbfgs_blocks<F>(
    mut f: F,
    x0: &[f64],
    opts: &LbfgsOptions,
    blocks: &[std::ops::Range<usize>],
) -> LbfgsResult
where
    F: FnMut(&[f64], &mut [f64]) -> Option<f64>,
{
    let n = x0.len();
    let mut evals = 0usize;
    let mut x = x0.to_vec();
    let mut g = vec![0.0; n];
    let fx = f(&x, &mut g);
    evals += 1;
    let Some(mut fx) = fx.filter(|v| v.is_finite()) else {
        return LbfgsResult {
            x,
            f: f64::INFINITY,
            grad_norm: f64::INFINITY,
            iterations: 0,
            evaluations: evals,
            exit: Exit::StartFailed,
            history: vec![],
        };
    };
    let mut pairs: std::collections::VecDeque<Pair> = Default::default();
    let mut history = vec![(evals, fx)];
    let mut exit = Exit::MaxIterations;
    let mut iterations = 0;
    let (c1, c2) = (1e-4, 0.9);
    for it in 0..opts.max_iter {
        iterations = it;
        if inf_norm(&g) <= opts.grad_tol {
            exit = Exit::GradientTolerance;
            break;
        }
        // Two-loop recursion: p = −H ∇f. Each update of q also forms the dot product the
        // next pair needs (one pass over q per pair; same sums as separate `dot`s).
        let mut q = g.clone();
        let k = pairs.len();
        let mut alphas = vec![0.0; k];
        if k > 0 {
            let mut sq = dot(&pairs[k - 1].s, &q);
            for i in (0..k).rev() {
                alphas[i] = sq / pairs[i].sy;
                let next = if i > 0 { &pairs[i - 1].s[..] } else { &[][..] };
                sq = axpy_dot(&mut q, -alphas[i], &pairs[i].y, next);
            }
        }
        let gamma = if let Some(last) = pairs.back() {
            last.sy / last.yy
        } else {
            1.0 / inf_norm(&g).max(1.0)
        };
        let mut scale = vec![gamma; n];
        if k > 0 && blocks.len() > 1 {
            let (s, y) = (&pairs[k - 1].s, &pairs[k - 1].y);
            for b in blocks {
                let (sy, yy) = (
                    dot(&s[b.clone()], &y[b.clone()]),
                    dot(&y[b.clone()], &y[b.clone()]),
                );
                if sy > 0.0 && yy > 0.0 {
                    scale[b.clone()].fill(sy / yy);
                }
            }
        }
        let first_y = pairs.front().map_or(&[][..], |pr| &pr.y[..]);
        let mut yq = scale_dot(&mut q, &scale, first_y);
        for i in 0..k {
            let beta = yq / pairs[i].sy;
            let next = if i + 1 < k {
                &pairs[i + 1].y[..]
            } else {
                &[][..]
            };
            yq = axpy_dot(&mut q, alphas[i] - beta, &pairs[i].s, next);
        }
        let mut p: Vec<f64> = q.iter().map(|v| -v).collect();
        let mut dg0 = dot(&p, &g);
        if !(dg0 < 0.0) {
            // Not a descent direction: restart with steepest descent.
            pairs.clear();
            let sc = 1.0 / inf_norm(&g).max(1.0);
            p = g.iter().map(|v| -v * sc).collect();
            dg0 = dot(&p, &g);
        }
        if let Some(cap) = opts.max_step {
            let big = inf_norm(&p);
            if big > cap {
                let sc = cap / big;
                p.iter_mut().for_each(|v| *v *= sc);
                dg0 *= sc;
            }
        }
        let budget = opts.max_evals.saturating_sub(evals);
        let ls = wolfe_search(&mut f, &x, fx, dg0, &p, c1, c2, budget);
        evals += ls.evals;
        match ls.step {
            Some((xn, fnew, gn)) => {
                let s: Vec<f64> = xn.iter().zip(&x).map(|(a, b)| a - b).collect();
                let yv: Vec<f64> = gn.iter().zip(&g).map(|(a, b)| a - b).collect();
                let (sy, yy) = (dot(&s, &yv), dot(&yv, &yv));
                if sy > 1e-12 * yy.sqrt() * dot(&s, &s).sqrt() {
                    if opts.memory > 0 {
                        while pairs.len() >= opts.memory {
                            pairs.pop_front();
                        }
                        pairs.push_back(Pair { s, y: yv, sy, yy });
                    }
                }
                let w = opts.value_window.max(1);
                let decrease = history
                    .len()
                    .checked_sub(w)
                    .map_or(f64::INFINITY, |i| history[i].1 - fnew);
                g = gn;
                fx = fnew;
                history.push((evals, fx));
                iterations = it + 1;
                x = xn;
                if decrease <= w as f64 * opts.value_tol * fx.abs().max(1.0) {
                    exit = Exit::ValueTolerance;
                    break;
                }
            }
            None => {
                if !pairs.is_empty() {
                    // Retry once from steepest descent before giving up.
                    pairs.clear();
                    if evals < opts.max_evals {
                        continue;
                    }
                }
                exit = if evals >= opts.max_evals {
                    Exit::MaxEvaluations
                } else {
                    Exit::LineSearchFailed
                };
                break;
            }
        }
        if evals >= opts.max_evals {
            exit = Exit::MaxEvaluations;
            break;
        }
    }
    if exit == Exit::MaxIterations && inf_norm(&g) <= opts.grad_tol {
        exit = Exit::GradientTolerance;
    }
    LbfgsResult {
        grad_norm: inf_norm(&g),
        x,
        f: fx,
        iterations,
        evaluations: evals,
        exit,
        history,
    }
}

/// One L-BFGS correction pair s = x_{k+1} − x_k, y = ∇f_{k+1} − ∇f_k, with sᵀy and yᵀy
/// (computed once, not in every two-loop recursion).
struct Pair {
    s: Vec<f64>,
    y: Vec<f64>,
    sy: f64,
    yy: f64,
}

struct LineSearch {
    step: Option<(Vec<f64>, f64, Vec<f64>)>,
    evals: usize,
}

/// Strong-Wolfe line search along `p` from `x` (f(x) = f0, ∇f·p = dg0 < 0).
#[allow(clippy::too_many_arguments)]
fn wolfe_search<F>(
    f: &mut F,
    x: &[f64],
    f0: f64,
    dg0: f64,
    p: &[f64],
    c1: f64,
    c2: f64,
    budget: usize,
) -> LineSearch
where
    F: FnMut(&[f64], &mut [f64]) -> Option<f64>,
{
    let n = x.len();
    let mut evals = 0;
    let mut phi = |a: f64, evals: &mut usize| -> (f64, f64, Vec<f64>, Vec<f64>) {
        let xa: Vec<f64> = (0..n).map(|i| x[i] + a * p[i]).collect();
        let mut ga = vec![0.0; n];
        *evals += 1;
        match f(&xa, &mut ga) {
            Some(v) if v.is_finite() && ga.iter().all(|g| g.is_finite()) => {
                let d = dot(&ga, p);
                (v, d, xa, ga)
            }
            _ => (f64::INFINITY, f64::NAN, xa, ga),
        }
    };
    let max_evals = budget.min(30);
    let (mut a_prev, mut f_prev, mut d_prev) = (0.0, f0, dg0);
    let mut a = 1.0;
    let mut best: Option<(Vec<f64>, f64, Vec<f64>)> = None;
    // Bracketing phase.
    let (mut lo, mut hi);
    loop {
        if evals >= max_evals {
            return LineSearch { step: best, evals };
        }
        let (fa, da, xa, ga) = phi(a, &mut evals);
        if fa.is_finite() && fa < f0 && best.as_ref().is_none_or(|b| fa < b.1) {
            best = Some((xa.clone(), fa, ga.clone()));
        }
        if !fa.is_finite() || fa > f0 + c1 * a * dg0 || (evals > 1 && fa >= f_prev) {
            lo = (a_prev, f_prev, d_prev);
            hi = (a, fa, da);
            break;
        }
        if da.abs() <= -c2 * dg0 {
            return LineSearch {
                step: Some((xa, fa, ga)),
                evals,
            };
        }
        if da >= 0.0 {
            lo = (a, fa, da);
            hi = (a_prev, f_prev, d_prev);
            break;
        }
        a_prev = a;
        f_prev = fa;
        d_prev = da;
        a *= 2.0;
    }
    // Zoom phase.
    loop {
        if evals >= max_evals || (hi.0 - lo.0).abs() < 1e-16 * lo.0.abs().max(1e-300) {
            return LineSearch { step: best, evals };
        }
        let at = interpolate(lo, hi);
        let (fa, da, xa, ga) = phi(at, &mut evals);
        if fa.is_finite() && fa < f0 && best.as_ref().is_none_or(|b| fa < b.1) {
            best = Some((xa.clone(), fa, ga.clone()));
        }
        if !fa.is_finite() || fa > f0 + c1 * at * dg0 || fa >= lo.1 {
            hi = (at, fa, da);
        } else {
            if da.abs() <= -c2 * dg0 {
                return LineSearch {
                    step: Some((xa, fa, ga)),
                    evals,
                };
            }
            if da * (hi.0 - lo.0) >= 0.0 {
                hi = lo;
            }
            lo = (at, fa, da);
        }
    }
}

/// Minimiser of the cubic through (a, f, f') at both ends, safeguarded into the middle 80 %
/// of the interval; bisection when the cubic is unusable.
fn interpolate(lo: (f64, f64, f64), hi: (f64, f64, f64)) -> f64 {
    let (a0, f0, d0) = lo;
    let (a1, f1, d1) = hi;
    let (left, right) = if a0 < a1 { (a0, a1) } else { (a1, a0) };
    let mid = 0.5 * (a0 + a1);
    if !(f1.is_finite() && d1.is_finite()) {
        return mid;
    }
    let d1c = d0 + d1 - 3.0 * (f0 - f1) / (a0 - a1);
    let disc = d1c * d1c - d0 * d1;
    if disc < 0.0 {
        return mid;
    }
    let d2 = (a1 - a0).signum() * disc.sqrt();
    let t = a1 - (a1 - a0) * (d1 + d2 - d1c) / (d1 - d0 + 2.0 * d2);
    let w = right - left;
    if t.is_finite() && t > left + 0.1 * w && t < right - 0.1 * w {
        t
    } else {
        mid
    }
}

/// How the parameter blocks are optimised.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum Schedule {
    /// All of (X, ln α, ln β) together.
    Joint,
    /// `rounds` × [(X, ln α) for `iters` iterations, then ln β only for `iters` iterations],
    /// then a final joint polish of up to `iters` iterations.
    Alternate { rounds: usize, iters: usize },
}

/// Initial inverse-Hessian scaling of L-BFGS (see [`lbfgs_blocks`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Scaling {
    /// One scalar for all coordinates (textbook L-BFGS).
    Scalar,
    /// One scalar for X, one for ln α, one for ln β.
    Blocks,
    /// One scalar for X and one per hyperparameter.
    PerHyperparameter,
}

/// Training options.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TrainOptions {
    /// Block schedule.
    pub schedule: Schedule,
    /// L-BFGS options (iteration counts are per phase for the joint schedule).
    pub lbfgs: LbfgsOptions,
    /// Initial inverse-Hessian scaling.
    pub scaling: Scaling,
}

impl Default for TrainOptions {
    fn default() -> Self {
        TrainOptions {
            schedule: Schedule::Joint,
            lbfgs: LbfgsOptions::default(),
            scaling: Scaling::Scalar,
        }
    }
}

/// Scaling blocks, in phase coordinates, for a phase optimising the θ indices `idx`
/// (X takes the first `nx` indices of θ, then 3 α and 4 β coordinates).
fn phase_blocks(idx: &[usize], nx: usize, scaling: Scaling) -> Vec<std::ops::Range<usize>> {
    let class = |i: usize| match scaling {
        Scaling::Scalar => 0,
        Scaling::Blocks if i < nx => 0,
        Scaling::Blocks if i < nx + 3 => 1,
        Scaling::Blocks => 2,
        Scaling::PerHyperparameter if i < nx => 0,
        Scaling::PerHyperparameter => 1 + i - nx,
    };
    let mut out: Vec<std::ops::Range<usize>> = vec![];
    for (k, &i) in idx.iter().enumerate() {
        match out.last_mut() {
            Some(r) if class(idx[r.start]) == class(i) => r.end = k + 1,
            _ => out.push(k..k + 1),
        }
    }
    out
}

/// What training did.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TrainReport {
    /// Objective (3DV eq. 7, negative log posterior without constants) at the start.
    pub initial_value: f64,
    /// Objective at the end.
    pub final_value: f64,
    /// Total objective evaluations.
    pub evaluations: usize,
    /// Stop reason of every phase, in order.
    pub exits: Vec<Exit>,
    /// Largest Cholesky jitter seen at the returned point (0 if none).
    pub max_jitter: f64,
    /// (cumulative evaluations, objective) after each iteration, over all phases.
    pub history: Vec<(usize, f64)>,
    /// (seconds since start, objective) at every evaluation, over all phases.
    pub trace: Vec<(f64, f64)>,
}

/// Minimises 3DV eq. 7 over X, α and β starting from the model's current parameters and stores
/// the best point found back into `model`.
pub fn train(model: &mut Gpdm, opts: &TrainOptions) -> Result<TrainReport> {
    let clock = std::time::Instant::now();
    let obj = model.objective()?;
    let mut theta = model.theta();
    let n_all = theta.len();
    let start = obj.eval(&theta, None)?;
    let start_jitter = start.jitter_x.max(start.jitter_y);
    let mut report = TrainReport {
        initial_value: start.value,
        final_value: start.value,
        evaluations: 1,
        exits: vec![],
        max_jitter: 0.0,
        history: vec![(1, start.value)],
        trace: vec![(clock.elapsed().as_secs_f64(), start.value)],
    };
    let nx_alpha = n_all - 4;
    let phases: Vec<(Vec<usize>, usize)> = match &opts.schedule {
        Schedule::Joint => vec![((0..n_all).collect(), opts.lbfgs.max_iter)],
        Schedule::Alternate { rounds, iters } => {
            let mut v = vec![];
            for _ in 0..*rounds {
                v.push(((0..nx_alpha).collect(), *iters));
                v.push(((nx_alpha..n_all).collect(), *iters));
            }
            v.push(((0..n_all).collect(), *iters));
            v
        }
    };
    let mut full_grad = vec![0.0; n_all];
    for (idx, iters) in phases {
        let base = theta.clone();
        let sub0: Vec<f64> = idx.iter().map(|&i| theta[i]).collect();
        let mut o = opts.lbfgs.clone();
        o.max_iter = iters;
        let blocks = phase_blocks(&idx, n_all - 7, opts.scaling);
        let res = lbfgs_blocks(
            |sub, g| {
                let mut t = base.clone();
                for (k, &i) in idx.iter().enumerate() {
                    t[i] = sub[k];
                }
                // A point whose kernel matrices need more Cholesky jitter than the start's is
                // numerically singular: treated as infeasible (the line search backs off).
                let e = obj
                    .eval(&t, Some(&mut full_grad))
                    .ok()
                    .filter(|e| e.jitter_x.max(e.jitter_y) <= start_jitter);
                let v = e.as_ref().map(|e| e.value).unwrap_or(f64::INFINITY);
                report.trace.push((clock.elapsed().as_secs_f64(), v));
                let e = e?;
                for (k, &i) in idx.iter().enumerate() {
                    g[k] = full_grad[i];
                }
                Some(e.value)
            },
            &sub0,
            &o,
            &blocks,
        );
        report.evaluations += res.evaluations;
        report.exits.push(res.exit);
        let offset = report.history.last().map(|h| h.0).unwrap_or(0);
        report
            .history
            .extend(res.history.iter().skip(1).map(|&(e, f)| (offset + e, f)));
        if res.f.is_finite() && res.f <= report.final_value {
            for (k, &i) in idx.iter().enumerate() {
                theta[i] = res.x[k];
            }
            report.final_value = res.f;
        }
    }
    let end = obj.eval(&theta, None)?;
    report.final_value = end.value;
    report.max_jitter = end.jitter_x.max(end.jitter_y);
    model.set_theta(&theta);
    Ok(report)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The fused two-loop passes give the same bits as the separate axpy and `dot` (the
    /// L-BFGS path must not change).
    #[test]
    fn fused_update_and_dot_equal_separate_ones() {
        let v = |n: usize, s: f64| -> Vec<f64> {
            (0..n)
                .map(|i| ((i as f64 + s) * 0.7371).sin() * 1e3_f64.powf((i % 5) as f64 - 2.0))
                .collect()
        };
        for n in 0..=13 {
            let (q0, y, s) = (v(n, 0.3), v(n, 1.9), v(n, 4.1));
            let a = -0.8137;
            let mut q1 = q0.clone();
            let d1 = axpy_dot(&mut q1, -a, &y, &s);
            let mut q2 = q0.clone();
            for (qj, yj) in q2.iter_mut().zip(&y) {
                *qj -= a * yj;
            }
            let d2 = if n > 0 { dot(&s, &q2) } else { 0.0 };
            assert!(
                q1.iter().zip(&q2).all(|(u, w)| u.to_bits() == w.to_bits()),
                "n = {n}"
            );
            assert_eq!(d1.to_bits(), d2.to_bits(), "n = {n}");
            let mut q3 = q0.clone();
            assert_eq!(axpy_dot(&mut q3, 2.5, &y, &[]), 0.0);
            let mut q4 = q0.clone();
            let sc = v(n, 7.7);
            let d3 = scale_dot(&mut q4, &sc, &y);
            let q5: Vec<f64> = q0.iter().zip(&sc).map(|(u, c)| u * c).collect();
            assert!(q4.iter().zip(&q5).all(|(u, w)| u.to_bits() == w.to_bits()));
            assert_eq!(
                d3.to_bits(),
                if n > 0 { dot(&y, &q5) } else { 0.0 }.to_bits()
            );
        }
    }
}
