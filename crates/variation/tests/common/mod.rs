//! What the stage-binary tests share: running a stage, and the tiny preset's locomotion model.
#![allow(dead_code)] // each test crate uses a part

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// Runs `bin` with `args` (one BLAS thread).
pub fn stage(bin: &str, args: &[&str]) -> Output {
    Command::new(bin).args(args).env("OPENBLAS_NUM_THREADS", "1").output().unwrap()
}

/// Runs `bin` with `args` and asserts that it succeeded.
pub fn ok(bin: &str, args: &[&str]) -> Output {
    let out = stage(bin, args);
    assert!(out.status.success(), "{bin} {args:?}: {}", String::from_utf8_lossy(&out.stderr));
    out
}

/// The tiny preset's walk and run prealigned (one pre-blend) and a GPDM trained on them, in `dir`.
pub fn tiny_model(dir: &Path) -> (PathBuf, PathBuf) {
    let set = dir.join("set");
    let cfg = synth::preset::preset("tiny", 0, true).unwrap();
    synth::capture_set_writer::synthesise(&cfg, &set, false, &|_| {}, &|| {}).unwrap();
    let (group, model) = (dir.join("locomotion.group"), dir.join("locomotion.model"));
    let s = |p: &Path| p.to_string_lossy().into_owned();
    ok(
        env!("CARGO_BIN_EXE_prealign"),
        &["-q", "--set", &s(&set), "--group-name", "locomotion", "--motions", "walk,run", "--blend-weights", "0.5", "--out", &s(&group)],
    );
    ok(env!("CARGO_BIN_EXE_gpdm-train"), &["-q", "--group", &s(&group), "--out", &s(&model)]);
    (group, model)
}
