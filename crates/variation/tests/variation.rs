//! Tests of the variation stages against independent truth: known time warps, hand-computed
//! metrics, blend endpoints, and an end-to-end run on the `tiny` synthetic capture set.

use std::collections::BTreeMap;

use mesh_core::capture_set::SubjectSpec;
use nalgebra::{DMatrix, Vector3};
use variation::contacts;
use variation::metrics;
use variation::prealign::{warp, PrealignOptions};

fn spec_with_contacts(c: serde_json::Value) -> SubjectSpec {
    let mut extra = BTreeMap::new();
    extra.insert("contacts".to_string(), c);
    SubjectSpec {
        fps: 25.0,
        units: "m".into(),
        up: "+y".into(),
        parts: BTreeMap::new(),
        curves: BTreeMap::new(),
        extra,
    }
}

#[test]
fn contacts_are_read_and_checked() {
    let s = spec_with_contacts(serde_json::json!({"walk": [[1, 0], [0, 1], [true, false]]}));
    let c = contacts::from_subject(&s, "walk", 3).unwrap().unwrap();
    assert_eq!(c, vec![[true, false], [false, true], [true, false]]);
    assert!(contacts::from_subject(&s, "run", 3).unwrap().is_none());
    let err = contacts::from_subject(&s, "walk", 4)
        .unwrap_err()
        .to_string();
    assert!(err.contains("3 frames") && err.contains("4"), "{err}");
    let bad = spec_with_contacts(serde_json::json!({"walk": [[2, 0]]}));
    assert!(contacts::from_subject(&bad, "walk", 1).is_err());
}

/// A "pose" of 20 points as a function of a phase in [0, 3] (no repeated pose).
fn pose(phi: f64) -> Vec<Vector3<f64>> {
    (0..20)
        .map(|k| {
            Vector3::new(
                (phi + k as f64).cos(),
                (0.5 * phi + 0.3 * k as f64).sin(),
                0.1 * k as f64,
            )
        })
        .collect()
}

#[test]
fn prealign_recovers_a_known_time_warp() {
    let n_ref = 40;
    let reference: Vec<_> = (0..n_ref)
        .map(|j| pose(3.0 * j as f64 / (n_ref - 1) as f64))
        .collect();
    // The motion plays the same poses with time warp ψ(i) = 39 (i / 59)^1.4 (in reference frames).
    let n = 60;
    let psi = |i: usize| (n_ref - 1) as f64 * (i as f64 / (n - 1) as f64).powf(1.4);
    let frames: Vec<_> = (0..n)
        .map(|i| pose(3.0 * psi(i) / (n_ref - 1) as f64))
        .collect();
    let w = warp(&frames, None, &reference, None, &PrealignOptions::default()).unwrap();
    assert_eq!(w.map.len(), n_ref);
    for (j, &i) in w.map.iter().enumerate() {
        assert!(
            (psi(i) - j as f64).abs() <= 1.0,
            "reference frame {j} got motion frame {i} (ψ = {})",
            psi(i)
        );
    }
}

#[test]
fn prealign_uses_contacts_to_break_ties() {
    // Identical poses everywhere: only the contacts say where the step is.
    let reference: Vec<_> = (0..10).map(|_| pose(0.0)).collect();
    let frames: Vec<_> = (0..10).map(|_| pose(0.0)).collect();
    let rc: contacts::Contacts = (0..10).map(|j| [j < 4, j >= 4]).collect();
    let mc: contacts::Contacts = (0..10).map(|i| [i < 6, i >= 6]).collect();
    let opts = PrealignOptions {
        contact_weight: Some(1.0),
        ..Default::default()
    };
    let w = warp(&frames, Some(&mc), &reference, Some(&rc), &opts).unwrap();
    for (j, &i) in w.map.iter().enumerate() {
        assert_eq!(
            mc[i], rc[j],
            "reference frame {j} paired with motion frame {i}"
        );
    }
}

