//! The learning curves' errors (CVPR figs. 7-9) against the true parts, PCA truncation
//! included.

use gp::gpr::GprOptions;
use mesh_core::sequence::MeshSequence;
use mesh_core::shapes::cylinder;
use nalgebra::{DMatrix, Vector3};
use capture::align::{align_motion, AlignedMotion};
use transfer::gpr_model::MeanFunction;
use transfer::learning_curves::{
    encode_pair, run_direction, sizes, train_side_len, truncation_label, vertex_rms,
    Correspondence, DirectionData,
};
use capture::part_pca::{fit, whole_body, PartAlignment, PcaModel};

/// A bending, swelling cylinder driven by four hidden factors: a 3-component
/// PCA cannot represent it exactly (non-zero truncation error).
fn motion(frames: usize, phase: f64) -> (AlignedMotion, mesh_core::TriMesh) {
    let t = cylinder(6, 10, 0.1, 1.0);
    let seq: Vec<Vec<Vector3<f64>>> = (0..frames)
        .map(|i| {
            let s = i as f64 * 0.21 + phase;
            let (a, b, c, d) = (s.sin(), (0.7 * s).cos(), (1.9 * s).sin(), (3.1 * s).cos());
            t.vertices
                .iter()
                .map(|v| {
                    Vector3::new(
                        v.x * (1.0 + 0.2 * a) + 0.05 * d * v.y,
                        v.y + 0.03 * c * v.x,
                        v.z * (1.0 + 0.1 * c) + 0.15 * b * v.y * v.y,
                    )
                })
                .collect()
        })
        .collect();
    let m = align_motion(&t, &MeshSequence::new(t.faces.clone(), seq)).unwrap();
    (m, t)
}

fn pca(m: &AlignedMotion, t: &mesh_core::TriMesh, comps: usize) -> PcaModel {
    fit(
        &t.vertices,
        &whole_body(t.n_vertices()),
        &[m],
        gp::pca::Components::Count(comps),
        PartAlignment::Body,
    )
    .unwrap()
    .0
}

/// `vertex_rms` is the per-vertex RMS between decoded coefficients and the
/// true part meshes, for exact and perturbed predictions alike.
#[test]
fn vertex_rms_measures_against_the_true_parts() {
    let (m, t) = motion(40, 0.0);
    let model = pca(&m, &t, 3);
    let pair: Vec<[usize; 2]> = (0..40).map(|i| [i, i]).collect();
    let enc = encode_pair(&m, &m, &pair, &[[0, 0]], &model, &model).unwrap();
    let truth = &enc.data.target_coeffs;
    let rows = model.part_rows(&m).unwrap();
    let n = t.n_vertices();
    let brute = |c: &DMatrix<f64>| {
        let dec = model.parts[0].pca.decode(c).unwrap();
        ((dec - &rows[0]).norm_squared() / (40 * n) as f64).sqrt()
    };
    let exact = vertex_rms(truth, truth, &enc.target_residual, &[n]);
    assert!(exact > 1e-4, "the truncation error must not vanish: {exact}");
    assert!((exact - brute(&truth[0])).abs() < 1e-9 * exact.max(1.0), "{exact} vs {}", brute(&truth[0]));
    let off = truth[0].map(|x| x * 0.9 + 0.01);
    let got = vertex_rms(&[off.clone()], truth, &enc.target_residual, &[n]);
    assert!((got - brute(&off)).abs() < 1e-9, "{got} vs {}", brute(&off));
    assert!(got > exact);
}

/// Identical subjects with the true (identity) correspondences: a regressor
/// that learns the identity scores the PCA truncation error, not 0, and the
/// `pca-truncation` floor equals the brute-force truncation error of the
/// held-out frames.
#[test]
fn perfect_mapping_scores_the_truncation_error() {
    let (m, t) = motion(60, 0.3);
    let model = pca(&m, &t, 3);
    let pair: Vec<[usize; 2]> = (0..60).map(|i| [i, i]).collect();
    let keys = vec![[5, 5], [20, 20], [35, 35], [50, 50]];
    let enc = encode_pair(&m, &m, &pair, &keys, &model, &model).unwrap();
    let n = t.n_vertices();
    let dir = DirectionData {
        label: "A->A".into(),
        correspondence: Correspondence::True,
        parts: vec![enc.clone()],
        whole: vec![enc],
        part_vertices: vec![n],
        whole_vertices: n,
        part_names: vec!["body".into()],
        frame_ratio: 1.0,
    };
    let opts = GprOptions {
        noise_var: 1e-8,
        ..Default::default()
    };
    let max = train_side_len(60, keys.len());
    let points = run_direction(&dir, &sizes(20, max, 2), false, MeanFunction::Zero, &opts, 7).unwrap();
    let floor: Vec<_> = points.iter().filter(|p| p.curve == truncation_label(true)).collect();
    assert!(!floor.is_empty());
    let trunc = floor[0].test_rms_m;
    assert!(trunc > 1e-4, "{trunc}");
    // Every frame's own truncation error, by decoding: the held-out floor lies within it.
    let rows = model.part_rows(&m).unwrap();
    let coeffs = model.encode_rows(&rows).unwrap();
    let dec = model.parts[0].pca.decode(&coeffs[0]).unwrap();
    let per_frame: Vec<f64> = (0..60)
        .map(|f| ((dec.row(f) - rows[0].row(f)).norm_squared() / n as f64).sqrt())
        .collect();
    let (lo, hi) = per_frame.iter().fold((f64::MAX, 0.0f64), |a, &e| (a.0.min(e), a.1.max(e)));
    assert!(trunc >= lo && trunc <= hi, "{trunc} outside [{lo}, {hi}]");
    let linear = points
        .iter()
        .filter(|p| p.curve == "gpr-linear dense parts")
        .last()
        .unwrap();
    assert!(
        (linear.test_rms_m - trunc).abs() < 0.02 * trunc,
        "identity learnt by the linear GP: {} vs truncation {trunc}",
        linear.test_rms_m
    );
    assert!(linear.train_rms_m >= floor.last().unwrap().train_rms_m * 0.999);
    for p in &points {
        assert!(p.test_rms_m >= trunc * 0.999, "{p:?} below the truncation floor {trunc}");
        assert_eq!(p.pairs, "true");
        assert_eq!(p.components, 3);
    }
    // Figure 8 is drawn for every method.
    for method in ["gpr-nn", "gpr-se", "gpr-linear", "keypose-affine"] {
        let label = format!("{method} keyposes-first parts");
        assert!(points.iter().any(|p| p.curve == label), "{label}");
    }
}
