//! Leg-deforming foot lock: a post-process after the root clean-up of [`crate::footskate`]
//! (the variation paper's "traditional post-processing such as foot-skating correction"; not
//! part of the GPDM model).
//!
//! A root shift can pin only a compromise of the two feet; sampled legs also jitter against
//! the body. So, per foot `f` and contact interval `I = [s, e)`, the residual horizontal offset
//! of the sole centroid from the interval's anchor `a_I` (its mean horizontal position over
//! `I`),
//!
//! `δ(t) = a_I − p_f(t)` (horizontal part, `t ∈ I`),
//!
//! is removed by displacing every vertex `v` of that leg by `w(v) δ(t)`, with the leg weights of
//! [`mesh_core::feet::leg_weights`]: `w = 1` on the sole vertices (so the sole centroid lands
//! exactly on `a_I`), `w = 0` at the hip seam, so the seam never opens. Between contacts the
//! displacement is eased in and out over [`EASE_FRAMES`] `= R` frames with the smoothstep `S`
//! ([`displacements`]), so nothing pops when a contact starts or ends. Three easings ([`Ease`]):
//! `position` blends the sole's horizontal *position* from its free path to the
//! anchor, `q(t) = a_I + S(u) (p_f(t) − a_I)` with `u` the distance to the contact in units of
//! `R + 1` frames, so the foot slows to rest as it touches down and starts from rest as it lifts
//! off (the constraint blending of Kovar et al. 2002, "Footskate cleanup for motion capture
//! editing"), at the price of a faster sole early in the ramp, where it is usually in the air
//! (up to about 1.6x a steady approach speed with `R = 4`); `offset` fades the contact's
//! *offset* `δ` instead, which keeps the free path's velocity: a foot that lands at swing speed
//! stops dead on the contact's first frame. `flight` (the default) eases by offset a take-off or
//! landing that both feet make together (the other foot's within `R` frames: a jump) and every
//! other one by position: the position ease hurries a sole that lands from a jump at flight
//! speed (0.15 m/frame on the outside set's jump, 0.2 in the ramp) early in its ramp, and the
//! whole body's best rigid fit turns with both legs faster than the captures ever turn.
//!
//! The displacement is at most [`MAX_SHIFT`] long (shortened along its direction beyond it). The
//! contacts are the source's at the DTW-matched frames, and the legs are sampled independently
//! of the body that match is made on: where a variation's leg is in another phase than the
//! source's, or its body has turned away from the anchor, the full offset would stretch the leg
//! across the floor to reach the anchor (a tear); such a sole keeps sliding by the rest instead.

use crate::footskate::intervals;
use mesh_core::feet::feet_tracks;
use crate::group::PartDef;
use nalgebra::Vector3;
use mesh_core::feet::smoothstep;

/// Frames `R` over which the displacement is eased in before and out after each contact.
pub const EASE_FRAMES: usize = 4;

/// Longest horizontal move of a sole by the lock (m; module doc): about a foot's length.
pub const MAX_SHIFT: f64 = 0.1;

/// How the lock's displacement is eased in before and out after each contact (module doc).
#[derive(
    Clone, Copy, Debug, PartialEq, Eq, Default, clap::ValueEnum, serde::Serialize, serde::Deserialize,
)]
#[serde(rename_all = "kebab-case")]
pub enum Ease {
    /// Blend the sole's position from its free path to the contact's anchor: the foot comes
    /// to rest as it lands and leaves from rest.
    Position,
    /// Fade the contact's offset: the free path's velocity is kept up to the contact.
    Offset,
    /// `offset` where both feet take off or land together (within [`EASE_FRAMES`] frames: a
    /// jump), `position` for any other lift-off and landing (a step, a run's stride).
    #[default]
    Flight,
}

/// Leg parts of a segmentation in the order of [`crate::group::soles`] (left first).
pub fn leg_parts(parts: &[PartDef]) -> Vec<&PartDef> {
    let mut legs: Vec<&PartDef> = parts.iter().filter(|p| p.name.starts_with("leg")).collect();
    legs.sort_by_key(|p| !p.name.ends_with('l'));
    legs
}

