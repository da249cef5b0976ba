//! `propose-curves`: limb loops for a template without annotation, into a copy of subject.json.
use std::path::PathBuf;
use std::process::ExitCode;

use clap::Parser;
use mesh_core::cli::{run_stage, CommonArgs};

/// Find the limbs' part curves on a template without annotation and write them into a copy of subject.json
#[derive(Parser)]
#[command(
    name = "propose-curves",
    version,
    after_help = "Check them: segment OUT --template MESH --out parts.seg; render --subject OUT MOTION_DIR --frames 0 --out DIR\n\
                  e.g.: propose-curves set/A/subject.json --template set/A/walk/000000.ply --out set/A/subject.json"
)]
struct Args {
    #[command(flatten)]
    common: CommonArgs,
    /// The subject's subject.json (its curves and part tree may be missing)
    subject: PathBuf,
    /// The mesh the curves index into (the subject's template)
    #[arg(long)]
    template: PathBuf,
    /// Output subject.json (may be SUBJECT itself)
    #[arg(short, long)]
    out: PathBuf,
}

fn main() -> ExitCode {
    let args = mesh_core::cli::parse::<Args>();
    run_stage("propose-curves", || {
        args.common.init()?;
        curves::stage::run(&args.subject, &args.template, &args.out)
    })
}
