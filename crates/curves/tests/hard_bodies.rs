//! `propose-curves` on bodies built here the way game characters are modelled: every body part
//! a separate closed capsule (a component of its own, pushed into the torso at the shoulder and
//! hip), up +y, facing +z, 1.78 m tall, with the hard cases added one at a time: a knee-long
//! hair sheet (an open mesh) hanging from the back of the head, a braid, a separate prop, arms
//! close to the body, a hand raised above the head, non-manifold edges. Every vertex's true
//! part is known from the piece it belongs to, so each case checks that the limb parts hold
//! their hand or foot and the hair and props stay with the torso.

use std::collections::BTreeMap;
use std::path::Path;
use std::process::Command;

use curves::limb_loops::{propose, with_curves, Settings};
use mesh_core::capture_set::SubjectSpec;
use mesh_core::shapes::capsule_body;
use mesh_core::TriMesh;
use nalgebra::{Rotation3, Vector3};

/// What a piece of the synthetic body is.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Piece {
    Torso,
    Head,
    Hair,
    Prop,
    /// Upper arm or thigh of `side` ('l' or 'r') with the hand or foot at its end.
    Arm(char),
    Leg(char),
    Foot(char),
}

struct Body {
    mesh: TriMesh,
    /// The piece of every vertex.
    piece: Vec<Piece>,
}

impl Body {
    fn new() -> Body {
        Body { mesh: TriMesh::new(Vec::new(), Vec::new()), piece: Vec::new() }
    }

    fn add(&mut self, m: &TriMesh, piece: Piece) {
        let base = self.mesh.vertices.len() as u32;
        self.mesh.vertices.extend(m.vertices.iter().copied());
        self.mesh.faces.extend(m.faces.iter().map(|f| [f[0] + base, f[1] + base, f[2] + base]));
        self.piece.extend(std::iter::repeat_n(piece, m.vertices.len()));
    }

    /// A capsule of `radius` round the segment `from`-`to`.
    fn capsule(&mut self, from: Vector3<f64>, to: Vector3<f64>, radius: f64, piece: Piece) {
        self.capsule_rings(from, to, radius, piece, 0.025);
    }

    /// A capsule with rings `spacing` apart along its axis.
    fn capsule_rings(&mut self, from: Vector3<f64>, to: Vector3<f64>, radius: f64, piece: Piece, spacing: f64) {
        let axis = to - from;
        let rings = ((axis.norm() / spacing) as usize).max(2);
        let (m, _) = capsule_body(rings, 16, radius, axis.norm());
        let rot = Rotation3::rotation_between(&Vector3::y(), &axis.normalize())
            .unwrap_or_else(|| Rotation3::from_axis_angle(&Vector3::x_axis(), std::f64::consts::PI));
        let placed = TriMesh::new(m.vertices.iter().map(|p| rot * p + from).collect(), m.faces.clone());
        self.add(&placed, piece);
    }

    /// The vertices of `piece` farthest along `dir` (the tip of a hand or foot).
    fn tip(&self, piece: Piece, dir: Vector3<f64>) -> u32 {
        (0..self.mesh.vertices.len() as u32)
            .filter(|&v| self.piece[v as usize] == piece)
            .max_by(|&a, &b| self.mesh.vertices[a as usize].dot(&dir).total_cmp(&self.mesh.vertices[b as usize].dot(&dir)))
            .unwrap()
    }
}

/// The plain body: torso, head, two arms hanging a little away from the body, two legs with
/// feet pointing forward (+z); the body's left is +x.
fn body(raised_right_hand: bool) -> Body {
    let v = Vector3::new;
    let mut b = Body::new();
    b.capsule(v(0.0, 0.92, 0.0), v(0.0, 1.36, 0.0), 0.15, Piece::Torso);
    b.capsule(v(0.0, 1.60, 0.0), v(0.0, 1.66, 0.0), 0.11, Piece::Head);
    for (side, x) in [('l', 1.0), ('r', -1.0)] {
        let hand = if raised_right_hand && side == 'r' { v(-0.30, 1.98, 0.0) } else { v(x * 0.30, 0.80, 0.0) };
        b.capsule(v(x * 0.12, 1.36, 0.0), hand, 0.045, Piece::Arm(side));
        b.capsule(v(x * 0.09, 1.0, 0.0), v(x * 0.09, 0.12, 0.0), 0.065, Piece::Leg(side));
        b.capsule(v(x * 0.09, 0.05, -0.04), v(x * 0.09, 0.05, 0.16), 0.045, Piece::Foot(side));
    }
    b
}

