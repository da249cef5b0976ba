//! `surfcap man` and `surfcap completions`: asks every installed stage for
//! its files generated from its clap definition (the hidden
//! `--surfcap-generate` of [`mesh_core::cli::parse`]), then writes
//! `surfcap`'s own, whose subcommands are the stages.

use std::path::Path;

use anyhow::{bail, Context, Result};
use mesh_core::clap_docs::{Kind, GENERATE_FLAG};

use crate::stages::STAGES;

/// `surfcap`'s own clap definition: the stages as subcommands (for its man
/// page and the completion of `surfcap <TAB>`).
pub fn command() -> clap::Command {
    let mut cmd = clap::Command::new("surfcap")
        .about("4D surface capture to new animation: one entry point to every stage")
        .version(env!("CARGO_PKG_VERSION"))
        .after_help("e.g.: surfcap help\n      surfcap check-set out/demo/set");
    for s in STAGES {
        cmd = cmd.subcommand(
            clap::Command::new(s.name)
                .about(s.about)
                .arg(clap::Arg::new("args").num_args(0..).trailing_var_arg(true).allow_hyphen_values(true)),
        );
    }
    cmd.subcommand(clap::Command::new("help").about("list the commands, or show a command's --help"))
        .subcommand(clap::Command::new("man").about("write every command's man page"))
        .subcommand(clap::Command::new("completions").about("write every command's shell completions"))
        .disable_help_subcommand(true)
}

/// Writes the man pages or completions of every installed stage, and of
/// `surfcap`, into `out`; stages are renamed to the name users type.
pub fn generate(bin_dir: &Path, kind: Kind, out: &Path) -> Result<usize> {
    let kind_word = match kind {
        Kind::Man => "man",
        Kind::Completions => "completions",
    };
    let mut n = 0;
    for s in crate::dispatch::installed(bin_dir) {
        let bin = bin_dir.join(s.bin);
        let status = std::process::Command::new(&bin)
            .args([GENERATE_FLAG, kind_word])
            .arg(out)
            .status()
            .with_context(|| format!("{}: cannot run", bin.display()))?;
        if !status.success() {
            bail!("{}: could not write its {kind_word} ({status})", bin.display());
        }
        n += 1;
    }
    mesh_core::clap_docs::write(command(), kind, out)?;
    Ok(n + 1)
}
