use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Context;
use clap::Parser;
use mesh_core::artifact::Artifact;
use mesh_core::capture_set::SubjectSpec;
use mesh_core::cli::{run_stage, CommonArgs};
use mesh_core::io::read_mesh;

/// Cut a subject's template into overlapping body parts along the curves of its subject.json
#[derive(Parser, Debug)]
#[command(
    name = "segment",
    version,
    after_help = "e.g.: segment set/A/subject.json --template set/A/walk/000000.ply --out work/A/parts.seg"
)]
struct Args {
    #[command(flatten)]
    common: CommonArgs,
    /// The subject's subject.json (part tree and curves)
    subject: PathBuf,
    /// Template mesh the curve indices refer to
    #[arg(long)]
    template: PathBuf,
    /// Output artifact (kind segmentation)
    #[arg(short, long)]
    out: PathBuf,
}

fn main() -> ExitCode {
    let args = mesh_core::cli::parse::<Args>();
    run_stage("segment", || {
        args.common.init()?;
        let subject = SubjectSpec::load(&args.subject)?;
        let template = read_mesh(&args.template)?;
        let parts = mesh_core::segmentation::segment(&template, &subject)
            .with_context(|| args.subject.display().to_string())?;
        let header = args
            .common
            .header("segment", env!("CARGO_PKG_VERSION"))
            .with_input(&args.subject)?
            .with_input(&args.template)?;
        parts.save(&args.out, &header)?;
        Ok(())
    })
}