/// Per-frame horizontal displacement `D_f(t)` of foot `f` (module doc): `a_I − p_f(t)` inside
/// contacts. In a gap `(p, s)` between the last contact frame `p` and the next contact start `s`
/// (a missing side counts as 0), with the fade `F(k) = 1 − S(k / (R + 1))`:
/// - [`Ease::Position`]: `F(t − p) (a_p − p_f(t)) + F(s − t) (a_s − p_f(t))`, or, when the gap is
///   too short for both ramps (`s − p ≤ 2 (R + 1)`), the sole carried from anchor to anchor,
///   `a_p + (a_s − a_p) S((t − p) / (s − p)) − p_f(t)`;
/// - [`Ease::Offset`]: `F(t − p) δ(p) + F(s − t) δ(s)`, or in a short gap the smoothstep
///   interpolation `δ(p) + (δ(s) − δ(p)) S((t − p) / (s − p))`;
/// - [`Ease::Flight`]: each side of the gap eased by offset where `other` (the other foot's
///   contacts) ends a contact within `R` frames of `p` (a take-off on both feet), or starts one
///   within `R` frames of `s` (a landing on both feet), by position otherwise; in a short gap
///   `(1 − S) A_p + S A_s` with `A_c` the side's own `to_anchor` term below.
///
/// Continuous at every contact end; all horizontal.
pub fn displacements(
    track: &[Vector3<f64>],
    contact: &[bool],
    other: &[bool],
    up: &Vector3<f64>,
    ease: Ease,
) -> Vec<Vector3<f64>> {
    let n = track.len().min(contact.len());
    let horizontal = |p: Vector3<f64>| p - up * up.dot(&p);
    let mut inside: Vec<Option<Vector3<f64>>> = vec![None; n];
    for (s, e) in intervals(&contact[..n]) {
        let anchor = (s..e).map(|t| track[t]).sum::<Vector3<f64>>() / (e - s) as f64;
        for (t, d) in inside.iter_mut().enumerate().take(e).skip(s) {
            *d = Some(horizontal(anchor - track[t]));
        }
    }
    let free: Vec<bool> = inside.iter().map(Option::is_none).collect();
    let ramp = (EASE_FRAMES + 1) as f64;
    let fade = |k: usize| 1.0 - smoothstep(k as f64 / ramp);
    let mut d: Vec<Vector3<f64>> = inside.iter().map(|x| x.unwrap_or_default()).collect();
    for (a, b) in intervals(&free) {
        // The neighbouring contact frames and their offsets `δ`; `track + δ` is the anchor.
        let before = a.checked_sub(1).map(|p| (p, d[p]));
        let after = (b < n).then(|| (b, d[b]));
        // Whether each side is eased by position: the take-off from `a − 1`, the landing at `b`.
        let by_position = |c: usize, edge: fn(&[bool], usize) -> bool| match ease {
            Ease::Position => true,
            Ease::Offset => false,
            Ease::Flight => !(c.saturating_sub(EASE_FRAMES)..=(c + EASE_FRAMES).min(n))
                .any(|k| edge(other, k)),
        };
        let takes_off = |o: &[bool], k: usize| o.get(k) == Some(&true) && o.get(k + 1) == Some(&false);
        let lands = |o: &[bool], k: usize| o.get(k) == Some(&true) && (k == 0 || o.get(k - 1) == Some(&false));
        let take_off = before.map(|(p, _)| by_position(p, takes_off)).unwrap_or(true);
        let landing = after.map(|(s, _)| by_position(s, lands)).unwrap_or(true);
        for t in a..b {
            // The offset of frame t from the anchor reached at contact frame c with offset δ.
            let to_anchor = |c: usize, delta: Vector3<f64>, position: bool| match position {
                true => delta + horizontal(track[c] - track[t]),
                false => delta,
            };
            d[t] = match (before, after) {
                (Some((p, dp)), Some((s, ds))) if (s - p) as f64 <= 2.0 * ramp => {
                    let x = smoothstep((t - p) as f64 / (s - p) as f64);
                    to_anchor(p, dp, take_off) * (1.0 - x) + to_anchor(s, ds, landing) * x
                }
                _ => {
                    before.map_or(Vector3::zeros(), |(p, dp)| to_anchor(p, dp, take_off) * fade(t - p))
                        + after.map_or(Vector3::zeros(), |(s, ds)| to_anchor(s, ds, landing) * fade(s - t))
                }
            };
        }
    }
    d
}

