//! Linear blend skinning: `v' = sum_b w_vb (R_b (v - h_b) + h'_b)` with rest heads `h_b`,
//! posed heads `h'_b` and world rotations `R_b` from forward kinematics.

use nalgebra::Vector3;

use crate::skeleton::{Pose, Skeleton};

/// Per-vertex skinning weights: (bone, weight) pairs summing to one.
pub type Weights = Vec<Vec<(usize, f64)>>;

/// Normalises each weight row to sum one (rows that are all zero stay empty).
pub fn normalise(weights: &mut Weights) {
    for row in weights.iter_mut() {
        row.retain(|&(_, w)| w > 0.0);
        let s: f64 = row.iter().map(|&(_, w)| w).sum();
        if s > 0.0 {
            for e in row.iter_mut() {
                e.1 /= s;
            }
        }
    }
}

/// Skins all vertices of `rest` with `weights` into `pose`.
pub fn skin(
    skel: &Skeleton,
    rest: &[Vector3<f64>],
    weights: &Weights,
    pose: &Pose,
) -> Vec<Vector3<f64>> {
    rest.iter()
        .zip(weights)
        .map(|(v, row)| skin_vertex(skel, v, row, pose))
        .collect()
}

/// One vertex of [`skin`].
pub fn skin_vertex(
    skel: &Skeleton,
    v: &Vector3<f64>,
    row: &[(usize, f64)],
    pose: &Pose,
) -> Vector3<f64> {
    let mut out = Vector3::zeros();
    for &(b, w) in row {
        out += w * (pose.rotations[b] * (v - skel.bones[b].head) + pose.heads[b]);
    }
    out
}
