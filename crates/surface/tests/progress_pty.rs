//! A stage's progress bar as a user sees it: drawn on a terminal (a real pty, through
//! util-linux `script`), absent on a pipe and with `-q` on a terminal. Driven with `correct`, and
//! with every other stage whose work grows with the capture, on the tiny preset (`synth`; needs
//! the synth assets, as `make test` does).
mod common;
use common::*;
use mesh_core::sequence::MeshSequence;
use std::process::Command;

/// Runs `shell_command` on a pseudo-terminal and returns everything written to it.
fn in_pty(shell_command: &str) -> String {
    let out = Command::new("script")
        .args(["-q", "-e", "-c", shell_command, "/dev/null"])
        .env("OPENBLAS_NUM_THREADS", "1")
        .output()
        .expect("util-linux `script` runs commands on a pty (apt-get install util-linux)");
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stdout));
    String::from_utf8_lossy(&out.stdout).into_owned()
}

#[test]
fn correct_shows_a_bar_on_a_terminal_only() {
    let dir = tempfile::tempdir().unwrap();
    let (rest, f) = tube(12, 15, 0.5, 0.1, true);
    let training: Vec<_> = (0..6).map(|k| bend(&rest, 0.3, 0.8, 0.3 * k as f64)).collect();
    MeshSequence::new(f.clone(), training).write_dir(dir.path().join("train")).unwrap();
    let preds: Vec<_> = (0..40).map(|k| bend(&rest, 0.3, 0.8, 0.04 * k as f64)).collect();
    MeshSequence::new(f, preds).write_dir(dir.path().join("pred")).unwrap();
    let p = |x: &str| dir.path().join(x).to_str().unwrap().to_string();
    let cmd = |extra: &str| {
        format!(
            "{} {extra} --training {} {} -o {}",
            env!("CARGO_BIN_EXE_correct"),
            p("train"),
            p("pred"),
            p("out")
        )
    };
    let tty = in_pty(&cmd(""));
    assert!(tty.contains("correct: frames [") && tty.contains("/40"), "no bar on the pty: {tty:?}");
    let quiet = in_pty(&cmd("-q"));
    assert!(quiet.trim().is_empty(), "-q on a pty: {quiet:?}");
    let piped = Command::new("sh").args(["-c", &cmd("")]).output().unwrap();
    assert!(piped.status.success());
    assert!(piped.stderr.is_empty(), "stderr on a pipe: {:?}", String::from_utf8_lossy(&piped.stderr));
    assert_eq!(MeshSequence::load_dir(dir.path().join("out")).unwrap().n_frames(), 40);
}

/// A stage binary of the workspace, next to this test's folder (`target/<profile>/deps/..`):
/// `cargo build --release --workspace` builds them all.
fn sibling(name: &str) -> String {
    let exe = std::env::current_exe().unwrap();
    let path = exe.parent().and_then(|d| d.parent()).unwrap().join(name);
    assert!(path.is_file(), "{} is missing: build the workspace first (cargo build --release --workspace)", path.display());
    path.to_string_lossy().into_owned()
}

/// The stages whose work grows with the capture (reading and writing frames, fitting parts,
/// time-aligning motions, measuring predictions) on the tiny preset, as one shell script
/// taking the extra flag as `$1`; each with the bar label it shows on a terminal.
fn stage_script(set: &str, work: &str) -> (String, Vec<&'static str>) {
    let b = |n: &str| sibling(n);
    let tpl = format!("{set}/B/walk/000000.ply");
    let lines = [
        format!("{} $1 {set}", b("check-set")),
        format!("{} $1 {set}/B/subject.json --template {tpl} --out {work}/parts.seg", b("segment")),
        format!("{} $1 --segmentation {work}/parts.seg --subject {set}/B/subject.json --template {tpl} {set}/B/walk --out {work}/walk.aligned", b("align")),
        format!("{} $1 --segmentation {work}/parts.seg --subject {set}/B/subject.json --template {tpl} {set}/B/run --out {work}/run.aligned", b("align")),
        format!("{} $1 --components 5 --template {tpl} --segmentation {work}/parts.seg {work}/walk.aligned {work}/run.aligned --out {work}/pca.model", b("pca-fit")),
        format!("{} $1 --set {set} --subject-name B --segmentation {work}/parts.seg --group-name loc --blend-weights 0.5 {work}/walk.aligned {work}/run.aligned --out {work}/loc.group", b("prealign")),
        format!("{} $1 {set}/B/walk --out {work}/objs", b("mesh-export")),
        format!("{} $1 {work}/objs --out {work}/imported", b("mesh-import")),
        format!("{} $1 --segmentation {work}/parts.seg --truth {set}/truth/B/punch {set}/truth/B/punch {set}/truth/B/punch --out {work}/quality.json", b("surface-quality")),
        format!("{} $1 --components 5 --template {tpl} --segmentation {work}/parts.seg --truth {set}/truth/B/punch {work}/walk.aligned {work}/run.aligned --out {work}/representation.json", b("representation-error")),
    ];
    let script = format!("set -e\n{}\n", lines.join("\n"));
    let labels = vec![
        "check-set: frames read [",
        "align: frames aligned [",
        "pca-fit: parts fitted [",
        "prealign: motions read, warped; blends [",
        "mesh-export: frames read [",
        "mesh-export: frames written [",
        "mesh-import: frames read [",
        "mesh-import: frames written [",
        "surface-quality: predictions [",
        "representation-error: reconstructions [",
    ];
    (script, labels)
}

#[test]
fn every_long_stage_shows_a_bar_on_a_terminal_only() {
    let dir = tempfile::tempdir().unwrap();
    let p = |x: &str| dir.path().join(x).to_str().unwrap().to_string();
    let synth = Command::new(sibling("synth")).args(["-q", "--preset", "tiny", "--out"]).arg(p("set")).output().unwrap();
    assert!(synth.status.success(), "synth (are the assets fetched? scripts/fetch-assets): {}", String::from_utf8_lossy(&synth.stderr));
    std::fs::create_dir(p("work")).unwrap();
    let (script, labels) = stage_script(&p("set"), &p("work"));
    std::fs::write(p("stages.sh"), script).unwrap();
    let tty = in_pty(&format!("sh {} ''", p("stages.sh")));
    for label in &labels {
        // The label, the bar, then `pos/len` with len > 0.
        let shown = tty.match_indices(label).any(|(i, m)| {
            let rest = &tty[i + m.len()..];
            rest.find(']').and_then(|j| rest[j + 1..].split_whitespace().next()).is_some_and(|counts| {
                counts.split_once('/').is_some_and(|(a, b)| a.parse::<u64>().is_ok() && b.parse::<u64>().is_ok_and(|n| n > 0))
            })
        });
        assert!(shown, "no bar with counts for {label:?} on the pty");
    }
    let quiet = in_pty(&format!("sh {} -q", p("stages.sh")));
    assert!(quiet.trim().is_empty(), "-q on a pty: {quiet:?}");
    let piped = Command::new("sh").arg(p("stages.sh")).arg("").output().unwrap();
    assert!(piped.status.success(), "{}", String::from_utf8_lossy(&piped.stderr));
    assert!(piped.stderr.is_empty(), "stderr on a pipe: {:?}", String::from_utf8_lossy(&piped.stderr));
    // The work was done: the imported frames are the exported walk.
    let walk = MeshSequence::load_dir(p("set/B/walk")).unwrap();
    let back = MeshSequence::load_dir(p("work/imported")).unwrap();
    assert_eq!(back.n_frames(), walk.n_frames());
}
