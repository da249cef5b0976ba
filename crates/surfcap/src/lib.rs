//! `surfcap`: one entry point to every stage. `surfcap <stage> ARGS...` runs
//! the stage binary beside it ([`dispatch`]), `surfcap help` lists the stages
//! in pipeline order ([`stages`]), `surfcap man` / `surfcap completions`
//! write the man pages and shell completions generated from every stage's
//! clap definition ([`docs`]).

pub mod dispatch;
pub mod docs;
pub mod stages;

use std::ffi::OsString;
use std::path::PathBuf;

use anyhow::{bail, Result};

/// What the command line asks for; `Err` holds a usage error's line.
pub fn run(args: &[OsString]) -> Result<()> {
    let dir = dispatch::bin_dir()?;
    let word = args.first().map(|a| a.to_string_lossy().into_owned());
    match word.as_deref() {
        None | Some("help" | "--help" | "-h") => match args.get(1).map(|a| a.to_string_lossy()) {
            Some(name) if word.as_deref() == Some("help") => {
                let Some(stage) = stages::find(&name) else { bail!(UsageError(dispatch::unknown(&name))) };
                Err(dispatch::exec(&dir, stage, &["--help".into()]))
            }
            _ => {
                print!("{}", dispatch::help_text(&dir));
                Ok(())
            }
        },
        Some("--version" | "-V") => {
            println!("surfcap {}", env!("CARGO_PKG_VERSION"));
            Ok(())
        }
        Some(w @ ("man" | "completions")) => {
            let kind = w.parse()?;
            let out = match &args[1..] {
                [flag, dir] if flag == "--out" || flag == "-o" => PathBuf::from(dir),
                _ => bail!(UsageError(format!("surfcap: usage: surfcap {w} --out DIR"))),
            };
            let n = docs::generate(&dir, kind, &out)?;
            mesh_core::info!("{w} of {n} commands in {}", out.display());
            Ok(())
        }
        Some(w) => match stages::find(w) {
            Some(stage) => Err(dispatch::exec(&dir, stage, &args[1..])),
            None => bail!(UsageError(dispatch::unknown(w))),
        },
    }
}

/// A usage error: printed as is, exit status 2.
#[derive(Debug)]
pub struct UsageError(pub String);

impl std::fmt::Display for UsageError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for UsageError {}
