//! `inspect`: print the kind, version and provenance header of artifacts.

use std::io::Write;
use std::path::PathBuf;
use std::process::ExitCode;

use clap::Parser;
use mesh_core::artifact::inspect_json;
use mesh_core::cli::{report_error, run_stage, AlreadyReported, CommonArgs};

/// Print the kind, version and provenance header of surfcap artifacts as JSON
#[derive(Parser)]
#[command(
    name = "inspect",
    version,
    after_help = "Prints one JSON object per file: {\"file\", \"kind\", \"kind_version\", \"header\", \"payload_bytes\"}.\n\
                  e.g.: inspect work/walk.aligned work/parts.pca | jq .header.inputs"
)]
struct Args {
    #[command(flatten)]
    common: CommonArgs,
    /// Artifact files to inspect
    #[arg(required = true, value_name = "ARTIFACT")]
    files: Vec<PathBuf>,
}

fn main() -> ExitCode {
    let args = mesh_core::cli::parse::<Args>();
    run_stage("inspect", || {
        args.common.init()?;
        let mut out = std::io::stdout().lock();
        let mut failed = 0;
        for file in &args.files {
            match inspect_json(file) {
                Ok(json) => {
                    serde_json::to_writer_pretty(&mut out, &json)?;
                    writeln!(out)?;
                }
                Err(e) => {
                    report_error(&e.into());
                    failed += 1;
                }
            }
        }
        out.flush()?;
        mesh_core::info!(
            "inspected {} of {} files",
            args.files.len() - failed,
            args.files.len()
        );
        if failed > 0 {
            return Err(AlreadyReported.into());
        }
        Ok(())
    })
}
