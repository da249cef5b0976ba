//! `surfcap <stage> ARGS...`: finds the stage's binary beside the running
//! `surfcap` and replaces this process with it (exit status and signals are
//! the stage's own); `surfcap help` lists the stages, as COLMAP's `colmap help`.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};

use crate::stages::{Stage, STAGES};

/// The folder holding `surfcap` and the stage binaries.
pub fn bin_dir() -> Result<PathBuf> {
    let exe = std::env::current_exe().context("cannot find the surfcap binary's own path")?;
    Ok(exe.parent().map(Path::to_path_buf).unwrap_or_default())
}

/// The stages whose binary is in `dir`, in pipeline order.
pub fn installed(dir: &Path) -> Vec<&'static Stage> {
    STAGES.iter().filter(|s| dir.join(s.bin).is_file()).collect()
}

/// The listing `surfcap help` prints: one line per installed stage, grouped.
pub fn help_text(dir: &Path) -> String {
    let mut out = String::from(
        "surfcap: 4D surface capture to new animation (CVPR 2017 transfer, 3DV 2017 variation)\n\n\
         Usage: surfcap <command> [ARGS...]     (surfcap <command> --help: its options and an example)\n\n\
         Commands, in pipeline order:\n",
    );
    let stages = installed(dir);
    let width = stages.iter().map(|s| s.name.len()).max().unwrap_or(0);
    let mut group = "";
    for s in stages {
        if s.group != group {
            group = s.group;
            out.push_str(&format!("  {group}\n"));
        }
        out.push_str(&format!("    {:width$}  {}\n", s.name, s.about));
    }
    out.push_str(
        "\n  help [COMMAND]     this list, or a command's --help\n  \
         man --out DIR      man pages of every command (DIR/man1/*.1)\n  \
         completions --out DIR   bash, zsh and fish completions of every command\n\n\
         e.g.: surfcap check-set out/demo/set\n      surfcap gpr-train --help\n",
    );
    out
}

/// The one-line error for a word that names no command.
pub fn unknown(word: &str) -> String {
    format!("surfcap: '{word}' is not a surfcap command; 'surfcap help' lists them")
}

/// Runs `stage` with `args` in place of this process (returns only on failure).
pub fn exec(dir: &Path, stage: &Stage, args: &[std::ffi::OsString]) -> anyhow::Error {
    let bin = dir.join(stage.bin);
    if !bin.is_file() {
        return anyhow::anyhow!(
            "{}: the '{}' binary is not built (make build)",
            bin.display(),
            stage.name
        );
    }
    let mut cmd = std::process::Command::new(&bin);
    cmd.args(args);
    #[cfg(unix)]
    {
        use std::os::unix::process::CommandExt;
        // Usage text and errors show the name the user typed.
        cmd.arg0(stage.name);
        anyhow::Error::new(cmd.exec()).context(bin.display().to_string())
    }
    #[cfg(not(unix))]
    {
        match cmd.status() {
            Ok(s) => std::process::exit(s.code().unwrap_or(1)),
            Err(e) => anyhow::Error::new(e).context(bin.display().to_string()),
        }
    }
}
