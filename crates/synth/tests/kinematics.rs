//! Skeleton, skinning, mocap parsing and retargeting against analytic truths
//! (needs the fetched assets: run scripts/fetch-assets).

use nalgebra::{Rotation3, Vector3};
use synth::assets::{asset_dir, paths};
use synth::mocap;
use synth::preset;
use synth::retarget::{Retarget, SourceKind};
use synth::subject::{BodyAssets, Subject, Topology};

fn assets() -> BodyAssets {
    let dir = asset_dir()
        .expect("assets missing: run scripts/fetch-assets (SURFCAP_CACHE or ~/.cache/surfcap)");
    BodyAssets::load(&dir).unwrap()
}

fn tiny_a(b: &BodyAssets) -> Subject {
    Subject::build(
        b,
        &preset::subject_a(Topology::Obj("notoes_collapse10pc.obj".into()), 20.0),
    )
    .unwrap()
}

#[test]
fn fk_of_identity_rotations_gives_the_rest_joints() {
    let b = assets();
    let s = tiny_a(&b);
    let pose = s.skeleton.rest_pose();
    for (i, bone) in s.skeleton.bones.iter().enumerate() {
        assert!((pose.heads[i] - bone.head).norm() < 1e-12, "{}", bone.name);
        assert!((s.skeleton.posed_tail(&pose, i) - bone.tail).norm() < 1e-12);
    }
    // A rigid motion of the whole body: every joint moves rigidly.
    let r = Rotation3::from_euler_angles(0.3, -1.1, 0.7);
    let t = Vector3::new(0.5, 0.2, -1.0);
    let root = s.skeleton.root();
    let pose = s.skeleton.forward_kinematics(
        vec![r; s.skeleton.bones.len()],
        s.skeleton.bones[root].head + t,
    );
    let h0 = s.skeleton.bones[root].head;
    for (i, bone) in s.skeleton.bones.iter().enumerate() {
        let want = h0 + t + r * (bone.head - h0);
        assert!((pose.heads[i] - want).norm() < 1e-12, "{}", bone.name);
    }
}

#[test]
fn skinning_at_rest_returns_the_rest_mesh_and_is_rigid_under_rigid_pose() {
    let b = assets();
    let s = tiny_a(&b);
    let rest = s.skin(&s.skeleton.rest_pose());
    for (p, q) in rest.iter().zip(&s.rest) {
        assert!((p - q).norm() < 1e-12);
    }
    let r = Rotation3::from_euler_angles(-0.4, 2.0, 0.1);
    let root = s.skeleton.root();
    let h0 = s.skeleton.bones[root].head;
    let pose = s
        .skeleton
        .forward_kinematics(vec![r; s.skeleton.bones.len()], h0);
    for (p, q) in s.skin(&pose).iter().zip(&s.rest) {
        assert!((p - (h0 + r * (q - h0))).norm() < 1e-9);
    }
    for row in &s.weights {
        assert!((row.iter().map(|e| e.1).sum::<f64>() - 1.0).abs() < 1e-12);
    }
}

#[test]
fn subjects_have_the_intended_heights_and_topologies() {
    let b = assets();
    let a = Subject::build(&b, &preset::subject_a(Topology::Body, 25.0)).unwrap();
    let bb = Subject::build(
        &b,
        &preset::subject_b(Topology::Obj("notoes.obj".into()), 50.0),
    )
    .unwrap();
    assert_eq!(a.rest.len(), 13380);
    assert_eq!(bb.rest.len(), 12272);
    assert!((a.height() - 1.6).abs() < 0.03, "A is {:.3} m", a.height());
    assert!(
        (bb.height() - 1.9).abs() < 0.05,
        "B is {:.3} m",
        bb.height()
    );
    // B is heavier: wider at the hips relative to height.
    let width = |s: &Subject| {
        let y = s.skeleton.bones[s.skeleton.root()].head.y;
        let band: Vec<f64> = s
            .rest
            .iter()
            .filter(|v| (v.y - y).abs() < 0.03)
            .map(|v| v.z)
            .collect();
        band.iter().cloned().fold(f64::MIN, f64::max)
            - band.iter().cloned().fold(f64::MAX, f64::min)
    };
    assert!(width(&bb) / bb.height() > 1.15 * width(&a) / a.height());
    // notoes vertices coincide with body vertices: most embed exactly.
    let obj =
        synth::makehuman::read_obj(&b.dir.join(paths::TOPOLOGY).join("notoes.obj"), 1.0, None)
            .unwrap();
    let e = synth::embedding::embed(&obj.vertices[..500], &b.base[..13380], &b.body_faces);
    assert!(e.iter().filter(|r| r.len() == 1).count() > 450);
    for (row, p) in e.iter().zip(&obj.vertices) {
        let q: Vector3<f64> = row.iter().map(|&(i, w)| b.base[i] * w).sum();
        assert!((q - p).norm() < 2e-3, "embedding off by {}", (q - p).norm());
    }
}

