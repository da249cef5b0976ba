//! Capture-set loading and validation of a subject's curves against its
//! template mesh: loop resolution by shortest edge paths, and every bad case
//! (index out of range, unclosable loop, degenerate loop, bad part tree).

use std::path::Path;

use mesh_core::capture_set::{resolve_loop, CaptureSet, SetSpec, SubjectSpec};
use mesh_core::sequence::MeshSequence;
use mesh_core::shapes::{capsule_body, cylinder, CapsuleLayout};
use mesh_core::topology::Topology;
use mesh_core::TriMesh;
use nalgebra::Vector3;

fn capsule() -> (TriMesh, CapsuleLayout, Topology) {
    let (m, l) = capsule_body(10, 16, 0.3, 1.5);
    let t = Topology::new(m.n_vertices(), &m.faces);
    (m, l, t)
}

#[test]
fn sparse_loop_is_joined_into_the_ring() {
    let (m, l, t) = capsule();
    let ring = l.ring(l.body_ring(4));
    // Every fourth ring vertex: the joins follow the ring (straight edges of
    // the ring are shorter than any detour through the neighbouring rings).
    let sparse: Vec<u32> = ring.iter().step_by(4).copied().collect();
    assert_eq!(resolve_loop(&m, &t, &sparse).unwrap(), ring);
    // The full ring, repeated entries and a closing repeat of the first vertex.
    let mut given = ring.clone();
    given.insert(3, ring[3]);
    given.push(ring[0]);
    assert_eq!(resolve_loop(&m, &t, &given).unwrap(), ring);
    // Reversed input gives the reversed loop.
    let mut rev = sparse.clone();
    rev.reverse();
    let got = resolve_loop(&m, &t, &rev).unwrap();
    assert_eq!(got.len(), ring.len());
    assert!(got.windows(2).all(|w| t.are_adjacent(w[0], w[1])));
}

#[test]
fn bad_loops_are_rejected_with_a_reason() {
    let (m, l, t) = capsule();
    let ring = l.ring(l.body_ring(2));
    let n = m.n_vertices() as u32;
    let msg = resolve_loop(&m, &t, &[ring[0], ring[5], n])
        .unwrap_err()
        .to_string();
    assert!(
        msg.contains(&n.to_string()) && msg.contains("out of range"),
        "{msg}"
    );
    let msg = resolve_loop(&m, &t, &[ring[0], ring[1], ring[0]])
        .unwrap_err()
        .to_string();
    assert!(msg.contains("2 distinct"), "{msg}");
    assert!(resolve_loop(&m, &t, &[]).is_err());
    // Three vertices on one straight run of the ring: the closing path
    // retraces the opening one, which is not a closed curve.
    let msg = resolve_loop(&m, &t, &[ring[0], ring[2], ring[4]])
        .unwrap_err()
        .to_string();
    assert!(msg.contains("twice"), "{msg}");
    // Loop across two disconnected pieces: cannot be closed.
    let c = cylinder(3, 8, 0.3, 1.0);
    let mut two = m.clone();
    let off = two.n_vertices() as u32;
    two.vertices
        .extend(c.vertices.iter().map(|v| v + Vector3::new(3.0, 0.0, 0.0)));
    two.faces.extend(c.faces.iter().map(|f| f.map(|i| i + off)));
    let t2 = Topology::new(two.n_vertices(), &two.faces);
    let msg = resolve_loop(&two, &t2, &[ring[0], ring[4], ring[8], off])
        .unwrap_err()
        .to_string();
    assert!(
        msg.contains("not closed") && msg.contains("cannot be joined"),
        "{msg}"
    );
}

fn subject_json(layout: &CapsuleLayout, extra: &str) -> String {
    let r = |k: usize| {
        format!(
            "{:?}",
            layout
                .ring(layout.body_ring(k))
                .iter()
                .step_by(3)
                .collect::<Vec<_>>()
        )
    };
    format!(
        r#"{{"fps": 25, "units": "m", "up": "+y",
            "parts": {{"torso": null, "arm_l": "torso", "hand_l": "arm_l"}},
            "curves": {{"arm_l": [{}, {}], "hand_l": [{}, {}]}}{extra}}}"#,
        r(6),
        r(8),
        r(8),
        r(9)
    )
}