/// Shortens every displacement longer than `max` to that length, along its direction
/// (continuous, so eased displacements stay eased).
pub fn limit(d: &mut [Vector3<f64>], max: f64) {
    for x in d {
        let n = x.norm();
        if n > max {
            *x *= max / n;
        }
    }
}

/// Per frame, the height of each leg's lowest point (`legs[f]`: the leg weights of
/// [`mesh_core::feet::leg_weights`], whose vertices are the leg) above `floor`.
pub fn legs_above_floor(
    frames: &[Vec<Vector3<f64>>],
    legs: &[Vec<(u32, f64)>; 2],
    up: &Vector3<f64>,
    floor: f64,
) -> Vec<[f64; 2]> {
    let lows: [Vec<f64>; 2] = [0, 1].map(|f| {
        let leg: Vec<u32> = legs[f].iter().map(|p| p.0).collect();
        crate::grounding::lowest(frames, &leg, up)
    });
    (0..frames.len()).map(|t| [lows[0][t] - floor, lows[1][t] - floor]).collect()
}

/// Contacts for the lock: each interval of `contacts[t][f]` grown on either side, by at most
/// `max_frames`, to the farthest frame where that foot's lowest point `low[t][f]` is within
/// `height` of the floor, the frames between included. A contact carried over from the source by
/// the DTW can start or end a few frames away from where the variation's own foot touches the
/// floor; a foot that touches down just before its contact (or leaves just after) would
/// otherwise skate along the floor there, and one that taps the floor, lifts a little and
/// lands is held in place through the tap (its heights are kept).
pub fn grow_over_touches(
    contacts: &[[bool; 2]],
    low: &[[f64; 2]],
    height: f64,
    max_frames: usize,
) -> Vec<[bool; 2]> {
    let n = contacts.len().min(low.len());
    let mut out = contacts[..n].to_vec();
    for f in 0..2 {
        let flags: Vec<bool> = contacts[..n].iter().map(|c| c[f]).collect();
        let down = |t: &usize| low[*t][f] <= height;
        for (s, e) in intervals(&flags) {
            if let Some(first) = (s.saturating_sub(max_frames)..s).find(down) {
                out[first..s].iter_mut().for_each(|c| c[f] = true);
            }
            if let Some(last) = (e..(e + max_frames).min(n)).rev().find(down) {
                out[e..=last].iter_mut().for_each(|c| c[f] = true);
            }
        }
    }
    out
}

/// The source's contacts completed at the clip's ends: per foot, the run of frames reaching the
/// clip's first or last frame in which the foot's lowest point `low[t][f]` is within `height`
/// of the floor is a contact. A clip that ends as a foot lands (or starts as one lifts off)
/// cuts that contact short, and an annotation made from the sole's speed misses it: the foot
/// still moves at landing speed on the last frame. Without it a variation's foot skates over
/// the floor in the clip's last frames where the source's foot lands.
pub fn close_clip_ends(contacts: &[[bool; 2]], low: &[[f64; 2]], height: f64) -> Vec<[bool; 2]> {
    let n = contacts.len().min(low.len());
    let mut out = contacts[..n].to_vec();
    for f in 0..2 {
        for t in (0..n).take_while(|&t| low[t][f] <= height) {
            out[t][f] = true;
        }
        for t in (0..n).rev().take_while(|&t| low[t][f] <= height) {
            out[t][f] = true;
        }
    }
    out
}