/// A knee-long open sheet of hair, 0.2 m wide, from inside the back of the head down the back.
fn add_hair_sheet(b: &mut Body) {
    let (cols, rows) = (9usize, 48usize);
    let mut vertices = Vec::new();
    for r in 0..rows {
        let y = 1.66 - (1.66 - 0.50) * r as f64 / (rows - 1) as f64;
        // Leaving the head's back (z = -0.08 inside it) and falling behind the torso (z = -0.2).
        let z = if y > 1.50 { -0.08 - 0.12 * (1.66 - y) / 0.16 } else { -0.20 };
        for c in 0..cols {
            vertices.push(Vector3::new(-0.1 + 0.2 * c as f64 / (cols - 1) as f64, y, z));
        }
    }
    let mut faces = Vec::new();
    for r in 0..rows - 1 {
        for c in 0..cols - 1 {
            let (a, bb, cc, d) = ((r * cols + c) as u32, (r * cols + c + 1) as u32, ((r + 1) * cols + c) as u32, ((r + 1) * cols + c + 1) as u32);
            faces.push([a, cc, bb]);
            faces.push([bb, cc, d]);
        }
    }
    b.add(&TriMesh::new(vertices, faces), Piece::Hair);
}

fn add_braid(b: &mut Body) {
    b.capsule(Vector3::new(0.03, 1.62, -0.09), Vector3::new(0.05, 0.95, -0.21), 0.015, Piece::Hair);
}

/// A pouch on the belt, not touching the body.
fn add_prop(b: &mut Body) {
    b.capsule(Vector3::new(0.0, 0.95, 0.20), Vector3::new(0.0, 1.02, 0.20), 0.035, Piece::Prop);
}

/// A fin of two triangles on a torso edge: that edge and its neighbour get a third face.
fn add_fin(b: &mut Body) {
    let f = b.mesh.faces[b.piece.iter().position(|p| *p == Piece::Torso).unwrap() + 200];
    let tip = b.mesh.vertices.len() as u32;
    let p = (b.mesh.vertices[f[0] as usize] + b.mesh.vertices[f[1] as usize]) / 2.0;
    b.mesh.vertices.push(p + Vector3::new(0.0, 0.0, 0.03));
    b.piece.push(Piece::Torso);
    b.mesh.faces.push([f[0], f[1], tip]);
    b.mesh.faces.push([f[1], f[2], tip]);
}

/// A tail from the back of the pelvis down to 0.1 m above the ground, behind the legs.
fn add_tail(b: &mut Body) {
    b.capsule(Vector3::new(0.0, 0.95, -0.12), Vector3::new(0.0, 0.10, -0.55), 0.04, Piece::Prop);
}

/// A staff slung across the back at the hips, sticking out 0.4 m on the right, not touching the
/// body.
fn add_staff(b: &mut Body) {
    b.capsule(Vector3::new(0.25, 1.05, -0.2), Vector3::new(-0.55, 1.05, -0.2), 0.02, Piece::Prop);
}

/// The plain body with its left arm bent across the front of the torso, the left hand beyond
/// the body's right side (the hand of a character holding a weapon): the upper arm, then the
/// forearm as its own piece.
fn body_with_crossed_arm() -> Body {
    let v = Vector3::new;
    let mut b = body(false);
    let arm = |p: &Piece| *p == Piece::Arm('l');
    let keep: Vec<bool> = b.piece.iter().map(|p| !arm(p)).collect();
    remove_vertices(&mut b, &keep);
    b.capsule(v(0.12, 1.36, 0.0), v(0.26, 1.10, 0.14), 0.045, Piece::Arm('l'));
    b.capsule(v(0.26, 1.10, 0.14), v(-0.26, 1.05, 0.32), 0.04, Piece::Foot('l'));
    b
}

/// `b` without the vertices not `keep`, and the faces that used them.
fn remove_vertices(b: &mut Body, keep: &[bool]) {
    let mut index = vec![u32::MAX; keep.len()];
    let mut n = 0;
    for (v, k) in keep.iter().enumerate() {
        if *k {
            index[v] = n;
            n += 1;
        }
    }
    let vertices = (0..keep.len()).filter(|&v| keep[v]).map(|v| b.mesh.vertices[v]).collect();
    let faces = b.mesh.faces.iter().filter(|f| f.iter().all(|&v| keep[v as usize])).map(|f| f.map(|v| index[v as usize])).collect();
    b.piece = b.piece.iter().zip(keep).filter(|(_, k)| **k).map(|(p, _)| *p).collect();
    b.mesh = TriMesh::new(vertices, faces);
}

