//! The placement of decoded frames keeps a capture's heading: integrating a captured sequence's
//! own root displacements with its own gravity values (`capture::root_placement`) gives back
//! its root poses, so whatever turns a variation is in what is decoded, not in the placement.

use std::path::Path;
use std::process::Command;

mod common;

use mesh_core::artifact::Artifact;
use variation::group::Group;

#[test]
fn integrating_a_captures_own_displacements_and_gravity_gives_back_its_poses() {
    let dir = tempfile::tempdir().unwrap();
    let set = common::tiny_set(dir.path());
    let group_path = dir.path().join("g.group");
    let s = |p: &Path| p.to_string_lossy().into_owned();
    let out = Command::new(env!("CARGO_BIN_EXE_prealign"))
        .args(["-q", "--set", &s(&set), "--group-name", "locomotion", "--blend-weights", "0.5", "--out", &s(&group_path)])
        .args(common::front_end(&set, "A", &["walk", "run"], dir.path()))
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let group = Group::load(&group_path).unwrap();
    let root = group.root_point();
    for seq in &group.sequences {
        let m = &seq.motion;
        let gravity = variation::part_data::gravity(m, &group.up, &root);
        let g = capture::root_placement::Gravity { targets: &gravity, up: &group.up };
        let placed = capture::root_placement::world_poses_from(&m.poses[0], &root, &m.displacements, m.n_frames(), Some(&g));
        let worst = placed
            .iter()
            .zip(&m.poses)
            .map(|(a, b)| (a.rotation.inverse() * b.rotation).angle().to_degrees())
            .fold(0.0, f64::max);
        let heading = |r: &nalgebra::Rotation3<f64>| {
            let f = r * nalgebra::Vector3::z();
            f.x.atan2(f.z).to_degrees()
        };
        eprintln!(
            "{}: worst rotation error {worst:.4} deg; last heading placed {:.1} capture {:.1}",
            seq.name,
            heading(&placed.last().unwrap().rotation),
            heading(&m.poses.last().unwrap().rotation)
        );
        assert!(worst < 1e-3, "{}: {worst} deg", seq.name);
    }
}
