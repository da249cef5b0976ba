//! Man pages and shell completions generated from a stage's clap definition
//! (`clap_mangen`, `clap_complete`), so that they never drift from `--help`.
//!
//! Every stage parses its arguments with [`crate::cli::parse`], which
//! answers the hidden first argument `--surfcap-generate man|completions DIR`
//! by writing the stage's files with [`write`] and exiting; `surfcap man` and
//! `surfcap completions` run each stage that way.

use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};
use clap_complete::{Generator, Shell};

/// The hidden first argument that asks a stage for its generated files.
pub const GENERATE_FLAG: &str = "--surfcap-generate";

/// What to generate.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// `DIR/man1/<name>.1` (roff).
    Man,
    /// `DIR/bash/<name>.bash`, `DIR/zsh/_<name>`, `DIR/fish/<name>.fish`.
    Completions,
}

impl std::str::FromStr for Kind {
    type Err = anyhow::Error;
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "man" => Ok(Kind::Man),
            "completions" => Ok(Kind::Completions),
            _ => bail!("'{s}': expected man or completions"),
        }
    }
}

const SHELLS: [Shell; 3] = [Shell::Bash, Shell::Zsh, Shell::Fish];

/// The files [`write`] makes for a command named `name`, relative to its folder.
pub fn files(kind: Kind, name: &str) -> Vec<PathBuf> {
    match kind {
        Kind::Man => vec![PathBuf::from(format!("man1/{name}.1"))],
        Kind::Completions => SHELLS
            .iter()
            .map(|s| PathBuf::from(s.to_string()).join(s.file_name(name)))
            .collect(),
    }
}

/// Writes the man page or the completions of `cmd` into `dir` (atomically, file by file).
pub fn write(mut cmd: clap::Command, kind: Kind, dir: &Path) -> Result<()> {
    cmd.build();
    for rel in files(kind, cmd.get_name()) {
        let d = dir.join(rel).parent().map(Path::to_path_buf).unwrap_or_default();
        std::fs::create_dir_all(&d).with_context(|| format!("{}: cannot create the folder", d.display()))?;
    }
    let name = cmd.get_name().to_string();
    match kind {
        Kind::Man => {
            let mut buf = Vec::new();
            clap_mangen::Man::new(cmd).render(&mut buf).context("cannot render the man page")?;
            let path = dir.join(&files(kind, &name)[0]);
            crate::atomic::write_bytes_atomic(&path, &buf)?;
        }
        Kind::Completions => {
            for (shell, rel) in SHELLS.iter().zip(files(kind, &name)) {
                let mut buf = Vec::new();
                clap_complete::generate(*shell, &mut cmd, name.clone(), &mut buf);
                crate::atomic::write_bytes_atomic(&dir.join(rel), &buf)?;
            }
        }
    }
    Ok(())
}