#[test]
fn metrics_match_hand_computed_values() {
    let mesh = mesh_core::shapes::icosphere(1);
    let rest = mesh.vertices.clone();
    let edges = metrics::edges(&mesh.faces);
    assert_eq!(edges.len(), 3 * mesh.faces.len() / 2);
    let scaled: Vec<_> = rest.iter().map(|p| p * 1.1).collect();
    assert!(
        (metrics::edge_distortion(&[scaled.clone(), rest.clone()], &rest, &edges) - 0.05).abs()
            < 1e-12
    );
    let moved: Vec<_> = rest
        .iter()
        .map(|p| p + Vector3::new(0.3, 0.4, 0.0))
        .collect();
    assert!((metrics::mean_vertex_distance(&[moved], &[rest.clone()]) - 0.5).abs() < 1e-12);
    let seq: Vec<_> = (0..8).map(|t| pose(0.3 * t as f64)).collect();
    let tpl = seq[0].clone();
    assert!(metrics::timing_offset(&seq, &seq, &tpl).abs() < 1e-12);

    // Two "feet" (one vertex each, y up): the left one slides 1 cm per frame on the ground, the
    // right one is lifted 10 cm from frame 2 on (no contact, not counted).
    let up = Vector3::y();
    let frames: Vec<Vec<Vector3<f64>>> = (0..5)
        .map(|t| {
            vec![
                Vector3::new(0.01 * t as f64, 0.0, 0.0),
                Vector3::new(0.5, if t >= 2 { 0.1 } else { 0.0 }, 0.0),
            ]
        })
        .collect();
    let soles = vec![vec![0u32], vec![1u32]];
    // Left: 4 pairs of 1 cm; right: 1 pair (frames 0-1) of 0 cm.
    let s = metrics::foot_sliding(&frames, &soles, &up, 0.02).unwrap();
    assert!((s - 0.04 / 5.0).abs() < 1e-12, "{s}");
    let st = metrics::Stats::of(&[1.0, 3.0, f64::NAN]);
    assert_eq!((st.mean, st.min, st.max), (2.0, 1.0, 3.0));
    let a = DMatrix::from_row_slice(1, 6, &[0.0, 0.0, 0.0, 1.0, 1.0, 1.0]);
    let b = DMatrix::from_row_slice(1, 6, &[3.0, 4.0, 0.0, 1.0, 1.0, 1.0]);
    assert!((metrics::mean_row_distance(&a, &b, 2) - 2.5).abs() < 1e-12);
}

#[test]
fn blends_at_zero_and_one_reproduce_the_endpoints() {
    use mesh_core::rigid::RigidMotion;
    use capture::align::AlignedMotion;
    use variation::group::{blend_sequences, GroupSequence};
    let mesh = mesh_core::shapes::icosphere(2);
    let n = 4;
    let make = |amp: f64, name: &str| {
        let frames: Vec<Vec<Vector3<f64>>> = (0..n)
            .map(|t| {
                mesh.vertices
                    .iter()
                    .map(|p| Vector3::new(p.x * (1.0 + amp * t as f64), p.y, p.z + amp * p.x * p.x))
                    .collect()
            })
            .collect();
        let disp: Vec<[f64; 6]> = (0..n)
            .map(|t| [0.01 * amp * t as f64, 0.0, 0.02, 0.0, 0.01 * amp, 0.0])
            .collect();
        let rel: Vec<RigidMotion> = disp[1..]
            .iter()
            .map(|d| RigidMotion::from_6vec(&nalgebra::Vector6::from_row_slice(d)))
            .collect();
        let poses = mesh_core::rigid::integrate(&RigidMotion::identity(), &rel);
        GroupSequence {
            name: name.into(),
            blend: None,
            blend_of: None,
            motion: AlignedMotion {
                faces: mesh.faces.clone(),
                frames,
                poses,
                displacements: disp,
                anchor: Vec::new(),
                capture: Default::default(),
            },
            contacts: None,
            map: (0..n).collect(),
        }
    };
    let (a, b) = (make(0.1, "a"), make(0.3, "b"));
    let blender = surface::blend::Blender::new(mesh.vertices.clone(), mesh.faces.clone()).unwrap();
    for (w, end) in [(0.0, &a), (1.0, &b)] {
        let s = blend_sequences(&blender, &a, &b, w, &nalgebra::Vector3::y(), &nalgebra::Vector3::zeros()).unwrap();
        let err = metrics::mean_vertex_distance(&s.motion.frames, &end.motion.frames);
        assert!(err < 1e-8, "w = {w}: {err}");
        let pe = s
            .motion
            .poses
            .iter()
            .zip(&end.motion.poses)
            .map(|(p, q)| (p.translation - q.translation).norm())
            .fold(0.0, f64::max);
        assert!(pe < 1e-12, "w = {w}: poses differ by {pe}");
    }
    let mid = blend_sequences(&blender, &a, &b, 0.5, &nalgebra::Vector3::y(), &nalgebra::Vector3::zeros()).unwrap();
    assert!(metrics::mean_vertex_distance(&mid.motion.frames, &a.motion.frames) > 1e-3);
    // Several weights from one decomposition per frame: the same sequences as one by one.
    let weights = [0.25, 0.5, 0.75];
    let many =
        variation::group::blend_sequences_at(&blender, &a, &b, &weights, &nalgebra::Vector3::y(), &nalgebra::Vector3::zeros())
            .unwrap();
    assert_eq!(many.len(), 3);
    for (s, &w) in many.iter().zip(&weights) {
        assert_eq!(s, &blend_sequences(&blender, &a, &b, w, &nalgebra::Vector3::y(), &nalgebra::Vector3::zeros()).unwrap());
    }
    // Latent blending (§7) at the bounding weights gives the bounding trajectories.
    let xa = DMatrix::from_fn(5, 3, |i, j| (i + j) as f64);
    let xb = DMatrix::from_fn(5, 3, |i, j| (i * j) as f64 - 1.0);
    assert_eq!(gpdm::blend::blend_pair(&xa, 0.0, &xb, 0.5, 0.0), xa);
    assert!((gpdm::blend::blend_pair(&xa, 0.0, &xb, 0.5, 0.5) - &xb).amax() < 1e-12);
}

