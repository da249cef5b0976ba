//! Ground truth implied by driving both subjects with the same source frames: each frame's
//! mocap time, dense frame correspondences, key-poses and feet contacts.

use nalgebra::Vector3;

use crate::style::TimeWarp;

/// Mocap times of a subject's frames: `τ_k = φ(k / fps)` for all `k` with `τ_k <= duration`.
pub fn frame_times(warp: &TimeWarp, fps: f64, duration: f64, max_frames: usize) -> Vec<f64> {
    (0..max_frames)
        .map(|k| warp.mocap_time(k as f64 / fps))
        .take_while(|&t| t <= duration + 1e-9)
        .collect()
}

/// Dense correspondences: for every source frame `i`, the target frame `j` whose mocap time is
/// closest to the source frame's (ties to the earlier frame). Both time lists are increasing.
pub fn correspondences(src: &[f64], tgt: &[f64]) -> Vec<[usize; 2]> {
    src.iter()
        .enumerate()
        .map(|(i, &t)| {
            let k = tgt.partition_point(|&x| x < t);
            let j = if k == 0 {
                0
            } else if k >= tgt.len() || (t - tgt[k - 1]) <= (tgt[k] - t) {
                (k - 1).min(tgt.len() - 1)
            } else {
                k
            };
            [i, j]
        })
        .collect()
}

/// `n` key-poses: source frames at the centres of `n` equal slices, with their correspondences.
pub fn keyposes(corr: &[[usize; 2]], n: usize) -> Vec<[usize; 2]> {
    let len = corr.len();
    let mut out: Vec<[usize; 2]> = (0..n)
        .map(|k| corr[((2 * k + 1) * len / (2 * n)).min(len - 1)])
        .collect();
    out.dedup();
    out
}

/// Feet contacts per frame `[left, right]`: the foot's lowest sole point within `height` of
/// the ground and moving horizontally slower than `speed` (m/s, central differences).
pub fn contacts(
    left: &[Vector3<f64>],
    right: &[Vector3<f64>],
    fps: f64,
    height: f64,
    speed: f64,
) -> Vec<[bool; 2]> {
    let n = left.len();
    let down = |feet: &[Vector3<f64>], k: usize| {
        let (a, b) = (k.saturating_sub(1), (k + 1).min(n - 1));
        let d = feet[b] - feet[a];
        let v = if b > a {
            (d.x * d.x + d.z * d.z).sqrt() * fps / (b - a) as f64
        } else {
            0.0
        };
        feet[k].y < height && v < speed
    };
    (0..n).map(|k| [down(left, k), down(right, k)]).collect()
}
