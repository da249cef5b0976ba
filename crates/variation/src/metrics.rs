//! Figures of merit for variations: distance to the source, timing offset,
//! edge-length distortion, foot sliding; and the reconstruction errors of figures 4 and 7b.

use gp::dtw::{dtw_path, DtwOptions};
use mesh_core::rigid::procrustes;
use nalgebra::{DMatrix, Vector3};
use serde::{Deserialize, Serialize};

/// Mean over frames and vertices of `‖a_t(v) − b_t(v)‖` (over the common frames).
pub fn mean_vertex_distance(a: &[Vec<Vector3<f64>>], b: &[Vec<Vector3<f64>>]) -> f64 {
    let n = a.len().min(b.len());
    if n == 0 {
        return 0.0;
    }
    let s: f64 = (0..n)
        .map(|t| {
            a[t].iter()
                .zip(&b[t])
                .map(|(p, q)| (p - q).norm())
                .sum::<f64>()
                / a[t].len().max(1) as f64
        })
        .sum();
    s / n as f64
}

/// Distance to the source's pose manifold, blind to timing: the mean over frames of `a` of the
/// smallest mean per-vertex distance to any frame of `b` (vertices evenly subsampled to at most
/// `max_vertices`). A variation that stays on the source's cycle scores about the data's own
/// frame-to-frame spacing; one that leaves it scores its pose error.
pub fn nearest_frame_distance(
    a: &[Vec<Vector3<f64>>],
    b: &[Vec<Vector3<f64>>],
    max_vertices: usize,
) -> f64 {
    let n = a.first().map_or(0, |f| f.len());
    if a.is_empty() || b.is_empty() || n == 0 {
        return 0.0;
    }
    let step = n.div_ceil(max_vertices.max(1)).max(1);
    let idx: Vec<usize> = (0..n).step_by(step).collect();
    // The subsampled vertices gathered once, contiguous per frame.
    let gather = |s: &[Vec<Vector3<f64>>]| -> Vec<Vec<Vector3<f64>>> {
        s.iter().map(|f| idx.iter().map(|&v| f[v]).collect()).collect()
    };
    let (ga, gb) = (gather(a), gather(b));
    ga.iter()
        .map(|fa| {
            let mut best = f64::INFINITY;
            for fb in &gb {
                // Summed in vertex order; a frame whose partial sum already reaches the best
                // cannot be nearer (the terms are >= 0), so it is left early.
                let mut sum = 0.0;
                for (i, (p, q)) in fa.iter().zip(fb).enumerate() {
                    sum += (p - q).norm();
                    if i % 64 == 63 && sum >= best {
                        break;
                    }
                }
                best = best.min(sum);
            }
            best / idx.len() as f64
        })
        .sum::<f64>()
        / a.len() as f64
}

/// Frames rigidly aligned to `template` (pose only: no travel, no heading).
pub fn normalise(
    frames: &[Vec<Vector3<f64>>],
    template: &[Vector3<f64>],
) -> Vec<Vec<Vector3<f64>>> {
    frames
        .iter()
        .map(|f| procrustes(f, template, None).apply_all(f))
        .collect()
}

/// How fast a sequence changes pose: the mean per-vertex distance between consecutive frames
/// of `pose` (frames aligned to the template, [`normalise`]), in m per frame; 0 for fewer than
/// two frames. A variation whose latent trajectory settles toward a point moves at a fraction
/// of its source's pace while every frame stays a plausible pose.
pub fn pose_speed(pose: &[Vec<Vector3<f64>>]) -> f64 {
    if pose.len() < 2 {
        return 0.0;
    }
    mean_vertex_distance(&pose[1..], &pose[..pose.len() - 1])
}

/// Below this horizontal travel (m) a source is taken to stay in place and [`travel_ratio`]
/// has nothing to compare with.
pub const MIN_TRAVEL_M: f64 = 0.25;

