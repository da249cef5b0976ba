//! Decoding through the leading eigenvectors of K_Y (`Predictor::with_kernel_basis`) against
//! the exact 3DV eq. 12, and the column-major decoding used for bulk decoding.

use gpdm::predict::Predictor;
use gpdm::{Gpdm, GpdmConfig};
use nalgebra::DMatrix;

/// Two sequences of a smooth 3-D latent cycle mapped to 30 noisy coordinates (untrained: the
/// PCA start is enough to exercise the decoder).
fn model() -> Gpdm {
    let seqs: Vec<DMatrix<f64>> = [40usize, 35]
        .iter()
        .enumerate()
        .map(|(s, &len)| {
            DMatrix::from_fn(len, 30, |t, j| {
                let ph = 0.3 * t as f64 + s as f64;
                let w = (j as f64 * 1.7).sin();
                0.1 * (w * ph.cos() + (1.0 - w) * (2.0 * ph).sin() + 0.2 * j as f64).sin()
                    + 1e-3 * ((t * 7919 + j * 104729) % 1000) as f64 / 1000.0
            })
        })
        .collect();
    let mut m = Gpdm::new(&seqs, GpdmConfig::default()).unwrap();
    m.alpha = [0.01, 0.5, 1e4];
    m
}

/// Training latents, the same pushed 20 % outwards, and points between them.
fn test_points(m: &Gpdm) -> DMatrix<f64> {
    let n = m.x.nrows();
    DMatrix::from_fn(3 * n - 1, m.x.ncols(), |i, c| {
        if i < n {
            m.x[(i, c)]
        } else if i < 2 * n {
            1.2 * m.x[(i - n, c)]
        } else {
            0.5 * (m.x[(i - 2 * n, c)] + m.x[(i - 2 * n + 1, c)])
        }
    })
}

#[test]
fn kernel_basis_error_stays_within_its_certified_bound() {
    let m = model();
    let exact = Predictor::new(&m).unwrap();
    let xs = test_points(&m);
    let want = exact.pose_mean(&xs).unwrap();
    let train = m.x.clone();
    let want_train = exact.pose_mean(&train).unwrap();
    let mut last_rank = 0;
    for tol in [1e-3, 1e-5, 1e-8] {
        let (p, r, bound) = Predictor::with_kernel_basis(&m, tol).unwrap();
        assert!(bound <= tol, "bound {bound} above tolerance {tol}");
        assert!(r >= last_rank, "rank shrinks as the tolerance tightens");
        last_rank = r;
        // At the training points: within the tolerance.
        let dev_train = (p.pose_mean(&train).unwrap() - &want_train).abs().max();
        assert!(
            dev_train <= tol * (1.0 + 1e-9),
            "tol {tol}: training deviation {dev_train}"
        );
        // Elsewhere: within the bound evaluated for those points.
        let dev = (p.pose_mean(&xs).unwrap() - &want).abs().max();
        let b = p.basis_error_bound(&xs).unwrap();
        assert!(
            dev <= b * (1.0 + 1e-9) + 1e-14,
            "tol {tol}: deviation {dev}, bound {b}"
        );
    }
    // The kernel's spectrum decays: a loose tolerance keeps few directions.
    let (_, r, _) = Predictor::with_kernel_basis(&m, 1e-3).unwrap();
    assert!(r < m.x.nrows() / 2, "rank {r} of {}", m.x.nrows());
    // Zero tolerance keeps every direction: exact up to rounding.
    let (p, r, _) = Predictor::with_kernel_basis(&m, 0.0).unwrap();
    assert_eq!(r, m.x.nrows());
    assert!((p.pose_mean(&xs).unwrap() - &want).abs().max() < 1e-10);
    assert!(exact.basis_error_bound(&xs).is_none());
    assert!(Predictor::with_kernel_basis(&m, f64::NAN).is_err());
}

#[test]
fn column_major_decoding_matches_pose_mean() {
    let m = model();
    let xs = test_points(&m);
    for p in [
        Predictor::new(&m).unwrap(),
        Predictor::with_kernel_basis(&m, 1e-6).unwrap().0,
    ] {
        let want = p.pose_mean(&xs).unwrap(); // T × D
        let mut out = vec![0.0; p.pose_dim() * xs.nrows()];
        p.pose_mean_cols(&xs, &mut out).unwrap();
        let got = DMatrix::from_column_slice(p.pose_dim(), xs.nrows(), &out).transpose();
        assert!((got - &want).abs().max() < 1e-13);
        assert!(p.pose_mean_cols(&xs, &mut out[1..]).is_err());
    }
}
