//! The `check-set` binary on `fixtures/tiny-set` (whose frames are empty files): every
//! unreadable frame and a missing motion are listed, one line each as `check-set: file:
//! problem`, with exit status 1; a usage error exits 2.

use std::process::Command;

fn fixture() -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/tiny-set")
}

#[test]
fn every_problem_of_the_fixture_is_one_line() {
    let tmp = tempfile::tempdir().unwrap();
    let set = tmp.path().join("set");
    let status = Command::new("cp").arg("-r").arg(fixture()).arg(&set).status().unwrap();
    assert!(status.success());
    std::fs::remove_dir_all(set.join("A/spinkick")).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_check-set")).arg(&set).output().unwrap();
    assert_eq!(out.status.code(), Some(1));
    let text = String::from_utf8(out.stderr).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    // The fixture's frame files, less spinkick's 25: each empty file is unreadable.
    let frames = walk(&set).into_iter().filter(|p| p.extension().is_some_and(|e| e == "ply")).count();
    assert!(lines.iter().all(|l| l.starts_with("check-set: ")), "{text}");
    let unreadable = lines.iter().filter(|l| l.contains(".ply: ")).count();
    assert_eq!(unreadable, frames, "{text}");
    assert!(lines.iter().any(|l| l.contains("A/spinkick: test motion 'spinkick'")), "{text}");
    assert_eq!(lines.len(), frames + 1, "{text}");
    assert!(out.stdout.is_empty());

    let usage = Command::new(env!("CARGO_BIN_EXE_check-set")).output().unwrap();
    assert_eq!(usage.status.code(), Some(2));
}

fn walk(dir: &std::path::Path) -> Vec<std::path::PathBuf> {
    let mut out = Vec::new();
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() { out.extend(walk(&p)); } else { out.push(p); }
    }
    out
}