/// The horizontal travel of `frames` (centroid, last frame minus first) along the source's
/// horizontal travel, as a fraction of the source's: 1 when the variation covers the source's
/// ground, 0 when it stays in place, negative when it goes backwards. None when the source
/// travels less than [`MIN_TRAVEL_M`].
pub fn travel_ratio(frames: &[Vec<Vector3<f64>>], source: &[Vec<Vector3<f64>>], up: &Vector3<f64>) -> Option<f64> {
    let travel = |f: &[Vec<Vector3<f64>>]| -> Option<Vector3<f64>> {
        let centroid = |v: &[Vector3<f64>]| v.iter().sum::<Vector3<f64>>() / v.len().max(1) as f64;
        let d = centroid(f.last()?) - centroid(f.first()?);
        let up = up.normalize();
        Some(d - up * d.dot(&up))
    };
    let s = travel(source)?;
    if s.norm() < MIN_TRAVEL_M {
        return None;
    }
    Some(travel(frames)?.dot(&s) / s.norm_squared())
}

/// Mean per-vertex distance between rows of two pose matrices (rows `(x, y, z, ...)`), ignoring
/// columns beyond `3 × n_vertices`.
pub fn mean_row_distance(a: &DMatrix<f64>, b: &DMatrix<f64>, n_vertices: usize) -> f64 {
    let mut s = 0.0;
    for t in 0..a.nrows() {
        for v in 0..n_vertices {
            let d = Vector3::new(
                a[(t, 3 * v)] - b[(t, 3 * v)],
                a[(t, 3 * v + 1)] - b[(t, 3 * v + 1)],
                a[(t, 3 * v + 2)] - b[(t, 3 * v + 2)],
            );
            s += d.norm();
        }
    }
    s / (a.nrows() * n_vertices).max(1) as f64
}

/// Timing offset in frames: mean `|i − j|` along the DTW path between the two sequences' poses
/// (each frame rigidly aligned to `template` first, so travel does not count).
pub fn timing_offset(
    a: &[Vec<Vector3<f64>>],
    b: &[Vec<Vector3<f64>>],
    template: &[Vector3<f64>],
) -> f64 {
    timing_offset_aligned(&normalise(a, template), &normalise(b, template))
}

/// [`timing_offset`] of sequences already aligned to the template ([`normalise`]).
pub fn timing_offset_aligned(a: &[Vec<Vector3<f64>>], b: &[Vec<Vector3<f64>>]) -> f64 {
    let cost = crate::prealign::pose_cost(a, b, 400);
    match dtw_path(&cost, &[], &DtwOptions::default()) {
        Ok(p) => {
            p.iter()
                .map(|&(i, j)| (i as f64 - j as f64).abs())
                .sum::<f64>()
                / p.len().max(1) as f64
        }
        Err(_) => f64::NAN,
    }
}

/// Unique undirected edges of `faces`.
pub fn edges(faces: &[[u32; 3]]) -> Vec<[u32; 2]> {
    let mut e: Vec<[u32; 2]> = faces
        .iter()
        .flat_map(|f| [[f[0], f[1]], [f[1], f[2]], [f[2], f[0]]])
        .map(|[a, b]| [a.min(b), a.max(b)])
        .collect();
    e.sort_unstable();
    e.dedup();
    e
}

/// Mean relative edge-length change `|l / l₀ − 1|` against `rest`, over frames and edges.
pub fn edge_distortion(
    frames: &[Vec<Vector3<f64>>],
    rest: &[Vector3<f64>],
    edges: &[[u32; 2]],
) -> f64 {
    let l0: Vec<f64> = edges
        .iter()
        .map(|&[a, b]| (rest[a as usize] - rest[b as usize]).norm())
        .collect();
    let mut s = 0.0;
    let mut n = 0usize;
    for f in frames {
        for (e, &l) in edges.iter().zip(&l0) {
            if l > 0.0 {
                s += ((f[e[0] as usize] - f[e[1] as usize]).norm() / l - 1.0).abs();
                n += 1;
            }
        }
    }
    if n == 0 {
        0.0
    } else {
        s / n as f64
    }
}

