//! The `inspect` stage: print the kind, version and provenance header of artifacts.

use std::io::Write;
use std::path::PathBuf;

use clap::Parser;
use serde::Serialize;

use crate::artifact::inspect_json;
use crate::cli::{report_error, AlreadyReported, CommonArgs};

/// Print the kind, version and provenance header of surfcap artifacts as JSON
#[derive(Parser, Debug, Serialize)]
#[command(
    name = "inspect",
    version,
    after_help = "Prints one JSON object per file: {\"file\", \"kind\", \"kind_version\", \"header\", \"payload_bytes\"}.\n\
                  e.g.: inspect work/walk.aligned work/parts.pca | jq .header.inputs"
)]
pub struct Params {
    #[command(flatten)]
    #[serde(skip)]
    pub common: CommonArgs,
    /// Artifact files to inspect
    #[arg(required = true, value_name = "ARTIFACT")]
    pub files: Vec<PathBuf>,
}

/// Prints one JSON object per readable file on stdout and one error line per unreadable one;
/// fails, without a further message, when any file could not be read.
pub fn run(p: &Params) -> anyhow::Result<()> {
    let mut out = std::io::stdout().lock();
    let mut failed = 0;
    for file in &p.files {
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
    crate::info!("inspected {} of {} files", p.files.len() - failed, p.files.len());
    if failed > 0 {
        return Err(AlreadyReported.into());
    }
    Ok(())
}

