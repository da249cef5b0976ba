//! The key-pose affine baseline on an exactly affine source -> target relation.
mod common;
use common::Rng;
use gp::affine_keypose::AffineKeypose;

#[test]
fn exact_affine_relation_is_reproduced() {
    let mut rng = Rng::new(30);
    // Target = A s + b with A: 4 x 3; 6 key-poses span the 3-D source affine space.
    let a = rng.matrix(4, 3, 1.0);
    let b = rng.matrix(1, 4, 1.0);
    let map = |s: &nalgebra::DMatrix<f64>| {
        let mut t = s * a.transpose();
        for mut r in t.row_iter_mut() {
            r += &b;
        }
        t
    };
    let sk = rng.matrix(6, 3, 1.0);
    let model = AffineKeypose::fit(&sk, &map(&sk)).unwrap();
    let xs = rng.matrix(10, 3, 2.0);
    let pred = model.predict(&xs).unwrap();
    assert!((&pred - map(&xs)).amax() < 1e-10);
    let w = model.weights(&xs).unwrap();
    for r in w.row_iter() {
        assert!((r.sum() - 1.0).abs() < 1e-12);
    }
}

#[test]
fn key_pose_maps_to_its_target_and_off_span_inputs_are_projected() {
    let mut rng = Rng::new(31);
    // 3 key-poses in 5-D: an affine plane; targets arbitrary.
    let sk = rng.matrix(3, 5, 1.0);
    let tk = rng.matrix(3, 2, 1.0);
    let model = AffineKeypose::fit(&sk, &tk).unwrap();
    let p = model.predict(&sk.rows(1, 1).into_owned()).unwrap();
    assert!((p - tk.rows(1, 1)).amax() < 1e-10);
    // A point off the plane maps like its orthogonal projection onto the plane.
    let normal_offset = {
        let e1 = (sk.row(1) - sk.row(0)).transpose();
        let e2 = (sk.row(2) - sk.row(0)).transpose();
        let basis = nalgebra::DMatrix::from_columns(&[e1, e2]);
        let qr = basis.qr();
        let q = qr.q();
        let v = rng.matrix(5, 1, 1.0);
        &v - &q * (q.transpose() * &v)
    };
    let on = (sk.row(0) * 0.3 + sk.row(1) * 0.3 + sk.row(2) * 0.4).into_owned();
    let off = &on + normal_offset.transpose();
    let as_mat = |r: &nalgebra::RowDVector<f64>| {
        nalgebra::DMatrix::from_iterator(1, r.len(), r.iter().copied())
    };
    let (pon, poff) = (
        model.predict(&as_mat(&on)).unwrap(),
        model.predict(&as_mat(&off)).unwrap(),
    );
    assert!((pon - poff).amax() < 1e-10);
}
