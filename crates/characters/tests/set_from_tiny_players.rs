//! A capture set built from two tiny hand-made players (a tetrahedron for each of legs, torso and
//! head, animated frame by frame), checked by `check-set`'s library and read back.

use std::path::Path;

use characters::character::Character;
use characters::set_writer::{write_set, SetPlan};
use export::md3::{encode_md3, Md3, Md3Frame, Surface, Tag};
use mesh_core::sequence::MeshSequence;
use nalgebra::{Matrix3, Vector3};

/// The frame numbers of a player file whose walk is 12 frames at 20 fps (4 cycles: 2.4 s).
const CFG: &str = "sex m\n\
0 30 0 25\n29 1 0 25\n30 30 0 25\n59 1 0 25\n60 30 0 25\n89 1 0 25\n\
90 40 0 13\n130 6 0 15\n136 6 0 15\n142 5 0 20\n147 4 0 20\n151 1 0 15\n152 1 0 15\n\
153 8 8 20\n161 12 12 20\n173 9 9 15\n182 10 10 18\n185 10 10 15\n202 8 0 15\n\
211 8 0 20\n219 9 0 15\n228 6 0 20\n234 10 10 10\n244 10 10 10\n254 7 7 18\n";

fn tetrahedron(n_frames: usize, size: f64, wobble: f64) -> Surface {
    let frames = (0..n_frames)
        .map(|f| {
            let s = (f as f64 * 0.3).sin() * wobble;
            vec![
                Vector3::new(0.0, 0.0, 0.0),
                Vector3::new(size, 0.0, 0.0),
                Vector3::new(0.0, size, 0.0),
                Vector3::new(s, 0.0, size),
            ]
        })
        .collect();
    Surface { name: "s".into(), triangles: vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]], frames }
}

fn model(n_frames: usize, tag: Option<(&str, f64)>, size: f64) -> Md3 {
    let frame = Md3Frame { name: String::new(), min: Vector3::zeros(), max: Vector3::zeros(), origin: Vector3::zeros(), radius: 1.0 };
    let tags = (0..n_frames)
        .map(|_| {
            tag.iter()
                .map(|(name, up)| Tag { name: name.to_string(), origin: Vector3::new(0.0, 0.0, *up), axis: Matrix3::identity() })
                .collect()
        })
        .collect();
    Md3 { name: String::new(), frames: vec![frame; n_frames], tags, surfaces: vec![tetrahedron(n_frames, size, 2.0)] }
}

/// A player folder: the legs hold the BOTH frames then the LEGS frames (254 + 7 - 63 = 198),
/// the torso the BOTH and TORSO frames (153), the head one frame.
fn write_player(dir: &Path, size: f64) {
    std::fs::create_dir_all(dir).unwrap();
    std::fs::write(dir.join("lower.md3"), encode_md3(&model(198, Some(("tag_torso", 10.0)), size)).unwrap()).unwrap();
    std::fs::write(dir.join("upper.md3"), encode_md3(&model(153, Some(("tag_head", 12.0)), size)).unwrap()).unwrap();
    std::fs::write(dir.join("head.md3"), encode_md3(&model(1, None, size / 2.0)).unwrap()).unwrap();
    std::fs::write(dir.join("animation.cfg"), CFG).unwrap();
}

#[test]
fn a_set_of_two_players_has_frames_fps_keyposes_and_references_and_nothing_else() {
    let tmp = tempfile::tempdir().unwrap();
    write_player(&tmp.path().join("big"), 16.0);
    write_player(&tmp.path().join("small"), 8.0);
    let big = Character::load(&tmp.path().join("big")).unwrap();
    let small = Character::load(&tmp.path().join("small")).unwrap();
    let set = tmp.path().join("sets/big-small");
    let plan = SetPlan { source: &big, target: &small, train: &["walk", "jump"], test: &["back"], fps: 25.0, provenance: "test" };
    let summaries = write_set(&plan, &set).unwrap();
    assert_eq!((summaries[0].vertices, summaries[0].faces, summaries[0].components), (12, 12, 3));

    let spec: serde_json::Value = serde_json::from_slice(&std::fs::read(set.join("set.json")).unwrap()).unwrap();
    assert_eq!(spec["source"], "big");
    assert_eq!(spec["test"], serde_json::json!(["back"]));
    assert_eq!(spec["reference"]["small"], serde_json::json!(["back"]));
    // 4 walk cycles of 12 frames at 20 fps: 2.4 s, 60 frames at 25 fps.
    let walk = MeshSequence::load_dir(set.join("big/walk")).unwrap();
    assert_eq!(walk.n_frames(), 60);
    assert_eq!(spec["train"][0]["keyposes"], serde_json::json!([[6, 6], [18, 18], [30, 30], [42, 42], [54, 54]]));
    let subject: serde_json::Value = serde_json::from_slice(&std::fs::read(set.join("small/subject.json")).unwrap()).unwrap();
    assert_eq!(subject["fps"], 25.0);
    for absent in ["parts", "curves", "contacts"] {
        assert!(subject.get(absent).is_none(), "{absent}");
    }
    assert!(!set.join("truth").exists());
    assert!(!set.join("small/back").exists(), "the target's test motion is a reference, not a motion");
    let reference = MeshSequence::load_dir(set.join("reference/small/back")).unwrap();
    assert_eq!(reference.n_vertices(), 12);

    // check-set reads every frame; what it cannot check is the part description, which a lab's
    // set need not have.
    let report = mesh_core::set_check::check_set(&set);
    for p in &report.problems {
        assert!(p.message.contains("`parts`"), "unexpected problem: {p}");
    }
    assert_eq!(report.subjects, 2);
    assert_eq!(report.motions, 5, "walk, jump, back of big; walk, jump of small: {report:?}");
}

#[test]
fn the_assembled_character_stands_on_its_feet_with_the_head_on_top() {
    let tmp = tempfile::tempdir().unwrap();
    write_player(&tmp.path().join("p"), 16.0);
    let c = Character::load(&tmp.path().join("p")).unwrap();
    let at = characters::character::FramePosition { a: 0, b: 0, t: 0.0 };
    let v = c.pose(at, at);
    // Legs at Quake z 0..16, torso from the tag at 10, head from 10 + 12 = 22: in metres
    // (1/32 m per unit, feet 24 units below the origin), y is (z + 24) / 32.
    let top = |r: std::ops::Range<usize>| v[r].iter().map(|p| p.y).fold(f64::NEG_INFINITY, f64::max);
    assert!((top(0..4) - 40.0 / 32.0).abs() < 1e-12);
    assert!((top(4..8) - 50.0 / 32.0).abs() < 1e-12);
    assert!((top(8..12) - 54.0 / 32.0).abs() < 1e-12);
}
