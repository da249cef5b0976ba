//! PCA: exact round trip at full rank, known principal axes, component selection.
mod common;
use common::Rng;
use gp::pca::{Components, Pca};
use nalgebra::DMatrix;

#[test]
fn round_trip_is_exact_when_m_equals_rank() {
    let mut rng = Rng::new(20);
    // 12 frames in D = 300 (D >> F): centred rank 11.
    let data = rng.matrix(12, 300, 2.0);
    let pca = Pca::fit(&data, Components::Count(100)).unwrap();
    assert_eq!(pca.rank, 11);
    assert_eq!(pca.n_components(), 11, "count is capped at the rank");
    let rms = pca.reconstruction_rms(&data).unwrap();
    assert!(rms < 1e-10, "{rms}");
    let ratio: f64 = pca.explained_variance_ratio().iter().sum();
    assert!((ratio - 1.0).abs() < 1e-12);
    // Orthonormal rows.
    let g = &pca.components * pca.components.transpose();
    assert!((g - DMatrix::identity(11, 11)).amax() < 1e-10);
}

/// 2³ factorial design along three orthonormal axes of R⁵ with standard deviations 3, 2, 1,
/// shifted by a mean: the sample covariance is exactly diag(9, 4, 1) · 8/7 in that basis.
fn known_axes_data() -> (DMatrix<f64>, DMatrix<f64>, Vec<f64>) {
    let s = 1.0 / 2f64.sqrt();
    let axes = DMatrix::from_row_slice(
        3,
        5,
        &[
            s, s, 0.0, 0.0, 0.0, //
            0.0, 0.0, 1.0, 0.0, 0.0, //
            s, -s, 0.0, 0.0, 0.0,
        ],
    );
    let mean = [1.0, -2.0, 0.5, 3.0, 0.0];
    let sd = [3.0, 2.0, 1.0];
    let mut data = DMatrix::zeros(8, 5);
    for f in 0..8 {
        for k in 0..3 {
            let sign = if (f >> k) & 1 == 1 { 1.0 } else { -1.0 };
            for d in 0..5 {
                data[(f, d)] += sign * sd[k] * axes[(k, d)];
            }
        }
        for d in 0..5 {
            data[(f, d)] += mean[d];
        }
    }
    (data, axes, sd.iter().map(|v| v * v * 8.0 / 7.0).collect())
}

#[test]
fn known_principal_axes_and_variances() {
    let (data, axes, variances) = known_axes_data();
    let pca = Pca::fit(&data, Components::default()).unwrap();
    assert_eq!(pca.n_components(), 3);
    for k in 0..3 {
        assert!(
            (pca.variances[k] - variances[k]).abs() < 1e-12,
            "{:?}",
            pca.variances
        );
        let cos = pca.components.row(k).dot(&axes.row(k)).abs();
        assert!((cos - 1.0).abs() < 1e-12, "axis {k}: |cos| = {cos}");
    }
    assert!((pca.mean[1] + 2.0).abs() < 1e-14);
    // Coefficients are ±sd along each axis (up to the sign of the axis).
    let c = pca.encode(&data).unwrap();
    for f in 0..8 {
        for k in 0..3 {
            assert!((c[(f, k)].abs() - [3.0, 2.0, 1.0][k]).abs() < 1e-12);
        }
    }
}

#[test]
fn choose_by_explained_variance_and_truncation_error() {
    let (data, _, _) = known_axes_data();
    // Ratios 9/14, 4/14, 1/14: 0.9 needs two components, 0.5 one.
    assert_eq!(
        Pca::fit(&data, Components::ExplainedVariance(0.9))
            .unwrap()
            .n_components(),
        2
    );
    assert_eq!(
        Pca::fit(&data, Components::ExplainedVariance(0.5))
            .unwrap()
            .n_components(),
        1
    );
    assert_eq!(
        Pca::fit(&data, Components::ExplainedVariance(1.0))
            .unwrap()
            .n_components(),
        3
    );
    // Dropping the third axis leaves an error of sd 1 along one of 5 coordinates-worth of
    // norm: per-coordinate rms = sqrt(1 / 5).
    let p2 = Pca::fit(&data, Components::Count(2)).unwrap();
    assert!((p2.reconstruction_rms(&data).unwrap() - (0.2f64).sqrt()).abs() < 1e-12);
    assert!(Pca::fit(&data, Components::ExplainedVariance(1.5)).is_err());
}

#[test]
fn bad_shapes_are_errors() {
    let (data, _, _) = known_axes_data();
    let pca = Pca::fit(&data, Components::default()).unwrap();
    assert!(pca.encode(&DMatrix::zeros(2, 4)).is_err());
    assert!(pca.decode(&DMatrix::zeros(2, 5)).is_err());
    assert!(Pca::fit(&DMatrix::zeros(1, 5), Components::default()).is_err());
    let e = Pca::fit(&data, Components::Count(0)).unwrap_err().to_string();
    assert!(e.contains("at least 1 component"), "{e}");
}

/// More frames than dimensions (the `long` preset's parts) takes the `D x D` route; padding the
/// same data with zero columns until `D > F` takes the `F x F` route: same variances, same
/// axes up to sign, zero weight on the padding, and the same reconstruction.
#[test]
fn frame_and_dimension_routes_agree() {
    let mut rng = Rng::new(21);
    let (f, d) = (60, 9);
    let data = &rng.matrix(f, d, 1.0) * DMatrix::from_fn(d, d, |i, j| if i == j { 1.0 + i as f64 } else { 0.1 });
    let tall = Pca::fit(&data, Components::Count(6)).unwrap();
    let wide_data = DMatrix::from_fn(f, f + 5, |i, j| if j < d { data[(i, j)] } else { 0.0 });
    let wide = Pca::fit(&wide_data, Components::Count(6)).unwrap();
    assert_eq!((tall.rank, wide.rank), (d, d));
    for k in 0..6 {
        assert!((tall.variances[k] - wide.variances[k]).abs() < 1e-10 * wide.variances[0], "variance {k}");
        let (a, b) = (tall.components.row(k), wide.components.row(k).columns(0, d).into_owned());
        let dot = a.dot(&b);
        assert!((dot.abs() - 1.0).abs() < 1e-10, "axis {k}: |cos| = {}", dot.abs());
        assert!(wide.components.row(k).columns(d, f + 5 - d).amax() < 1e-12);
    }
    assert!((tall.total_variance - wide.total_variance).abs() < 1e-10 * wide.total_variance);
    let (rt, rw) = (tall.reconstruction_rms(&data).unwrap(), wide.reconstruction_rms(&wide_data).unwrap());
    // RMS over every coordinate: the padding's zeros count in the wide one.
    let (st, sw) = (rt * rt * d as f64, rw * rw * (f + 5) as f64);
    assert!((st - sw).abs() < 1e-10 * sw && st > 0.1, "{st} vs {sw}");
}
