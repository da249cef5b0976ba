//! A motion and a PCA model of different subjects, and artifacts rewritten
//! with a valid checksum but out-of-range indices: each is one clear error,
//! never a panic and never a wrong result.

use gp::pca::Components;
use mesh_core::artifact::{Artifact, Header};
use mesh_core::segmentation::Segmentation;
use mesh_core::sequence::MeshSequence;
use mesh_core::shapes::cylinder;
use mesh_core::TriMesh;
use nalgebra::Vector3;
use capture::align::{align_motion, AlignedMotion};
use capture::part_pca::{fit, whole_body, PartAlignment, PcaModel};

fn motion_of(t: &TriMesh, n: usize) -> AlignedMotion {
    let frames: Vec<Vec<Vector3<f64>>> = (0..n)
        .map(|i| {
            let a = (i as f64 * 0.7).sin();
            t.vertices
                .iter()
                .map(|v| Vector3::new(v.x * (1.0 + 0.2 * a), v.y, v.z + 0.1 * a * v.y))
                .collect()
        })
        .collect();
    align_motion(t, &MeshSequence::new(t.faces.clone(), frames)).unwrap()
}

fn model_of(t: &TriMesh) -> (PcaModel, AlignedMotion) {
    let m = motion_of(t, 8);
    let (model, _) = fit(
        &t.vertices,
        &whole_body(t.n_vertices()),
        &[&m],
        Components::Count(4),
        PartAlignment::Body,
    )
    .unwrap();
    (model, m)
}

#[test]
fn motion_of_another_vertex_count_is_refused_by_every_projection() {
    let (model, own) = model_of(&cylinder(8, 10, 0.1, 1.0));
    assert!(model.encode(&own).is_ok());
    for other in [cylinder(6, 10, 0.1, 1.0), cylinder(10, 10, 0.1, 1.0)] {
        let m = motion_of(&other, 5);
        let err = model.encode(&m).unwrap_err().to_string();
        assert!(err.contains("vertices") && err.contains("80"), "{err}");
        assert!(model.part_rows(&m).is_err());
    }
}

#[test]
fn fit_refuses_a_later_frame_of_another_size() {
    let t = cylinder(8, 10, 0.1, 1.0);
    let mut m = motion_of(&t, 6);
    m.frames[3].pop();
    let r = fit(&t.vertices, &whole_body(80), &[&m], Components::Count(4), PartAlignment::Body);
    assert!(r.unwrap_err().to_string().contains("79"));
}

/// Saves `value` (the writer does not validate), loads it back: the
/// checksum is right, the contents are not.
fn reload<T: Artifact>(value: &T) -> String {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("x.art");
    value.save(&path, &Header::new("test", "0")).unwrap();
    let bytes = std::fs::read(&path).unwrap();
    let err = T::decode(&bytes).err().expect("decode accepted a bad payload");
    let err_file = T::load(&path).err().expect("load accepted a bad payload").to_string();
    assert!(err_file.starts_with(&path.display().to_string()) && err_file.contains(&err));
    err
}

#[test]
fn pca_model_indices_are_validated_after_decoding() {
    let (model, _) = model_of(&cylinder(8, 10, 0.1, 1.0));
    let mut bad = model.clone();
    bad.parts[0].vertices[5] = 1000;
    assert!(reload(&bad).contains("index 1000"));
    let mut bad = model.clone();
    bad.parts[0].reference.pop();
    assert!(reload(&bad).contains("reference"));
    let mut bad = model.clone();
    bad.n_vertices = usize::MAX / 2;
    assert!(reload(&bad).contains("cannot cover"));
    let mut bad = model.clone();
    bad.anchor = vec![80];
    assert!(reload(&bad).contains("anchor"));
}

#[test]
fn aligned_motion_indices_are_validated_after_decoding() {
    let t = cylinder(8, 10, 0.1, 1.0);
    let m = motion_of(&t, 4);
    let mut bad = m.clone();
    bad.faces[0][1] = 80;
    assert!(reload(&bad).contains("face"));
    let mut bad = m.clone();
    bad.frames[2].truncate(10);
    assert!(reload(&bad).contains("frame 2"));
    let mut bad = m.clone();
    bad.poses.pop();
    assert!(reload(&bad).contains("poses"));
    let mut bad = m.clone();
    bad.frames[1][0].x = f64::NAN;
    assert!(reload(&bad).contains("non-finite"));
}

#[test]
fn segmentation_indices_are_validated_after_decoding() {
    let seg: Segmentation = whole_body(80);
    let mut bad = seg.clone();
    bad.parts[0].vertices.push(500);
    assert!(reload(&bad).contains("index 500"));
    let mut bad = seg.clone();
    bad.parts[0].faces = vec![[0, 1, 90]];
    assert!(reload(&bad).contains("face"));
    let mut bad = seg.clone();
    bad.n_vertices = 20_000_000;
    assert!(reload(&bad).contains("cannot cover"));
    let mut bad = seg.clone();
    bad.parts[0].parent = Some("nowhere".into());
    assert!(reload(&bad).contains("parent"));
}

#[test]
fn correspondences_are_a_path_through_their_key_poses() {
    use transfer::densify::Correspondences;
    let good = Correspondences {
        source_motion: "walk".into(),
        target_motion: "walk".into(),
        keyposes: vec![[0, 0], [2, 3]],
        pairs: vec![[0, 0], [1, 1], [1, 2], [2, 3], [3, 3]],
    };
    assert_eq!(good.validate(), Ok(()));
    let mut bad = good.clone();
    bad.pairs.swap(1, 2);
    bad.pairs[1] = [2, 2];
    assert!(reload(&bad).contains("backwards"));
    let mut bad = good.clone();
    bad.keyposes.push([3, 0]);
    assert!(reload(&bad).contains("key-pose [3, 0]"));
    let mut bad = good.clone();
    bad.pairs.clear();
    assert!(reload(&bad).contains("no frame pairs"));
}
