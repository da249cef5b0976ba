//! `propose-curves` on the four game characters `make characters-data` builds (OpenArena's
//! sarge, sorceress, major and liz: a few hundred vertices in several pieces, open meshes,
//! props, a hat, a tail, hands held across the body). Needs the fetched OpenArena assets and the
//! `characters` binary beside `propose-curves` (`cargo build --release -p characters`); skipped,
//! saying why, without them.

use std::path::{Path, PathBuf};
use std::process::Command;

use mesh_core::capture_set::SubjectSpec;

fn assets() -> Option<PathBuf> {
    let cache = std::env::var_os("SURFCAP_CACHE").map(PathBuf::from).or_else(|| std::env::var_os("HOME").map(|h| Path::new(&h).join(".cache/surfcap")))?;
    Some(cache.join("assets/openarena")).filter(|p| p.join("sarge").is_dir() && p.join("liz").is_dir())
}

/// The extremities named on the `-v` line `extremities: head 12 (...), hand_l 811 (...), ...`.
fn extremities(stderr: &str) -> Vec<(String, u32)> {
    let line = stderr.lines().find(|l| l.contains("extremities:")).unwrap_or_else(|| panic!("{stderr}"));
    line.split("extremities: ").nth(1).unwrap().split("), ").map(|e| {
        let mut w = e.split(' ');
        (w.next().unwrap().to_string(), w.next().unwrap().parse().unwrap())
    }).collect()
}

#[test]
fn every_character_gets_a_limb_part_holding_each_hand_and_foot() {
    let bin = Path::new(env!("CARGO_BIN_EXE_propose-curves")).with_file_name("characters");
    let Some(assets) = assets() else {
        eprintln!("skipped: no OpenArena assets (scripts/fetch-assets)");
        return;
    };
    if !bin.exists() {
        eprintln!("skipped: {} is not built (cargo build --release -p characters)", bin.display());
        return;
    }
    let tmp = tempfile::tempdir().unwrap();
    let st = Command::new(&bin).arg("-q").arg("--assets").arg(&assets).arg("--out").arg(tmp.path()).output().unwrap();
    assert!(st.status.success(), "{}", String::from_utf8_lossy(&st.stderr));
    for subject in ["sarge-sorceress/sarge", "sarge-sorceress/sorceress", "major-liz/major", "major-liz/liz"] {
        let dir = tmp.path().join(subject);
        let (tpl, out) = (dir.join("walk/000000.ply"), dir.join("proposed.json"));
        let run = Command::new(env!("CARGO_BIN_EXE_propose-curves"))
            .arg(dir.join("subject.json")).arg("--template").arg(&tpl).arg("--out").arg(&out).arg("-v")
            .output().unwrap();
        let stderr = String::from_utf8_lossy(&run.stderr).to_string();
        assert!(run.status.success(), "{subject}: {stderr}");
        let mesh = mesh_core::io::read_mesh(&tpl).unwrap();
        let spec = SubjectSpec::load(&out).unwrap();
        let seg = mesh_core::segmentation::segment(&mesh, &spec).unwrap();
        seg.check().unwrap();
        let named = extremities(&stderr);
        let vertex = |n: &str| named.iter().find(|(m, _)| m == n).unwrap().1;
        let torso = seg.part("torso").unwrap();
        assert!(torso.vertices.binary_search(&vertex("head")).is_ok(), "{subject}: the torso does not hold the head");
        for (part, end) in [("arm_l", "hand_l"), ("arm_r", "hand_r"), ("leg_l", "foot_l"), ("leg_r", "foot_r")] {
            let p = seg.part(part).unwrap();
            assert!(p.vertices.binary_search(&vertex(end)).is_ok(), "{subject}: {part} does not hold {end}");
            assert!(p.vertices.binary_search(&vertex("head")).is_err(), "{subject}: {part} holds the head");
            for (other, e) in named.iter().filter(|(n, _)| n != end && n != "head") {
                assert!(p.vertices.binary_search(e).is_err(), "{subject}: {part} holds {other}");
            }
            assert!(p.vertices.len() < torso.vertices.len(), "{subject}: {part} is larger than the torso");
        }
    }
}
