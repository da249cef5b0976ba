//! The `synth` binary end to end (needs the fetched assets: run scripts/fetch-assets).

use std::path::Path;
use std::process::Command;

fn synth() -> Command {
    Command::new(env!("CARGO_BIN_EXE_synth"))
}

fn files(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else {
                out.push((
                    p.strip_prefix(dir).unwrap().display().to_string(),
                    std::fs::read(&p).unwrap(),
                ));
            }
        }
    }
    out.sort();
    out
}

#[test]
fn same_seed_gives_byte_identical_sets_whatever_the_threads() {
    let tmp = tempfile::tempdir().unwrap();
    let (a, b, c) = (
        tmp.path().join("a"),
        tmp.path().join("b"),
        tmp.path().join("c"),
    );
    for (dir, threads, seed) in [(&a, "1", "3"), (&b, "2", "3"), (&c, "2", "4")] {
        let st = synth()
            .args([
                "--preset",
                "tiny",
                "-q",
                "--threads",
                threads,
                "--seed",
                seed,
                "--out",
            ])
            .arg(dir)
            .status()
            .unwrap();
        assert!(
            st.success(),
            "synth failed (are the assets fetched? run scripts/fetch-assets)"
        );
    }
    let (fa, fb, fc) = (files(&a), files(&b), files(&c));
    assert!(fa.len() > 300, "too few files: {}", fa.len());
    assert!(fa == fb, "same seed, different bytes");
    assert!(fa != fc, "different seeds gave identical noise");
}

#[test]
fn bad_usage_and_unwritable_output_fail_with_one_line() {
    let st = synth().args(["--preset", "huge", "--out", "x"]).output().unwrap();
    assert_eq!(st.status.code(), Some(2));
    let tmp = tempfile::tempdir().unwrap();
    let f = tmp.path().join("file");
    std::fs::create_dir(&f).unwrap();
    std::fs::write(f.join("keep.txt"), b"precious").unwrap();
    let out = synth()
        .args(["--preset", "tiny", "-q", "--out"])
        .arg(&f)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    assert!(err.contains("not a capture set"), "{err}");
    assert!(f.join("keep.txt").is_file());
}