/// Locks planted feet in place (module doc), in place; returns the largest displacement.
/// `legs[f]` are the weights of [`mesh_core::feet::leg_weights`], `soles[f]` the sole vertices, `contacts[t][f]`.
pub fn lock(
    frames: &mut [Vec<Vector3<f64>>],
    legs: &[Vec<(u32, f64)>; 2],
    soles: &[Vec<u32>; 2],
    contacts: &[[bool; 2]],
    up: &Vector3<f64>,
    ease: Ease,
) -> f64 {
    let tracks = feet_tracks(frames, soles);
    let mut max: f64 = 0.0;
    for f in 0..2 {
        let flags: Vec<bool> = contacts.iter().map(|c| c[f]).collect();
        let other: Vec<bool> = contacts.iter().map(|c| c[1 - f]).collect();
        let mut d = displacements(&tracks[f], &flags, &other, up, ease);
        limit(&mut d, MAX_SHIFT);
        for (frame, dt) in frames.iter_mut().zip(&d) {
            max = max.max(dt.norm());
            for &(v, w) in &legs[f] {
                frame[v as usize] += dt * w;
            }
        }
    }
    max
}

#[cfg(test)]
mod tests {
    use super::*;
    use mesh_core::feet::leg_weights;

    /// A leg strip: vertex `i` at height `0.1 i` (i = 0..=10), plus a "torso" vertex 11 at
    /// height 1.0 sharing a face with the top leg vertex 10 (the seam). Sole: vertex 0.
    fn leg() -> (Vec<Vector3<f64>>, Vec<[u32; 3]>, Vec<u32>, Vec<u32>) {
        let mut t: Vec<_> = (0..=10)
            .map(|i| Vector3::new(0.0, 0.1 * i as f64, 0.0))
            .collect();
        t.push(Vector3::new(0.1, 1.0, 0.0));
        let mut faces: Vec<[u32; 3]> = (0..9).map(|i| [i, i + 1, i + 2]).collect();
        faces.push([9, 10, 11]);
        (t, faces, (0..=10).collect(), vec![0])
    }

    #[test]
    fn a_landing_the_clip_cuts_short_becomes_a_contact() {
        // Left foot: down on frames 0-1 (annotated 0-2), up, then landing on frames 7-9, the
        // last, without annotation. Right foot: down on frame 4 only (not at an end) and
        // 2.1 cm up on the last frame.
        let contacts: Vec<[bool; 2]> = (0..10).map(|t| [t <= 2, false]).collect();
        let low: Vec<[f64; 2]> = (0..10)
            .map(|t| {
                let left = if t <= 1 || t >= 7 { 0.01 } else { 0.2 };
                let right = match t {
                    4 => 0.0,
                    9 => 0.021,
                    _ => 0.3,
                };
                [left, right]
            })
            .collect();
        let out = close_clip_ends(&contacts, &low, 0.02);
        let left: Vec<bool> = out.iter().map(|c| c[0]).collect();
        let right: Vec<bool> = out.iter().map(|c| c[1]).collect();
        let expected_left: Vec<bool> = (0..10).map(|t| t <= 2 || t >= 7).collect();
        assert_eq!(left, expected_left, "annotated start kept, landing at the end added");
        assert_eq!(right, vec![false; 10], "a touch inside the clip or above the height is not a contact");
    }

    #[test]
    fn weights_run_from_sole_to_seam() {
        let (t, faces, legv, sole) = leg();
        let w = leg_weights(&legv, &sole, &t, &faces, &Vector3::y());
        let get = |v: u32| w.iter().find(|p| p.0 == v).map_or(0.0, |p| p.1);
        assert_eq!(get(0), 1.0);
        // Boundary loop: vertices 9 and 10 share a face with the torso; the lowest, 9 (0.9),
        // is the top of the ramp: height 0.45 is half-way, smoothstep(0.5) = 0.5.
        assert_eq!(get(9), 0.0);
        assert_eq!(get(10), 0.0);
        assert!((get(4) - (1.0 - smoothstep(0.4 / 0.9))).abs() < 1e-12);
        for v in 1..9 {
            assert!(get(v) < get(v - 1), "weights decrease upwards");
        }
    }

