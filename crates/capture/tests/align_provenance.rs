//! `align` on a small written motion: the aligned motion carries the subject's frame rate, up
//! axis and template hash, and the header lists every input file with its SHA-256 (computed
//! here independently) and every parameter under its flag's name, defaults included (the
//! stage's `Params` is the record). The other stages' headers are checked in
//! `transfer/tests/provenance.rs`.

use std::path::{Path, PathBuf};
use std::process::Command;

use capture::align::AlignedMotion;
use mesh_core::artifact::{read_header, Artifact};
use sha2::{Digest, Sha256};

fn sha256(path: &Path) -> String {
    Sha256::digest(std::fs::read(path).unwrap()).iter().map(|b| format!("{b:02x}")).collect()
}

fn run(bin: &str, args: &[&Path]) {
    let out = Command::new(bin).args(args).output().unwrap();
    assert!(out.status.success(), "{bin}: {}", String::from_utf8_lossy(&out.stderr));
}

fn recorded(artifact: &Path) -> Vec<(String, String)> {
    let (_, _, header) = read_header(artifact).unwrap();
    header.inputs.into_iter().map(|r| (r.path, r.sha256)).collect()
}

#[test]
fn align_records_the_capture_and_every_input() {
    let dir = tempfile::tempdir().unwrap();
    let (mesh, _) = mesh_core::shapes::capsule_body(30, 12, 0.15, 1.6);
    let frames: Vec<_> = (0..4)
        .map(|i| mesh.vertices.iter().map(|v| v + nalgebra::Vector3::new(0.0, 0.0, 0.1 * i as f64)).collect())
        .collect();
    let motion = dir.path().join("S/walk");
    mesh_core::sequence::MeshSequence::new(mesh.faces.clone(), frames).write_dir(&motion).unwrap();
    let subject = dir.path().join("S/subject.json");
    std::fs::write(&subject, r#"{"fps": 30, "up": "-z", "parts": {"torso": null}, "curves": {}}"#).unwrap();
    let template = motion.join("000000.ply");
    let out = dir.path().join("walk.aligned");
    let p = Path::new;
    run(
        env!("CARGO_BIN_EXE_align"),
        &[p("--frame"), p("body"), p("--subject"), &subject, p("--template"), &template, &motion, p("--out"), &out],
    );
    let m = AlignedMotion::load(&out).unwrap();
    assert_eq!(m.capture.fps, 30.0);
    assert_eq!(m.capture.up, [0.0, 0.0, -1.0]);
    assert_eq!(m.capture.template_sha256, sha256(&template));

    let mut given: Vec<PathBuf> = std::fs::read_dir(&motion).unwrap().map(|e| e.unwrap().path()).collect();
    given.sort();
    assert_eq!(given.len(), 4);
    given.extend([subject.clone(), template.clone()]);
    let inputs = recorded(&out);
    for f in &given {
        let want = (f.display().to_string(), sha256(f));
        assert!(inputs.contains(&want), "{} not recorded with its hash", f.display());
    }
    assert_eq!(inputs.len(), given.len(), "subject, template and the four frames (frame 0 is the template)");

    // Every parameter, as given on the command line or defaulted, and nothing else.
    let (_, _, header) = read_header(&out).unwrap();
    let s = |x: &Path| serde_json::Value::from(x.display().to_string());
    let want = serde_json::json!({
        "subject": s(&subject), "template": s(&template), "frame": "body", "segmentation": null,
        "motion": s(&motion), "out": s(&out),
    });
    assert_eq!(header.params, want);
    // The same names as the flags: every non-null parameter is a flag or the positional MOTION.
    let help = Command::new(env!("CARGO_BIN_EXE_align")).arg("--help").output().unwrap();
    let help = String::from_utf8(help.stdout).unwrap();
    for key in header.params.as_object().unwrap().keys().filter(|k| *k != "motion") {
        assert!(help.contains(&format!("--{}", key.replace('_', "-"))), "{key} is not a flag of align");
    }
}
