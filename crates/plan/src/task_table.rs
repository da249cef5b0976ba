//! The task table of one stage kind: one JSON object per line (a [`Task`]), line `i` being
//! array task `i`. Any scheduler that can run "task `i` of file F" runs the pipelines with
//! `plan run-task --table F --task i`, which skips the task when its target is up to date
//! (newer than its inputs and stage binaries, as make decides) and otherwise runs its steps.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::SystemTime;

use anyhow::{bail, Context, Result};

use crate::task::{Step, Task};

/// The table's text: one task per line.
pub fn write_table(tasks: &[&Task]) -> Result<String> {
    let mut out = String::new();
    for t in tasks {
        out.push_str(&serde_json::to_string(t)?);
        out.push('\n');
    }
    Ok(out)
}

/// Task `index` (0-based line) of the table at `path`.
pub fn read_task(path: &Path, index: usize) -> Result<Task> {
    let text = std::fs::read_to_string(path).with_context(|| path.display().to_string())?;
    let lines: Vec<&str> = text.lines().collect();
    let line = lines.get(index).with_context(|| {
        format!("{}: no task {index} (the table has {} tasks)", path.display(), lines.len())
    })?;
    serde_json::from_str(line).with_context(|| format!("{}: task {index}: invalid task", path.display()))
}

fn mtime(p: &Path) -> Option<SystemTime> {
    std::fs::metadata(p).and_then(|m| m.modified()).ok()
}

/// Whether the task's target exists and is newer than all its inputs and binaries (a missing
/// input counts as newer, so the task runs and reports it).
pub fn up_to_date(task: &Task, bin_dir: &Path) -> bool {
    let Some(t) = mtime(Path::new(&task.target)) else { return false };
    let bins = task.bins().into_iter().map(|b| bin_dir.join(b));
    let inputs = task.inputs.iter().map(PathBuf::from);
    inputs.chain(bins).all(|p| mtime(&p).is_some_and(|m| m <= t))
}

fn run(bin: &Path, args: &[String]) -> Result<()> {
    let status = Command::new(bin)
        .args(args)
        .status()
        .with_context(|| format!("cannot run {}", bin.display()))?;
    if !status.success() {
        bail!("{} failed ({status})", bin.file_name().unwrap_or_default().to_string_lossy());
    }
    Ok(())
}

/// Sorted entry names of a directory that satisfy `keep`.
fn entries(dir: &Path, keep: impl Fn(&Path, &str) -> bool) -> Result<Vec<String>> {
    let mut names = Vec::new();
    for e in std::fs::read_dir(dir).with_context(|| dir.display().to_string())? {
        let e = e.with_context(|| dir.display().to_string())?;
        let name = e.file_name().to_string_lossy().into_owned();
        if keep(&e.path(), &name) {
            names.push(name);
        }
    }
    names.sort();
    Ok(names)
}

/// Runs the task's steps with the stage binaries of `bin_dir`.
pub fn run_task(task: &Task, bin_dir: &Path) -> Result<()> {
    for d in &task.dirs {
        std::fs::create_dir_all(d).with_context(|| format!("cannot create {d}"))?;
    }
    for step in &task.steps {
        match step {
            Step::Run { bin, args } => run(&bin_dir.join(bin), args)?,
            Step::Remove { paths } => {
                for p in paths {
                    let p = Path::new(p);
                    if p.is_dir() {
                        std::fs::remove_dir_all(p).with_context(|| p.display().to_string())?;
                    } else if p.exists() {
                        std::fs::remove_file(p).with_context(|| p.display().to_string())?;
                    }
                }
            }
            Step::RenderVariations { dir, out_dir, flags } => {
                for seq in entries(Path::new(dir), |p, _| p.is_dir())? {
                    // The same strings as the make recipe's glob (`<dir>/<seq>//var0`).
                    let d = format!("{dir}/{seq}/");
                    let vars = entries(Path::new(&d), |_, n| n.starts_with("var"))?;
                    let mut args = flags.clone();
                    args.extend(["--labels".to_string(), vars.join(","), "--out".into(), format!("{out_dir}/{seq}")]);
                    args.extend(vars.iter().map(|v| format!("{d}/{v}")));
                    run(&bin_dir.join("render"), &args)?;
                }
            }
            Step::Rename { from, to } => {
                std::fs::rename(from, to).with_context(|| format!("cannot rename {from} to {to}"))?
            }
        }
    }
    Ok(())
}
