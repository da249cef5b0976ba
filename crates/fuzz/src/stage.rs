//! The `fuzz` stage: the in-process mutation fuzzer over every reader ([`crate::run_to_json`]).
//! `src/bin/fuzz.rs` only parses [`Params`] and calls [`run`].

use std::path::PathBuf;
use std::time::Duration;

use clap::Parser;
use mesh_core::cli::CommonArgs;
use serde::Serialize;

/// Mutation-fuzz every surfcap reader in process; report inputs, panics, hangs and peak memory
#[derive(Parser, Debug, Serialize)]
#[command(name = "fuzz", version, after_help = "e.g.: fuzz --inputs 10000000 --corpus out/tiny --keep crates/fuzz/regressions --out out/fuzz.json")]
pub struct Params {
    #[command(flatten)]
    #[serde(skip)]
    pub common: CommonArgs,
    /// Stop after this many inputs
    #[arg(long, default_value_t = 100_000)]
    pub inputs: u64,
    /// Stop after this many seconds
    #[arg(long, default_value_t = 3600)]
    pub seconds: u64,
    /// Folders of extra seed files (PLY, OBJ, PC2, set.json, subject.json, artifacts), searched recursively
    #[arg(long)]
    pub corpus: Vec<PathBuf>,
    /// Folder to keep the inputs that panic or hang in
    #[arg(long)]
    pub keep: Option<PathBuf>,
    /// JSON report
    #[arg(short, long)]
    pub out: PathBuf,
}

/// Fuzzes (seeded by `--seed`) until `--inputs` or `--seconds` run out and writes the report to
/// `--out`; fails when any input panicked or hung (those are kept in `--keep`).
pub fn run(p: &Params) -> anyhow::Result<()> {
    let report = crate::run_to_json(p.common.seed, &p.corpus, p.inputs, Duration::from_secs(p.seconds), p.keep.as_deref());
    mesh_core::atomic::write_bytes_atomic(&p.out, serde_json::to_string_pretty(&report)?.as_bytes())?;
    if report["panics"].as_u64() != Some(0) || report["hangs"].as_u64() != Some(0) {
        anyhow::bail!("{} panics, {} hangs: inputs kept in --keep", report["panics"], report["hangs"]);
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_option_is_recorded_under_its_flag_name() {
        let argv = ["fuzz", "--inputs", "10", "--corpus", "a", "--corpus", "b", "--out", "r.json"];
        assert_eq!(mesh_core::cli::unrecorded_options::<Params>(&argv).unwrap(), Vec::<String>::new());
    }
}