/// Writes a two-subject capture set (both capsules) under `root`.
fn make_set(root: &Path, subject_a: &str) {
    let (m, l, _) = capsule();
    std::fs::write(
        root.join("set.json"),
        r#"{"source": "A", "target": "B",
            "train": [{"source": "walk", "target": "walk2", "keyposes": [[0, 0], [2, 1]]}],
            "test": ["punch"]}"#,
    )
    .unwrap();
    for (s, motion, json) in [
        ("A", "walk", subject_a.to_string()),
        ("B", "walk2", subject_json(&l, "")),
    ] {
        std::fs::create_dir_all(root.join(s)).unwrap();
        std::fs::write(root.join(s).join("subject.json"), json).unwrap();
        let frames = (0..3)
            .map(|k| {
                m.vertices
                    .iter()
                    .map(|v| v * (1.0 + 0.01 * k as f64))
                    .collect()
            })
            .collect();
        MeshSequence::new(m.faces.clone(), frames)
            .write_dir(root.join(s).join(motion))
            .unwrap();
    }
    MeshSequence::new(m.faces.clone(), vec![m.vertices.clone()])
        .write_dir(root.join("A/punch"))
        .unwrap();
    MeshSequence::new(m.faces.clone(), vec![m.vertices.clone()])
        .write_dir(root.join("truth/B/punch"))
        .unwrap();
}

#[test]
fn capture_set_opens_and_resolves_curves() {
    let dir = tempfile::tempdir().unwrap();
    let (_, l, _) = capsule();
    make_set(dir.path(), &subject_json(&l, ""));
    let set = CaptureSet::open(dir.path()).unwrap();
    assert_eq!(set.spec.train[0].keyposes, vec![[0, 0], [2, 1]]);
    assert_eq!(set.frames("A", "walk").unwrap().len(), 3);
    assert_eq!(set.motions("A").unwrap(), vec!["punch", "walk"]);
    assert!(set.has_truth("B", "punch") && !set.has_truth("A", "punch"));
    let a = set.subject("A").unwrap();
    assert_eq!(a.spec.root(), Some("torso"));
    assert_eq!(a.curves["arm_l"][0], l.ring(l.body_ring(6)));
    assert_eq!(a.curves["hand_l"][1], l.ring(l.body_ring(9)));
    // Round trip of the spec through JSON.
    let back: SetSpec = serde_json::from_str(&serde_json::to_string(&set.spec).unwrap()).unwrap();
    assert_eq!(back, set.spec);
}

fn subject_error(json: &str) -> String {
    let dir = tempfile::tempdir().unwrap();
    make_set(dir.path(), json);
    let set = CaptureSet::open(dir.path()).unwrap();
    let msg = set.subject("A").unwrap_err().to_string();
    assert!(msg.contains("subject.json") && !msg.contains('\n'), "{msg}");
    msg
}

/// subject.json with parts torso <- arm_l <- hand_l and the given curves.
fn subject_with(arm: &[Vec<u32>], hand: &[Vec<u32>]) -> String {
    format!(
        r#"{{"fps": 25, "parts": {{"torso": null, "arm_l": "torso", "hand_l": "arm_l"}},
            "curves": {{"arm_l": {arm:?}, "hand_l": {hand:?}}}}}"#
    )
}

