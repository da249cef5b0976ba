//! SO(3) exp/log maps: agreement with nalgebra's independent implementation,
//! round trips at every angle including near 0 and near pi, and the
//! derivative of exp at 0 by finite differences.

use std::f64::consts::PI;

use mesh_core::rigid::{hat, so3_exp, so3_log, RigidMotion};
use nalgebra::{Rotation3, Vector3, Vector6};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn unit(r: &mut ChaCha8Rng) -> Vector3<f64> {
    loop {
        let v = Vector3::new(
            r.random_range(-1.0..1.0),
            r.random_range(-1.0..1.0),
            r.random_range(-1.0..1.0),
        );
        let n = v.norm();
        if n > 0.1 && n < 1.0 {
            return v / n;
        }
    }
}

/// Angles that stress each branch: tiny, the Taylor switch, ordinary, pi/2, near pi.
const ANGLES: [f64; 14] = [
    0.0,
    1e-300,
    1e-12,
    1e-8,
    9.99e-5,
    1.001e-4,
    0.3,
    1.0,
    PI / 2.0 - 1e-12,
    PI / 2.0 + 1e-12,
    2.5,
    PI - 1e-6,
    PI - 1e-9,
    PI - 1e-13,
];

#[test]
fn exp_matches_nalgebra() {
    let mut r = ChaCha8Rng::seed_from_u64(10);
    for &theta in &ANGLES {
        for _ in 0..20 {
            let h = unit(&mut r) * theta;
            let ours = so3_exp(&h);
            let theirs = Rotation3::from_scaled_axis(h);
            assert!(
                (ours.matrix() - theirs.matrix()).norm() < 1e-14,
                "theta {theta}"
            );
            let m = ours.matrix();
            assert!((m.transpose() * m - nalgebra::Matrix3::identity()).norm() < 1e-14);
        }
    }
}

#[test]
fn log_inverts_exp_at_every_angle() {
    let mut r = ChaCha8Rng::seed_from_u64(11);
    for &theta in &ANGLES {
        for _ in 0..50 {
            let h = unit(&mut r) * theta;
            let back = so3_log(&so3_exp(&h));
            // Absolute error ~ eps near 0; near pi the axis comes from the
            // symmetric part, whose error is ~ eps as well.
            assert!((back - h).norm() < 1e-12, "theta {theta}: {h} -> {back}");
        }
    }
}

#[test]
fn log_at_exactly_pi_gives_an_equivalent_vector() {
    let mut r = ChaCha8Rng::seed_from_u64(12);
    for _ in 0..50 {
        let a = unit(&mut r);
        let rot = Rotation3::from_axis_angle(&nalgebra::Unit::new_normalize(a), PI);
        let h = so3_log(&rot);
        assert!((h.norm() - PI).abs() < 1e-12);
        assert!(
            (h.normalize().dot(&a).abs() - 1.0).abs() < 1e-12,
            "axis lost"
        );
        assert!((so3_exp(&h).matrix() - rot.matrix()).norm() < 1e-12);
    }
    // Axis-aligned half turns have exact zeros in the antisymmetric part.
    for a in [Vector3::x(), Vector3::y(), Vector3::z()] {
        let rot = so3_exp(&(a * PI));
        assert!((so3_exp(&so3_log(&rot)).matrix() - rot.matrix()).norm() < 1e-12);
    }
}

#[test]
fn exp_of_log_for_random_rotations() {
    let mut r = ChaCha8Rng::seed_from_u64(13);
    for _ in 0..500 {
        let q = nalgebra::Quaternion::new(
            r.random_range(-1.0..1.0),
            r.random_range(-1.0..1.0),
            r.random_range(-1.0..1.0),
            r.random_range(-1.0..1.0),
        );
        let rot = nalgebra::UnitQuaternion::from_quaternion(q).to_rotation_matrix();
        let h = so3_log(&rot);
        assert!(h.norm() <= PI + 1e-15);
        assert!((so3_exp(&h).matrix() - rot.matrix()).norm() < 1e-13);
        assert!((h - rot.scaled_axis()).norm() < 1e-10 || h.norm() > PI - 1e-6);
    }
}

#[test]
fn derivative_of_exp_at_zero_is_the_hat_matrix() {
    let mut r = ChaCha8Rng::seed_from_u64(14);
    let eps = 1e-6;
    for _ in 0..10 {
        let h = unit(&mut r) * 0.7;
        let fd = (so3_exp(&(h * eps)).matrix() - so3_exp(&(h * -eps)).matrix()) / (2.0 * eps);
        assert!((fd - hat(&h)).norm() < 1e-9);
        let v = unit(&mut r);
        assert!((hat(&h) * v - h.cross(&v)).norm() < 1e-15);
    }
}

#[test]
fn six_vector_round_trip_and_layout() {
    let mut r = ChaCha8Rng::seed_from_u64(15);
    for _ in 0..50 {
        let h = unit(&mut r) * r.random_range(0.0..3.1);
        let t = unit(&mut r) * 2.0;
        let m = RigidMotion::new(so3_exp(&h), t);
        let v = m.to_6vec();
        assert!((v - Vector6::new(t.x, t.y, t.z, h.x, h.y, h.z)).norm() < 1e-12);
        let back = RigidMotion::from_6vec(&v);
        assert!((back.rotation.matrix() - m.rotation.matrix()).norm() < 1e-13);
        assert_eq!(back.translation, t);
    }
}
