//! `fuzz`: the in-process mutation fuzzer over every reader (see the `fuzz` crate).

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Duration;

use clap::Parser;
use mesh_core::cli::{run_stage, CommonArgs};

/// Mutation-fuzz every surfcap reader in process; report inputs, panics, hangs and peak memory
#[derive(Parser)]
#[command(name = "fuzz", version, after_help = "e.g.: fuzz --inputs 10000000 --corpus out/tiny --keep crates/fuzz/regressions --out out/fuzz.json")]
struct Args {
    #[command(flatten)]
    common: CommonArgs,
    /// Stop after this many inputs
    #[arg(long, default_value_t = 100_000)]
    inputs: u64,
    /// Stop after this many seconds
    #[arg(long, default_value_t = 3600)]
    seconds: u64,
    /// Folders of extra seed files (PLY, OBJ, PC2, set.json, subject.json, artifacts), searched recursively
    #[arg(long)]
    corpus: Vec<PathBuf>,
    /// Folder to keep the inputs that panic or hang in
    #[arg(long)]
    keep: Option<PathBuf>,
    /// JSON report
    #[arg(short, long)]
    out: PathBuf,
}

fn main() -> ExitCode {
    let args = mesh_core::cli::parse::<Args>();
    run_stage("fuzz", || {
        args.common.init()?;
        let report = fuzz::run_to_json(
            args.common.seed,
            &args.corpus,
            args.inputs,
            Duration::from_secs(args.seconds),
            args.keep.as_deref(),
        );
        mesh_core::atomic::write_bytes_atomic(&args.out, serde_json::to_string_pretty(&report)?.as_bytes())?;
        if report["panics"].as_u64() != Some(0) || report["hangs"].as_u64() != Some(0) {
            anyhow::bail!("{} panics, {} hangs: inputs kept in --keep", report["panics"], report["hangs"]);
        }
        Ok(())
    })
}
