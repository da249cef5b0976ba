//! `surfcap` against the workspace itself: `surfcap help` lists exactly the stage binaries
//! built beside it (the bin targets `cargo metadata` reports: none missing, none stale), every
//! `surfcap <stage> --help` reaches the stage, an unknown command says how to list them, and
//! `surfcap man` / `surfcap completions` write a man page and bash/zsh/fish completions for
//! every stage (bash completions checked by `bash -n`).

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use mesh_core::clap_docs::Kind;
use surfcap::stages::STAGES;

fn surfcap(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_surfcap")).args(args).output().unwrap()
}

fn bin_dir() -> PathBuf {
    Path::new(env!("CARGO_BIN_EXE_surfcap")).parent().unwrap().to_path_buf()
}

/// Every bin target of the workspace but `surfcap` and the studies crate's, from `cargo metadata`.
fn workspace_bins() -> BTreeSet<String> {
    let out = Command::new(env!("CARGO"))
        .args(["metadata", "--no-deps", "--format-version", "1", "--offline"])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let mut bins = BTreeSet::new();
    // The studies crate's binaries are research programs, not stages.
    for p in v["packages"].as_array().unwrap().iter().filter(|p| p["name"] != "studies") {
        for t in p["targets"].as_array().unwrap() {
            if t["kind"].as_array().unwrap().iter().any(|k| k == "bin") && t["name"] != "surfcap" {
                bins.insert(t["name"].as_str().unwrap().to_string());
            }
        }
    }
    bins
}

#[test]
fn help_lists_every_stage_binary_in_pipeline_order() {
    let bins = workspace_bins();
    let table: BTreeSet<String> = STAGES.iter().map(|s| s.bin.to_string()).collect();
    assert_eq!(table, bins, "the stage table and the workspace's binaries differ");
    let out = surfcap(&["help"]);
    assert!(out.status.success());
    let text = String::from_utf8(out.stdout).unwrap();
    // Listed: the stages whose binary is built beside surfcap (all of them after a workspace build).
    let listed: Vec<&str> = text
        .lines()
        .filter(|l| l.starts_with("    ") && !l[4..].starts_with(' '))
        .map(|l| l.split_whitespace().next().unwrap())
        .collect();
    let built: Vec<&str> = STAGES.iter().filter(|s| bin_dir().join(s.bin).is_file()).map(|s| s.name).collect();
    assert_eq!(listed, built);
    assert_eq!(built.len(), bins.len(), "every workspace binary is built: {text}");
    // Pipeline order: capture sets before transfer before results.
    let pos = |n: &str| listed.iter().position(|l| *l == n).unwrap();
    assert!(pos("synth") < pos("check-set") && pos("check-set") < pos("segment"));
    assert!(pos("segment") < pos("gpr-train") && pos("gpr-train") < pos("gpr-predict"));
    assert!(pos("gpdm-train") < pos("hmc-sample"));
    assert_eq!(surfcap(&[]).stdout, text.as_bytes(), "no command lists them too");
}

#[test]
fn every_stage_answers_help_through_surfcap() {
    for s in STAGES {
        let out = surfcap(&[s.name, "--help"]);
        assert_eq!(out.status.code(), Some(0), "{}", s.name);
        let text = String::from_utf8(out.stdout).unwrap();
        assert!(text.contains("Usage:") && text.contains("e.g.:"), "{}: {text}", s.name);
        let help = surfcap(&["help", s.name]);
        assert_eq!(help.stdout, text.as_bytes(), "{}", s.name);
    }
    // Arguments pass through, and so does the exit status (a usage error is 2).
    let out = surfcap(&["check-set"]);
    assert_eq!(out.status.code(), Some(2));
}

#[test]
fn an_unknown_command_says_how_to_list_them() {
    let out = surfcap(&["gpr-trian"]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8(out.stderr).unwrap();
    assert_eq!(err.trim_end(), "surfcap: 'gpr-trian' is not a surfcap command; 'surfcap help' lists them");
}

#[test]
fn man_pages_and_completions_are_written_for_every_stage() {
    let dir = tempfile::tempdir().unwrap();
    let man = dir.path().join("man");
    let out = surfcap(&["man", "--out", man.to_str().unwrap()]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let comp = dir.path().join("completions");
    let out = surfcap(&["completions", "--out", comp.to_str().unwrap()]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let names: Vec<&str> = STAGES.iter().map(|s| s.bin).chain(["surfcap"]).collect();
    for n in &names {
        let page = std::fs::read_to_string(man.join(format!("man1/{n}.1"))).unwrap();
        assert!(page.contains(".TH") && page.contains(".SH SYNOPSIS"), "{n}");
        let files = mesh_core::clap_docs::files(Kind::Completions, n);
        assert_eq!(files.len(), 3);
        for f in &files {
            let text = std::fs::read_to_string(comp.join(f)).unwrap_or_else(|e| panic!("{}: {e}", f.display()));
            assert!(text.len() > 100 && text.contains(n), "{}", f.display());
        }
        let st = Command::new("bash").arg("-n").arg(comp.join(&files[0])).status().unwrap();
        assert!(st.success(), "bash -n {n}");
    }
    // surfcap's own completion offers the stage names.
    let own = std::fs::read_to_string(comp.join(&mesh_core::clap_docs::files(Kind::Completions, "surfcap")[0])).unwrap();
    assert!(STAGES.iter().all(|s| own.contains(s.name)));
    assert_eq!(std::fs::read_dir(man.join("man1")).unwrap().count(), names.len(), "no stray pages");
}
