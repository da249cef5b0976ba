//! End-to-end: the `inspect` binary on good, corrupt and missing files.

use std::path::Path;
use std::process::{Command, Output};

use mesh_core::artifact::{write_artifact, Header};

fn inspect(args: &[&Path]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_inspect"))
        .args(args)
        .output()
        .unwrap()
}

fn good(dir: &Path) -> std::path::PathBuf {
    let p = dir.join("model.art");
    let header = Header::new("fit", "0.1.0")
        .with_command_line(["fit", "--seed", "5"])
        .with_params(&serde_json::json!({"m": 20}))
        .unwrap()
        .with_seed(5);
    write_artifact(&p, "pca-model", 2, &header, &vec![1.0f64; 100]).unwrap();
    p
}

#[test]
fn prints_the_header_of_a_good_file() {
    let dir = tempfile::tempdir().unwrap();
    let p = good(dir.path());
    let out = inspect(&[&p]);
    assert_eq!(out.status.code(), Some(0));
    assert!(
        out.stderr.is_empty(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["file"], p.display().to_string());
    assert_eq!(v["kind"], "pca-model");
    assert_eq!(v["kind_version"], 2);
    assert_eq!(v["header"]["producer"]["stage"], "fit");
    assert_eq!(v["header"]["params"]["m"], 20);
    assert_eq!(v["header"]["seed"], 5);
    // bincode standard(): one length byte (100) + 100 f64.
    assert_eq!(v["payload_bytes"], 801);
}

#[test]
fn corrupt_file_gives_one_line_and_exit_1() {
    let dir = tempfile::tempdir().unwrap();
    let p = good(dir.path());
    let mut bytes = std::fs::read(&p).unwrap();
    let n = bytes.len();
    bytes[n - 100] ^= 1;
    std::fs::write(&p, &bytes).unwrap();
    let out = inspect(&[&p]);
    assert_eq!(out.status.code(), Some(1));
    assert!(out.stdout.is_empty());
    assert_eq!(
        String::from_utf8(out.stderr).unwrap(),
        format!(
            "inspect: {}: checksum mismatch (file corrupt)\n",
            p.display()
        )
    );
}

#[test]
fn good_and_bad_files_together() {
    let dir = tempfile::tempdir().unwrap();
    let p = good(dir.path());
    let missing = dir.path().join("missing.art");
    let out = inspect(&[&missing, &p]);
    assert_eq!(out.status.code(), Some(1));
    let stderr = String::from_utf8(out.stderr).unwrap();
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(
        stderr.starts_with(&format!("inspect: {}: ", missing.display())),
        "{stderr}"
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["kind"], "pca-model");
}

#[test]
fn usage_errors_exit_2_and_help_shows_an_example() {
    let out = Command::new(env!("CARGO_BIN_EXE_inspect"))
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let out = Command::new(env!("CARGO_BIN_EXE_inspect"))
        .arg("--bogus")
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let out = Command::new(env!("CARGO_BIN_EXE_inspect"))
        .arg("--help")
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0));
    assert!(String::from_utf8_lossy(&out.stdout).contains("e.g.: inspect "));
}
