//! Constrained dynamic time warping (CVPR eq. 7): the least-cost monotonic, continuous path through
//! the `f_s x f_t` cost matrix `C_ij = -log P_ij` that passes through every key-pose pair.
//!
//! Conventions pinned here:
//! - rows are source frames `i`, columns target frames `j`; a path is a list of nodes
//!   `(i, j)` with steps diagonal `(1, 1)`, vertical `(1, 0)` (source advances) or horizontal
//!   `(0, 1)` (target advances); the path cost is the sum of `C` over its nodes;
//! - "not more than 3 vertical or horizontal consecutive nodes in a row" is read as at most
//!   `max_run = 3` consecutive vertical steps and at most 3 consecutive horizontal steps.
//!   A run of vertical steps must be broken by a diagonal or horizontal step, so the
//!   steepest slope reachable is `max_run + 1 = 4` rows per column: a 50 fps source against a
//!   25 fps target (slope 2: alternate diagonal and vertical) is well inside the limit;
//! - by default ([`Endpoints::Corners`]) the path starts at `(0, 0)` and ends at
//!   `(f_s - 1, f_t - 1)`, so every frame of both sequences is paired; with
//!   [`Endpoints::KeyPoses`] it spans the first to the last key-pose only;
//! - key-poses are enforced exactly: the dynamic programme only visits the rectangles
//!   between consecutive waypoints (start, key-poses, end) and only allows a step from one
//!   rectangle into the next at their shared corner, so the path passes through each key
//!   node; the run-length state carries across key nodes (one global optimum over the whole
//!   path, equal to solving the segments in sequence with the run state handed over).

use crate::{invalid, Result};
use nalgebra::DMatrix;

/// The paper's run-length limit.
pub const PAPER_MAX_RUN: usize = 3;

/// Where the path starts and ends.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Endpoints {
    /// From `(0, 0)` to `(f_s - 1, f_t - 1)`.
    #[default]
    Corners,
    /// From the first to the last key-pose pair.
    KeyPoses,
}

/// Settings of [`dtw_path`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DtwOptions {
    /// Maximum consecutive vertical (or horizontal) steps.
    pub max_run: usize,
    pub endpoints: Endpoints,
}

impl Default for DtwOptions {
    fn default() -> Self {
        Self {
            max_run: PAPER_MAX_RUN,
            endpoints: Endpoints::Corners,
        }
    }
}

/// Run state of the last step into a node: 0 = diagonal (or start), `1..=r` vertical runs,
/// `r+1..=2r` horizontal runs.
const NO_PRED: u8 = u8::MAX;

