//! Feet contacts of a capture without annotations, from its meshes: a foot is planted in a frame
//! when its sole is near the floor and barely moves horizontally.
//!
//! Per foot and frame, the sole height is the mean height of the sole's 5 lowest vertices above
//! the floor, the floor being the 2nd percentile over the motion of the lower sole's height
//! (robust to a few noisy frames); the speed is the horizontal speed of the sole's centroid by
//! central differences. A frame is a contact when height < [`Rule::height`] and speed <
//! [`Rule::speed`]; isolated flips shorter than [`Rule::min_run`] frames are removed and gaps of
//! at most [`Rule::max_gap`] seconds during which the sole stays low are filled (as `synth`'s
//! rule on skeleton joints does).

use nalgebra::Vector3;

use mesh_core::contacts::Contacts;

/// Thresholds of [`detect`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rule {
    /// Sole height above the floor below which a foot may be planted (m).
    pub height: f64,
    /// Horizontal sole speed below which a foot may be planted (m/s).
    pub speed: f64,
    /// Longest gap filled between two contacts while the sole stays low (s).
    pub max_gap: f64,
    /// Shortest run of equal flags kept (frames); shorter runs take their neighbours' value.
    pub min_run: usize,
}

impl Default for Rule {
    fn default() -> Self {
        Rule {
            height: 0.10,
            speed: 0.6,
            max_gap: 0.1,
            min_run: 2,
        }
    }
}

/// Per-frame `[left, right]` contacts of world-space `frames` at `fps`, `soles` the two feet's
/// sole vertices (`mesh_core::feet::soles`). None when there are not two non-empty soles.
pub fn detect(
    frames: &[Vec<Vector3<f64>>],
    soles: &[Vec<u32>],
    up: &Vector3<f64>,
    fps: f64,
    rule: &Rule,
) -> Option<Contacts> {
    if soles.len() != 2 || soles.iter().any(|s| s.is_empty()) || frames.is_empty() {
        return None;
    }
    let n = frames.len();
    let height = |f: &[Vector3<f64>], sole: &[u32]| {
        let mut h: Vec<f64> = sole
            .iter()
            .filter_map(|&v| f.get(v as usize).map(|p| p.dot(up)))
            .collect();
        h.sort_by(f64::total_cmp);
        let k = h.len().min(5).max(1);
        h[..k].iter().sum::<f64>() / k as f64
    };
    let centroid = |f: &[Vector3<f64>], sole: &[u32]| {
        let s: Vector3<f64> = sole.iter().filter_map(|&v| f.get(v as usize)).sum();
        let p = s / sole.len() as f64;
        p - up * p.dot(up)
    };
    let heights: Vec<[f64; 2]> = frames
        .iter()
        .map(|f| [height(f, &soles[0]), height(f, &soles[1])])
        .collect();
    let mut lows: Vec<f64> = heights.iter().map(|h| h[0].min(h[1])).collect();
    lows.sort_by(f64::total_cmp);
    let floor = lows[(0.02 * (n - 1) as f64).round() as usize];
    let mut out: Contacts = vec![[false; 2]; n];
    for foot in 0..2 {
        let c: Vec<Vector3<f64>> = frames.iter().map(|f| centroid(f, &soles[foot])).collect();
        let low = |t: usize| heights[t][foot] - floor < rule.height;
        let mut down: Vec<bool> = (0..n)
            .map(|t| {
                let (a, b) = (t.saturating_sub(1), (t + 1).min(n - 1));
                let v = if b > a {
                    (c[b] - c[a]).norm() * fps / (b - a) as f64
                } else {
                    0.0
                };
                low(t) && v < rule.speed
            })
            .collect();
        remove_short_runs(&mut down, rule.min_run);
        let max_gap = (rule.max_gap * fps).round() as usize;
        let mut last: Option<usize> = None;
        for t in 0..n {
            if down[t] {
                if let Some(j) = last {
                    if t - j - 1 <= max_gap && (j + 1..t).all(low) {
                        down[j + 1..t].iter_mut().for_each(|d| *d = true);
                    }
                }
                last = Some(t);
            }
        }
        for (o, d) in out.iter_mut().zip(down) {
            o[foot] = d;
        }
    }
    Some(out)
}

/// Runs of equal flags shorter than `min_run` inside the sequence take the preceding value.
fn remove_short_runs(flags: &mut [bool], min_run: usize) {
    let n = flags.len();
    let mut start = 0;
    while start < n {
        let mut end = start;
        while end < n && flags[end] == flags[start] {
            end += 1;
        }
        if end - start < min_run && start > 0 && end < n {
            let v = flags[start - 1];
            flags[start..end].iter_mut().for_each(|f| *f = v);
        }
        start = end;
    }
}

/// Precision and recall of `detected` against `truth`, over both feet and every frame
/// (None for an empty denominator).
pub fn precision_recall(detected: &Contacts, truth: &Contacts) -> (Option<f64>, Option<f64>) {
    let (mut tp, mut fp, mut fnn) = (0usize, 0usize, 0usize);
    for (d, t) in detected.iter().zip(truth) {
        for f in 0..2 {
            match (d[f], t[f]) {
                (true, true) => tp += 1,
                (true, false) => fp += 1,
                (false, true) => fnn += 1,
                _ => {}
            }
        }
    }
    let ratio = |a: usize, b: usize| (a + b > 0).then(|| a as f64 / (a + b) as f64);
    (ratio(tp, fp), ratio(tp, fnn))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two one-vertex "soles": the left stands on the floor for frames 0-9 then swings (15 cm
    /// up), the right swings then stands; 2 mm of noise on the heights. Then the same with the
    /// standing foot skating fast along the floor: no contact.
    #[test]
    fn a_synthetic_gait_is_found_exactly() {
        let fps = 25.0;
        let gait = |skate: f64| -> Vec<Vec<Vector3<f64>>> {
            (0..20)
                .map(|t| {
                    let noise = 0.002 * ((t * 7 % 5) as f64 - 2.0) / 2.0;
                    let tt = t as f64;
                    let left = if t < 10 {
                        Vector3::new(skate * tt, 0.01 + noise, 0.0)
                    } else {
                        Vector3::new(skate * 9.0 + 0.02 * (tt - 9.0), 0.15 + noise, 0.0)
                    };
                    let right = if t < 10 {
                        Vector3::new(1.0 + 0.02 * tt, 0.15 + noise, 0.3)
                    } else {
                        Vector3::new(1.18 + skate * (tt - 9.0), 0.01 + noise, 0.3)
                    };
                    vec![left, right]
                })
                .collect()
        };
        let soles = [vec![0], vec![1]];
        let c = detect(&gait(0.0), &soles, &Vector3::y(), fps, &Rule::default()).unwrap();
        let truth: Contacts = (0..20).map(|t| [t < 10, t >= 10]).collect();
        assert_eq!(c, truth);
        assert_eq!(precision_recall(&c, &truth), (Some(1.0), Some(1.0)));
        // 0.04 m/frame = 1 m/s along the floor: sliding, not planted.
        let c = detect(&gait(0.04), &soles, &Vector3::y(), fps, &Rule::default()).unwrap();
        assert!(c.iter().all(|f| !f[0] && !f[1]), "{c:?}");
        assert!(detect(
            &gait(0.0),
            &soles[..1],
            &Vector3::y(),
            fps,
            &Rule::default()
        )
        .is_none());
    }

    #[test]
    fn short_flips_are_removed() {
        let mut f = vec![true, true, false, true, true, false, false, false];
        remove_short_runs(&mut f, 2);
        assert_eq!(f, vec![true, true, true, true, true, false, false, false]);
    }
}
