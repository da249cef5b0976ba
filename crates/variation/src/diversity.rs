//! Coverage, global and local diversity of variations against their source, as single-sequence
//! motion synthesis reports them (GANimator, Li et al., SIGGRAPH 2022, §6.1; their
//! `evaluations/perwindow_nn.py` and `patched_nn.py`), with the per-frame pose distance of
//! meshes instead of joint rotations.
//!
//! `c(i, k)` is the distance between frame `i` of a variation and frame `k` of the source: the
//! mean per-vertex distance of the two frames, each rigidly aligned to the template
//! ([`crate::metrics::normalise`], vertices subsampled to at most 400). The cost of matching the
//! variation's window `[i, i + T)` to the source's window starting at `k` is
//! `C_T(i, k) = (1/T) Σ_{t<T} c(i + t, k + t)`.
//!
//! - **Local diversity** (window `T_l`, 0.5 s): the mean over the variation's windows of
//!   `min_k C_{T_l}(i, k)`, the distance to the nearest source window. 0 for a copy.
//! - **Global diversity** (pieces of at least `T_g`, 1 s): the variation tiled by the fewest-cost
//!   sequence of pieces, each at least `T_g` frames and matched to one contiguous source window,
//!   by dynamic programming (`G(0) = 0`, `G(j) = min_{l ≤ j − T_g, k} G(l) + T C_T(l, k)` with
//!   `T = j − l`); `G(L) / L`. 0 for a copy or a re-ordering of long source pieces.
//! - **Coverage** (window `T_g`, threshold `τ`): the share of the source's windows
//!   `[k, k + T_g)` that some variation matches, `min_{var, i} C_{T_g} < τ` (source and variation
//!   roles swapped in `C`). 1 when the variations together revisit the whole capture.
//!
//! Windows longer than a sequence are cut to its length.

use nalgebra::{DMatrix, Vector3};
use serde::{Deserialize, Serialize};

use crate::metrics::normalise;
use crate::prealign::pose_cost;

/// Window of the local diversity (s).
pub const LOCAL_WINDOW_S: f64 = 0.5;
/// Shortest piece of the global diversity and window of the coverage (s).
pub const GLOBAL_WINDOW_S: f64 = 1.0;
/// Coverage threshold τ on the mean per-vertex pose distance of a window (m).
pub const COVERAGE_THRESHOLD_M: f64 = 0.03;

/// The three figures of one set of variations of a source.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Diversity {
    /// Share of the source's windows matched by some variation within the threshold.
    pub coverage: f64,
    /// Mean over the variations of their global diversity (m).
    pub global_m: f64,
    /// Mean over the variations of their local diversity (m).
    pub local_m: f64,
    pub local_window_frames: usize,
    pub global_window_frames: usize,
    pub coverage_threshold_m: f64,
}

/// `min_k C_T(i, k)` for every window start `i` of the rows of `c` (rows: the windowed
/// sequence, columns: the one searched); `T` cut to both lengths.
pub fn nearest_windows(c: &DMatrix<f64>, t: usize) -> Vec<f64> {
    let (n, m) = c.shape();
    let t = t.min(n).min(m).max(1);
    if n == 0 || m == 0 {
        return Vec::new();
    }
    (0..=n - t)
        .map(|i| {
            (0..=m - t)
                .map(|k| (0..t).map(|s| c[(i + s, k + s)]).sum::<f64>() / t as f64)
                .fold(f64::INFINITY, f64::min)
        })
        .collect()
}

/// Local diversity of one variation: the mean of [`nearest_windows`] with `c` = variation × source.
pub fn local(c: &DMatrix<f64>, t: usize) -> f64 {
    let w = nearest_windows(c, t);
    w.iter().sum::<f64>() / w.len().max(1) as f64
}

/// Global diversity of one variation (module doc), `c` = variation × source, pieces ≥ `t`.
pub fn global(c: &DMatrix<f64>, t: usize) -> f64 {
    let (n, m) = c.shape();
    if n == 0 || m == 0 {
        return 0.0;
    }
    let t = t.min(n).min(m).max(1);
    let mut g = vec![f64::INFINITY; n + 1];
    g[0] = 0.0;
    for l in 0..n {
        if !g[l].is_finite() {
            continue;
        }
        // Pieces [l, j) matched to source frames starting at k: accumulate along the diagonal.
        for k in 0..m {
            let mut sum = 0.0;
            for s in 0..(n - l).min(m - k) {
                sum += c[(l + s, k + s)];
                let j = l + s + 1;
                if s + 1 >= t && g[l] + sum < g[j] {
                    g[j] = g[l] + sum;
                }
            }
        }
    }
    if g[n].is_finite() {
        g[n] / n as f64
    } else {
        // The variation is longer than any piece can tile (source shorter than the last
        // remainder): the nearest-window figure of the whole.
        local(c, t)
    }
}

/// The three figures of `variations` against `source` (world frames, aligned to `template`
/// here) at `fps`.
pub fn measure(
    variations: &[&Vec<Vec<Vector3<f64>>>],
    source: &[Vec<Vector3<f64>>],
    template: &[Vector3<f64>],
    fps: f64,
) -> Diversity {
    let aligned: Vec<Vec<Vec<Vector3<f64>>>> =
        variations.iter().map(|v| normalise(v, template)).collect();
    let refs: Vec<&Vec<Vec<Vector3<f64>>>> = aligned.iter().collect();
    measure_aligned(&refs, &normalise(source, template), fps)
}