#[test]
fn bad_subjects_give_one_line_errors_naming_subject_json() {
    let (m, l, _) = capsule();
    let n = m.n_vertices() as u32;
    let ring = |k: usize| l.ring(l.body_ring(k));
    let sparse = |k: usize| ring(k).into_iter().step_by(3).collect::<Vec<u32>>();
    let arm = [sparse(6), sparse(8)];
    // Control: the same builder with good curves is accepted.
    let dir = tempfile::tempdir().unwrap();
    make_set(dir.path(), &subject_with(&arm, &[sparse(8), sparse(9)]));
    assert!(CaptureSet::open(dir.path()).unwrap().subject("A").is_ok());

    let mut out_of_range = sparse(9);
    out_of_range.push(n);
    let msg = subject_error(&subject_with(&arm, &[sparse(8), out_of_range]));
    assert!(
        msg.contains("part 'hand_l', curve 2") && msg.contains("out of range"),
        "{msg}"
    );
    let msg = subject_error(&subject_with(
        &arm,
        &[vec![ring(8)[0], ring(8)[1], ring(8)[1]], sparse(9)],
    ));
    assert!(
        msg.contains("part 'hand_l', curve 1") && msg.contains("distinct"),
        "{msg}"
    );
    let r = ring(8);
    let msg = subject_error(&subject_with(&arm, &[vec![r[0], r[2], r[4]], sparse(9)]));
    assert!(msg.contains("hand_l") && msg.contains("twice"), "{msg}");
    let msg = subject_error(&subject_with(&arm, &[sparse(8)]));
    assert!(
        msg.contains("'hand_l' needs exactly 2 curves, found 1")
            || msg.contains("exactly 2 curves"),
        "{msg}"
    );

    let good = subject_with(&arm, &[sparse(8), sparse(9)]);
    assert!(
        subject_error(&good.replace("\"hand_l\": \"arm_l\"", "\"hand_l\": null"))
            .contains("exactly one root")
    );
    assert!(
        subject_error(&good.replace("\"hand_l\": \"arm_l\"", "\"hand_l\": \"leg\""))
            .contains("unknown parent 'leg'")
    );
    let cycle = r#"{"fps": 25, "parts": {"torso": null, "a": "b", "b": "a"}, "curves": {"a": [[0,1,2],[0,1,2]], "b": [[0,1,2],[0,1,2]]}}"#;
    assert!(subject_error(cycle).contains("cycle"));
    let root_curves = good.replace(
        "\"curves\": {",
        "\"curves\": {\"torso\": [[0,1,2],[0,1,2]], ",
    );
    assert!(subject_error(&root_curves).contains("root part"));
    assert!(subject_error("{\"fps\": 25, \"parts\": ").contains("invalid JSON"));
    assert!(subject_error(&good.replace("\"fps\": 25", "\"fps\": -1")).contains("fps"));
    let sideways = good.replace("\"fps\": 25", "\"fps\": 25, \"up\": \"y\"");
    assert!(subject_error(&sideways).contains("up must be"));
}

#[test]
fn bad_set_files_give_one_line_errors() {
    let dir = tempfile::tempdir().unwrap();
    let msg = CaptureSet::open(dir.path()).unwrap_err().to_string();
    assert!(msg.contains("set.json"), "{msg}");
    let (_, l, _) = capsule();
    make_set(dir.path(), &subject_json(&l, ""));
    let p = dir.path().join("set.json");
    std::fs::write(&p, r#"{"source": "A", "target": "B", "train": []}"#).unwrap();
    let msg = SetSpec::load(&p).unwrap_err().to_string();
    assert!(msg.contains("set.json") && msg.contains("train"), "{msg}");
    std::fs::write(&p, r#"{"source": "../A", "target": "B", "train": [{"source": "w", "target": "w", "keyposes": [[0,0]]}]}"#).unwrap();
    assert!(SetSpec::load(&p)
        .unwrap_err()
        .to_string()
        .contains("plain directory name"));
    std::fs::write(&p, r#"{"source": "A", "target": "B", "train": [{"source": "run", "target": "walk2", "keyposes": [[0,0]]}]}"#).unwrap();
    let msg = CaptureSet::open(dir.path()).unwrap_err().to_string();
    assert!(msg.contains("run") && msg.contains("missing"), "{msg}");
    // Keyposes beyond the motions' frames (each motion has 3 frames).
    std::fs::write(
        &p,
        r#"{"source": "A", "target": "B", "train": [{"source": "walk", "target": "walk2", "keyposes": [[0,0],[1,3]]}]}"#,
    )
    .unwrap();
    let msg = CaptureSet::open(dir.path()).unwrap_err().to_string();
    assert!(
        msg.contains("set.json") && msg.contains("[1, 3]") && msg.contains("3 / 3 frames"),
        "{msg}"
    );
    std::fs::write(
        &p,
        r#"{"source": "A", "target": "B", "train": [{"source": "walk", "target": "walk2", "keyposes": [[2,2]]}], "test": ["kick"]}"#,
    )
    .unwrap();
    let msg = CaptureSet::open(dir.path()).unwrap_err().to_string();
    assert!(msg.contains("kick") && msg.contains("test motion"), "{msg}");
    let msg = SubjectSpec::load(dir.path().join("C/subject.json"))
        .unwrap_err()
        .to_string();
    assert!(msg.contains("C/subject.json"), "{msg}");
}
