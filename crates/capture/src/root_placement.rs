//! Placing a body in the world from its root's per-frame rigid displacements: the inverse of
//! [`crate::align`]'s displacements (CVPR §4, "Rigid Transformation": `P_i = P_{i-1} ∘ D_i`).
//!
//! Displacements are motions of the template's root point `c` ([`crate::align::root_point`]),
//! so they are integrated as *root poses* `Q_i = P_i ∘ T(c)`:
//!
//! - [`integrate`]: `Q_0 = start`, `Q_i = Q_{i-1} ∘ D_i` (the first displacement, `D_0`, is not
//!   used: frame 0 stands at `start`), optionally corrected per frame by a [`Gravity`] target
//!   (3DV: the decoded height and up axis of the root, `Q_i = G_i(Q_{i-1} ∘ D_i)`, frame 0 too);
//! - [`world_poses`]: `P_i = Q_i ∘ T(-c)`, the poses of the template-frame vertices
//!   ([`world_poses_from`]: both, from a world start pose);
//! - [`place`] / [`place_in_place`]: each frame's vertices moved by its pose, `P_i(x)`.

use mesh_core::rigid::RigidMotion;
use nalgebra::{Rotation3, Vector3, Vector6};

/// The gravity correction `G_i` of [`integrate`]: per frame `[h, u_x, u_y, u_z]`, the root
/// point's height `h` along the unit `up` axis and the body-frame direction `u` that should
/// point up. `G_i` is the smallest world rotation of the root pose taking its body-frame `u`
/// onto `up` (none when `u` is zero), then the root point's height set to `h`; heading and
/// horizontal travel stay integrated. Frames past the end of `targets` are not corrected.
#[derive(Clone, Copy, Debug)]
pub struct Gravity<'a> {
    pub targets: &'a [[f64; 4]],
    pub up: &'a Vector3<f64>,
}

impl Gravity<'_> {
    /// `pose` corrected toward frame `t`'s target (unchanged past the last target).
    fn correct(&self, t: usize, pose: &mut RigidMotion) {
        let Some(g) = self.targets.get(t) else {
            return;
        };
        let u = Vector3::new(g[1], g[2], g[3]);
        if u.norm() > 1e-9 {
            // The world direction the body-frame up axis points to now, turned onto `up`.
            let now = pose.rotation * u.normalize();
            if let Some(q) = Rotation3::rotation_between(&now, self.up) {
                pose.rotation = q * pose.rotation;
            }
        }
        pose.translation += self.up * (g[0] - pose.translation.dot(self.up));
    }
}

/// Root poses of `n` frames (module doc): `Q_0 = start`, `Q_i = Q_{i-1} ∘ D_i` with `D_i` the
/// 6-vector `displacements[i]` (translation, then log-rotation), each corrected by `gravity`
/// when given. `displacements` needs at least `n` entries.
pub fn integrate(start: &RigidMotion, displacements: &[[f64; 6]], n: usize, gravity: Option<&Gravity>) -> Vec<RigidMotion> {
    let mut poses = Vec::with_capacity(n);
    let mut cur = *start;
    for t in 0..n {
        if t > 0 {
            cur = cur.compose(&RigidMotion::from_6vec(&Vector6::from_column_slice(&displacements[t])));
        }
        if let Some(g) = gravity {
            g.correct(t, &mut cur);
        }
        poses.push(cur);
    }
    poses
}

/// World poses of `n` frames of a body whose frame 0 stands at the world pose `start`: its root
/// pose `start ∘ T(c)` ([`crate::align::root_poses`]) [`integrate`]d, then [`world_poses`].
pub fn world_poses_from(
    start: &RigidMotion,
    root: &Vector3<f64>,
    displacements: &[[f64; 6]],
    n: usize,
    gravity: Option<&Gravity>,
) -> Vec<RigidMotion> {
    let q0 = crate::align::root_poses(std::slice::from_ref(start), root)[0];
    world_poses(&integrate(&q0, displacements, n, gravity), root)
}

/// World poses `P_i = Q_i ∘ T(-c)` of root poses `Q_i` of the root point `root`.
pub fn world_poses(root_poses: &[RigidMotion], root: &Vector3<f64>) -> Vec<RigidMotion> {
    let back = RigidMotion::new(Rotation3::identity(), -root);
    root_poses.iter().map(|q| q.compose(&back)).collect()
}

/// Each frame's (template-frame) vertices moved by its pose; as many frames as both have.
pub fn place(poses: &[RigidMotion], frames: &[Vec<Vector3<f64>>]) -> Vec<Vec<Vector3<f64>>> {
    frames.iter().zip(poses).map(|(f, p)| p.apply_all(f)).collect()
}

