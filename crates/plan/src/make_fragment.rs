//! The task graph as a make fragment: one rule per task (target, stage binaries and inputs as
//! prerequisites, the steps as the recipe) and the pipelines' variables. `pipelines/plan.mk`
//! writes it with `plan make` and both pipelines include it.

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

fn command(bin: &str, args: &[String]) -> String {
    let mut line = format!("$(BIN)/{bin}");
    for a in args {
        line.push(' ');
        line.push_str(&make_escape(&shell_quote(a)));
    }
    line
}

/// The recipe lines of one task (without the leading tab).
pub fn recipe(task: &Task) -> Vec<String> {
    let mut lines = Vec::new();
    if !task.dirs.is_empty() {
        let dirs: Vec<String> = task.dirs.iter().map(|d| make_escape(&shell_quote(d))).collect();
        lines.push(format!("@mkdir -p {}", dirs.join(" ")));
    }
    for step in &task.steps {
        match step {
            Step::Run { bin, args } => lines.push(command(bin, args)),
            Step::Remove { paths } => {
                let p: Vec<String> = paths.iter().map(|d| make_escape(&shell_quote(d))).collect();
                lines.push(format!("rm -rf {}", p.join(" ")));
            }
            Step::RenderVariations { dir, out_dir, flags } => {
                let flags: Vec<String> = flags.iter().map(|f| make_escape(&shell_quote(f))).collect();
                lines.push(format!(
                    "for d in {}/*/; do s=$$(basename $$d); \\\n\t  $(BIN)/render {} --labels $$(cd $$d && ls -d var* | paste -sd,) --out {}/$$s $$d/var*; done",
                    make_escape(&shell_quote(dir)),
                    flags.join(" "),
                    make_escape(&shell_quote(out_dir)),
                ));
            }
            Step::Rename { from, to } => lines.push(format!(
                "mv {} {}",
                make_escape(&shell_quote(from)),
                make_escape(&shell_quote(to))
            )),
        }
    }
    lines
}

/// The whole fragment.
pub fn fragment(graph: &Graph) -> String {
    let mut out = String::from(
        "# The pipelines' task graph, written by `plan make` from the capture set and the options\n\
         # (pipelines/plan.mk regenerates it when either changes). Do not edit.\n\n",
    );
    for (name, words) in &graph.variables {
        out.push_str(&format!("{name} := {}\n", make_escape(&words.join(" "))));
    }
    for task in &graph.tasks {
        out.push('\n');
        let mut prereqs: Vec<String> = task.bins().iter().map(|b| format!("$(BIN)/{b}")).collect();
        prereqs.extend(task.inputs.iter().map(|i| make_escape(i)));
        out.push_str(&format!("{}: {}\n", make_escape(&task.target), prereqs.join(" ")));
        for line in recipe(task) {
            out.push('\t');
            out.push_str(&line);
            out.push('\n');
        }
    }
    out
}
