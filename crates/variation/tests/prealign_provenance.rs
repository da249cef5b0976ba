//! `prealign` on the tiny preset: the group's header lists set.json, the subject's
//! subject.json and template and every frame of the grouped motions, each with its SHA-256
//! (computed here independently), and every parameter given.

use std::path::{Path, PathBuf};
use std::process::Command;

use mesh_core::artifact::read_header;
use sha2::{Digest, Sha256};

fn sha256(path: &Path) -> String {
    Sha256::digest(std::fs::read(path).unwrap()).iter().map(|b| format!("{b:02x}")).collect()
}

#[test]
fn prealign_records_every_input_file_and_parameter() {
    let dir = tempfile::tempdir().unwrap();
    let set = dir.path().join("set");
    let cfg = synth::preset::preset("tiny", 0, true).unwrap();
    synth::capture_set_writer::synthesise(&cfg, &set, false, &|_| {}, &|| {}).unwrap();
    let out = dir.path().join("loco.group");
    let st = Command::new(env!("CARGO_BIN_EXE_prealign"))
        .args(["-q", "--set"])
        .arg(&set)
        .args(["--group-name", "loco", "--motions", "walk,run", "--blend-weights", "0.25,0.75", "--out"])
        .arg(&out)
        .env("OPENBLAS_NUM_THREADS", "1")
        .output()
        .unwrap();
    assert!(st.status.success(), "{}", String::from_utf8_lossy(&st.stderr));
    let (_, _, header) = read_header(&out).unwrap();
    let mut given: Vec<PathBuf> = vec![set.join("set.json"), set.join("A/subject.json")];
    for m in ["walk", "run"] {
        let mut frames: Vec<PathBuf> = std::fs::read_dir(set.join("A").join(m)).unwrap().map(|e| e.unwrap().path()).collect();
        frames.sort();
        assert!(frames.len() > 5);
        given.extend(frames);
    }
    for f in &given {
        let rec = header.inputs.iter().find(|r| Path::new(&r.path) == f.as_path());
        let rec = rec.unwrap_or_else(|| panic!("{} not recorded", f.display()));
        assert_eq!(rec.sha256, sha256(f), "{}", f.display());
    }
    assert_eq!(header.params["group"], "loco");
    assert_eq!(header.params["motions"], serde_json::json!(["walk", "run"]));
    assert_eq!(header.params["blend_weights"], serde_json::json!([0.25, 0.75]));
    assert_eq!(header.params["gait_cycles"], false);
    assert_eq!(header.params["subject"], "A");
}