/// The proposed parts of `b` (segmented as `segment` does) and the vertices of each.
fn proposed_parts(b: &Body, hints: &BTreeMap<String, u32>) -> BTreeMap<String, Vec<u32>> {
    let limbs = propose(&b.mesh, &Vector3::y(), &Settings::default(), hints).into_result().unwrap();
    let value = with_curves(serde_json::json!({"fps": 25, "up": "+y"}), &limbs).unwrap();
    let spec: SubjectSpec = serde_json::from_value(value).unwrap();
    let seg = mesh_core::segmentation::segment(&b.mesh, &spec).unwrap();
    seg.check().unwrap();
    seg.parts.iter().map(|p| (p.name.clone(), p.vertices.clone())).collect()
}

/// Each limb part holds all of its hand or foot (the far half of its piece) and nothing of
/// the other limbs, the head, the hair or the props; the torso keeps those.
fn assert_parts_right(b: &Body, parts: &BTreeMap<String, Vec<u32>>) {
    let pos = &b.mesh.vertices;
    let has = |part: &str, v: u32| parts[part].binary_search(&v).is_ok();
    for v in 0..pos.len() as u32 {
        let p = pos[v as usize];
        let expected: Option<&str> = match b.piece[v as usize] {
            Piece::Torso | Piece::Head | Piece::Hair | Piece::Prop => Some("torso"),
            // The hand half of an arm (below the elbow, or above it for a raised arm).
            Piece::Arm(s) if (p.y - 1.36).abs() > 0.3 => Some(if s == 'l' { "arm_l" } else { "arm_r" }),
            Piece::Leg(s) if p.y < 0.55 => Some(if s == 'l' { "leg_l" } else { "leg_r" }),
            Piece::Foot(s) => Some(if s == 'l' { "leg_l" } else { "leg_r" }),
            _ => None,
        };
        if let Some(e) = expected {
            assert!(has(e, v), "vertex {v} of {:?} at {p:?} is not in {e}", b.piece[v as usize]);
            for other in ["arm_l", "arm_r", "leg_l", "leg_r"].iter().filter(|o| **o != e) {
                assert!(!has(other, v), "vertex {v} of {:?} at {p:?} is in {other}", b.piece[v as usize]);
            }
        }
    }
}

fn check(b: &Body) {
    assert_parts_right(b, &proposed_parts(b, &BTreeMap::new()));
}

#[test]
fn a_body_of_separate_pieces_gets_each_hand_and_foot_in_its_own_limb() {
    check(&body(false));
}

#[test]
fn a_knee_long_hair_sheet_stays_with_the_torso_and_is_not_taken_for_a_limb() {
    let mut b = body(false);
    add_hair_sheet(&mut b);
    check(&b);
}

#[test]
fn a_braid_stays_with_the_torso_and_is_not_taken_for_a_limb() {
    let mut b = body(false);
    add_braid(&mut b);
    check(&b);
}

#[test]
fn a_separate_prop_goes_with_the_torso_it_is_nearest_to() {
    let mut b = body(false);
    add_prop(&mut b);
    check(&b);
}

#[test]
fn a_hand_raised_above_the_head_falls_in_its_arm() {
    let mut b = body(true);
    add_hair_sheet(&mut b);
    check(&b);
}

#[test]
fn non_manifold_edges_and_every_hard_case_at_once_still_give_the_right_parts() {
    let mut b = body(true);
    add_hair_sheet(&mut b);
    add_braid(&mut b);
    add_prop(&mut b);
    add_fin(&mut b);
    let topo = mesh_core::topology::Topology::new(b.mesh.vertices.len(), &b.mesh.faces);
    assert!(!topo.is_edge_manifold());
    check(&b);
}

#[test]
fn a_tail_reaching_the_ground_stays_with_the_torso_and_is_taken_for_no_foot_or_hand() {
    let mut b = body(false);
    add_tail(&mut b);
    check(&b);
}

#[test]
fn a_long_prop_across_the_back_stays_with_the_torso_and_is_taken_for_no_hand() {
    let mut b = body(false);
    add_staff(&mut b);
    check(&b);
}