/// Least-cost path (see the module doc) through `cost` (`f_s x f_t`, finite or `+inf` for a
/// forbidden node) through every `keys` pair `(i, j)`. Keys must be non-decreasing in both
/// coordinates once sorted by `i`. Returns the path nodes in order.
pub fn dtw_path(
    cost: &DMatrix<f64>,
    keys: &[(usize, usize)],
    opts: &DtwOptions,
) -> Result<Vec<(usize, usize)>> {
    let (fs, ft) = (cost.nrows(), cost.ncols());
    if fs == 0 || ft == 0 {
        return invalid("DTW on an empty cost matrix");
    }
    if cost.iter().any(|v| v.is_nan() || *v == f64::NEG_INFINITY) {
        return invalid("DTW cost matrix contains NaN or -inf");
    }
    let r = opts.max_run;
    if r == 0 || r > 100 {
        return invalid(format!("DTW run-length limit must be in 1..=100, got {r}"));
    }
    let mut ks: Vec<(usize, usize)> = keys.to_vec();
    ks.sort_unstable();
    ks.dedup();
    for &(i, j) in &ks {
        if i >= fs || j >= ft {
            return invalid(format!(
                "key-pose ({i}, {j}) outside the {fs} x {ft} cost matrix"
            ));
        }
    }
    for w in ks.windows(2) {
        if w[1].1 < w[0].1 {
            return invalid(format!(
                "key-poses {:?} and {:?} are not monotonic (a path cannot go back in time)",
                w[0], w[1]
            ));
        }
    }
    // Waypoints: start, keys, end.
    let mut way = Vec::with_capacity(ks.len() + 2);
    match opts.endpoints {
        Endpoints::Corners => {
            way.push((0, 0));
            way.extend(&ks);
            way.push((fs - 1, ft - 1));
        }
        Endpoints::KeyPoses => {
            if ks.is_empty() {
                return invalid("DTW between key-poses needs at least one key-pose pair");
            }
            way.extend(&ks);
        }
    }
    way.dedup();
    let (start, end) = (way[0], *way.last().unwrap());
    if way.len() == 1 {
        return Ok(vec![start]);
    }
    // Segment of every node: segment k is the rectangle between waypoints k and k+1; a shared
    // corner belongs to the segment it starts. Nodes outside every rectangle are forbidden.
    const OUT: u32 = u32::MAX;
    let nseg = way.len() - 1;
    let mut seg = vec![OUT; fs * ft];
    for k in (0..nseg).rev() {
        let (a, b) = (way[k], way[k + 1]);
        for i in a.0..=b.0 {
            for j in a.1..=b.1 {
                if (i, j) != b || k == nseg - 1 || seg[i * ft + j] == OUT {
                    seg[i * ft + j] = k as u32;
                }
            }
        }
    }
    // A step p -> q stays inside a segment, or enters segment k exactly at its start corner
    // (this is what forces the path through every key-pose: a diagonal step cannot cut a
    // corner).
    let step_ok = |p: (usize, usize), q: (usize, usize)| -> bool {
        let (sp, sq) = (seg[p.0 * ft + p.1], seg[q.0 * ft + q.1]);
        sp != OUT && (sp == sq || (sq == sp + 1 && q == way[sq as usize]))
    };
    let ns = 2 * r + 1;
    let idx = |i: usize, j: usize, s: usize| (i * ft + j) * ns + s;
    let mut acc = vec![f64::INFINITY; fs * ft * ns];
    let mut pred = vec![NO_PRED; fs * ft * ns];
    acc[idx(start.0, start.1, 0)] = cost[start];
    for i in start.0..=end.0 {
        for j in start.1..=end.1 {
            if (i, j) == start || seg[i * ft + j] == OUT {
                continue;
            }
            let c = cost[(i, j)];
            // Diagonal from any state.
            if i > 0 && j > 0 && step_ok((i - 1, j - 1), (i, j)) {
                let (v, s) = best(&acc, idx(i - 1, j - 1, 0), ns);
                relax(&mut acc, &mut pred, idx(i, j, 0), v + c, s as usize);
            }
            // Vertical from (i-1, j): state 0 or horizontal -> run 1; run k -> k+1.
            if i > 0 && step_ok((i - 1, j), (i, j)) {
                let b = idx(i - 1, j, 0);
                let mut cands = vec![(acc[b], 0usize)];
                cands.extend((r + 1..=2 * r).map(|s| (acc[b + s], s)));
                let (v, s) = argmin(&cands);
                relax(&mut acc, &mut pred, idx(i, j, 1), v + c, s as usize);
                for k in 1..r {
                    let v = acc[b + k] + c;
                    relax(&mut acc, &mut pred, idx(i, j, k + 1), v, k);
                }
            }
            // Horizontal from (i, j-1).
            if j > 0 && step_ok((i, j - 1), (i, j)) {
                let b = idx(i, j - 1, 0);
                let mut cands = vec![(acc[b], 0usize)];
                cands.extend((1..=r).map(|s| (acc[b + s], s)));
                let (v, s) = argmin(&cands);
                relax(&mut acc, &mut pred, idx(i, j, r + 1), v + c, s as usize);
                for k in 1..r {
                    let v = acc[b + r + k] + c;
                    relax(&mut acc, &mut pred, idx(i, j, r + k + 1), v, r + k);
                }
            }
        }
    }
    let (total, mut s) = best(&acc, idx(end.0, end.1, 0), ns);
    if !total.is_finite() {
        return invalid(format!(
            "no finite-cost path from {start:?} to {end:?} through the key-poses with at most {r} \
             consecutive vertical or horizontal steps (frame counts {fs} and {ft} may differ by \
             more than a factor {})",
            r + 1
        ));
    }
    let mut path = vec![end];
    let (mut i, mut j) = end;
    while (i, j) != start {
        let p = pred[idx(i, j, s as usize)];
        let state = s as usize;
        (i, j) = if state == 0 {
            (i - 1, j - 1)
        } else if state <= r {
            (i - 1, j)
        } else {
            (i, j - 1)
        };
        s = p;
        path.push((i, j));
    }
    path.reverse();
    Ok(path)
}

fn best(acc: &[f64], base: usize, ns: usize) -> (f64, u8) {
    let mut b = (f64::INFINITY, 0u8);
    for s in 0..ns {
        if acc[base + s] < b.0 {
            b = (acc[base + s], s as u8);
        }
    }
    b
}

fn argmin(c: &[(f64, usize)]) -> (f64, u8) {
    let mut b = (f64::INFINITY, 0u8);
    for &(v, s) in c {
        if v < b.0 {
            b = (v, s as u8);
        }
    }
    b
}

fn relax(acc: &mut [f64], pred: &mut [u8], at: usize, v: f64, s: usize) {
    if v < acc[at] {
        acc[at] = v;
        pred[at] = s as u8;
    }
}

/// Total cost of a path (sum of the cost matrix over its nodes).
pub fn path_cost(cost: &DMatrix<f64>, path: &[(usize, usize)]) -> f64 {
    path.iter().map(|&p| cost[p]).sum()
}
