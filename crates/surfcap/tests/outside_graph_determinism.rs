//! Same inputs, same bytes, for the stages that the pipelines' task graph does not run (those are
//! covered by `scripts/slurm-test`, which runs the graph with 1 and 2 threads, quiet and verbose):
//! `synth`, `mesh-import`, `mesh-export` (.glb, .pc2 and a frame folder), `render`,
//! `propose-curves` and `html-report`, each run once with `-q --threads 1` and once with
//! `-v --threads 2`, their whole outputs compared byte for byte.
//!
//! Needs the synth assets (`make assets`) and the report's web tools (`make setup-web`), as
//! `make test` provides; the stage binaries are the workspace's release build.

use std::path::{Path, PathBuf};
use std::process::Command;

/// A stage binary next to this test's folder (`target/<profile>/deps/..`).
fn bin(name: &str) -> PathBuf {
    let exe = std::env::current_exe().unwrap();
    let path = exe.parent().and_then(|d| d.parent()).unwrap().join(name);
    assert!(path.is_file(), "{} is missing: build the workspace first (cargo build --release --workspace)", path.display());
    path
}

/// The two invocations compared: quiet on one thread, verbose on two.
const RUNS: [[&str; 3]; 2] = [["-q", "--threads", "1"], ["-v", "--threads", "2"]];

fn run(stage: &str, flags: &[&str], args: &[&str], out: &Path) {
    let output = Command::new(bin(stage))
        .args(flags)
        .args(args)
        .arg("--out")
        .arg(out)
        .env("OPENBLAS_NUM_THREADS", "1")
        .env_remove("SURFCAP_VERBOSE")
        .env_remove("RAYON_NUM_THREADS")
        .output()
        .unwrap();
    assert!(output.status.success(), "{stage} {flags:?} {args:?} failed: {}", String::from_utf8_lossy(&output.stderr));
}

/// Every file under `path` (or `path` itself), as (relative path, bytes), sorted.
fn files(path: &Path) -> Vec<(PathBuf, Vec<u8>)> {
    let mut out = Vec::new();
    let mut stack = vec![path.to_path_buf()];
    while let Some(p) = stack.pop() {
        if p.is_dir() {
            stack.extend(std::fs::read_dir(&p).unwrap().map(|e| e.unwrap().path()));
        } else {
            out.push((p.strip_prefix(path).unwrap().to_path_buf(), std::fs::read(&p).unwrap()));
        }
    }
    out.sort();
    out
}

/// Runs `stage` both ways into `dir/<run>/<out_name>` and requires the same files and bytes.
fn same_bytes_both_ways(dir: &Path, stage: &str, args: &[&str], out_name: &str) {
    let outputs: Vec<PathBuf> = RUNS
        .iter()
        .enumerate()
        .map(|(k, flags)| {
            let run_dir = dir.join(format!("{stage}-{k}"));
            std::fs::create_dir_all(&run_dir).unwrap();
            let out = run_dir.join(out_name);
            if stage == "html-report" {
                // It reports on a pipeline's output folder, which must exist.
                std::fs::create_dir_all(&out).unwrap();
            }
            run(stage, flags, args, &out);
            // The whole run folder is compared: some outputs write a sibling (the .pc2's template OBJ).
            run_dir
        })
        .collect();
    let (a, b) = (files(&outputs[0]), files(&outputs[1]));
    assert!(!a.is_empty(), "{stage} wrote nothing");
    let names = |v: &[(PathBuf, Vec<u8>)]| v.iter().map(|(p, _)| p.clone()).collect::<Vec<_>>();
    assert_eq!(names(&a), names(&b), "{stage}: other files for {:?} and {:?}", RUNS[0], RUNS[1]);
    for ((name, x), (_, y)) in a.iter().zip(&b) {
        assert!(x == y, "{stage}: {} differs between {:?} and {:?}", name.display(), RUNS[0], RUNS[1]);
    }
}

#[test]
fn stages_outside_the_task_graph_write_the_same_bytes_for_any_threads_and_verbosity() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    same_bytes_both_ways(dir, "synth", &["--preset", "tiny"], "set");
    let set = dir.join("synth-0/set");
    let walk = set.join("A/walk");
    let walk = walk.to_str().unwrap();
    same_bytes_both_ways(dir, "mesh-import", &[walk], "walk");
    for out in ["walk.glb", "walk.pc2", "walk"] {
        same_bytes_both_ways(&dir.join(out), "mesh-export", &[walk], out);
    }
    same_bytes_both_ways(dir, "render", &[walk, "--size", "96", "--frames", "0:6", "--contact-columns", "3"], "render");

    let mut subject: serde_json::Value =
        serde_json::from_slice(&std::fs::read(set.join("A/subject.json")).unwrap()).unwrap();
    subject.as_object_mut().unwrap().remove("curves");
    subject.as_object_mut().unwrap().remove("parts");
    let bare = dir.join("subject.json");
    std::fs::write(&bare, subject.to_string()).unwrap();
    let template = format!("{walk}/000000.ply");
    same_bytes_both_ways(dir, "propose-curves", &[bare.to_str().unwrap(), "--template", &template], "subject.json");

    let view = format!("walk={walk}");
    same_bytes_both_ways(dir, "html-report", &["--view", &view], "report");
}
