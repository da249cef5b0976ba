//! `check-set`'s validation on broken copies of the tiny preset's capture set (the set
//! `fixtures/tiny-set` describes, synthesised here with its real frames; needs the synth
//! assets, as `make test` does): one test per kind of problem, each finding exactly the
//! problem made, and one set with several problems listing all of them.

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use mesh_core::set_check::{check_set, Report};
use serde_json::Value;

/// The tiny preset's set, synthesised once per test binary.
fn pristine() -> &'static Path {
    static SET: OnceLock<(tempfile::TempDir, PathBuf)> = OnceLock::new();
    &SET.get_or_init(|| {
        let tmp = tempfile::tempdir().unwrap();
        let set = tmp.path().join("set");
        let cfg = synth::preset::preset("tiny", 0, false).unwrap();
        synth::capture_set_writer::synthesise(&cfg, &set, false, &|_| {}, &|| {})
            .expect("synth failed (are the assets fetched? run scripts/fetch-assets)");
        (tmp, set)
    })
    .1
}

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap() {
        let e = e.unwrap();
        let t = to.join(e.file_name());
        if e.path().is_dir() {
            copy_dir(&e.path(), &t);
        } else {
            std::fs::copy(e.path(), t).unwrap();
        }
    }
}

/// A fresh copy of the pristine set.
fn copy() -> (tempfile::TempDir, PathBuf) {
    let tmp = tempfile::tempdir().unwrap();
    let set = tmp.path().join("set");
    copy_dir(pristine(), &set);
    (tmp, set)
}

fn edit_json(path: &Path, f: impl FnOnce(&mut Value)) {
    let mut v: Value = serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    f(&mut v);
    std::fs::write(path, serde_json::to_string_pretty(&v).unwrap()).unwrap();
}

fn lines(r: &Report) -> Vec<String> {
    r.problems.iter().map(ToString::to_string).collect()
}

/// Exactly one problem, about `file`, whose text holds every word of `words`.
fn one_problem(r: &Report, file: &Path, words: &[&str]) {
    let l = lines(r);
    assert_eq!(l.len(), 1, "{l:#?}");
    assert_eq!(r.problems[0].path, file, "{l:#?}");
    for w in words {
        assert!(l[0].contains(w), "'{w}' not in {l:#?}");
    }
    assert!(!l[0].contains('\n'));
}

#[test]
fn the_synthesised_set_has_no_problems() {
    let r = check_set(pristine());
    assert!(r.problems.is_empty(), "{:#?}", lines(&r));
    // Both subjects, every motion folder (8 of A, 6 of B) and every frame were looked at.
    assert_eq!((r.subjects, r.motions), (2, 14));
    let n: usize = ["A", "B"]
        .iter()
        .flat_map(|x| std::fs::read_dir(pristine().join(x)).unwrap())
        .map(|e| e.unwrap().path())
        .filter(|p| p.is_dir())
        .map(|p| std::fs::read_dir(p).unwrap().count())
        .sum();
    assert!(r.frames > n, "{} frames counted, {n} outside truth", r.frames);
}

#[test]
fn a_missing_test_motion_is_named() {
    let (_t, set) = copy();
    edit_json(&set.join("set.json"), |v| v["test"].as_array_mut().unwrap().push("swim".into()));
    one_problem(&check_set(&set), &set.join("A/swim"), &["test motion 'swim'", "no folder"]);
}

#[test]
fn a_missing_training_motion_is_named() {
    let (_t, set) = copy();
    std::fs::remove_dir_all(set.join("B/kick")).unwrap();
    one_problem(&check_set(&set), &set.join("B/kick"), &["training motion 'kick'", "subject 'B'"]);
}

#[test]
fn a_missing_subject_is_named() {
    let (_t, set) = copy();
    edit_json(&set.join("set.json"), |v| v["target"] = "C".into());
    let r = check_set(&set);
    assert_eq!(r.problems[0].path, set.join("C"), "{:#?}", lines(&r));
    assert!(lines(&r)[0].contains("subject 'C'"));
    assert_eq!(r.problems.len(), 1, "{:#?}", lines(&r));
}

#[test]
fn a_missing_subject_description_is_named() {
    let (_t, set) = copy();
    std::fs::remove_file(set.join("B/subject.json")).unwrap();
    one_problem(&check_set(&set), &set.join("B/subject.json"), &["subject 'B'", "missing"]);
}

#[test]
fn key_poses_out_of_range_are_listed() {
    let (_t, set) = copy();
    // A's walk has 25 frames, B's 37: frame 25 of A and 37 of B do not exist.
    edit_json(&set.join("set.json"), |v| {
        v["train"][0]["keyposes"].as_array_mut().unwrap().push(serde_json::json!([25, 3]));
        v["train"][1]["keyposes"].as_array_mut().unwrap().push(serde_json::json!([3, 37]));
    });
    let r = check_set(&set);
    let l = lines(&r);
    assert_eq!(l.len(), 2, "{l:#?}");
    assert!(l[0].contains("[25, 3]") && l[0].contains("25 / 37"), "{l:#?}");
    assert!(l[1].contains("[3, 37]") && l[1].contains("run"), "{l:#?}");
}