    #[test]
    fn a_drifting_planted_sole_comes_back_pinned() {
        // Frames 0-19; the foot is planted in frames 5-14 and its sole drifts there by
        // 1 cm/frame along x and 0.5 cm/frame along z (plus a vertical bob that is kept).
        let (t, faces, legv, sole) = leg();
        let up = Vector3::y();
        let drift = |k: usize| {
            let s = (k.clamp(5, 14) - 5) as f64;
            Vector3::new(0.01 * s, 0.002 * (k as f64).sin(), 0.005 * s)
        };
        let orig: Vec<Vec<Vector3<f64>>> = (0..20)
            .map(|k| {
                let mut f = t.clone();
                f[0] += drift(k);
                f[1] += drift(k) * 0.5;
                f
            })
            .collect();
        let contacts: Vec<[bool; 2]> = (0..20).map(|k| [(5..15).contains(&k), false]).collect();
        let legs = [leg_weights(&legv, &sole, &t, &faces, &up), Vec::new()];
        let mut frames = orig.clone();
        lock(&mut frames, &legs, &[sole.clone(), vec![]], &contacts, &up, Ease::Offset);
        // Known answer: the anchor is the mean drift over the interval (4.5 cm, 2.25 cm).
        let anchor = Vector3::new(0.045, 0.0, 0.0225);
        for k in 5..15 {
            let p = frames[k][0];
            assert!((p.x - anchor.x).abs() < 1e-12 && (p.z - anchor.z).abs() < 1e-12);
            assert!((p.y - orig[k][0].y).abs() < 1e-15, "heights are kept");
        }
        for k in 0..20 {
            // w = 0 vertices (the seam and the torso) are untouched.
            for v in [9, 10, 11] {
                assert_eq!(frames[k][v], orig[k][v]);
            }
            // Far from the contact nothing moves.
            if !(5 - EASE_FRAMES..15 + EASE_FRAMES).contains(&k) {
                assert_eq!(frames[k], orig[k]);
            }
        }
        // Eased: the sole never jumps by more than the 4.5 cm anchor offset spread over the ramp.
        for k in 1..20 {
            let step = (frames[k][0] - frames[k - 1][0]).norm();
            assert!(step < 0.02, "frame {k}: step {step}");
        }
    }

    #[test]
    fn contacts_grow_to_the_farthest_touch_within_reach() {
        // Left planted in frames 3-5; its foot stays within 2 cm in frames 1-7, then lifts.
        // Right never planted: never grown. At most 3 frames each side.
        let contacts: Vec<[bool; 2]> = (0..12).map(|t| [(3..6).contains(&t), false]).collect();
        let low: Vec<[f64; 2]> = (0..12)
            .map(|t| [if (1..8).contains(&t) { 0.01 } else { 0.2 }, 0.0])
            .collect();
        let g = grow_over_touches(&contacts, &low, 0.02, 3);
        let left: Vec<bool> = g.iter().map(|c| c[0]).collect();
        let want: Vec<bool> = (0..12).map(|t| (1..8).contains(&t)).collect();
        assert_eq!(left, want);
        assert!(g.iter().all(|c| !c[1]));
        // A cap of one frame.
        let g = grow_over_touches(&contacts, &low, 0.02, 1);
        let left: Vec<bool> = g.iter().map(|c| c[0]).collect();
        assert_eq!(left, (0..12).map(|t| (2..7).contains(&t)).collect::<Vec<_>>());
        // A tap: the foot touches at frame 1, lifts in frame 2 and lands with its contact at 3;
        // after the contact it lifts at 6 and skims the floor again at 8. Grown over both
        // within 3 frames, not over a touch 4 frames away (frame 9 is up, 10 down).
        let low: Vec<[f64; 2]> = (0..12)
            .map(|t| [if [1, 3, 4, 5, 8, 10].contains(&t) { 0.01 } else { 0.05 }, 0.0])
            .collect();
        let g = grow_over_touches(&contacts, &low, 0.02, 3);
        let left: Vec<bool> = g.iter().map(|c| c[0]).collect();
        assert_eq!(left, (0..12).map(|t| (1..9).contains(&t)).collect::<Vec<_>>());
    }