#[test]
fn mocap_files_parse_with_known_frame_counts() {
    let dir = asset_dir().expect("assets missing: run scripts/fetch-assets");
    let leg = mocap::deepmimic_leg_length(&dir.join(paths::HUMANOID_URDF)).unwrap();
    assert!((leg - 0.25 * (1.686184 + 1.639480)).abs() < 1e-9);
    let walk = mocap::parse_deepmimic(
        &dir.join(paths::MOTIONS).join("humanoid3d_walk.txt"),
        "walk",
        leg,
    )
    .unwrap();
    assert_eq!(walk.n_frames(), 39);
    assert!((walk.duration() - 38.0 * 0.033332).abs() < 1e-9);
    // Walking forward: DeepMimic +x becomes the body's +z.
    assert!(
        walk.root[38].z - walk.root[0].z > 1.0 && (walk.root[38].x - walk.root[0].x).abs() < 0.1
    );
    let looped = walk.clone().looped(3);
    assert_eq!(looped.n_frames(), 1 + 3 * 38);
    assert!((looped.duration() - 3.0 * walk.duration()).abs() < 1e-9);
    let bvh = mocap::parse_bvh(&dir.join(paths::CMU_BVH), "01_01").unwrap();
    assert_eq!(bvh.n_frames(), 2752);
    assert_eq!(bvh.segments.len(), 31);
    assert!((bvh.times[1] - 0.0083333).abs() < 1e-12);
    assert!((bvh.root[0] - Vector3::new(9.3722, 17.8693, -17.3198)).norm() < 1e-9);
}

fn posed_dir(s: &Subject, pose: &synth::skeleton::Pose, bone: &str) -> Vector3<f64> {
    let i = s.skeleton.index(bone).unwrap();
    (s.skeleton.posed_tail(pose, i) - pose.heads[i]).normalize()
}