#[test]
fn a_frame_of_another_topology_is_named() {
    let (_t, set) = copy();
    // A frame of B among A's: another vertex count.
    std::fs::copy(set.join("B/walk/000004.ply"), set.join("A/jump/000004.ply")).unwrap();
    one_problem(&check_set(&set), &set.join("A/jump/000004.ply"), &["vertices but the template"]);
    // Same vertex count, faces permuted: the faces differ.
    let (_t2, set) = copy();
    let p = set.join("A/kick/000002.ply");
    let mut m = mesh_core::io::read_mesh(&p).unwrap();
    m.faces.swap(0, 1);
    mesh_core::io::write_ply(&p, &m).unwrap();
    one_problem(&check_set(&set), &p, &["faces differ"]);
}

#[test]
fn an_unreadable_frame_and_a_gap_are_named() {
    let (_t, set) = copy();
    std::fs::write(set.join("A/punch/000003.ply"), b"ply\nformat ascii 1.0\nelement vertex 9\n").unwrap();
    std::fs::remove_file(set.join("B/run/000010.ply")).unwrap();
    let r = check_set(&set);
    let l = lines(&r);
    assert_eq!(l.len(), 2, "{l:#?}");
    assert!(r.problems.iter().any(|p| p.path == set.join("A/punch/000003.ply")), "{l:#?}");
    let gap = r.problems.iter().find(|p| p.path == set.join("B/run")).expect("the gap");
    assert!(gap.message.contains("000010.ply is missing"), "{l:#?}");
}

#[test]
fn bad_curves_are_named_per_part_and_loop() {
    let (_t, set) = copy();
    edit_json(&set.join("A/subject.json"), |v| {
        v["curves"]["arm_l"][0] = serde_json::json!([1, 2, 999_999]);
        v["curves"]["leg_r"][1] = serde_json::json!([5, 5]);
    });
    let r = check_set(&set);
    let l = lines(&r);
    assert_eq!(l.len(), 2, "{l:#?}");
    assert!(l.iter().all(|x| x.starts_with(&set.join("A/subject.json").display().to_string())));
    assert!(l[0].contains("part 'arm_l', curve 1") && l[0].contains("999999"), "{l:#?}");
    assert!(l[1].contains("part 'leg_r', curve 2") && l[1].contains("distinct"), "{l:#?}");
}

#[test]
fn a_curve_that_does_not_cut_the_mesh_is_named() {
    let (_t, set) = copy();
    // One face's three corners: a valid closed loop that encloses one triangle, so the far
    // loop of the arm no longer separates anything.
    let tpl = mesh_core::io::read_mesh(set.join("A/walk/000000.ply")).unwrap();
    let f = tpl.faces[0];
    edit_json(&set.join("A/subject.json"), |v| v["curves"]["arm_r"][1] = serde_json::json!(f));
    let r = check_set(&set);
    one_problem(&r, &set.join("A/subject.json"), &["curves against the template"]);
}

#[test]
fn bad_frame_rate_fields_are_named() {
    let (_t, set) = copy();
    edit_json(&set.join("A/subject.json"), |v| v["fps"] = "25".into());
    edit_json(&set.join("B/subject.json"), |v| v["fps"] = serde_json::json!(-50.0));
    let r = check_set(&set);
    let l = lines(&r);
    assert_eq!(l.len(), 2, "{l:#?}");
    assert!(l[0].contains("A/subject.json") && l[0].contains("'fps'") && l[0].contains("\"25\""), "{l:#?}");
    assert!(l[1].contains("B/subject.json") && l[1].contains("-50"), "{l:#?}");
}

#[test]
fn a_set_with_several_problems_lists_all_of_them() {
    let (_t, set) = copy();
    edit_json(&set.join("set.json"), |v| {
        v["test"].as_array_mut().unwrap().push("swim".into());
        v["train"][2]["keyposes"].as_array_mut().unwrap().push(serde_json::json!([99, 0]));
    });
    edit_json(&set.join("B/subject.json"), |v| {
        v["fps"] = serde_json::json!(0);
        v["curves"]["leg_l"][0] = serde_json::json!([0, 1, 123_456]);
    });
    std::fs::write(set.join("A/dance/000007.ply"), b"garbage").unwrap();
    std::fs::copy(set.join("A/walk/000000.ply"), set.join("B/dance/000001.ply")).unwrap();
    let r = check_set(&set);
    let l = lines(&r);
    let expect: [(PathBuf, &str); 6] = [
        (set.join("A/swim"), "test motion 'swim'"),
        (set.join("set.json"), "[99, 0]"),
        (set.join("B/subject.json"), "'fps'"),
        (set.join("B/subject.json"), "part 'leg_l', curve 1"),
        (set.join("A/dance/000007.ply"), ""),
        (set.join("B/dance/000001.ply"), "vertices but the template"),
    ];
    assert_eq!(l.len(), expect.len(), "{l:#?}");
    for (path, word) in &expect {
        assert!(
            r.problems.iter().any(|p| &p.path == path && p.message.contains(word)),
            "no problem about {} with '{word}' in {l:#?}",
            path.display()
        );
    }
}

#[test]
fn a_subject_without_curves_is_pointed_to_propose_curves() {
    let (_t, set) = copy();
    edit_json(&set.join("B/subject.json"), |v| {
        v.as_object_mut().unwrap().remove("curves");
        v.as_object_mut().unwrap().remove("parts");
    });
    // Not a problem: a note that the pipelines propose them.
    let report = check_set(&set);
    assert!(report.problems.is_empty(), "{:?}", report.problems);
    let json = set.join("B/subject.json");
    let notes: Vec<String> = report.notes.iter().filter(|n| n.path == json).map(|n| n.message.clone()).collect();
    assert!(notes.iter().any(|n| n.contains("no part curves") && n.contains("propose-curves")), "{notes:?}");
}
