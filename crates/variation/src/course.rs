//! Keeping a variation on its source's course (a deviation from the paper, docs/DEVIATIONS.md).
//!
//! 3DV §4 places every frame by integrating the decoded displacements `(δT, δR)`: a variation's
//! heading is the sum of its decoded turns, a random walk whose bias nothing pulls back. A
//! captured straight run turns ±7° per frame about a mean near 0; a sampled run whose latent
//! trajectory leaves the learned one by a few tenths of the latent spread decodes a steady 4-10°
//! per frame, which is a circle within a second. Height and tilt are absolute for the same
//! reason ([`crate::part_data`], gravity values); the heading gets a reference here.
//!
//! [`keep`] follows the source through the variation's correspondence to it (the DTW matches
//! of [`crate::grounding::MatchSource`]): with `h_v(t)` the variation's heading at frame `t` and
//! `h_s(m_t)` the source's at the matched frame (both from their first frame, about the up axis,
//! unwrapped), the correction `c(t)` is the slowly varying part of `h_s(m_t) − h_v(t)`: a
//! Gaussian-weighted local linear fit of width `σ` (a local linear fit follows a steady drift
//! to the clip's ends, where a plain Gaussian average lags). Every frame turns by `c(t)` about the
//! vertical axis through its core point, and the horizontal travel is re-integrated along the
//! corrected heading. What stays of the variation's own heading is what departs from the source
//! faster than `σ`: the sway within a stride.

use nalgebra::{Rotation3, Unit, Vector3};

use mesh_core::rigid::procrustes;

/// Width σ of the correction's local fit, in seconds ([`keep`]): a heading change faster than
/// about 3 Hz stays the variation's own, anything slower follows the source. Wider, a variation's
/// own turns within a few tenths of a second stay and pass 1.25 × the captures' largest turn
/// from the start: tiny preset (seed 0) 0.25 s: 43 frames, 0.15 s: 11, 0.1 s: 0; the holdout's
/// run (50 fps, latent dimension 5) 0.1 s: 9 frames, 0.05 s: 0.
pub const SIGMA_SECONDS: f64 = 0.05;

/// Signed heading (radians, unwrapped) of the vertices `core` of every frame from the first
/// frame: the angle about `up` by which the best rigid fit of frame 0's core onto frame `t`'s
/// turns a horizontal direction.
pub fn headings(frames: &[Vec<Vector3<f64>>], core: &[u32], up: &Vector3<f64>) -> Vec<f64> {
    let pick = |f: &[Vector3<f64>]| -> Vec<Vector3<f64>> {
        if core.is_empty() {
            f.to_vec()
        } else {
            core.iter().map(|&v| f[v as usize]).collect()
        }
    };
    let Some(first) = frames.first().map(|f| pick(f)) else { return Vec::new() };
    let up = up.normalize();
    let across = horizontal(&up);
    let mut out: Vec<f64> = Vec::with_capacity(frames.len());
    for f in frames {
        let r = procrustes(&first, &pick(f), None).rotation;
        let g = r * across;
        let g = g - up * g.dot(&up);
        let angle = across.cross(&g).dot(&up).atan2(across.dot(&g));
        // Unwrap: consecutive headings differ by less than half a turn.
        let h = match out.last() {
            Some(&prev) => prev + wrap(angle - prev),
            None => angle,
        };
        out.push(h);
    }
    out
}

/// A unit vector perpendicular to `up`.
fn horizontal(up: &Vector3<f64>) -> Vector3<f64> {
    let trial = if up.x.abs() < 0.9 { Vector3::x() } else { Vector3::z() };
    (trial - up * trial.dot(up)).normalize()
}

/// `a` wrapped into (−π, π].
fn wrap(a: f64) -> f64 {
    let t = std::f64::consts::TAU;
    let r = a.rem_euclid(t);
    if r > std::f64::consts::PI { r - t } else { r }
}

