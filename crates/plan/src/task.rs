//! A task of the pipelines' graph: one stage invocation (or a short fixed sequence of steps) with
//! the files it reads, the directories it creates, and the one file whose existence says that all
//! of its outputs are complete (its `target`, written last).

use serde::{Deserialize, Serialize};

/// One step of a task. Paths and arguments are plain strings, exactly as they appear on the
/// command line (artifact headers record the command line, so they must not be rewritten).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Step {
    /// Run the stage binary `bin` (from the binary directory) with `args`.
    Run { bin: String, args: Vec<String> },
    /// Remove these files or directories (recursively) if they exist.
    Remove { paths: Vec<String> },
    /// For every sequence directory `<dir>/<seq>/` (sorted), draw its `var*` variations overlaid:
    /// `render <flags> --labels var0,var1,... --out <out_dir>/<seq> <dir>/<seq>//var0 ...`.
    RenderVariations { dir: String, out_dir: String, flags: Vec<String> },
    /// Rename `from` to `to` (the task's last step when a stage writes its stamp under a
    /// temporary name).
    Rename { from: String, to: String },
}

/// One node of the task graph.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Task {
    /// The stage kind, which names the task's Slurm job array (`align`, `gpr-train`, ...).
    pub kind: String,
    /// The file that exists only once every output of the task is complete.
    pub target: String,
    /// Files the task reads (stage binaries are implied by its `Run` steps).
    pub inputs: Vec<String>,
    /// Directories created before the first step.
    pub dirs: Vec<String>,
    pub steps: Vec<Step>,
}

impl Task {
    /// A task of one `Run` step of stage `bin` (its kind) writing `target`.
    pub fn run(bin: &str, target: impl Into<String>, inputs: Vec<String>, args: Vec<String>) -> Self {
        Task {
            kind: bin.to_string(),
            target: target.into(),
            inputs,
            dirs: Vec::new(),
            steps: vec![Step::Run {
                bin: bin.to_string(),
                args,
            }],
        }
    }

    /// Creates `dir` before the first step.
    pub fn mkdir(mut self, dir: impl Into<String>) -> Self {
        self.dirs.push(dir.into());
        self
    }

    /// Creates the target's own directory before the first step.
    pub fn mkdir_target(self) -> Self {
        let dir = parent(&self.target);
        self.mkdir(dir)
    }

    /// The stage binaries the task runs, in order, without repeats.
    pub fn bins(&self) -> Vec<&str> {
        let mut out: Vec<&str> = Vec::new();
        for s in &self.steps {
            let b = match s {
                Step::Run { bin, .. } => bin.as_str(),
                Step::RenderVariations { .. } => "render",
                _ => continue,
            };
            if !out.contains(&b) {
                out.push(b);
            }
        }
        out
    }
}

/// A command-line word: the tasks' arguments are `String`s, most of them literals.
pub(crate) fn s(x: impl Into<String>) -> String {
    x.into()
}

/// The directory part of a path string (`"."` for a bare file name), as make's `$(@D)`.
pub fn parent(path: &str) -> String {
    match path.rfind('/') {
        Some(0) => "/".to_string(),
        Some(i) => path[..i].to_string(),
        None => ".".to_string(),
    }
}

/// How the plan splits the fit of a model of several parts into tasks.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum PartTasks {
    /// One task writes the whole model; the stage fits its parts in parallel (`plan make`: one
    /// machine, where a process per part would read the inputs once per part and leave cores
    /// idle while a serial make runs one part at a time).
    #[default]
    OnePerModel,
    /// One task per part writing a piece, and their merge (`plan slurm`, `plan make
    /// --part-tasks`: one array task fits one part).
    OnePerPart,
}

/// Both pipelines' tasks plus the variables the pipelines' make targets read.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Graph {
    /// How models of several parts are split into tasks (set before the pipelines plan).
    #[serde(skip)]
    pub part_tasks: PartTasks,
    pub tasks: Vec<Task>,
    /// How many of the first tasks are the transfer pipeline's (the rest are the variation's):
    /// each pipeline's step lines count its own tasks.
    #[serde(skip)]
    pub transfer_tasks: usize,
    /// `(name, words)`: make variables, e.g. `TRANSFER_RECORDS` (the evaluation records).
    pub variables: Vec<(String, Vec<String>)>,
}

impl Graph {
    pub fn push(&mut self, task: Task) -> String {
        let target = task.target.clone();
        self.tasks.push(task);
        target
    }

    pub fn variable(&mut self, name: &str, words: Vec<String>) {
        self.variables.push((name.to_string(), words));
    }

    /// The place (1-based) of task `i` among its pipeline's tasks, and their number.
    pub fn place(&self, i: usize) -> (usize, usize) {
        let t = self.transfer_tasks.min(self.tasks.len());
        if i < t {
            (i + 1, t)
        } else {
            (i + 1 - t, self.tasks.len() - t)
        }
    }

    /// The task writing `target`, if any.
    pub fn producer(&self, target: &str) -> Option<&Task> {
        self.tasks.iter().find(|t| t.target == target)
    }
}
