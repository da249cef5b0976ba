//! Body-frame displacements (transfer paper §4) and their integration.

use mesh_core::rigid::{integrate, relative_in_body_frame, relative_motions, so3_exp, RigidMotion};
use nalgebra::Vector3;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn random_motion(r: &mut ChaCha8Rng) -> RigidMotion {
    let mut v = || {
        Vector3::new(
            r.random_range(-1.0..1.0),
            r.random_range(-1.0..1.0),
            r.random_range(-1.0..1.0),
        )
    };
    RigidMotion::new(so3_exp(&(v() * 1.5)), v() * 3.0)
}

fn close(a: &RigidMotion, b: &RigidMotion, tol: f64) -> bool {
    (a.rotation.matrix() - b.rotation.matrix()).norm() < tol
        && (a.translation - b.translation).norm() < tol
}

#[test]
fn integrate_inverts_relative_motions() {
    let mut r = ChaCha8Rng::seed_from_u64(20);
    let motions: Vec<_> = (0..30).map(|_| random_motion(&mut r)).collect();
    let rel = relative_motions(&motions);
    assert_eq!(rel.len(), motions.len() - 1);
    let back = integrate(&motions[0], &rel);
    assert_eq!(back.len(), motions.len());
    for (a, b) in back.iter().zip(&motions) {
        assert!(close(a, b, 1e-11));
    }
    assert_eq!(integrate(&motions[0], &[]), vec![motions[0]]);
}

#[test]
fn relative_motion_satisfies_its_definition() {
    let mut r = ChaCha8Rng::seed_from_u64(21);
    for _ in 0..20 {
        let prev = random_motion(&mut r);
        let cur = random_motion(&mut r);
        let d = relative_in_body_frame(&prev, &cur);
        assert!(close(&prev.compose(&d), &cur, 1e-12));
        // A point fixed in the body moves, seen from the previous body frame, by d.
        let p = Vector3::new(0.3, -0.2, 0.9);
        let seen = prev.inverse().apply(&cur.apply(&p));
        assert!((seen - d.apply(&p)).norm() < 1e-12);
    }
}

#[test]
fn displacements_do_not_depend_on_start_position_or_heading() {
    let mut r = ChaCha8Rng::seed_from_u64(22);
    let motions: Vec<_> = (0..10).map(|_| random_motion(&mut r)).collect();
    let g = random_motion(&mut r);
    let moved: Vec<_> = motions.iter().map(|m| g.compose(m)).collect();
    for (a, b) in relative_motions(&motions)
        .iter()
        .zip(&relative_motions(&moved))
    {
        assert!(close(a, b, 1e-11));
    }
}
