//! Procrustes recovers known motions and never returns a reflection;
//! RigidMotion algebra agrees with applying motions one after the other.

use mesh_core::rigid::{procrustes, RigidMotion};
use nalgebra::{Matrix3, Rotation3, UnitQuaternion, Vector3};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn rng(seed: u64) -> ChaCha8Rng {
    ChaCha8Rng::seed_from_u64(seed)
}

fn random_point(r: &mut ChaCha8Rng) -> Vector3<f64> {
    Vector3::new(
        r.random_range(-1.0..1.0),
        r.random_range(-1.0..1.0),
        r.random_range(-1.0..1.0),
    )
}

/// A uniformly random rotation from a normalised Gaussian-ish quaternion
/// (built independently of the code under test).
fn random_rotation(r: &mut ChaCha8Rng) -> Rotation3<f64> {
    let q = nalgebra::Quaternion::new(
        r.random_range(-1.0..1.0),
        r.random_range(-1.0..1.0),
        r.random_range(-1.0..1.0),
        r.random_range(-1.0..1.0),
    );
    UnitQuaternion::from_quaternion(q).to_rotation_matrix()
}

fn random_motion(r: &mut ChaCha8Rng) -> RigidMotion {
    RigidMotion::new(random_rotation(r), random_point(r) * 5.0)
}

fn assert_proper_rotation(m: &Matrix3<f64>) {
    assert!(
        (m.transpose() * m - Matrix3::identity()).norm() < 1e-12,
        "not orthonormal: {m}"
    );
    assert!(
        (m.determinant() - 1.0).abs() < 1e-12,
        "det = {}",
        m.determinant()
    );
}

fn weighted_residual(m: &RigidMotion, src: &[Vector3<f64>], dst: &[Vector3<f64>]) -> f64 {
    src.iter()
        .zip(dst)
        .map(|(s, d)| (m.apply(s) - d).norm_squared())
        .sum()
}

#[test]
fn recovers_a_known_rotation_and_translation() {
    let mut r = rng(1);
    for _ in 0..20 {
        let truth = random_motion(&mut r);
        let src: Vec<_> = (0..50).map(|_| random_point(&mut r)).collect();
        let dst = truth.apply_all(&src);
        let est = procrustes(&src, &dst, None);
        assert_proper_rotation(est.rotation.matrix());
        assert!((est.rotation.matrix() - truth.rotation.matrix()).norm() < 1e-10);
        assert!((est.translation - truth.translation).norm() < 1e-10);
    }
}

#[test]
fn zero_weights_ignore_outliers() {
    let mut r = rng(2);
    let truth = random_motion(&mut r);
    let src: Vec<_> = (0..40).map(|_| random_point(&mut r)).collect();
    let mut dst = truth.apply_all(&src);
    let mut w = vec![1.0; src.len()];
    for i in (0..src.len()).step_by(3) {
        dst[i] += random_point(&mut r) * 10.0; // outlier
        w[i] = 0.0;
    }
    let est = procrustes(&src, &dst, Some(&w));
    assert!((est.rotation.matrix() - truth.rotation.matrix()).norm() < 1e-10);
    assert!((est.translation - truth.translation).norm() < 1e-10);
    // Without the weights the outliers pull the answer away.
    let unweighted = procrustes(&src, &dst, None);
    assert!((unweighted.translation - truth.translation).norm() > 1e-3);
}

#[test]
fn mirrored_data_gives_the_best_proper_rotation_not_a_reflection() {
    let mut r = rng(3);
    let mirror = Matrix3::from_diagonal(&Vector3::new(-1.0, 1.0, 1.0));
    for _ in 0..10 {
        let src: Vec<_> = (0..30).map(|_| random_point(&mut r)).collect();
        let rot = random_rotation(&mut r);
        let dst: Vec<_> = src
            .iter()
            .map(|p| rot * (mirror * p) + Vector3::new(1.0, 2.0, 3.0))
            .collect();
        let w: Vec<f64> = (0..src.len()).map(|_| r.random_range(0.5..2.0)).collect();
        let est = procrustes(&src, &dst, Some(&w));
        assert_proper_rotation(est.rotation.matrix());
        // Optimality against independent candidates: perturbations of the
        // estimate and random rotations, each with its own best translation.
        let cost = |m: &RigidMotion| -> f64 {
            src.iter()
                .zip(&dst)
                .zip(&w)
                .map(|((s, d), w)| w * (m.apply(s) - d).norm_squared())
                .sum()
        };
        let best_translation = |rot: Rotation3<f64>| {
            let tw: f64 = w.iter().sum();
            let t = src
                .iter()
                .zip(&dst)
                .zip(&w)
                .fold(Vector3::zeros(), |acc, ((s, d), w)| {
                    acc + (d - rot * s) * *w
                })
                / tw;
            RigidMotion::new(rot, t)
        };
        let c0 = cost(&est);
        for _ in 0..200 {
            let small = Rotation3::from_scaled_axis(random_point(&mut r) * 0.05);
            assert!(cost(&best_translation(small * est.rotation)) >= c0 - 1e-9);
            assert!(cost(&best_translation(random_rotation(&mut r))) >= c0 - 1e-9);
        }
    }
}

#[test]
fn degenerate_inputs() {
    assert_eq!(procrustes(&[], &[], None), RigidMotion::identity());
    let p = [Vector3::new(1.0, 2.0, 3.0)];
    let q = [Vector3::new(0.0, 0.0, 1.0)];
    assert_eq!(procrustes(&p, &q, Some(&[0.0])), RigidMotion::identity());
    // One point: any rotation fits; the translation must map it exactly.
    let m = procrustes(&p, &q, None);
    assert!((m.apply(&p[0]) - q[0]).norm() < 1e-12);
    // Non-finite input propagates as NaN rather than hanging or panicking.
    let nan = [
        Vector3::new(f64::NAN, 0.0, 0.0),
        Vector3::new(1.0, 0.0, 0.0),
    ];
    let m = procrustes(&nan, &nan, None);
    assert!(m.translation.x.is_nan());
}

#[test]
fn compose_inverse_and_identity() {
    let mut r = rng(4);
    for _ in 0..20 {
        let a = random_motion(&mut r);
        let b = random_motion(&mut r);
        let p = random_point(&mut r);
        assert!((a.compose(&b).apply(&p) - a.apply(&b.apply(&p))).norm() < 1e-12);
        assert!((a.inverse().apply(&a.apply(&p)) - p).norm() < 1e-12);
        let id = a.compose(&a.inverse());
        assert!((id.rotation.matrix() - Matrix3::identity()).norm() < 1e-12);
        assert!(id.translation.norm() < 1e-12);
        assert_eq!(RigidMotion::identity().apply(&p), p);
        let src: Vec<_> = (0..10).map(|_| random_point(&mut r)).collect();
        assert!(weighted_residual(&a, &src, &a.apply_all(&src)) < 1e-20);
    }
}