#[test]
fn torso_vector_round_trips_displacement_and_gravity() {
    use variation::part_data::{split_torso, with_displacement, DisplacementScale};
    let rows = DMatrix::from_fn(2, 6, |i, j| (i * 6 + j) as f64);
    let disp = [
        [0.1, 0.2, 0.3, 0.01, 0.02, 0.03],
        [0.4, 0.5, 0.6, 0.04, 0.05, 0.06],
    ];
    let grav = [[1.0, 0.0, 1.0, 0.0], [1.1, 0.1, 0.99, 0.0]];
    let scale = DisplacementScale {
        translation: 7.0,
        rotation: 30.0,
    };
    let m = with_displacement(&rows, &disp, &grav, scale);
    assert_eq!(m.ncols(), 16);
    assert!((m[(0, 6)] - 0.7).abs() < 1e-12 && (m[(0, 9)] - 0.3).abs() < 1e-12);
    for t in 0..2 {
        let row: Vec<f64> = m.row(t).iter().copied().collect();
        let (v, d, g) = split_torso(&row, scale);
        assert_eq!(v.len(), 2);
        assert!((v[1] - Vector3::new(rows[(t, 3)], rows[(t, 4)], rows[(t, 5)])).norm() < 1e-12);
        for k in 0..6 {
            assert!((d[k] - disp[t][k]).abs() < 1e-12);
        }
        for k in 0..4 {
            assert!((g[k] - grav[t][k]).abs() < 1e-12);
        }
    }
}

#[test]
fn manifold_distance_ignores_timing_but_not_pose() {
    use nalgebra::Vector3;
    use variation::metrics::nearest_frame_distance;
    let frame = |t: usize| -> Vec<Vector3<f64>> {
        let a = std::f64::consts::TAU * t as f64 / 20.0;
        (0..30)
            .map(|v| Vector3::new(a.cos() * v as f64 * 0.01, a.sin(), v as f64 * 0.02))
            .collect()
    };
    let source: Vec<_> = (0..40).map(frame).collect();
    // Same cycle, other phase and speed: on the manifold.
    let shifted: Vec<_> = (0..25).map(|t| frame(2 * t + 7)).collect();
    assert!(nearest_frame_distance(&shifted, &source, 1000) < 1e-12);
    // Every vertex 1 cm off along an axis the cycle never moves: 1 cm off the manifold.
    let off: Vec<Vec<_>> = shifted
        .iter()
        .map(|f| f.iter().map(|p| p + Vector3::new(0.0, 0.0, 0.01)).collect())
        .collect();
    let d = nearest_frame_distance(&off, &source, 1000);
    assert!((d - 0.01).abs() < 1e-12, "{d}");
}
