//! `plan step`: runs one command of a pipeline recipe and prints one short line about it,
//! `gpr-predict A-to-B/punch/gpr-nn-scaled-source (12/120), 4.1 s`, instead of make's echo of the
//! whole command line; with `-v` (`make ... V=1`) it prints the command first.
//!
//! While the command runs: a spinner with the elapsed time when stderr is a terminal and make runs
//! one job at a time; otherwise (a log, or `make -j`, where spinners of parallel jobs would
//! overwrite each other) a `still running` line every [`HEARTBEAT`], so no step is silent for
//! minutes. The command's own stderr passes through; its exit status is the step's.

use std::process::{Command, ExitStatus};
use std::time::{Duration, Instant};

use anyhow::{Context, Result};
use mesh_core::cli::CommonArgs;

/// How often a long step says it is still running when no spinner is shown.
pub const HEARTBEAT: Duration = Duration::from_secs(60);

/// What the line says about a step: its label and its place in the graph.
#[derive(Clone, Debug, PartialEq)]
pub struct StepLine {
    pub label: String,
    /// `(index, total)`, 1-based, the task's place in the graph's order.
    pub place: Option<(usize, usize)>,
}

impl StepLine {
    /// The line printed when the step ends after `elapsed`.
    pub fn done(&self, elapsed: Duration) -> String {
        format!("{}, {}", self.head(), seconds(elapsed))
    }

    /// The label with its place: `align A/walk (3/120)`.
    pub fn head(&self) -> String {
        match self.place {
            Some((i, n)) => format!("{} ({i}/{n})", self.label),
            None => self.label.clone(),
        }
    }
}

/// `0.3 s`, `4.1 s`, `2 min 05 s`.
pub fn seconds(d: Duration) -> String {
    let s = d.as_secs_f64();
    if s < 60.0 {
        format!("{s:.1} s")
    } else {
        let whole = s.round() as u64;
        format!("{} min {:02} s", whole / 60, whole % 60)
    }
}

/// `I/N` as given to `--of`.
pub fn parse_place(text: &str) -> Result<(usize, usize), String> {
    let (i, n) = text.split_once('/').ok_or_else(|| format!("{text}: expected I/N"))?;
    let i: usize = i.parse().map_err(|_| format!("{text}: expected I/N"))?;
    let n: usize = n.parse().map_err(|_| format!("{text}: expected I/N"))?;
    if i == 0 || i > n {
        return Err(format!("{text}: I must be in 1..=N"));
    }
    Ok((i, n))
}

/// True when make runs several jobs at once (its flags carry `-jN` or a job server).
fn parallel_make() -> bool {
    let flags = std::env::var("MAKEFLAGS").unwrap_or_default();
    flags.contains("--jobserver") || flags.split_whitespace().any(|w| w.starts_with("-j") && w != "-j1")
}

/// Runs `program args`, showing progress as described in the module doc; prints the done line
/// on success (unless `-q`) and returns the command's exit status.
pub fn run(line: &StepLine, program: &str, args: &[String], common: &CommonArgs) -> Result<ExitStatus> {
    if mesh_core::cli::verbosity() >= 1 {
        let words: Vec<String> = std::iter::once(program)
            .chain(args.iter().map(String::as_str))
            .map(crate::make_fragment::shell_quote)
            .collect();
        eprintln!("{}", words.join(" "));
    }
    let start = Instant::now();
    let mut child = Command::new(program)
        .args(args)
        .spawn()
        .with_context(|| format!("{program}: cannot start"))?;
    let quiet_spinner = CommonArgs { quiet: common.quiet || parallel_make(), ..common.clone() };
    let spinner = mesh_core::cli::spinner(&line.head(), &quiet_spinner);
    let mut next_beat = HEARTBEAT;
    let status = loop {
        if let Some(status) = child.try_wait().with_context(|| format!("{program}: cannot wait"))? {
            break status;
        }
        std::thread::sleep(Duration::from_millis(100));
        if spinner.is_hidden() && !common.quiet && start.elapsed() >= next_beat {
            eprintln!("{}: still running, {}", line.head(), seconds(start.elapsed()));
            next_beat += HEARTBEAT;
        }
    };
    spinner.finish_and_clear();
    if status.success() && !common.quiet {
        eprintln!("{}", line.done(start.elapsed()));
    } else if !status.success() {
        eprintln!("{}: failed after {}", line.head(), seconds(start.elapsed()));
    }
    Ok(status)
}
