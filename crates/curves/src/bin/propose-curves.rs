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
    after_help = "Check them by eye with --render: the template from the front, the side and the back, parts coloured, loops in black\n\
                  e.g.: propose-curves set/A/subject.json --template set/A/walk/000000.ply --out set/A/subject.json --render curves-A.png"
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
    /// Also draw the template with its loops and parts coloured (PNG), for checking them
    #[arg(long, value_name = "PNG")]
    render: Option<PathBuf>,
}

fn main() -> ExitCode {
    let args = mesh_core::cli::parse::<Args>();
    run_stage("propose-curves", || {
        args.common.init()?;
        curves::stage::run(&args.subject, &args.template, &args.out, args.render.as_deref())
    })
}