/// Foot sliding (m per frame): mean horizontal motion of each sole's centroid between
/// consecutive frames in which that foot is in contact in both. A foot is in contact when its
/// lowest sole vertex is within `contact_height` of the sequence's ground (the lowest sole
/// vertex over all frames). The same rule is applied to training and synthesised sequences.
pub fn foot_sliding(
    frames: &[Vec<Vector3<f64>>],
    soles: &[Vec<u32>],
    up: &Vector3<f64>,
    contact_height: f64,
) -> Option<f64> {
    let ground = soles
        .iter()
        .flat_map(|s| {
            frames
                .iter()
                .flat_map(move |f| s.iter().map(move |&v| f[v as usize].dot(up)))
        })
        .fold(f64::INFINITY, f64::min);
    let mut total = 0.0;
    let mut count = 0usize;
    for s in soles.iter().filter(|s| !s.is_empty()) {
        let low = |f: &Vec<Vector3<f64>>| {
            s.iter()
                .map(|&v| f[v as usize].dot(up))
                .fold(f64::INFINITY, f64::min)
        };
        let centre = |f: &Vec<Vector3<f64>>| {
            s.iter().map(|&v| f[v as usize]).sum::<Vector3<f64>>() / s.len() as f64
        };
        for w in frames.windows(2) {
            if low(&w[0]) - ground <= contact_height && low(&w[1]) - ground <= contact_height {
                let d = centre(&w[1]) - centre(&w[0]);
                total += (d - up * d.dot(up)).norm();
                count += 1;
            }
        }
    }
    (count > 0).then(|| total / count as f64)
}

pub use mesh_core::feet::contact_sliding;

/// Summary statistics of a list of values.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Stats {
    pub mean: f64,
    pub min: f64,
    pub max: f64,
}

impl Stats {
    pub fn of(v: &[f64]) -> Stats {
        let v: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
        if v.is_empty() {
            return Stats {
                mean: f64::NAN,
                min: f64::NAN,
                max: f64::NAN,
            };
        }
        Stats {
            mean: v.iter().sum::<f64>() / v.len() as f64,
            min: v.iter().copied().fold(f64::INFINITY, f64::min),
            max: v.iter().copied().fold(f64::NEG_INFINITY, f64::max),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pose_speed_is_the_mean_vertex_step_and_travel_ratio_compares_ground_covered() {
        // Two vertices; the second moves 3 cm a frame, the first stays: 1.5 cm per frame.
        let pose: Vec<Vec<Vector3<f64>>> =
            (0..5).map(|t| vec![Vector3::zeros(), Vector3::new(0.03 * t as f64, 0.0, 0.0)]).collect();
        assert!((pose_speed(&pose) - 0.015).abs() < 1e-12);
        assert_eq!(pose_speed(&pose[..1]), 0.0);
        let up = Vector3::y();
        let walk = |step: Vector3<f64>, n: usize| -> Vec<Vec<Vector3<f64>>> {
            (0..n).map(|t| vec![step * t as f64, step * t as f64 + Vector3::new(0.0, 1.0, 0.0)]).collect()
        };
        let source = walk(Vector3::new(0.0, 0.0, 0.1), 11); // 1 m along +z
        // Half the distance, with a climb that does not count; sideways counts nothing; backwards.
        assert!((travel_ratio(&walk(Vector3::new(0.0, 0.3, 0.05), 11), &source, &up).unwrap() - 0.5).abs() < 1e-12);
        assert!(travel_ratio(&walk(Vector3::new(0.1, 0.0, 0.0), 11), &source, &up).unwrap().abs() < 1e-12);
        assert!((travel_ratio(&walk(Vector3::new(0.0, 0.0, -0.1), 11), &source, &up).unwrap() + 1.0).abs() < 1e-12);
        // A source that stays in place has no ratio.
        assert_eq!(travel_ratio(&source, &walk(Vector3::new(0.0, 0.0, 0.01), 11), &up), None);
    }

    #[test]
    fn contact_sliding_counts_annotated_pairs_only() {
        // Left sole slides 1 cm/frame (plus 5 cm/frame vertically, not counted), right 3 cm/frame;
        // the left is planted in frames 0-2, the right in frames 2-3.
        let up = Vector3::y();
        let frames: Vec<Vec<Vector3<f64>>> = (0..4)
            .map(|t| {
                let t = t as f64;
                vec![
                    Vector3::new(0.01 * t, 0.05 * t, 0.0),
                    Vector3::new(0.0, 0.0, 0.03 * t),
                ]
            })
            .collect();
        let soles = vec![vec![0u32], vec![1u32]];
        let c = [[true, false], [true, false], [true, true], [false, true]];
        // Left pairs (0,1), (1,2): 1 cm each; right pair (2,3): 3 cm.
        let s = contact_sliding(&frames, &soles, &c, &up).unwrap();
        assert!((s - 0.05 / 3.0).abs() < 1e-12, "{s}");
        assert_eq!(
            contact_sliding(&frames, &soles, &[[false; 2]; 4], &up),
            None
        );
    }
}