/// Turns every frame of the variation `frames` back onto the course of its source (module doc):
/// `source_heading` is the source's [`headings`] on `core`, `matches[t]` the source frame
/// (fractional) matched to frame `t`, `core` the vertices the headings are measured on and whose
/// centroid each frame turns about, `sigma` the local fit's width in frames. Returns the
/// correction `c(t)` applied (radians).
pub fn keep(
    frames: &mut [Vec<Vector3<f64>>],
    source_heading: &[f64],
    matches: &[f64],
    core: &[u32],
    up: &Vector3<f64>,
    sigma: f64,
) -> Vec<f64> {
    if frames.len() < 2 || source_heading.is_empty() || matches.len() != frames.len() {
        return vec![0.0; frames.len()];
    }
    let hv = headings(frames, core, up);
    let hs = source_heading;
    let error: Vec<f64> =
        (0..frames.len()).map(|t| crate::grounding::at(hs, matches[t]) - crate::grounding::at(hs, matches[0]) - hv[t]).collect();
    let c = crate::local_linear::fit(&error, sigma);
    let axis = Unit::new_normalize(*up);
    let centre = |f: &[Vector3<f64>]| -> Vector3<f64> {
        let n = if core.is_empty() { f.len() } else { core.len() };
        let sum: Vector3<f64> = if core.is_empty() {
            f.iter().sum()
        } else {
            core.iter().map(|&v| f[v as usize]).sum()
        };
        sum / n.max(1) as f64
    };
    let centres: Vec<Vector3<f64>> = frames.iter().map(|f| centre(f)).collect();
    let mut placed = centres[0];
    for t in 0..frames.len() {
        let turn = Rotation3::from_axis_angle(&axis, c[t]);
        if t > 0 {
            let step = centres[t] - centres[t - 1];
            let vertical = axis.into_inner() * step.dot(&axis);
            placed += turn * (step - vertical) + vertical;
        }
        let from = centres[t];
        for p in frames[t].iter_mut() {
            *p = turn * (*p - from) + placed;
        }
    }
    c
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A small irregular body facing +z.
    fn body() -> Vec<Vector3<f64>> {
        vec![
            Vector3::new(0.0, 0.0, 0.0),
            Vector3::new(0.3, 0.1, 0.0),
            Vector3::new(0.1, 1.2, 0.1),
            Vector3::new(-0.2, 0.6, 0.25),
            Vector3::new(0.15, 0.9, -0.1),
        ]
    }

    /// `body` turned by `heading` about +y and put at `at`.
    fn posed(heading: f64, at: Vector3<f64>) -> Vec<Vector3<f64>> {
        let r = Rotation3::from_axis_angle(&Vector3::y_axis(), heading);
        body().iter().map(|p| r * p + at).collect()
    }

    /// A body walking along its heading, which changes by `rate(t)` per frame.
    fn walk(n: usize, rate: impl Fn(usize) -> f64) -> Vec<Vec<Vector3<f64>>> {
        let (mut h, mut at) = (0.0, Vector3::zeros());
        (0..n)
            .map(|t| {
                if t > 0 {
                    h += rate(t);
                    at += Rotation3::from_axis_angle(&Vector3::y_axis(), h) * Vector3::new(0.0, 0.0, 0.1);
                }
                posed(h, at)
            })
            .collect()
    }

    #[test]
    fn headings_measure_a_turn_about_up_with_its_sign_past_half_a_turn() {
        let frames: Vec<_> = [0.0, 0.5, -0.3, 2.5, 4.0, 5.5, 7.0].iter().map(|&h| posed(h, Vector3::new(1.0, 0.0, 2.0))).collect();
        let h = headings(&frames, &[], &Vector3::y());
        for (got, want) in h.iter().zip([0.0, 0.5, -0.3, 2.5, 4.0, 5.5, 7.0]) {
            assert!((got - want).abs() < 1e-9, "{got} vs {want}");
        }
    }

    #[test]
    fn a_variation_that_circles_is_brought_back_to_a_straight_source_and_keeps_its_sway() {
        let n = 40;
        let sway = |t: usize| 0.05 * (t as f64 * std::f64::consts::PI / 2.0).cos();
        let source = walk(n, |_| 0.0);
        let mut var = walk(n, |t| sway(t) + 0.08); // 4.6° a frame: 180° in 40 frames
        let matches: Vec<f64> = (0..n).map(|t| t as f64).collect();
        let before = headings(&var, &[], &Vector3::y());
        assert!(before[n - 1] > 3.0, "{}", before[n - 1]);
        keep(&mut var, &headings(&source, &[], &Vector3::y()), &matches, &[], &Vector3::y(), 5.0);
        let after = headings(&var, &[], &Vector3::y());
        let own: Vec<f64> = (0..n).map(|t| (1..=t).map(sway).sum::<f64>()).collect();
        for t in 0..n {
            // The sway (±0.05 rad a frame, ±0.05 rad in heading) is kept; the drift is gone.
            assert!((after[t] - own[t]).abs() < 0.03, "frame {t}: {} vs {}", after[t], own[t]);
        }
        // The travel follows the corrected heading: the body ends ahead of its start, not
        // back where a half circle would take it.
        let c = |f: &[Vector3<f64>]| f.iter().sum::<Vector3<f64>>() / f.len() as f64;
        let travel = c(&var[n - 1]) - c(&var[0]);
        assert!(travel.z > 3.5 && travel.x.abs() < 0.5, "{travel:?}");
        // The up coordinates are untouched.
        let height = |f: &[Vector3<f64>]| f.iter().map(|p| p.y).sum::<f64>();
        assert!((height(&var[n - 1]) - height(&walk(n, |_| 0.0)[n - 1])).abs() < 1e-9);
    }

    #[test]
    fn a_variation_on_its_sources_turning_course_is_left_where_it_is() {
        let n = 30;
        let source = walk(n, |_| 0.03);
        let mut var = walk(n, |t| 0.03 + 0.02 * (t as f64).sin());
        let orig = var.clone();
        let matches: Vec<f64> = (0..n).map(|t| t as f64).collect();
        let c = keep(&mut var, &headings(&source, &[], &Vector3::y()), &matches, &[], &Vector3::y(), 5.0);
        assert!(c.iter().all(|v| v.abs() < 0.03), "{c:?}");
        let moved = var.iter().zip(&orig).flat_map(|(a, b)| a.iter().zip(b).map(|(p, q)| (p - q).norm())).fold(0.0, f64::max);
        assert!(moved < 0.1, "{moved}");
    }
}
