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

/// Rule of [`contacts`]: when a foot counts as planted on the floor.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContactRule {
    /// Largest height (m) of the foot's lowest sole point above the floor (`y = 0`).
    pub height: f64,
    /// Largest horizontal speed (m/s) of the sole centroid (central differences).
    pub speed: f64,
    /// Longest gap (s) between two contact frames of a foot that is filled in.
    pub max_gap: f64,
}

impl Default for ContactRule {
    /// 10 cm, 0.6 m/s, 0.1 s. The height is generous because retargeted feet are not pinned to
    /// the floor: in the demo's run the stance foot's lowest sole point stays 2-9 cm up (the
    /// foot rolls from heel to toes) and in the jumps' crouch 3-7 cm, while swing feet below
    /// 10 cm always move faster than 0.9 m/s. A vertical jump's feet are still at the apex but
    /// 15-25 cm up. The gap filling bridges single-frame speed spikes of a planted foot (heel
    /// strike, the stance foot of the 50 fps subject's run sliding at 0.6-0.9 m/s).
    fn default() -> Self {
        ContactRule {
            height: 0.10,
            speed: 0.6,
            max_gap: 0.1,
        }
    }
}

/// Feet contacts per frame `[left, right]` from each foot's per-frame point `(x, lowest sole
/// height y, z)` (`y` up, floor at 0): a foot is in contact when its lowest sole point is
/// within `rule.height` of the floor and it moves horizontally slower than `rule.speed`;
/// runs of non-contact frames no longer than `rule.max_gap` between two contacts, with the
/// foot within `rule.height` throughout, become contacts too (a short flight does not).
pub fn contacts(
    left: &[Vector3<f64>],
    right: &[Vector3<f64>],
    fps: f64,
    rule: &ContactRule,
) -> Vec<[bool; 2]> {
    let (l, r) = (
        foot_contacts(left, fps, rule),
        foot_contacts(right, fps, rule),
    );
    l.into_iter().zip(r).map(|(a, b)| [a, b]).collect()
}

/// [`contacts`] of one foot.
fn foot_contacts(feet: &[Vector3<f64>], fps: f64, rule: &ContactRule) -> Vec<bool> {
    let n = feet.len();
    let mut down: Vec<bool> = (0..n)
        .map(|k| {
            let (a, b) = (k.saturating_sub(1), (k + 1).min(n - 1));
            let d = feet[b] - feet[a];
            let v = if b > a {
                (d.x * d.x + d.z * d.z).sqrt() * fps / (b - a) as f64
            } else {
                0.0
            };
            feet[k].y < rule.height && v < rule.speed
        })
        .collect();
    let max_gap = (rule.max_gap * fps).round() as usize;
    let mut last: Option<usize> = None;
    for k in 0..n {
        if down[k] {
            if let Some(j) = last {
                let low = feet[j + 1..k].iter().all(|p| p.y < rule.height);
                if k - j - 1 <= max_gap && low {
                    down[j + 1..k].iter_mut().for_each(|c| *c = true);
                }
            }
            last = Some(k);
        }
    }
    down
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
        let c = contacts(&left, &right, 25.0, &ContactRule::default());
        assert!(c.iter().all(|f| f[0] && !f[1]));
    }

    /// One foot at 25 fps from per-frame (horizontal step in m, sole height in m).
    fn foot(steps: &[(f64, f64)]) -> Vec<Vector3<f64>> {
        let mut x = 0.0;
        steps
            .iter()
            .map(|&(dx, h)| {
                x += dx;
                Vector3::new(x, h, 0.0)
            })
            .collect()
    }

    fn flags(c: &[[bool; 2]], foot: usize) -> String {
        c.iter().map(|f| if f[foot] { '1' } else { '0' }).collect()
    }

    #[test]
    fn running_stance_floating_a_few_cm_is_a_contact() {
        // Run at 25 fps: swing 4 frames at 0.3 m/frame (7.5 m/s) high up, stance 5 frames
        // rolling from 3 to 8 cm at 0.01 m/frame (0.25 m/s), then swing again.
        let mut s = vec![(0.3, 0.3); 4];
        s.extend([
            (0.01, 0.03),
            (0.01, 0.05),
            (0.01, 0.06),
            (0.01, 0.07),
            (0.01, 0.08),
        ]);
        s.extend(vec![(0.3, 0.3); 4]);
        let f = foot(&s);
        let c = contacts(&f, &f, 25.0, &ContactRule::default());
        // Central differences: the last stance frame's straddles the first swing step.
        assert_eq!(flags(&c, 0), "0000111100000");
        // The old rule (3 cm) saw at most one frame of it.
        let strict = ContactRule {
            height: 0.03,
            ..ContactRule::default()
        };
        assert_eq!(flags(&contacts(&f, &f, 25.0, &strict), 0), "0000000000000");
    }

    #[test]
    fn walk_and_jump_keep_their_answers() {
        // Walk: stance flat at 1 cm, swing 4 frames at 0.1 m/frame (2.5 m/s), 0-9 cm up.
        let walk = foot(&[
            (0.0, 0.01),
            (0.0, 0.01),
            (0.1, 0.04),
            (0.1, 0.09),
            (0.1, 0.05),
            (0.1, 0.02),
            (0.0, 0.01),
            (0.0, 0.01),
        ]);
        let c = contacts(&walk, &walk, 25.0, &ContactRule::default());
        // Frames next to a swing step move at 1.25 m/s (central differences).
        assert_eq!(flags(&c, 0), "10000011");
        // Vertical jump in place: still feet crouching 5 cm up, then 20 cm up at the apex
        // with no horizontal speed at all: only the floor frames are contacts.
        let jump = foot(&[
            (0.0, 0.02),
            (0.0, 0.05),
            (0.0, 0.05),
            (0.0, 0.15),
            (0.0, 0.2),
            (0.0, 0.15),
            (0.0, 0.04),
            (0.0, 0.01),
        ]);
        let c = contacts(&jump, &jump, 25.0, &ContactRule::default());
        assert_eq!(flags(&c, 1), "11100011");
    }

    #[test]
    fn short_speed_spikes_of_a_planted_foot_are_bridged() {
        // A planted foot slips 6 cm in one frame (0.75 m/s both central differences around it):
        // bridged at 25 fps (gap of 2 frames <= 0.1 s), not when the gap is longer.
        let mut s = vec![(0.0, 0.01); 4];
        s.push((0.06, 0.01));
        s.extend(vec![(0.0, 0.01); 4]);
        let f = foot(&s);
        let c = contacts(&f, &f, 25.0, &ContactRule::default());
        assert_eq!(flags(&c, 0), "111111111");
        let no_fill = ContactRule {
            max_gap: 0.0,
            ..ContactRule::default()
        };
        assert_eq!(flags(&contacts(&f, &f, 25.0, &no_fill), 0), "111001111");
        // Nothing is filled before the first contact: the foot slides in fast and low.
        let mut s = vec![(0.1, 0.01); 2];
        s.extend(vec![(0.0, 0.01); 4]);
        let f = foot(&s);
        assert_eq!(
            flags(&contacts(&f, &f, 25.0, &ContactRule::default()), 0),
            "001111"
        );
    }
}
