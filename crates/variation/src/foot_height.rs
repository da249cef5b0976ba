//! Per-foot height clean-up: a post-process between the root clean-up of [`crate::footskate`]
//! and the horizontal [`crate::foot_lock`] (the variation paper's "traditional post-processing
//! such as foot-skating correction"; not part of the GPDM model).
//!
//! Grounding moves the whole body, so only the lower foot can follow the source's floor. The two
//! leg parts are sampled independently, and a sampled swing foot often passes a centimetre over
//! the floor while the planted one floats: that swing is what a height rule counts as sliding.
//! Per foot `f` and frame `t`, with `h_f(t)` the height of the lowest vertex of the variation's
//! leg (its foot, toes included: a sampled foot may point its toes below its sole) and
//! `g_f(t) = h^s_f(m(t))` the source's at the DTW-matched frame `m(t)`, the vertical offset
//!
//! `o_f(t) = g_f(t) − h_f(t)` on frames where the source plants the foot,
//! `o_f(t) = max(0, g_f(t) − h_f(t))` elsewhere (a swing foot is raised to the source's
//! clearance, never lowered),
//!
//! each clamped to ±[`MAX_OFFSET`] and smoothed in time by [`local_linear::fit`] (σ =
//! [`SIGMA_FRAMES`]), moves every vertex `v` of that leg by `w(v) o_f(t) up`, with the leg
//! weights of [`mesh_core::feet::leg_weights`] (1 on the
//! sole, 0 at the hip seam, so the seam never opens).
//!
//! The clamp: the legs are sampled independently of the body the DTW matches to the source, so
//! a variation's leg can be in another phase than the source's at the matched frame (planted
//! where the source's swings, or the reverse). Following the source's height there would lift a
//! planted foot by the source's whole clearance (and the body with it: the lowest point floats)
//! or pull a swinging foot down to the floor, stretching the leg by as much. The errors the
//! clean-up is for are centimetres; a foot farther than [`MAX_OFFSET`] from the source's height
//! is moved by that much at most and otherwise keeps its own motion.
//!
//! [`local_linear::fit`]: crate::local_linear::fit

use nalgebra::Vector3;

use crate::grounding::{at, lowest};

/// Smoothing width of the offsets (frames): one frame, so that a swing's peak clearance is kept.
pub const SIGMA_FRAMES: f64 = 1.0;

/// Largest vertical move of a foot (m; module doc).
pub const MAX_OFFSET: f64 = 0.05;

/// The smoothed offsets `o_f(t)` of one foot (module doc). `var_low[t]` = `h_f(t)`,
/// `source_low` the source's lowest sole heights per source frame, `matches[t]` = `m(t)`,
/// `planted[t]` the source's contact at `m(t)`.
pub fn offsets(
    var_low: &[f64],
    source_low: &[f64],
    matches: &[f64],
    planted: &[bool],
    sigma: f64,
) -> Vec<f64> {
    if source_low.is_empty() {
        return vec![0.0; var_low.len()];
    }
    let raw: Vec<f64> = var_low
        .iter()
        .zip(matches)
        .zip(planted)
        .map(|((&h, &m), &p)| {
            let d = at(source_low, m) - h;
            let d = if p { d } else { d.max(0.0) };
            d.clamp(-MAX_OFFSET, MAX_OFFSET)
        })
        .collect();
    crate::local_linear::fit(&raw, sigma)
}