/// [`measure`] of variations and source already aligned to the template
/// ([`crate::metrics::normalise`]); the variations' cost matrices in parallel.
pub fn measure_aligned(
    variations: &[&Vec<Vec<Vector3<f64>>>],
    src: &[Vec<Vector3<f64>>],
    fps: f64,
) -> Diversity {
    use rayon::prelude::*;
    let costs: Vec<DMatrix<f64>> = variations.par_iter().map(|v| pose_cost(v, src, 400)).collect();
    from_costs(&costs, src.len(), fps)
}

/// The three figures from each variation's cost matrix against the source (`c(i, k)` of the
/// module doc: `prealign::pose_cost` of the aligned frames, 400 vertices), the source having
/// `source_frames` frames.
pub fn from_costs(costs: &[DMatrix<f64>], source_frames: usize, fps: f64) -> Diversity {
    let frames = |s: f64| ((s * fps).round() as usize).max(1);
    let (tl, tg) = (frames(LOCAL_WINDOW_S), frames(GLOBAL_WINDOW_S));
    let mut covered = vec![false; source_frames.saturating_sub(tg.min(source_frames)) + 1];
    let (mut gsum, mut lsum) = (0.0, 0.0);
    for c in costs {
        gsum += global(c, tg);
        lsum += local(c, tl);
        for (flag, d) in covered.iter_mut().zip(nearest_windows(&c.transpose(), tg)) {
            *flag |= d < COVERAGE_THRESHOLD_M;
        }
    }
    let n = costs.len().max(1) as f64;
    Diversity {
        coverage: if source_frames == 0 {
            0.0
        } else {
            covered.iter().filter(|&&c| c).count() as f64 / covered.len() as f64
        },
        global_m: gsum / n,
        local_m: lsum / n,
        local_window_frames: tl,
        global_window_frames: tg,
        coverage_threshold_m: COVERAGE_THRESHOLD_M,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Frame distance of scalar "poses": |a_i − b_k|.
    fn cost(a: &[f64], b: &[f64]) -> DMatrix<f64> {
        DMatrix::from_fn(a.len(), b.len(), |i, k| (a[i] - b[k]).abs())
    }

    #[test]
    fn a_copy_and_a_reordering_of_long_pieces_have_no_global_diversity() {
        let src: Vec<f64> = (0..40).map(|t| t as f64).collect();
        assert_eq!(global(&cost(&src, &src), 10), 0.0);
        assert_eq!(local(&cost(&src, &src), 5), 0.0);
        // Second half first: two pieces of 20 frames, each a source window.
        let swapped: Vec<f64> = (20..40).chain(0..20).map(|t| t as f64).collect();
        assert_eq!(global(&cost(&swapped, &src), 10), 0.0);
        // With pieces of at least 30 frames the swap cannot be tiled for free.
        assert!(global(&cost(&swapped, &src), 30) > 1.0);
    }

    #[test]
    fn constant_offset_gives_that_distance_everywhere() {
        let src: Vec<f64> = (0..30).map(|t| (t as f64 * 0.3).sin()).collect();
        let var: Vec<f64> = src.iter().map(|x| x + 0.25).collect();
        let c = cost(&var, &src);
        // Any window's nearest is at most 0.25 (the aligned one); the aligned tiling is 0.25.
        assert!(global(&c, 10) <= 0.25 + 1e-12);
        assert!(local(&c, 5) <= 0.25 + 1e-12);
        // Far away: both figures are exactly the offset.
        let far: Vec<f64> = src.iter().map(|x| x + 10.0).collect();
        let c = cost(&far, &src);
        let lo = 10.0 - 2.0; // sin amplitude bounds
        assert!(global(&c, 10) >= lo && local(&c, 5) >= lo);
    }

    #[test]
    fn nearest_windows_finds_the_shifted_copy() {
        // The variation is source frames 7..17: its only window of 10 matches exactly.
        let src: Vec<f64> = (0..25).map(|t| (t * t) as f64).collect();
        let var: Vec<f64> = src[7..17].to_vec();
        assert_eq!(nearest_windows(&cost(&var, &src), 10), vec![0.0]);
        // Coverage direction: of the source's 16 windows of 10 frames, only k = 7 is matched.
        let back = nearest_windows(&cost(&src, &var), 10);
        assert_eq!(back.len(), 16);
        assert_eq!(back.iter().filter(|&&d| d < 1e-9).count(), 1);
        assert_eq!(back[7], 0.0);
    }

    #[test]
    fn coverage_of_meshes_counts_windows_any_variation_matches() {
        // One-vertex "meshes" (a template of 3 points so that alignment is defined): the
        // source moves a point along x; variation A copies its first half, B its second.
        let template = vec![
            Vector3::new(0.0, 0.0, 0.0),
            Vector3::new(1.0, 0.0, 0.0),
            Vector3::new(0.0, 1.0, 0.0),
            Vector3::new(0.0, 0.0, 1.0),
        ];
        let frame = |x: f64| {
            let mut f = template.clone();
            f[3].x = x;
            f
        };
        let source: Vec<_> = (0..20).map(|t| frame(0.5 * t as f64)).collect();
        let a: Vec<_> = (0..10).map(|t| source[t].clone()).collect();
        let b: Vec<_> = (10..20).map(|t| source[t].clone()).collect();
        // fps 10: coverage window 10 frames: source windows k = 0..=10; A matches k = 0,
        // B matches k = 10.
        let d = measure(&[&a], &source, &template, 10.0);
        assert!((d.coverage - 1.0 / 11.0).abs() < 1e-12, "{}", d.coverage);
        let d = measure(&[&a, &b], &source, &template, 10.0);
        assert!((d.coverage - 2.0 / 11.0).abs() < 1e-12, "{}", d.coverage);
        assert!(d.global_m < 1e-9 && d.local_m < 1e-9, "copies: no diversity");
    }
}