#[test]
fn a_hand_held_across_the_body_is_sided_by_its_shoulder() {
    let b = body_with_crossed_arm();
    let parts = proposed_parts(&b, &BTreeMap::new());
    let has = |part: &str, v: u32| parts[part].binary_search(&v).is_ok();
    // The forearm's hand half (beyond x = 0) is in arm_l, and in no other limb.
    for v in (0..b.mesh.vertices.len() as u32).filter(|&v| b.piece[v as usize] == Piece::Foot('l') && b.mesh.vertices[v as usize].x < 0.0) {
        assert!(has("arm_l", v), "vertex {v} of the left forearm at {:?} is not in arm_l", b.mesh.vertices[v as usize]);
        assert!(!has("arm_r", v) && !has("leg_l", v) && !has("leg_r", v), "vertex {v} of the left forearm is in another limb");
    }
    // The right arm keeps its hand, the torso its head.
    assert!(has("arm_r", b.tip(Piece::Arm('r'), -Vector3::y())));
    assert!(has("torso", b.tip(Piece::Head, Vector3::y())));
}

#[test]
fn coarse_limbs_with_few_rings_still_get_two_loops_each() {
    // Arms of three rings (shoulder, elbow, wrist), legs of four.
    let v = Vector3::new;
    let mut b = body(false);
    let keep: Vec<bool> = b.piece.iter().map(|p| !matches!(p, Piece::Arm(_) | Piece::Leg(_))).collect();
    remove_vertices(&mut b, &keep);
    for (side, x) in [('l', 1.0), ('r', -1.0)] {
        b.capsule_rings(v(x * 0.12, 1.36, 0.0), v(x * 0.30, 0.80, 0.0), 0.045, Piece::Arm(side), 0.2);
        b.capsule_rings(v(x * 0.09, 1.0, 0.0), v(x * 0.09, 0.12, 0.0), 0.065, Piece::Leg(side), 0.25);
    }
    let parts = proposed_parts(&b, &BTreeMap::new());
    for (part, piece) in [("arm_l", Piece::Arm('l')), ("arm_r", Piece::Arm('r')), ("leg_l", Piece::Foot('l')), ("leg_r", Piece::Foot('r'))] {
        let tip = b.tip(piece, if part.starts_with("arm") { -Vector3::y() } else { Vector3::z() });
        assert!(parts[part].binary_search(&tip).is_ok(), "{part} does not hold its extremity {tip}");
        assert!(parts[part].iter().all(|&w| matches!(b.piece[w as usize], Piece::Arm(_) | Piece::Leg(_) | Piece::Foot(_))), "{part} holds torso, head or props");
    }
}

#[test]
fn extremities_given_as_hints_replace_the_choice() {
    // Hints that swap the hands: the arm called left then holds the right hand.
    let b = body(false);
    let (left_hand, right_hand) = (b.tip(Piece::Arm('l'), -Vector3::y()), b.tip(Piece::Arm('r'), -Vector3::y()));
    let hints: BTreeMap<String, u32> = [("hand_l".to_string(), right_hand), ("hand_r".to_string(), left_hand)].into();
    let limbs = propose(&b.mesh, &Vector3::y(), &Settings::default(), &hints).into_result().unwrap();
    let arm_l = limbs.iter().find(|l| l.part == "arm_l").unwrap();
    assert_eq!(arm_l.extremity, right_hand);
    let parts = proposed_parts(&b, &hints);
    assert!(parts["arm_l"].binary_search(&right_hand).is_ok() && parts["arm_r"].binary_search(&left_hand).is_ok());
}

/// A body whose legs end in round caps (no feet): nothing tells its left from its right.
fn footless() -> Body {
    let mut b = body(false);
    let keep: Vec<bool> = b.piece.iter().map(|p| !matches!(p, Piece::Foot(_))).collect();
    remove_vertices(&mut b, &keep);
    b
}