/// Applies the clean-up in place (module doc); returns the largest |offset| (m). `legs[f]` are
/// the leg weights (their vertices are the leg whose lowest point is measured),
/// `source_legs[f]` the source's lowest height of that leg per source frame ([`lowest`] of
/// the same vertices), `contacts[t][f]` the source's contacts at the matched frames, `matches`
/// the DTW correspondence to the source.
pub fn lift(
    frames: &mut [Vec<Vector3<f64>>],
    source_legs: &[Vec<f64>; 2],
    matches: &[f64],
    legs: &[Vec<(u32, f64)>; 2],
    contacts: &[[bool; 2]],
    up: &Vector3<f64>,
) -> f64 {
    let mut max: f64 = 0.0;
    for f in 0..2 {
        let leg: Vec<u32> = legs[f].iter().map(|&(v, _)| v).collect();
        if leg.is_empty() {
            continue;
        }
        let planted: Vec<bool> = (0..frames.len())
            .map(|t| contacts.get(t).is_some_and(|c| c[f]))
            .collect();
        let o = offsets(
            &lowest(frames, &leg, up),
            &source_legs[f],
            matches,
            &planted,
            SIGMA_FRAMES,
        );
        for (frame, &d) in frames.iter_mut().zip(&o) {
            max = max.max(d.abs());
            let shift = up * d;
            for &(v, w) in &legs[f] {
                frame[v as usize] += shift * w;
            }
        }
    }
    max
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn planted_feet_follow_the_source_and_swings_are_only_raised() {
        // Source sole heights 0 (planted) then 0.08 (swing); the variation's foot floats 3 cm
        // while planted, then swings 4 cm too low (frames 5-9) and 7 cm too high (frames 10-14).
        let src: Vec<f64> = (0..15).map(|t| if t < 5 { 0.0 } else { 0.08 }).collect();
        let var: Vec<f64> = (0..15)
            .map(|t| match t {
                0..=4 => 0.03,
                5..=9 => 0.04,
                _ => 0.15,
            })
            .collect();
        let matches: Vec<f64> = (0..15).map(|t| t as f64).collect();
        let planted: Vec<bool> = (0..15).map(|t| t < 5).collect();
        let o = offsets(&var, &src, &matches, &planted, 0.0);
        for t in 0..5 {
            assert!((o[t] + 0.03).abs() < 1e-12, "planted: lowered onto the floor");
        }
        for t in 5..10 {
            assert!((o[t] - 0.04).abs() < 1e-12, "low swing raised to the source's clearance");
        }
        for t in 10..15 {
            assert_eq!(o[t], 0.0, "a higher swing is kept");
        }
    }

    #[test]
    fn a_foot_in_another_phase_than_the_source_moves_by_the_clamp_at_most() {
        // The source swings its foot 40 cm up where the variation's is planted (frames 0-4), and
        // plants it where the variation's swings 30 cm up (frames 5-9).
        let src: Vec<f64> = (0..10).map(|t| if t < 5 { 0.40 } else { 0.0 }).collect();
        let var: Vec<f64> = (0..10).map(|t| if t < 5 { 0.0 } else { 0.30 }).collect();
        let matches: Vec<f64> = (0..10).map(|t| t as f64).collect();
        let planted: Vec<bool> = (0..10).map(|t| t >= 5).collect();
        let o = offsets(&var, &src, &matches, &planted, 0.0);
        for t in 0..5 {
            assert_eq!(o[t], MAX_OFFSET, "a planted foot is not lifted to the source's swing");
        }
        for t in 5..10 {
            assert_eq!(o[t], -MAX_OFFSET, "a swinging foot is not pulled down to the floor");
        }
    }

    #[test]
    fn a_leg_is_lifted_by_its_weights_and_the_seam_stays() {
        // Two "vertices" per foot: sole (w = 1) and knee (w = 0.5); vertex 4 is the torso.
        let up = Vector3::z();
        let frame = |h: f64| {
            vec![
                Vector3::new(0.0, 0.0, h),
                Vector3::new(0.0, 0.0, 0.5),
                Vector3::new(0.3, 0.0, 0.0),
                Vector3::new(0.3, 0.0, 0.5),
                Vector3::new(0.1, 0.0, 1.0),
            ]
        };
        let source: Vec<_> = (0..6).map(|_| frame(0.0)).collect();
        let mut var: Vec<_> = (0..6).map(|_| frame(0.02)).collect();
        let legs = [vec![(0, 1.0), (1, 0.5)], vec![(2, 1.0), (3, 0.5)]];
        let matches: Vec<f64> = (0..6).map(|t| t as f64).collect();
        let contacts = vec![[true, true]; 6];
        let source_legs = [0, 1].map(|f| lowest(&source, &[legs[f][0].0, legs[f][1].0], &up));
        let m = lift(&mut var, &source_legs, &matches, &legs, &contacts, &up);
        assert!((m - 0.02).abs() < 1e-12);
        for f in &var {
            assert!(f[0].z.abs() < 1e-12, "sole on the source's floor");
            assert!((f[1].z - 0.49).abs() < 1e-12, "knee moved by half");
            assert_eq!(f[2], Vector3::new(0.3, 0.0, 0.0), "the other foot already matches");
            assert_eq!(f[4], Vector3::new(0.1, 0.0, 1.0), "torso untouched");
        }
    }
}