#[test]
fn retargeted_rest_poses_match_the_sources_rest_poses() {
    let b = assets();
    let s = tiny_a(&b);
    let tmp = tempfile::tempdir().unwrap();
    // DeepMimic identity frame: arms and legs straight down; knee at -90 degrees: shin backward.
    let mut frame = vec![0.0; 44];
    frame[0] = 0.1;
    frame[2] = 0.9;
    for k in [4, 8, 12, 16, 21, 25, 30, 35, 39] {
        frame[k] = 1.0;
    }
    frame[20] = -std::f64::consts::FRAC_PI_2; // right knee
    frame[43] = std::f64::consts::FRAC_PI_2; // left elbow
    let json = serde_json::json!({"Loop": "none", "Frames": [frame, frame]});
    let p = tmp.path().join("m.txt");
    std::fs::write(&p, json.to_string()).unwrap();
    let clip = mocap::parse_deepmimic(&p, "m", 0.83).unwrap();
    let rt = Retarget::new(&s.skeleton, &clip, SourceKind::DeepMimic).unwrap();
    let (rots, root) = rt.at(&clip, 0.0);
    let pose = s.skeleton.forward_kinematics(rots, root);
    let down = -Vector3::y();
    for bone in [
        "LeftArm",
        "RightArm",
        "RightForeArm",
        "LeftUpLeg",
        "RightUpLeg",
        "LeftLeg",
    ] {
        assert!((posed_dir(&s, &pose, bone) - down).norm() < 1e-9, "{bone}");
    }
    assert!(
        (posed_dir(&s, &pose, "RightLeg") - (-Vector3::z())).norm() < 1e-9,
        "knee flexion moves the shin back"
    );
    assert!(
        (posed_dir(&s, &pose, "LeftForeArm") - Vector3::z()).norm() < 1e-9,
        "elbow flexion moves the forearm forward"
    );
    // CMU zero frame: the T-pose, arms horizontal (left arm along +x).
    let bvh = "HIERARCHY\nROOT Hips\n{\n OFFSET 0 0 0\n CHANNELS 6 Xposition Yposition Zposition Zrotation Yrotation Xrotation\n";
    let mut text = bvh.to_string();
    // Build the CMU skeleton names the rig uses, as one flat chain per limb.
    let chain = |names: &[(&str, &str)]| {
        let mut s = String::new();
        for (n, o) in names {
            s +=
                &format!("JOINT {n}\n{{\n OFFSET {o}\n CHANNELS 3 Zrotation Yrotation Xrotation\n");
        }
        s += "End Site\n{\n OFFSET 0 1 0\n}\n";
        for _ in names {
            s += "}\n";
        }
        s
    };
    text += &chain(&[
        ("LHipJoint", "0 0 0"),
        ("LeftUpLeg", "1 -1 0"),
        ("LeftLeg", "0 -7 0"),
        ("LeftFoot", "0 -7 0"),
        ("LeftToeBase", "0 -1 2"),
    ]);
    text += &chain(&[
        ("RHipJoint", "0 0 0"),
        ("RightUpLeg", "-1 -1 0"),
        ("RightLeg", "0 -7 0"),
        ("RightFoot", "0 -7 0"),
        ("RightToeBase", "0 -1 2"),
    ]);
    text += &chain(&[
        ("LowerBack", "0 0 0"),
        ("Spine", "0 2 0"),
        ("Spine1", "0 2 0"),
        ("Neck", "0 2 0"),
        ("Neck1", "0 1 0"),
        ("Head", "0 1 0"),
    ]);
    text += &chain(&[
        ("LeftShoulder", "0 0 0"),
        ("LeftArm", "3 0 0"),
        ("LeftForeArm", "5 0 0"),
        ("LeftHand", "5 0 0"),
        ("LeftFingerBase", "1 0 0"),
        ("LeftHandFinger1", "1 0 0"),
        ("LThumb", "1 0 0"),
    ]);
    text += &chain(&[
        ("RightShoulder", "0 0 0"),
        ("RightArm", "-3 0 0"),
        ("RightForeArm", "-5 0 0"),
        ("RightHand", "-5 0 0"),
        ("RightFingerBase", "-1 0 0"),
        ("RightHandFinger1", "-1 0 0"),
        ("RThumb", "-1 0 0"),
    ]);
    text += "}\nMOTION\nFrames: 1\nFrame Time: 0.01\n";
    let n_channels = 6 + 3 * 30;
    text += &vec!["0"; n_channels].join(" ");
    text += "\n";
    let p = tmp.path().join("t.bvh");
    std::fs::write(&p, &text).unwrap();
    let clip = mocap::parse_bvh(&p, "t").unwrap();
    let rt = Retarget::new(&s.skeleton, &clip, SourceKind::Cmu).unwrap();
    let (rots, root) = rt.at(&clip, 0.0);
    let pose = s.skeleton.forward_kinematics(rots, root);
    assert!((posed_dir(&s, &pose, "LeftArm") - Vector3::x()).norm() < 1e-9);
    assert!((posed_dir(&s, &pose, "RightForeArm") + Vector3::x()).norm() < 1e-9);
    assert!((posed_dir(&s, &pose, "LeftLeg") + Vector3::y()).norm() < 1e-9);
    // A truncated file fails with a message naming the problem.
    std::fs::write(&p, &text[..text.len() - 40]).unwrap();
    let err = mocap::parse_bvh(&p, "t").unwrap_err().to_string();
    assert!(err.contains("t.bvh") && err.contains("frame"), "{err}");
}

#[test]
fn part_loops_ring_the_upper_limb_bones_in_order() {
    let b = assets();
    let s = tiny_a(&b);
    let curves = synth::parts::part_curves(&s).unwrap();
    assert_eq!(curves.len(), 4);
    for (part, bone) in [
        ("arm_l", "LeftArm"),
        ("arm_r", "RightArm"),
        ("leg_l", "LeftUpLeg"),
        ("leg_r", "RightUpLeg"),
    ] {
        let bn = &s.skeleton.bones[s.skeleton.index(bone).unwrap()];
        let (h, d, len) = (bn.head, bn.direction(), (bn.tail - bn.head).norm());
        let along = |l: &Vec<u32>| {
            l.iter()
                .map(|&i| (s.rest[i as usize] - h).dot(&d))
                .sum::<f64>()
                / l.len() as f64
                / len
        };
        let loops = &curves[part];
        assert_eq!(loops.len(), 2);
        assert!(
            !loops[0].iter().any(|v| loops[1].contains(v)),
            "{part}: loops share vertices"
        );
        let (a0, a1) = (along(&loops[0]), along(&loops[1]));
        assert!(
            0.0 < a0 && a0 < a1 && a1 < 1.0,
            "{part}: loops at {a0:.2}, {a1:.2} of the bone"
        );
        for l in loops {
            // Every loop vertex is on this limb's side of the body.
            let side = if part.ends_with("_l") { 1.0 } else { -1.0 };
            assert!(
                l.iter().all(|&i| side * s.rest[i as usize].x > 0.0),
                "{part}"
            );
        }
    }
}