    #[test]
    fn short_gaps_are_bridged_without_popping() {
        // Contacts [0, 5) and [7, 12) with a 2-frame gap; the raw track drifts 1 cm/frame
        // throughout. Contact frames are pinned to their anchors, the gap interpolates.
        let up = Vector3::y();
        let track: Vec<_> = (0..12)
            .map(|t| Vector3::new(0.01 * t as f64, 0.0, 0.0))
            .collect();
        let contact: Vec<bool> = (0..12).map(|t| !(5..7).contains(&t)).collect();
        let d = displacements(&track, &contact, &[], &up, Ease::Offset);
        let pinned: Vec<f64> = (0..12).map(|t| track[t].x + d[t].x).collect();
        for t in 0..5 {
            assert!((pinned[t] - 0.02).abs() < 1e-12, "frame {t}: {}", pinned[t]);
        }
        for t in 7..12 {
            assert!((pinned[t] - 0.09).abs() < 1e-12, "frame {t}: {}", pinned[t]);
        }
        // Gap: smoothstep of δ from −0.02 (frame 4) to +0.02 (frame 7), thirds of the way.
        assert!((d[5].x - (-0.02 + 0.04 * smoothstep(1.0 / 3.0))).abs() < 1e-12);
        assert!((d[6].x - (-0.02 + 0.04 * smoothstep(2.0 / 3.0))).abs() < 1e-12);
        // No contact at all: nothing moves.
        assert!(displacements(&track, &[false; 12], &[], &up, Ease::Position)
            .iter()
            .all(|v| v.norm() == 0.0));
    }

    #[test]
    fn a_landing_foot_comes_to_rest_with_the_position_ease() {
        // The sole arrives at 10 cm/frame along x and is planted at x = 0 from frame 10 on.
        // Known answer, position ease: q(10 − k) = −S(k / 5) · 0.1 k, so the last step into the
        // contact is S(0.2) · 0.1 = 0.0104 and the steps shrink towards it; the offset ease keeps
        // the landing speed (0.1) on that step.
        let up = Vector3::y();
        let track: Vec<_> = (0..16)
            .map(|t| Vector3::new(0.1 * (t.min(10) as f64 - 10.0), 0.0, 0.0))
            .collect();
        let contact: Vec<bool> = (0..16).map(|t| t >= 10).collect();
        let placed = |ease| -> Vec<f64> {
            let d = displacements(&track, &contact, &[], &up, ease);
            (0..16).map(|t| track[t].x + d[t].x).collect()
        };
        let q = placed(Ease::Position);
        for k in 1..=EASE_FRAMES {
            let want = -smoothstep(k as f64 / 5.0) * 0.1 * k as f64;
            assert!((q[10 - k] - want).abs() < 1e-12, "frame {}: {}", 10 - k, q[10 - k]);
        }
        assert!((q[10] - q[9] - 0.1 * smoothstep(0.2)).abs() < 1e-12);
        // Slowing down over the last three steps; the ramp's first steps are faster than the
        // free path (at most 1.64x here: the sole catches up the distance it will not cover).
        for t in 7..10 {
            assert!(q[t + 1] - q[t] < q[t] - q[t - 1], "slowing down at frame {t}");
        }
        assert!((1..16).all(|t| q[t] - q[t - 1] <= 0.165));
        // Outside the ramp the free path is kept; inside the contact the sole is pinned.
        for t in 0..=10 - EASE_FRAMES - 1 {
            assert_eq!(q[t], track[t].x);
        }
        assert!(q[10..].iter().all(|x| x.abs() < 1e-12));
        let o = placed(Ease::Offset);
        assert!((o[10] - o[9] - 0.1).abs() < 1e-12);
    }

    #[test]
    fn a_sole_out_of_reach_moves_by_the_limit_along_its_offset() {
        // The sole stands at the origin, then 1 m away (a leg in another phase than the
        // source's), in one contact: the anchor is half way, 50 cm from either, and the sole
        // moves 10 cm towards it.
        let up = Vector3::y();
        let track: Vec<_> = (0..10)
            .map(|t| if t < 5 { Vector3::zeros() } else { Vector3::new(0.6, 0.0, 0.8) })
            .collect();
        let contact = vec![true; 10];
        let mut d = displacements(&track, &contact, &[], &up, Ease::Position);
        limit(&mut d, MAX_SHIFT);
        for (t, x) in d.iter().enumerate() {
            assert!(x.norm() <= MAX_SHIFT + 1e-12, "frame {t}: {x}");
        }
        assert!((d[0] - Vector3::new(0.06, 0.0, 0.08)).norm() < 1e-12, "{}", d[0]);
        assert!((d[9] + d[0]).norm() < 1e-12, "{}", d[9]);
        let mut small = vec![Vector3::new(0.03, 0.0, 0.04)];
        limit(&mut small, MAX_SHIFT);
        assert_eq!(small[0], Vector3::new(0.03, 0.0, 0.04), "a reachable offset is kept");
    }

