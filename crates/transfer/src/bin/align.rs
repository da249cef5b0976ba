use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Context;
use clap::Parser;
use mesh_core::artifact::Artifact;
use mesh_core::cli::{run_stage, CommonArgs};
use mesh_core::io::read_mesh;
use mesh_core::sequence::MeshSequence;

/// Rigidly align every frame of a motion to the subject's template and record per-frame displacements
#[derive(Parser, Debug)]
#[command(
    name = "align",
    version,
    after_help = "e.g.: align --template set/A/walk/000000.ply set/A/walk --out work/A/walk.aligned"
)]
struct Args {
    #[command(flatten)]
    common: CommonArgs,
    /// Template mesh of the subject (PLY or OBJ); every frame must share its topology
    #[arg(long)]
    template: PathBuf,
    /// Motion folder of frames 000000.ply, 000001.ply, ...
    motion: PathBuf,
    /// Output artifact (kind aligned-motion)
    #[arg(short, long)]
    out: PathBuf,
}

fn main() -> ExitCode {
    let args = Args::parse();
    run_stage("align", || {
        args.common.init()?;
        let template = read_mesh(&args.template)?;
        let motion = MeshSequence::load_dir(&args.motion)?;
        let aligned = transfer::align::align_motion(&template, &motion)
            .with_context(|| args.motion.display().to_string())?;
        let header = args
            .common
            .header("align", env!("CARGO_PKG_VERSION"))
            .with_input(&args.template)?;
        aligned.save(&args.out, &header)?;
        Ok(())
    })
}
