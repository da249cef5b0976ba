//! What the stage-binary tests share: running a stage, the tiny preset's capture set and its locomotion model.
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

/// The front end of subject `x`'s `motions` in `set`, as the pipelines run it (`segment`, then
/// `align` of each motion on the root part's core) into `dir`: prealign's arguments, the
/// segmentation and the aligned motions (`--segmentation <seg> <dir>/<motion>.aligned ...`).
pub fn front_end(set: &Path, x: &str, motions: &[&str], dir: &Path) -> Vec<String> {
    use clap::Parser;
    let s = |p: &Path| p.to_string_lossy().into_owned();
    let json = set.join(x).join("subject.json");
    let spec = mesh_core::capture_set::SubjectSpec::load(&json).unwrap();
    let template = mesh_core::capture_set::CaptureSet::open(set).unwrap().template_path(x, &spec).unwrap();
    let seg = dir.join(format!("{x}-parts.seg"));
    let p = capture::stage::segment::Params::try_parse_from(["segment", "-q", &s(&json), "--template", &s(&template), "--out", &s(&seg)]).unwrap();
    capture::stage::segment::run(&p).unwrap();
    let mut args = vec!["--segmentation".to_string(), s(&seg)];
    for m in motions {
        let out = dir.join(format!("{x}-{m}")).join(format!("{m}.aligned"));
        std::fs::create_dir_all(out.parent().unwrap()).unwrap();
        let p = capture::stage::align::Params::try_parse_from([
            "align", "-q", "--subject", &s(&json), "--template", &s(&template), "--segmentation", &s(&seg), &s(&set.join(x).join(m)), "--out", &s(&out),
        ])
        .unwrap();
        capture::stage::align::run(&p).unwrap();
        args.push(s(&out));
    }
    args
}

/// The tiny preset's capture set (seed 0), synthesised into `dir/set`.
pub fn tiny_set(dir: &Path) -> PathBuf {
    let set = dir.join("set");
    let cfg = synth::preset::preset("tiny", 0, true).unwrap();
    synth::capture_set_writer::synthesise(&cfg, &set, false, &|_| {}, &|| {}).unwrap();
    set
}

/// The tiny preset's walk and run prealigned (one pre-blend) and a GPDM trained on them, in `dir`.
pub fn tiny_model(dir: &Path) -> (PathBuf, PathBuf) {
    let set = tiny_set(dir);
    let (group, model) = (dir.join("locomotion.group"), dir.join("locomotion.model"));
    let s = |p: &Path| p.to_string_lossy().into_owned();
    let mut args: Vec<String> = ["-q", "--set", &s(&set), "--group-name", "locomotion", "--blend-weights", "0.5", "--out", &s(&group)].map(String::from).to_vec();
    args.extend(front_end(&set, "A", &["walk", "run"], dir));
    ok(env!("CARGO_BIN_EXE_prealign"), &args.iter().map(String::as_str).collect::<Vec<_>>());
    ok(env!("CARGO_BIN_EXE_gpdm-train"), &["-q", "--group", &s(&group), "--out", &s(&model)]);
    (group, model)
}
