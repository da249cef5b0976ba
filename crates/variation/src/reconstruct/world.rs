//! World placement: the root poses integrated from the decoded displacements, corrected by the
//! decoded gravity (height and up axis), and applied to the template-aligned body.

use mesh_core::rigid::RigidMotion;
use nalgebra::{Vector3, Vector6};

/// World poses `P_t` of [`place`] (module doc there) for `n` frames.
pub fn world_poses(
    n: usize,
    displacements: &[[f64; 6]],
    gravity: &[[f64; 4]],
    up: &Vector3<f64>,
    start: &RigidMotion,
    root: &Vector3<f64>,
) -> Vec<RigidMotion> {
    let mut poses = Vec::with_capacity(n);
    let to_root = RigidMotion::new(nalgebra::Rotation3::identity(), *root);
    let back = to_root.inverse();
    // The root pose `Q = P ∘ T(root)` is integrated and corrected; each frame's `P = Q ∘ T(−root)`.
    let mut cur = start.compose(&to_root);
    for t in 0..n {
        if t > 0 {
            cur = cur.compose(&RigidMotion::from_6vec(&Vector6::from_row_slice(
                &displacements[t],
            )));
        }
        if let Some(g) = gravity.get(t) {
            let u = Vector3::new(g[1], g[2], g[3]);
            if u.norm() > 1e-9 {
                // World direction the decoded body-up axis currently points to; rotate it onto `up`.
                let now = cur.rotation * u.normalize();
                if let Some(q) = nalgebra::Rotation3::rotation_between(&now, up) {
                    cur.rotation = q * cur.rotation;
                }
            }
            cur.translation += up * (g[0] - cur.translation.dot(up));
        }
        poses.push(cur.compose(&back));
    }
    poses
}

/// World frames `P_t = Q_t ∘ T(−root)` of the root poses `Q_0 = G_0(start ∘ T(root))`,
/// `Q_t = G_t(Q_{t−1} ∘ D_t)` (the first displacement is ignored), where `G_t` is the gravity
/// correction (deviation, see [`crate::part_data`]): the smallest world rotation about the root
/// point taking the pose's body-frame up axis to the decoded one, then the root point's height
/// set to the decoded height. Heading and horizontal travel stay
/// integrated. Frame 0 is corrected too: a variation starts at its source's first pose, whose
/// lean and height can be another motion's (a blend starts where its first motion does), and
/// would otherwise tilt by the difference between frames 0 and 1. With `gravity` empty, plain
/// integration.
pub fn place(
    body: &[Vec<Vector3<f64>>],
    displacements: &[[f64; 6]],
    gravity: &[[f64; 4]],
    up: &Vector3<f64>,
    start: &RigidMotion,
    root: &Vector3<f64>,
) -> Vec<Vec<Vector3<f64>>> {
    let poses = world_poses(body.len(), displacements, gravity, up, start, root);
    body.iter()
        .zip(&poses)
        .map(|(f, p)| p.apply_all(f))
        .collect()
}
