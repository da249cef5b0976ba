//! Feet on the floor: sole vertices of a template and how far planted feet slide.
//! Shared by the transfer's evaluation and the variation's figures of merit.

use nalgebra::Vector3;
use std::collections::HashSet;

/// Fails unless the smoothness `λ` of a foot-skating clean-up (the weight of its second
/// differences) is a finite number >= 0.
pub fn check_smoothness(smoothness: f64) -> crate::Result<()> {
    if smoothness.is_finite() && smoothness >= 0.0 {
        Ok(())
    } else {
        Err(crate::Error::invalid(format!(
            "foot-skating smoothness must be a finite number >= 0, got {smoothness}"
        )))
    }
}

/// Height above a leg's lowest template vertex (m) within which its vertices form the sole.
pub const SOLE_TOLERANCE: f64 = 0.015;

/// Sole vertices of the two legs: of the parts (`(name, template vertices)`) named `leg*`,
/// the vertices within `tol` of the part's lowest template vertex along `up` (left first if
/// named `*_l`). Without leg parts, the lowest vertices of the whole template split in two.
pub fn soles(
    parts: &[(&str, &[u32])],
    template: &[Vector3<f64>],
    up: &Vector3<f64>,
    tol: f64,
) -> Vec<Vec<u32>> {
    let mut legs: Vec<&(&str, &[u32])> = parts.iter().filter(|p| p.0.starts_with("leg")).collect();
    if legs.is_empty() {
        return split_soles(template, up, tol);
    }
    legs.sort_by_key(|p| !p.0.ends_with('l'));
    legs.iter()
        .map(|(_, vertices)| {
            let h = |v: u32| template.get(v as usize).map_or(f64::INFINITY, |p| p.dot(up));
            let lo = vertices.iter().map(|&v| h(v)).fold(f64::INFINITY, f64::min);
            vertices.iter().copied().filter(|&v| h(v) <= lo + tol).collect()
        })
        .collect()
}

/// Without leg parts: the template vertices within `tol` of the lowest, split in two by the
/// horizontal axis along which they spread most (the feet stand apart).
fn split_soles(template: &[Vector3<f64>], up: &Vector3<f64>, tol: f64) -> Vec<Vec<u32>> {
    let lo = template
        .iter()
        .map(|p| p.dot(up))
        .fold(f64::INFINITY, f64::min);
    let low: Vec<u32> = (0..template.len() as u32)
        .filter(|&v| template[v as usize].dot(up) <= lo + tol)
        .collect();
    if low.is_empty() {
        return Vec::new();
    }
    let c = low
        .iter()
        .map(|&v| template[v as usize])
        .sum::<Vector3<f64>>()
        / low.len() as f64;
    let axes = [Vector3::x(), Vector3::y(), Vector3::z()];
    let spread = |a: &Vector3<f64>| {
        low.iter()
            .map(|&v| (template[v as usize] - c).dot(a).powi(2))
            .sum::<f64>()
    };
    let axis = axes
        .iter()
        .filter(|a| a.dot(up).abs() < 0.5)
        .max_by(|a, b| spread(a).total_cmp(&spread(b)))
        .copied()
        .unwrap_or(Vector3::x());
    let (l, r): (Vec<u32>, Vec<u32>) = low
        .iter()
        .partition(|&&v| (template[v as usize] - c).dot(&axis) > 0.0);
    vec![l, r]
}

/// Smoothstep `3x² − 2x³` of `x` clamped to `[0, 1]`.
pub fn smoothstep(x: f64) -> f64 {
    let x = x.clamp(0.0, 1.0);
    x * x * (3.0 - 2.0 * x)
}

/// Weights `(vertex, w(v))`, `w > 0`, of a leg deformation that moves the sole and leaves the
/// hip seam in place: `w = 1` on the `sole` vertices, `w = 0` at and above the lowest vertex of
/// the leg part's boundary loop (the seam with the torso; the leg's top without one), a
/// smoothstep of the template height along `up` between. `leg` is the leg part's vertices.
pub fn leg_weights(
    leg: &[u32],
    sole: &[u32],
    template: &[Vector3<f64>],
    faces: &[[u32; 3]],
    up: &Vector3<f64>,
) -> Vec<(u32, f64)> {
    let h = |v: u32| template[v as usize].dot(up);
    let in_leg: HashSet<u32> = leg.iter().copied().collect();
    let is_sole: HashSet<u32> = sole.iter().copied().collect();
    // Boundary loop: leg vertices sharing a face with a vertex outside the leg.
    let mut top = f64::INFINITY;
    for f in faces {
        if f.iter().any(|v| in_leg.contains(v)) && f.iter().any(|v| !in_leg.contains(v)) {
            for &v in f.iter().filter(|v| in_leg.contains(v)) {
                top = top.min(h(v));
            }
        }
    }
    if !top.is_finite() {
        top = leg.iter().map(|&v| h(v)).fold(f64::NEG_INFINITY, f64::max);
    }
    let bottom = sole.iter().map(|&v| h(v)).fold(f64::NEG_INFINITY, f64::max);
    let span = top - bottom;
    leg.iter()
        .filter_map(|&v| {
            let w = if is_sole.contains(&v) {
                1.0
            } else if span > 0.0 {
                1.0 - smoothstep((h(v) - bottom) / span)
            } else {
                0.0
            };
            (w > 0.0).then_some((v, w))
        })
        .collect()
}

/// Sole centroid of each foot in every frame.
pub fn feet_tracks(frames: &[Vec<Vector3<f64>>], soles: &[Vec<u32>; 2]) -> [Vec<Vector3<f64>>; 2] {
    soles.clone().map(|s| {
        frames
            .iter()
            .map(|f| s.iter().map(|&v| f[v as usize]).sum::<Vector3<f64>>() / s.len().max(1) as f64)
            .collect()
    })
}

/// Foot sliding on annotated contacts (m per frame): mean horizontal motion of each sole's
/// centroid (`soles` = [left, right]) between consecutive frames in which `contacts` mark that
/// foot as planted in both. For a source, its own annotations; for a variation, the source's
/// at the DTW-matched frames (what [`crate::footskate`] pins, so not independent of it).
pub fn contact_sliding(
    frames: &[Vec<Vector3<f64>>],
    soles: &[Vec<u32>],
    contacts: &[[bool; 2]],
    up: &Vector3<f64>,
) -> Option<f64> {
    let mut total = 0.0;
    let mut count = 0usize;
    for (f, s) in soles
        .iter()
        .enumerate()
        .take(2)
        .filter(|(_, s)| !s.is_empty())
    {
        let centre = |fr: &Vec<Vector3<f64>>| {
            s.iter().map(|&v| fr[v as usize]).sum::<Vector3<f64>>() / s.len() as f64
        };
        for t in 1..frames.len().min(contacts.len()) {
            if contacts[t - 1][f] && contacts[t][f] {
                let d = centre(&frames[t]) - centre(&frames[t - 1]);
                total += (d - up * d.dot(up)).norm();
                count += 1;
            }
        }
    }
    (count > 0).then(|| total / count as f64)
}

