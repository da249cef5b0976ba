//! Foot-skating clean-up of synthesised variations: a post-process, not part of the GPDM model
//! (the variation paper describes none; the transfer paper's §6 names foot-skating correction
//! among the "traditional post-processing"). Applied after [`crate::grounding`].
//!
//! Sampled trajectories carry their own root travel (the torso's displacement values) which
//! need not match the legs' strides, so planted feet slide. Per frame `t` the whole body is
//! shifted horizontally by `d(t)` (orthogonal to `up`), solved by [`capture::footskate`] (the
//! objective is stated there) with one anchor term per contact interval of each foot: its sole
//! centroids, once shifted, stay at one free anchor, so with both feet planted the correction is
//! the least-squares compromise of the two. The smoothness `λ` = [`SMOOTHNESS`] removes drift
//! slower than about 6 frames and leaves frame-to-frame jitter of the foot on the foot rather
//! than shaking the whole body; `d(0) = 0` keeps the variation's start, the source's first
//! pose; the ridge (1e-9) only keeps the system definite when every contact lasts a single
//! frame. A sequence with planted feet that do not slide comes back unchanged (`d = 0`).
//!
//! Contacts of a variation come from its source's annotations at the DTW-matched frames
//! ([`transfer_contacts`], the correspondence [`crate::grounding`] uses): the variation follows
//! the source's phase, and its own sole speeds cannot say which foot is planted precisely
//! because its feet slide (0.03-0.16 m per frame before the clean-up).

use capture::footskate::Problem;
use mesh_core::feet::feet_tracks;
use mesh_core::{Error, Result};
use nalgebra::Vector3;

/// Default weight `λ` of the second differences of the correction (per frame², against
/// weight 1 per contact residual).
pub const SMOOTHNESS: f64 = 1.0;

/// Ridge weight `μ` (module doc; [`capture::footskate`]).
const RIDGE: f64 = 1e-9;

/// Contacts of a variation's frames: the source's at the nearest DTW-matched frame `matches[t]`.
pub fn transfer_contacts(source: &[[bool; 2]], matches: &[f64]) -> Vec<[bool; 2]> {
    if source.is_empty() {
        return vec![[false; 2]; matches.len()];
    }
    matches
        .iter()
        .map(|&m| source[(m.round().max(0.0) as usize).min(source.len() - 1)])
        .collect()
}

/// Maximal runs `[start, end)` of `true` in `flags`.
pub fn intervals(flags: &[bool]) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let mut start = None;
    for (t, &f) in flags.iter().enumerate() {
        match (f, start) {
            (true, None) => start = Some(t),
            (false, Some(s)) => {
                out.push((s, t));
                start = None;
            }
            _ => {}
        }
    }
    if let Some(s) = start {
        out.push((s, flags.len()));
    }
    out
}

/// Horizontal root corrections `d(t)` (module doc) for feet tracks `feet[f][t]` (one point per
/// foot and frame, e.g. the sole centroid) and contacts `contacts[t][f]`. Jitter retries of the
/// factorisation go to `notes`.
pub fn corrections(
    feet: &[Vec<Vector3<f64>>; 2],
    contacts: &[[bool; 2]],
    up: &Vector3<f64>,
    smoothness: f64,
    notes: &mut Vec<String>,
) -> Result<Vec<Vector3<f64>>> {
    let n = contacts.len();
    mesh_core::feet::check_smoothness(smoothness)?;
    if feet.iter().any(|f| f.len() != n) {
        return Err(Error::invalid(format!(
            "foot-skating clean-up: {n} contact frames but feet tracks of {} and {} frames",
            feet[0].len(),
            feet[1].len()
        )));
    }
    let runs: [Vec<(usize, usize)>; 2] =
        [0, 1].map(|f| intervals(&contacts.iter().map(|c| c[f]).collect::<Vec<_>>()));
    if n == 0 || runs.iter().all(Vec::is_empty) {
        return Ok(vec![Vector3::zeros(); n]);
    }
    let horizontal = |p: &Vector3<f64>| p - up * up.dot(p);
    let mut problem = Problem::<3>::new(n, smoothness, RIDGE)?;
    for (f, runs) in runs.iter().enumerate() {
        for &(s, e) in runs {
            let sole: Vec<[f64; 3]> = (s..e).map(|t| horizontal(&feet[f][t]).into()).collect();
            problem.add_anchor(s, &sole);
        }
    }
    let d = problem.solve(notes)?;
    Ok(std::iter::once(Vector3::zeros())
        .chain(d[1..].iter().map(|d| horizontal(&Vector3::from(*d))))
        .collect())
}

