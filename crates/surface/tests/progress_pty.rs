//! A stage's progress bar as a user sees it: drawn on a terminal (a real pty, through
//! util-linux `script`), absent on a pipe and with `-q` on a terminal. Driven with `correct`.
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