/// [`place`] without a second copy of the frames: each frame is replaced by its placed self,
/// and frames past the last pose are dropped.
pub fn place_in_place(poses: &[RigidMotion], frames: &mut Vec<Vec<Vector3<f64>>>) {
    frames.truncate(poses.len());
    for (f, p) in frames.iter_mut().zip(poses) {
        for v in f.iter_mut() {
            *v = p.apply(v);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mesh_core::rigid::so3_exp;

    /// Constant body-frame steps of 0.1 m forward and a quarter turn per frame trace a square:
    /// after 4 steps the body is back at the start.
    #[test]
    fn integrates_a_square_path() {
        let start = RigidMotion::new(so3_exp(&Vector3::new(0.0, 0.3, 0.0)), Vector3::new(1.0, 0.0, 2.0));
        let step = [0.0, 0.0, 0.1, 0.0, std::f64::consts::FRAC_PI_2, 0.0];
        let p = integrate(&start, &[[9.0; 6], step, step, step, step], 5, None);
        assert_eq!(p.len(), 5);
        assert!((p[0].translation - start.translation).norm() < 1e-12, "D_0 is ignored");
        assert!((p[4].translation - start.translation).norm() < 1e-12);
        assert!(((p[1].translation - p[0].translation).norm() - 0.1).abs() < 1e-12);
        assert!(((p[2].translation - p[0].translation).norm() - 0.1 * 2f64.sqrt()).abs() < 1e-12);
    }

    /// The gravity correction puts the root point at each target height and turns each target's
    /// body-frame axis onto up, frame 0 included, while the heading stays integrated; frames past
    /// the targets are left as integrated.
    #[test]
    fn gravity_sets_height_and_up_axis_and_keeps_heading() {
        let up = Vector3::y();
        // Tilted 0.2 rad about x and 0.5 m too high at the start; then steps of 0.1 m forward
        // and a turn of 0.1 rad about the body's up axis, the last one also tilting.
        let start = RigidMotion::new(so3_exp(&Vector3::new(0.2, 0.0, 0.0)), Vector3::new(0.0, 1.5, 0.0));
        let turn = [0.0, 0.0, 0.1, 0.0, 0.1, 0.0];
        let tilt = [0.0, 0.0, 0.1, 0.05, 0.1, 0.0];
        let targets = [[1.0, 0.0, 1.0, 0.0], [1.1, 0.0, 1.0, 0.0], [0.9, 0.0, 1.0, 0.0]];
        let g = Gravity { targets: &targets, up: &up };
        let p = integrate(&start, &[turn, turn, turn, tilt], 4, Some(&g));
        for (pose, t) in p.iter().zip(&targets) {
            assert!((pose.translation.y - t[0]).abs() < 1e-12, "height {} vs {}", pose.translation.y, t[0]);
            assert!((pose.rotation * Vector3::y() - up).norm() < 1e-12, "body up is world up");
        }
        // The heading about up turns by the step's 0.1 rad each frame.
        let heading = |r: &Rotation3<f64>| {
            let f = r * Vector3::z();
            f.x.atan2(f.z)
        };
        for w in p[..3].windows(2) {
            assert!((heading(&w[1].rotation) - heading(&w[0].rotation) - 0.1).abs() < 1e-9);
        }
        // Frame 3 has no target: it is frame 2 composed with the step, uncorrected.
        let free = p[2].compose(&RigidMotion::from_6vec(&Vector6::from_column_slice(&tilt)));
        assert!((p[3].translation - free.translation).norm() < 1e-15);
        assert!(p[3].rotation.angle_to(&free.rotation) < 1e-15);
        assert!((p[3].rotation * Vector3::y() - up).norm() > 1e-3, "frame 3 leans: uncorrected");
    }

    /// `world_poses_from` places the root point where the integrated root poses are, and frame 0
    /// at `start` itself; `place` and `place_in_place` move vertices alike.
    #[test]
    fn world_poses_carry_the_root_offset() {
        let root = Vector3::new(0.1, 0.9, -0.2);
        let start = RigidMotion::new(so3_exp(&Vector3::new(0.0, 1.0, 0.0)), Vector3::new(2.0, 0.0, 1.0));
        let steps = [[0.0; 6], [0.0, 0.0, 0.3, 0.0, 0.5, 0.0]];
        let world = world_poses_from(&start, &root, &steps, 2, None);
        assert!((world[0].translation - start.translation).norm() < 1e-12);
        assert!(world[0].rotation.angle_to(&start.rotation) < 1e-12);
        // The root point moved 0.3 m along the body's forward axis at frame 0.
        let moved = world[1].apply(&root) - world[0].apply(&root);
        assert!((moved - start.rotation * Vector3::new(0.0, 0.0, 0.3)).norm() < 1e-12);
        let frames = vec![vec![root, Vector3::zeros()]; 2];
        let placed = place(&world, &frames);
        let mut in_place = frames.clone();
        place_in_place(&world, &mut in_place);
        assert_eq!(placed, in_place);
        assert!((placed[1][0] - world[1].apply(&root)).norm() < 1e-15);
    }
}