/// Cleans `frames` in place (module doc): shifts every frame by its correction; returns the
/// corrections. `soles` are the left and right sole vertices, `contacts` per frame
/// `[left, right]`.
pub fn clean(
    frames: &mut [Vec<Vector3<f64>>],
    soles: &[Vec<u32>; 2],
    contacts: &[[bool; 2]],
    up: &Vector3<f64>,
    smoothness: f64,
    notes: &mut Vec<String>,
) -> Result<Vec<Vector3<f64>>> {
    let d = corrections(&feet_tracks(frames, soles), contacts, up, smoothness, notes)?;
    for (f, dt) in frames.iter_mut().zip(&d) {
        f.iter_mut().for_each(|p| *p += dt);
    }
    Ok(d)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn intervals_and_transfer() {
        assert_eq!(
            intervals(&[true, true, false, true, false, false, true]),
            vec![(0, 2), (3, 4), (6, 7)]
        );
        assert!(intervals(&[false, false]).is_empty());
        let src = [[true, false], [false, false], [false, true]];
        assert_eq!(
            transfer_contacts(&src, &[0.0, 0.4, 0.6, 1.7, 5.0]),
            vec![
                [true, false],
                [true, false],
                [false, false],
                [false, true],
                [false, true]
            ]
        );
    }

    /// A walking "body" of 4 points at frame `t` (y up, travel along x): two soles and two
    /// body points. Left foot planted at x = 0 for frames 0-9 then at 0.8 for 14-23, right foot
    /// planted at 0.4 in frames 5-18; the body moves at 0.04 m/frame.
    fn walk(t: usize) -> Vec<Vector3<f64>> {
        let tf = t as f64;
        let left = if t < 10 {
            0.0
        } else if t < 14 {
            0.2 * (tf - 9.0)
        } else {
            0.8
        };
        let right = if t < 5 {
            0.4 - 0.08 * (5.0 - tf)
        } else if t < 19 {
            0.4
        } else {
            0.4 + 0.1 * (tf - 18.0)
        };
        vec![
            Vector3::new(left, 0.0, 0.1),
            Vector3::new(right, 0.0, -0.1),
            Vector3::new(0.04 * tf, 1.0, 0.0),
            Vector3::new(0.04 * tf, 1.5, 0.05),
        ]
    }

    fn contacts(n: usize) -> Vec<[bool; 2]> {
        (0..n)
            .map(|t| [t < 10 || t >= 14, (5..19).contains(&t)])
            .collect()
    }

    const SOLES: [&[u32]; 2] = [&[0], &[1]];

    fn soles() -> [Vec<u32>; 2] {
        SOLES.map(|s| s.to_vec())
    }

    #[test]
    fn planted_feet_are_left_alone() {
        let mut frames: Vec<_> = (0..24).map(walk).collect();
        let orig = frames.clone();
        let mut notes = Vec::new();
        let d = clean(
            &mut frames,
            &soles(),
            &contacts(24),
            &Vector3::y(),
            SMOOTHNESS,
            &mut notes,
        )
        .unwrap();
        assert!(d.iter().all(|v| v.norm() < 1e-9), "{d:?}");
        for (fa, fb) in frames.iter().zip(&orig) {
            for (p, q) in fa.iter().zip(fb) {
                assert!((p - q).norm() < 1e-9);
            }
        }
        assert!(notes.is_empty());
    }

    #[test]
    fn a_known_drift_comes_back_out() {
        // The whole body drifts horizontally by δ(t) (linear: 1 cm/frame along x, 0.5 along z):
        // the correction is −δ(t) (δ(0) = 0: the start is kept), to rounding.
        let n = 24;
        let drift = |t: usize| Vector3::new(0.01 * t as f64, 0.0, -0.005 * t as f64);
        let truth: Vec<_> = (0..n).map(walk).collect();
        let mut frames: Vec<Vec<Vector3<f64>>> = truth
            .iter()
            .enumerate()
            .map(|(t, f)| f.iter().map(|p| p + drift(t)).collect())
            .collect();
        let mut notes = Vec::new();
        let d = clean(
            &mut frames,
            &soles(),
            &contacts(n),
            &Vector3::y(),
            SMOOTHNESS,
            &mut notes,
        )
        .unwrap();
        for t in 0..n {
            assert!((d[t] + drift(t)).norm() < 1e-7, "frame {t}: {}", d[t]);
            for (p, q) in frames[t].iter().zip(&truth[t]) {
                assert!((p - q).norm() < 1e-7);
            }
        }
        // Planted feet stay put (the metric the clean-up targets): no sliding left.
        let tracks = feet_tracks(&frames, &soles());
        for (f, runs) in [0, 1].map(|f| {
            (
                f,
                intervals(&contacts(n).iter().map(|c| c[f]).collect::<Vec<_>>()),
            )
        }) {
            for (s, e) in runs {
                for t in s + 1..e {
                    assert!((tracks[f][t] - tracks[f][s]).norm() < 1e-5);
                }
            }
        }
        // Heights are untouched.
        for (fa, fb) in frames.iter().zip(&truth) {
            for (p, q) in fa.iter().zip(fb) {
                assert!((p.y - q.y).abs() < 1e-15);
            }
        }
    }

    #[test]
    fn a_slide_within_one_contact_is_removed_smoothly() {
        // Only the left foot's second stance slides, +2 cm/frame once it is the only planted
        // foot (frames 19-23; the right foot is right). Removing it needs d = −slide there,
        // eased in from the double support without a step.
        let n = 24;
        let slide = |t: usize| if t > 18 { 0.02 * (t - 18) as f64 } else { 0.0 };
        let mut frames: Vec<Vec<Vector3<f64>>> = (0..n)
            .map(|t| {
                let mut f = walk(t);
                f[0].x += slide(t);
                f
            })
            .collect();
        let before = feet_tracks(&frames, &soles());
        let slide_before = (before[0][23] - before[0][14]).norm();
        assert!((slide_before - 0.1).abs() < 1e-12);
        let mut notes = Vec::new();
        let d = clean(
            &mut frames,
            &soles(),
            &contacts(n),
            &Vector3::y(),
            SMOOTHNESS,
            &mut notes,
        )
        .unwrap();
        let after = feet_tracks(&frames, &soles());
        let spread = |f: usize, s: usize, e: usize| {
            (s..e)
                .flat_map(|i| (s..e).map(move |j| (i, j)))
                .map(|(i, j)| (after[f][i] - after[f][j]).norm())
                .fold(0.0, f64::max)
        };
        let (left, right) = (spread(0, 14, 24), spread(1, 5, 19));
        assert!(left < 0.1 * slide_before, "left foot still slides {left}");
        assert!(right < 0.1 * slide_before, "right foot slides {right}");
        for t in 1..n {
            let step = (d[t] - d[t - 1]).norm();
            assert!(step < 0.021, "frame {t}: step {step}");
        }
    }

    #[test]
    fn wrong_lengths_are_an_error() {
        let tracks = [vec![Vector3::zeros(); 3], vec![Vector3::zeros(); 2]];
        let e = corrections(
            &tracks,
            &[[true; 2]; 3],
            &Vector3::y(),
            1.0,
            &mut Vec::new(),
        );
        assert!(e.is_err());
    }
}
