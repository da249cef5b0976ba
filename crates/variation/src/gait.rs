//! Whole gait cycles of locomotion (before the DTW of [`crate::prealign`]).
//!
//! Motions of one locomotion group rarely hold the same number of cycles over their length
//! (the demo's walk has 2 strides in 64 frames, its run 3 in 61), so a corner-to-corner DTW of
//! the whole clips cannot pair them cycle for cycle and the pre-blended `Y_w` of §7 would blend
//! a walk stride with a run stride of another phase. Each motion is therefore cut to the same
//! number `k` of whole cycles before the DTW:
//!
//! * its period `P` is the first strong minimum of the pose self-distance
//!   `S(L) = mean_t mean_v ‖y_t(v) − y_{t+L}(v)‖` over lags `L` (frames aligned to the
//!   template, so `S` sees pose only): the first lag that is a local minimum and lies below
//!   `threshold · S̄`, `S̄` the mean distance over all frame pairs;
//! * `k = min_m ⌊n_m / P_m⌋` over the group's motions;
//! * the reference keeps frames `[0, k·P_ref)`; every other motion keeps the window
//!   `[s, s + k·P_m)` whose corner-to-corner DTW onto the reference cut has the least mean cost
//!   (which sets the phase: the windows start at the same point of the cycle).
//!
//! The period comes from the poses rather than the feet contacts because contacts can be
//! sparse on fast motions (a run has flight phases and brief, fast stance phases); the
//! contacts still weight the DTW.

use mesh_core::{Error, Result};
use nalgebra::Vector3;

/// Settings of [`period`].
#[derive(Clone, Debug, PartialEq)]
pub struct GaitOptions {
    /// Shortest period considered (frames).
    pub min_period: usize,
    /// A minimum of `S(L)` counts when below `threshold · S̄`.
    pub threshold: f64,
    /// Vertices used (evenly subsampled).
    pub max_vertices: usize,
}

impl Default for GaitOptions {
    fn default() -> Self {
        GaitOptions {
            min_period: 6,
            threshold: 0.5,
            max_vertices: 600,
        }
    }
}

fn subsample(n: usize, max_vertices: usize) -> Vec<usize> {
    let step = n.div_ceil(max_vertices.max(1)).max(1);
    (0..n).step_by(step).collect()
}

fn frame_distance(a: &[Vector3<f64>], b: &[Vector3<f64>], idx: &[usize]) -> f64 {
    idx.iter().map(|&v| (a[v] - b[v]).norm()).sum::<f64>() / idx.len().max(1) as f64
}

/// `S(L)` for `L = 0..n` (`S(0) = 0`; lags with fewer than 2 frame pairs are `+inf`), and `S̄`.
pub fn self_distance(frames: &[Vec<Vector3<f64>>], max_vertices: usize) -> (Vec<f64>, f64) {
    let n = frames.len();
    let idx = subsample(frames.first().map_or(0, |f| f.len()), max_vertices);
    let mut d = vec![vec![0.0; n]; n];
    for i in 0..n {
        for j in i + 1..n {
            d[i][j] = frame_distance(&frames[i], &frames[j], &idx);
        }
    }
    let s: Vec<f64> = (0..n)
        .map(|l| {
            if l == 0 {
                0.0
            } else if n - l < 2 {
                f64::INFINITY
            } else {
                (0..n - l).map(|t| d[t][t + l]).sum::<f64>() / (n - l) as f64
            }
        })
        .collect();
    let pairs = n * n.saturating_sub(1) / 2;
    let mean = if pairs == 0 {
        0.0
    } else {
        (0..n)
            .flat_map(|i| (i + 1..n).map(move |j| (i, j)))
            .map(|(i, j)| d[i][j])
            .sum::<f64>()
            / pairs as f64
    };
    (s, mean)
}

/// The gait period of a motion (module doc), `None` when the poses do not repeat. Lags are
/// searched up to `n − max(min_period, n/4)` so each compares at least a quarter of the clip.
pub fn period(frames: &[Vec<Vector3<f64>>], opts: &GaitOptions) -> Option<usize> {
    let n = frames.len();
    let (s, mean) = self_distance(frames, opts.max_vertices);
    let last = n.checked_sub(opts.min_period.max(n / 4))?;
    (opts.min_period.max(1)..=last).find(|&l| {
        s[l] < opts.threshold * mean && s[l] <= s[l - 1] && l + 1 < n && s[l] <= s[l + 1]
    })
}

/// Number of whole cycles `k = min_m ⌊n_m / P_m⌋` common to motions of `(length, period)`.
pub fn common_cycles(lengths_periods: &[(usize, usize)]) -> Result<usize> {
    let k = lengths_periods
        .iter()
        .map(|&(n, p)| n / p.max(1))
        .min()
        .unwrap_or(0);
    if k == 0 {
        return Err(Error::invalid(
            "gait cycles: a motion is shorter than its period",
        ));
    }
    Ok(k)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Frames of a two-vertex "body" whose pose is periodic with `p` frames.
    fn periodic(n: usize, p: f64) -> Vec<Vec<Vector3<f64>>> {
        (0..n)
            .map(|t| {
                let a = std::f64::consts::TAU * t as f64 / p;
                vec![
                    Vector3::new(a.sin(), 0.0, 0.0),
                    Vector3::new(0.0, (a).cos() * 0.5, 1.0),
                ]
            })
            .collect()
    }

    #[test]
    fn period_of_periodic_poses_is_found() {
        assert_eq!(
            period(&periodic(64, 32.0), &GaitOptions::default()),
            Some(32)
        );
        assert_eq!(
            period(&periodic(61, 20.0), &GaitOptions::default()),
            Some(20)
        );
        // Non-integer period: the nearest lag.
        assert_eq!(
            period(&periodic(70, 21.4), &GaitOptions::default()),
            Some(21)
        );
    }

    #[test]
    fn non_periodic_motion_has_no_period() {
        // A pose that drifts monotonically never comes back.
        let frames: Vec<_> = (0..50)
            .map(|t| vec![Vector3::new(t as f64 * 0.1, 0.0, 0.0)])
            .collect();
        assert_eq!(period(&frames, &GaitOptions::default()), None);
    }

    #[test]
    fn common_cycles_is_the_smallest_count() {
        assert_eq!(common_cycles(&[(64, 32), (61, 20)]).unwrap(), 2);
        assert!(common_cycles(&[(10, 32)]).is_err());
    }
}
