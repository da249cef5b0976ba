//! The task graph as a make fragment: one rule per task (target, stage binaries and inputs as
//! prerequisites, the steps as the recipe) and the pipelines' variables. `pipelines/plan.mk`
//! writes it with `plan make` and both pipelines include it.
//!
//! A task's stage runs under `plan step` ([`crate::step_line`]), which prints one line per task
//! (`gpr-predict A-to-B/punch/gpr-nn-scaled-source (12/120), 4.1 s`) instead of make echoing the
//! command; `make ... V=1` echoes every command again.

use crate::task::{Graph, Step, Task};

/// A word for the shell: kept as is when it holds only safe characters, else single-quoted.
pub fn shell_quote(word: &str) -> String {
    let safe = !word.is_empty()
        && word
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || "_./,=:+-@%".contains(c));
    if safe {
        word.to_string()
    } else {
        format!("'{}'", word.replace('\'', r"'\''"))
    }
}

/// Text make passes through unchanged (`$` doubled).
fn make_escape(text: &str) -> String {
    text.replace('$', "$$")
}

fn push_args(line: &mut String, args: &[String]) {
    for a in args {
        line.push(' ');
        line.push_str(&make_escape(&shell_quote(a)));
    }
}

/// What a task's step line calls it: its kind and its target, without the pipeline's output
/// folder, `work/` and the extension (`gpr-predict predict/A-to-B/punch/gpr-nn-scaled-source`).
pub fn label(task: &Task, out: &str) -> String {
    let mut t = task.target.as_str();
    let out = out.trim_end_matches('/');
    if let Some(rest) = t.strip_prefix(out).and_then(|r| r.strip_prefix('/')) {
        t = rest;
    }
    t = t.strip_prefix("work/").unwrap_or(t);
    let file = t.rsplit('/').next().unwrap_or(t);
    if let Some(dot) = file.rfind('.').filter(|&d| d > 0) {
        t = &t[..t.len() - (file.len() - dot)];
    }
    format!("{} {t}", task.kind)
}

/// The recipe lines of one task (without the leading tab); `label` and `place` (1-based index,
/// total) are what its step line says.
pub fn recipe(task: &Task, label: &str, place: (usize, usize)) -> Vec<String> {
    let mut lines = Vec::new();
    if !task.dirs.is_empty() {
        let dirs: Vec<String> = task.dirs.iter().map(|d| make_escape(&shell_quote(d))).collect();
        lines.push(format!("@mkdir -p {}", dirs.join(" ")));
    }
    for step in &task.steps {
        match step {
            Step::Run { bin, args } => {
                let mut line = format!(
                    "@$(STEP) --label {} --of {}/{} -- $(BIN)/{bin}",
                    make_escape(&shell_quote(label)),
                    place.0,
                    place.1
                );
                push_args(&mut line, args);
                lines.push(line);
            }
            Step::Remove { paths } => {
                let p: Vec<String> = paths.iter().map(|d| make_escape(&shell_quote(d))).collect();
                lines.push(format!("$(Q)rm -rf {}", p.join(" ")));
            }
            Step::RenderVariations { dir, out_dir, flags } => {
                let flags: Vec<String> = flags.iter().map(|f| make_escape(&shell_quote(f))).collect();
                lines.push(format!(
                    "$(Q)for d in {}/*/; do s=$$(basename $$d); \\\n\t  $(BIN)/render {} --labels $$(cd $$d && ls -d var* | paste -sd,) --out {}/$$s $$d/var*; done",
                    make_escape(&shell_quote(dir)),
                    flags.join(" "),
                    make_escape(&shell_quote(out_dir)),
                ));
            }
            Step::Rename { from, to } => lines.push(format!(
                "$(Q)mv {} {}",
                make_escape(&shell_quote(from)),
                make_escape(&shell_quote(to))
            )),
        }
    }
    lines
}

/// The whole fragment; `pipeline_out` is the pipelines' output folder (left out of the labels).
pub fn fragment(graph: &Graph, pipeline_out: &str) -> String {
    let mut out = String::from(
        "# The pipelines' task graph, written by `plan make` from the capture set and the options\n\
         # (pipelines/plan.mk regenerates it when either changes). Do not edit.\n\
         # Each stage prints one line through `plan step`; V=1 echoes the commands.\n\
         Q := $(if $(filter 1,$(V)),,@)\n\
         STEP := $(BIN)/plan step $(if $(filter 1,$(V)),-v)\n\n",
    );
    for (name, words) in &graph.variables {
        out.push_str(&format!("{name} := {}\n", make_escape(&words.join(" "))));
    }
    for (i, task) in graph.tasks.iter().enumerate() {
        out.push('\n');
        let mut prereqs: Vec<String> = task.bins().iter().map(|b| format!("$(BIN)/{b}")).collect();
        prereqs.extend(task.inputs.iter().map(|i| make_escape(i)));
        out.push_str(&format!("{}: {}\n", make_escape(&task.target), prereqs.join(" ")));
        for line in recipe(task, &label(task, pipeline_out), graph.place(i)) {
            out.push('\t');
            out.push_str(&line);
            out.push('\n');
        }
    }
    out
}
