//! `plan run-task` as a scheduler's array task runs it: up-to-date tasks are skipped, stale or
//! missing ones run, a failing stage fails the task with the stage's one-line error, and the
//! variation contact sheets are drawn per sequence in sorted order.

use std::path::Path;
use std::process::Command;

use plan::task::{Step, Task};
use plan::task_table::{read_task, up_to_date, write_table};

fn touch_later(path: &Path, secs: u64) {
    let t = std::time::SystemTime::now() + std::time::Duration::from_secs(secs);
    std::fs::File::options().write(true).open(path).unwrap().set_modified(t).unwrap();
}

/// A fake stage directory: `stage` appends its arguments to a log and writes its `--out`.
fn fake_bins(dir: &Path) {
    let body = "#!/bin/sh\necho \"$(basename $0) $*\" >> \"$LOG\"\nwhile [ $# -gt 0 ]; do [ \"$1\" = --out ] && { mkdir -p \"$(dirname \"$2\")\"; echo made > \"$2\"; }; shift; done\n";
    for b in ["stage", "render"] {
        let p = dir.join(b);
        std::fs::write(&p, body).unwrap();
        Command::new("chmod").arg("+x").arg(&p).status().unwrap();
    }
    let fail = dir.join("broken");
    std::fs::write(&fail, "#!/bin/sh\necho 'broken: in.txt: not a mesh' >&2\nexit 1\n").unwrap();
    Command::new("chmod").arg("+x").arg(&fail).status().unwrap();
}

fn run(bin: &Path, table: &Path, i: usize, log: &Path) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_plan"))
        .args(["run-task", "--bin", bin.to_str().unwrap(), "--table", table.to_str().unwrap(), "--task", &i.to_string()])
        .env("LOG", log)
        .output()
        .unwrap()
}

#[test]
fn skips_complete_tasks_runs_stale_ones_and_fails_with_the_stage_error() {
    let d = tempfile::tempdir().unwrap();
    let bin = d.path().join("bin");
    std::fs::create_dir(&bin).unwrap();
    fake_bins(&bin);
    let input = d.path().join("in.txt");
    std::fs::write(&input, "x").unwrap();
    let target = d.path().join("o/out.txt");
    let s = |p: &Path| p.to_str().unwrap().to_string();
    let tasks = [
        Task::run("stage", s(&target), vec![s(&input)], vec!["--out".into(), s(&target)]).mkdir_target(),
        Task::run("broken", s(&d.path().join("never")), vec![s(&input)], vec![]),
    ];
    let table = d.path().join("stage.tasks");
    std::fs::write(&table, write_table(&tasks.iter().collect::<Vec<_>>()).unwrap()).unwrap();
    assert_eq!(read_task(&table, 0).unwrap(), tasks[0]);
    assert!(read_task(&table, 2).is_err());
    let log = d.path().join("log");

    assert!(run(&bin, &table, 0, &log).status.success());
    assert_eq!(std::fs::read_to_string(&log).unwrap().lines().count(), 1);
    // Complete: skipped on re-submission.
    touch_later(&target, 5);
    assert!(up_to_date(&tasks[0], &bin));
    assert!(run(&bin, &table, 0, &log).status.success());
    assert_eq!(std::fs::read_to_string(&log).unwrap().lines().count(), 1, "an up-to-date task ran");
    // An input newer than the target: runs again.
    touch_later(&input, 10);
    assert!(!up_to_date(&tasks[0], &bin));
    assert!(run(&bin, &table, 0, &log).status.success());
    assert_eq!(std::fs::read_to_string(&log).unwrap().lines().count(), 2);
    // A failing stage: non-zero exit, its one-line error in the task's output, no target.
    let out = run(&bin, &table, 1, &log);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("broken: in.txt: not a mesh"), "{err}");
    assert!(!d.path().join("never").exists());
}

#[test]
fn variation_sheets_per_sequence_in_order() {
    let d = tempfile::tempdir().unwrap();
    let bin = d.path().join("bin");
    std::fs::create_dir(&bin).unwrap();
    fake_bins(&bin);
    let var = d.path().join("v/g");
    for seq in ["walk", "blend-0.5", "run"] {
        for k in ["var1", "var0"] {
            std::fs::create_dir_all(var.join(seq).join(k)).unwrap();
        }
    }
    let stamp = d.path().join("stamp.json");
    let s = |p: &Path| p.to_str().unwrap().to_string();
    let task = Task {
        kind: "hmc-sample".into(),
        target: s(&stamp),
        inputs: vec![],
        dirs: vec![],
        steps: vec![
            Step::RenderVariations { dir: s(&var), out_dir: s(&d.path().join("r")), flags: vec!["-q".into()] },
            Step::Run { bin: "stage".into(), args: vec!["--out".into(), s(&d.path().join("tmp"))] },
            Step::Rename { from: s(&d.path().join("tmp")), to: s(&stamp) },
        ],
    };
    let log = d.path().join("log");
    std::env::set_var("LOG", &log);
    plan::task_table::run_task(&task, &bin).unwrap();
    let lines: Vec<String> = std::fs::read_to_string(&log).unwrap().lines().map(String::from).collect();
    let v = s(&var);
    let r = s(&d.path().join("r"));
    assert_eq!(lines[0], format!("render -q --labels var0,var1 --out {r}/blend-0.5 {v}/blend-0.5//var0 {v}/blend-0.5//var1"));
    assert!(lines[1].starts_with("render -q --labels var0,var1 --out ") && lines[1].contains("/run "));
    assert!(lines[2].contains("/walk "));
    assert!(stamp.is_file() && !d.path().join("tmp").exists());
}