fn run_stage(dir: &Path, mesh: &TriMesh, hints: &[String]) -> (std::process::Output, std::path::PathBuf, std::path::PathBuf) {
    let tpl = dir.join("body.ply");
    mesh_core::io::write_ply(&tpl, mesh).unwrap();
    let json = dir.join("subject.json");
    std::fs::write(&json, r#"{"fps": 25, "up": "+y"}"#).unwrap();
    let (out, png) = (dir.join("out.json"), dir.join("check.png"));
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_propose-curves"));
    cmd.arg(&json).arg("--template").arg(&tpl).arg("--out").arg(&out).arg("--render").arg(&png);
    for h in hints {
        cmd.arg("--extremity").arg(h);
    }
    (cmd.output().unwrap(), out, png)
}

/// Pixels of the extremities' colour in a PNG.
fn extremity_pixels(png_path: &Path) -> usize {
    let dec = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(png_path).unwrap()));
    let mut reader = dec.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    reader.next_frame(&mut buf).unwrap();
    buf.chunks(3).filter(|p| *p == curves::check_image::EXTREMITY_COLOUR).count()
}

#[test]
fn when_it_cannot_decide_it_names_the_extremities_and_still_draws_them() {
    let dir = tempfile::tempdir().unwrap();
    let b = footless();
    let (run, out, png) = run_stage(dir.path(), &b.mesh, &[]);
    assert_eq!(run.status.code(), Some(1));
    let err = String::from_utf8(run.stderr).unwrap();
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.starts_with("propose-curves: ") && err.contains("left from its right"), "{err}");
    for name in curves::extremities::NAMES {
        assert!(err.contains(&format!("{name} ")), "{name} missing from: {err}");
    }
    assert!(!out.exists(), "no subject.json is written on failure");
    // Five marks of 7x7 pixels in each of the three views, plus their names and the legend.
    assert!(extremity_pixels(&png) > 3 * 5 * 30, "{} marked pixels", extremity_pixels(&png));

    // The hints the message asks for: the left hand and foot, then it succeeds.
    let hints = [format!("hand_l={}", b.tip(Piece::Arm('l'), -Vector3::y())), format!("foot_l={}", b.tip(Piece::Leg('l'), -Vector3::y()))];
    let (run, out, _) = run_stage(dir.path(), &b.mesh, &hints);
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
    let spec = SubjectSpec::load(&out).unwrap();
    let seg = mesh_core::segmentation::segment(&b.mesh, &spec).unwrap();
    let parts: BTreeMap<String, Vec<u32>> = seg.parts.iter().map(|p| (p.name.clone(), p.vertices.clone())).collect();
    assert_parts_right(&b, &parts);
}

#[test]
fn a_malformed_hint_is_a_usage_error_and_a_vertex_past_the_mesh_a_one_line_error() {
    let dir = tempfile::tempdir().unwrap();
    let b = body(false);
    for bad in ["elbow=3", "hand_l=x", "hand_l"] {
        let (run, out, png) = run_stage(dir.path(), &b.mesh, &[bad.to_string()]);
        assert_eq!(run.status.code(), Some(2), "{bad}");
        assert!(String::from_utf8(run.stderr).unwrap().contains("--extremity"));
        assert!(!out.exists() && !png.exists());
    }
    let (run, out, png) = run_stage(dir.path(), &b.mesh, &["hand_l=99999999".to_string()]);
    assert_eq!(run.status.code(), Some(1));
    let err = String::from_utf8(run.stderr).unwrap();
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.starts_with("propose-curves: ") && err.contains("--extremity hand_l=99999999"), "{err}");
    assert!(!out.exists() && !png.exists());
}

#[test]
fn verbose_names_the_extremities_chosen_on_success() {
    let dir = tempfile::tempdir().unwrap();
    let b = body(false);
    let tpl = dir.path().join("body.ply");
    mesh_core::io::write_ply(&tpl, &b.mesh).unwrap();
    let json = dir.path().join("subject.json");
    std::fs::write(&json, r#"{"fps": 25}"#).unwrap();
    let run = Command::new(env!("CARGO_BIN_EXE_propose-curves"))
        .arg(&json).arg("--template").arg(&tpl).arg("--out").arg(dir.path().join("o.json")).arg("-v")
        .output().unwrap();
    assert!(run.status.success());
    let err = String::from_utf8(run.stderr).unwrap();
    let line = err.lines().find(|l| l.contains("extremities:")).unwrap_or_else(|| panic!("{err}"));
    let hand_l = b.tip(Piece::Arm('l'), -Vector3::y());
    // The left hand named is a vertex of the left arm's hand end.
    let named: u32 = line.split("hand_l ").nth(1).unwrap().split(' ').next().unwrap().parse().unwrap();
    assert_eq!(b.piece[named as usize], Piece::Arm('l'));
    assert!((b.mesh.vertices[named as usize] - b.mesh.vertices[hand_l as usize]).norm() < 0.1);
}
