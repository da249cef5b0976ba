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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn correspondences_pick_the_nearest_time() {
        let src = [0.0, 0.1, 0.2, 0.3];
        let tgt = [0.0, 0.04, 0.09, 0.13, 0.16, 0.31];
        let c = correspondences(&src, &tgt);
        assert_eq!(c, vec![[0, 0], [1, 2], [2, 4], [3, 5]]);
        assert_eq!(keyposes(&c, 2), vec![[1, 2], [3, 5]]);
    }

    #[test]
    fn frame_times_follow_the_warp_and_stop_at_the_clip_end() {
        let w = TimeWarp {
            rate: 0.5,
            amp: 0.0,
            period: 1.0,
            phase: 0.0,
        };
        let t = frame_times(&w, 10.0, 1.0, 1000);
        assert_eq!(t.len(), 21);
        assert!((t[20] - 1.0).abs() < 1e-12);
    }

    #[test]
    fn contacts_need_low_and_still_feet() {
        let low = |x: f64| Vector3::new(x, 0.0, 0.0);
        let left: Vec<_> = (0..5).map(|_| low(0.0)).collect();
        let right: Vec<_> = (0..5).map(|k| low(k as f64 * 0.1)).collect(); // 2.5 m/s at 25 fps
        let c = contacts(&left, &right, 25.0, 0.03, 0.6);
        assert!(c.iter().all(|f| f[0] && !f[1]));
    }
}
