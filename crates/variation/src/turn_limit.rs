//! Slows a variation wherever it turns faster than the captures ever do.
//!
//! A sampled trajectory can pass through a stretch of the learned motion (a jump's landing, a
//! fast swing of a leg) faster than any capture passed through it, and decoded, the body turns
//! faster from one frame to the next than a viewer accepts
//! ([`crate::turns_and_tears`]). The limit re-times a variation where any of its steps passes a
//! spin bound ([`CaptureLimits::spin_bound_deg`], [`CaptureLimits::heading_spin_bound_deg`]):
//! each step from frame `t` to `t + 1` whose whole-body turn or heading change passes
//! [`MARGIN`] × the bound is spread over as many output frames as bring it under that share,
//! the frames in between interpolated linearly. Steps under it keep one frame each, so a
//! variation that never turns too fast is left bit for bit, and the variation keeps its frame
//! count (it ends a little earlier in the motion). `hmc-sample` limits each variation last, after
//! the clean-ups, which turn the decoded frames less than they were sampled.

use nalgebra::Vector3;

use crate::turns_and_tears::{heading_turn_degrees, turn_degrees, CaptureLimits};

/// Share of the spin bound a slowed step is brought to (the linear interpolation of two turned
/// frames turns a little unevenly along the step).
pub const MARGIN: f64 = 0.95;
/// Passes of re-timing at most: each measures the re-timed frames again.
const PASSES: usize = 3;

/// Re-times `frames` so that no step turns faster than the captures' spin bounds (module
/// doc); `core` and `up` as for the headings ([`heading_turn_degrees`]). Returns the time of
/// every output frame in input frames (`times[i] <= i`), or None when no step was slowed.
pub fn limit(frames: &mut Vec<Vec<Vector3<f64>>>, core: &[u32], up: &Vector3<f64>, limits: &CaptureLimits) -> Option<Vec<f64>> {
    let bounds = [limits.spin_bound_deg(), limits.heading_spin_bound_deg()];
    // Captures that never turn give no bound to hold a variation to.
    if frames.len() < 2 || !bounds.iter().all(|b| b.is_finite() && *b > 0.0) {
        return None;
    }
    let mut times: Option<Vec<f64>> = None;
    for _ in 0..PASSES {
        let turns = turn_degrees(frames);
        let headings = heading_turn_degrees(frames, core, up);
        let rates: Vec<f64> = turns
            .iter()
            .zip(&headings)
            .map(|(&a, &h)| {
                let r = f64::max(a / (MARGIN * bounds[0]), h / (MARGIN * bounds[1]));
                if r.is_finite() { r.max(1.0) } else { 1.0 }
            })
            .collect();
        let over = turns.iter().zip(&headings).any(|(&a, &h)| a > bounds[0] || h > bounds[1]);
        if !over {
            break;
        }
        let step = retimed(&rates, frames.len());
        *frames = step.iter().map(|&u| frame_at(frames, u)).collect();
        times = Some(match times {
            None => step,
            Some(prev) => step.iter().map(|&u| value_at(&prev, u)).collect(),
        });
    }
    times
}

/// Times (in input frames) of `count` output frames, one output frame spending one unit of
/// `rate[t]`-weighted time: step `t` (frame `t` to `t + 1`) takes `rate[t]` output frames.
pub fn retimed(rate: &[f64], count: usize) -> Vec<f64> {
    let last = rate.len() as f64;
    let mut times = Vec::with_capacity(count);
    let mut u = 0.0_f64;
    for _ in 0..count {
        times.push(u);
        let mut budget = 1.0;
        while budget > 0.0 && u < last {
            let t = (u.floor() as usize).min(rate.len() - 1);
            let cost = (t as f64 + 1.0 - u) * rate[t];
            if cost <= budget {
                budget -= cost;
                u = t as f64 + 1.0;
            } else {
                u += budget / rate[t];
                budget = 0.0;
            }
        }
    }
    times
}

/// The frame at time `u` of `frames`, interpolated linearly between its two neighbours.
fn frame_at(frames: &[Vec<Vector3<f64>>], u: f64) -> Vec<Vector3<f64>> {
    let t = (u.floor() as usize).min(frames.len() - 1);
    let f = u - t as f64;
    if f <= 0.0 || t + 1 >= frames.len() {
        return frames[t].clone();
    }
    frames[t].iter().zip(&frames[t + 1]).map(|(a, b)| a + (b - a) * f).collect()
}

