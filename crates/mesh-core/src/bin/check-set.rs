//! `check-set`: validate a whole capture set, every problem one line.
use std::path::PathBuf;
use std::process::ExitCode;

use clap::Parser;
use mesh_core::cli::{run_stage, AlreadyReported, CommonArgs};

/// Validate a capture set (set.json, subjects, curves, motions, frames, key-poses) and list every problem, one line each
#[derive(Parser)]
#[command(
    name = "check-set",
    version,
    after_help = "Exit status 1 when there is any problem. docs/FORMATS.md describes the layout.\n\
                  e.g.: check-set out/demo/set\n\
                  e.g.: check-set -v fixtures/tiny-set     # also a summary of what was checked"
)]
struct Args {
    #[command(flatten)]
    common: CommonArgs,
    /// Capture-set folder (holding set.json)
    set: PathBuf,
}

fn main() -> ExitCode {
    let args = mesh_core::cli::parse::<Args>();
    run_stage("check-set", || {
        args.common.init()?;
        let report = mesh_core::set_check::check_set(&args.set);
        for p in &report.problems {
            mesh_core::cli::report_error(&anyhow::anyhow!("{p}"));
        }
        mesh_core::info!(
            "{}: {} subjects, {} motion folders, {} frames: {} problems",
            args.set.display(),
            report.subjects,
            report.motions,
            report.frames,
            report.problems.len()
        );
        if !report.problems.is_empty() {
            return Err(AlreadyReported.into());
        }
        Ok(())
    })
}
