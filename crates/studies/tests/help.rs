//! Every study program parses its command line with clap: `--help` prints what it does and
//! its flags and exits 0 without running the study, and an unknown flag is a usage error.

use std::path::PathBuf;
use std::process::Command;

/// The study binaries, by their source files in `src/bin`, and the directory cargo built them in
/// (the parent of this test's `deps` directory).
fn programs() -> (Vec<String>, PathBuf) {
    let src = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("src/bin");
    let mut names: Vec<String> = std::fs::read_dir(&src)
        .unwrap()
        .filter_map(|e| e.ok()?.file_name().to_str()?.strip_suffix(".rs").map(str::to_string))
        .collect();
    names.sort();
    let exe = std::env::current_exe().unwrap();
    let dir = exe.parent().and_then(|d| d.parent()).unwrap().to_path_buf();
    (names, dir)
}

#[test]
fn every_study_program_answers_help_and_refuses_an_unknown_flag() {
    let (names, dir) = programs();
    assert!(names.len() >= 20, "{} study programs found", names.len());
    for name in &names {
        let bin = dir.join(name);
        assert!(bin.exists(), "{} not built", bin.display());
        let help = Command::new(&bin).arg("--help").output().unwrap();
        let text = String::from_utf8_lossy(&help.stdout);
        assert!(help.status.success(), "{name} --help: {:?}", help.status);
        assert!(text.contains("Usage:"), "{name} --help prints no usage:\n{text}");
        let bad = Command::new(&bin).arg("--no-such-flag").output().unwrap();
        assert_eq!(bad.status.code(), Some(2), "{name} --no-such-flag: {:?}", bad.status);
    }
}