    #[test]
    fn a_short_step_is_carried_from_anchor_to_anchor() {
        // Planted at x = 0 in frames 0-3 and at x = 0.3 in frames 7-11; between, the free sole
        // wanders (not toward the next anchor). With the position ease it moves from anchor to
        // anchor along the smoothstep, whatever the free path did; heights are never touched.
        let up = Vector3::y();
        let track: Vec<_> = (0..12)
            .map(|t| match t {
                0..=3 => Vector3::new(0.0, 0.0, 0.0),
                4..=6 => Vector3::new(-0.05 * t as f64, 0.1, 0.02 * t as f64),
                _ => Vector3::new(0.3, 0.0, 0.0),
            })
            .collect();
        let contact: Vec<bool> = (0..12).map(|t| !(4..7).contains(&t)).collect();
        let d = displacements(&track, &contact, &[], &up, Ease::Position);
        for t in 4..7 {
            let x = smoothstep((t - 3) as f64 / 4.0);
            let q = track[t] + d[t];
            assert!((q.x - 0.3 * x).abs() < 1e-12 && q.z.abs() < 1e-12, "frame {t}: {q}");
            assert_eq!(d[t].y, 0.0);
        }
    }
    #[test]
    fn a_flight_is_eased_by_offset_and_a_step_by_position() {
        // One foot leaves a contact in frames 0-1, lands at 10 cm/frame on frame 13 after a
        // long gap, stands on frames 13-14, and steps in a short gap (frames 15-17, where the
        // free sole wanders) to a contact from frame 18 on. The other foot is either off the
        // ground in both gaps (a jump: flights) or planted throughout (steps).
        let up = Vector3::y();
        let track: Vec<_> = (0..24)
            .map(|t| match t {
                0..=14 => Vector3::new(0.1 * (t.clamp(2, 13) as f64 - 13.0), 0.0, 0.0),
                15..=17 => Vector3::new(0.02 * t as f64, 0.1, -0.01 * t as f64),
                _ => Vector3::new(0.3 + 0.001 * t as f64, 0.0, 0.0),
            })
            .collect();
        let contact: Vec<bool> = (0..24).map(|t| t <= 1 || (13..15).contains(&t) || t >= 18).collect();
        let eased = |other: &[bool], ease| displacements(&track, &contact, other, &up, ease);
        let (jump, planted) = (contact.clone(), vec![true; 24]);
        assert_eq!(eased(&jump, Ease::Flight), eased(&jump, Ease::Offset), "flights by offset");
        assert_eq!(eased(&planted, Ease::Flight), eased(&planted, Ease::Position), "steps by position");
        assert_ne!(eased(&jump, Ease::Offset), eased(&jump, Ease::Position));
        // Known answers: out of the flight the sole lands at its 10 cm/frame (its offset is 0
        // on the contact); across the short flight the offset is interpolated.
        let d = eased(&jump, Ease::Flight);
        let q: Vec<Vector3<f64>> = (0..24).map(|t| track[t] + d[t]).collect();
        assert!((q[13].x - q[12].x - 0.1).abs() < 1e-12, "{}", q[13].x - q[12].x);
        for t in 15..18 {
            let want = d[14] + (d[18] - d[14]) * smoothstep((t - 14) as f64 / 4.0);
            assert!((d[t] - want).norm() < 1e-12, "frame {t}: {}", d[t]);
        }
        // A run's other foot takes off and lands more than R frames from this foot's (here at
        // least 6 frames apart): both gaps are steps.
        let run: Vec<bool> = (0..24).map(|t| (5..9).contains(&t)).collect();
        assert_eq!(eased(&run, Ease::Flight), eased(&run, Ease::Position));
    }
}
