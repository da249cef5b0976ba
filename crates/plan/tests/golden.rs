//! Golden files of the plan on the tiny preset's description (`fixtures/tiny-set`: set.json,
//! subject.json and empty frame files named as `synth --preset tiny` writes them): the make
//! fragment and the Slurm arrays (kinds, task counts, dependencies, resources, targets).
//! `UPDATE_GOLDEN=1 cargo test --release -p plan --test golden` rewrites them after a reviewed
//! change of the pipelines.

use std::path::{Path, PathBuf};
use std::process::Command;

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..").canonicalize().unwrap()
}

fn check(golden: &str, text: &str) {
    let path = repo().join("fixtures/plan").join(golden);
    if std::env::var_os("UPDATE_GOLDEN").is_some() {
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(&path, text).unwrap();
        return;
    }
    let want = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    if want != text {
        let line = want.lines().zip(text.lines()).position(|(a, b)| a != b).unwrap_or(0);
        panic!(
            "{} differs from the plan at line {}:\n golden: {}\n   plan: {}",
            path.display(),
            line + 1,
            want.lines().nth(line).unwrap_or(""),
            text.lines().nth(line).unwrap_or("")
        );
    }
}

fn plan(args: &[&str]) -> std::process::Output {
    let out = Command::new(env!("CARGO_BIN_EXE_plan"))
        .current_dir(repo())
        .args(args)
        .output()
        .unwrap();
    assert!(out.status.success(), "plan {args:?}: {}", String::from_utf8_lossy(&out.stderr));
    out
}

#[test]
fn make_fragment_of_the_tiny_set() {
    let dir = tempfile::tempdir().unwrap();
    let frag = dir.path().join("plan.mk");
    plan(&["make", "--set", "fixtures/tiny-set", "--pipeline-out", "out", "--out", frag.to_str().unwrap()]);
    check("tiny-set.plan.mk", &std::fs::read_to_string(&frag).unwrap());
}

#[test]
fn slurm_arrays_of_the_tiny_set() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("slurm-run");
    plan(&[
        "slurm", "--set", "fixtures/tiny-set", "--pipeline-out", "out", "--bin", "/opt/surfcap/bin",
        "--workdir", "/work/surfcap", "--out", out.to_str().unwrap(),
    ]);
    // One summary line per array (in submission order) and its tasks' targets, with the
    // temporary directory replaced so the golden file does not depend on it.
    let tmp = out.to_str().unwrap();
    let run = std::fs::read_to_string(out.join("run.sbatch")).unwrap().replace(tmp, "OUT");
    let mut text = run.clone();
    for line in run.lines().filter(|l| l.contains("=$(sbatch")) {
        let kind = line.split('=').next().unwrap().replace('_', "-");
        let script = std::fs::read_to_string(out.join("slurm").join(format!("{kind}.sbatch"))).unwrap();
        text.push_str(&format!("\n== {kind}.sbatch\n{}", script.replace(tmp, "OUT")));
        let table = std::fs::read_to_string(out.join("slurm").join(format!("{kind}.tasks"))).unwrap();
        for (i, row) in table.lines().enumerate() {
            let task: plan::task::Task = serde_json::from_str(row).unwrap();
            assert_eq!(task.kind, kind);
            text.push_str(&format!("{i} {}\n", task.target));
        }
        assert!(out.join("slurm/logs").join(&kind).is_dir(), "no log directory for {kind}");
    }
    check("tiny-set.slurm.txt", &text);
}

/// Every input of every task is either a file of the capture set or the target of another task,
/// and no two tasks write the same target: the graph is closed and make/Slurm can order it.
#[test]
fn graph_is_closed_and_targets_unique() {
    let root = repo();
    let set = root.join("fixtures/tiny-set");
    let opts = plan::options::PipelineOptions {
        paths: plan::options::Paths { set: set.clone(), pipeline_out: "out".into() },
        transfer: parse_default_transfer(),
        variation: parse_default_variation(),
    };
    let g = plan::stage::graph(&opts).unwrap();
    let mut targets: Vec<&str> = g.tasks.iter().map(|t| t.target.as_str()).collect();
    targets.sort();
    let n = targets.len();
    targets.dedup();
    assert_eq!(targets.len(), n, "two tasks write the same target");
    for t in &g.tasks {
        for i in &t.inputs {
            let from_set = Path::new(i).starts_with(&set);
            assert!(from_set || targets.binary_search(&i.as_str()).is_ok(), "{}: input {i} has no producer", t.target);
        }
    }
    // Slurm needs the kinds in an order where each array only reads earlier ones.
    let arrays = plan::slurm::arrays(&g).unwrap();
    for (k, (kind, _, deps)) in arrays.iter().enumerate() {
        for d in deps {
            assert!(arrays[..k].iter().any(|(e, _, _)| e == d), "{kind} submitted before {d}");
        }
    }
}

#[derive(clap::Parser)]
struct T {
    #[command(flatten)]
    t: plan::options::TransferOptions,
    #[command(flatten)]
    v: plan::options::VariationOptions,
}

fn parse_default_transfer() -> plan::options::TransferOptions {
    <T as clap::Parser>::parse_from(["t"]).t
}
fn parse_default_variation() -> plan::options::VariationOptions {
    <T as clap::Parser>::parse_from(["t"]).v
}