/// How many input steps `times` ([`limit`]) spread over more than one output frame.
pub fn slowed_steps(times: &[f64]) -> usize {
    let mut steps: Vec<usize> = times.windows(2).filter(|w| w[1] - w[0] < 1.0 - 1e-9).map(|w| w[0].floor() as usize).collect();
    steps.dedup();
    steps.len()
}

/// `values` at time `u`, interpolated linearly.
pub fn value_at(values: &[f64], u: f64) -> f64 {
    let t = (u.floor() as usize).min(values.len() - 1);
    let f = u - t as f64;
    match values.get(t + 1) {
        Some(&b) if f > 0.0 => values[t] + (b - values[t]) * f,
        _ => values[t],
    }
}

/// `values` at time `u`: the nearest frame's.
pub fn nearest<T: Clone>(values: &[T], u: f64) -> T {
    values[(u.round() as usize).min(values.len() - 1)].clone()
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Rotation3, Vector3};

    fn limits(turn: f64) -> CaptureLimits {
        CaptureLimits { max_turn_deg: turn, max_edge_m: 1.0, max_course_turn_deg: 90.0, max_heading_turn_deg: turn }
    }

    /// A rigid cloud turned about the vertical by `angles[t]` degrees at frame `t`.
    fn turned(angles: &[f64]) -> Vec<Vec<Vector3<f64>>> {
        let body: Vec<Vector3<f64>> = (0..40)
            .map(|i| {
                let s = i as f64;
                Vector3::new((s * 0.7).sin(), 0.1 * s, (s * 1.3).cos())
            })
            .collect();
        angles
            .iter()
            .map(|a| {
                let r = Rotation3::from_axis_angle(&Vector3::y_axis(), a.to_radians());
                body.iter().map(|p| r * p).collect()
            })
            .collect()
    }

    #[test]
    fn a_variation_under_the_bound_is_left_bit_for_bit() {
        let mut frames = turned(&[0.0, 2.0, 4.0, 5.0, 7.0]);
        let before = frames.clone();
        assert!(limit(&mut frames, &[], &Vector3::y(), &limits(2.0)).is_none());
        assert_eq!(frames, before);
    }

    #[test]
    fn a_fast_step_is_spread_over_frames_that_turn_under_the_bound() {
        // Captures turn at most 2°/frame (bound 2.5°); the variation turns 10° in one step.
        let angles = [0.0, 2.0, 4.0, 14.0, 16.0, 18.0, 20.0, 22.0];
        let mut frames = turned(&angles);
        let times = limit(&mut frames, &[], &Vector3::y(), &limits(2.0)).expect("slowed");
        assert_eq!(frames.len(), angles.len());
        let turns = turn_degrees(&frames);
        assert!(turns.iter().all(|&a| a <= 2.5 + 1e-9), "{turns:?}");
        // The steps before the fast one (frame 2 to 3) are untouched; it takes 10 / (0.95 × 2.5)
        // ≈ 4.2 of the 5 output frames left, the rest at the input's rate after frame 3.
        assert_eq!(&times[..3], &[0.0, 1.0, 2.0]);
        assert_eq!(&frames[..3], &turned(&angles)[..3]);
        let end = times[angles.len() - 1];
        assert!((end - (3.0 + 5.0 - 10.0 / 2.375)).abs() < 1e-9, "{times:?}");
        // Time runs forward and never faster than the input's.
        assert!(times.windows(2).all(|w| w[1] > w[0] && w[1] - w[0] <= 1.0 + 1e-12));
    }

    #[test]
    fn captures_that_never_turn_give_no_limit() {
        let mut frames = turned(&[0.0, 30.0, 60.0]);
        assert!(limit(&mut frames, &[], &Vector3::y(), &limits(0.0)).is_none());
    }

    #[test]
    fn times_spend_each_steps_rate() {
        let t = retimed(&[1.0, 2.0, 1.0], 5);
        assert_eq!(t, vec![0.0, 1.0, 1.5, 2.0, 3.0]);
        assert_eq!(value_at(&[0.0, 10.0, 20.0], 1.5), 15.0);
        assert_eq!(value_at(&[0.0, 10.0], 1.0), 10.0);
        assert_eq!(nearest(&[1, 2, 3], 1.6), 3);
        assert_eq!(slowed_steps(&t), 1);
    }
}
