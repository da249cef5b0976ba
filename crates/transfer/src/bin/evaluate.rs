use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Context;
use clap::Parser;
use mesh_core::cli::{run_stage, CommonArgs};
use mesh_core::sequence::MeshSequence;
use transfer::evaluate::{rms_errors, EvalRecord};

/// Per-vertex RMS error of a transferred sequence against its ground truth (pose-aligned and as placed)
#[derive(Parser, Debug)]
#[command(
    name = "evaluate",
    version,
    after_help = "e.g.: evaluate out/transfer/A-to-B/punch/gpr-nn set/truth/B/punch --direction 'A->B' --motion punch --method gpr-nn --out out/eval/A-to-B/punch/gpr-nn.json"
)]
struct Args {
    #[command(flatten)]
    common: CommonArgs,
    /// Transferred sequence folder (from gpr-predict)
    prediction: PathBuf,
    /// Ground-truth folder (same frame count and topology)
    truth: PathBuf,
    /// Direction label for the record, e.g. A->B
    #[arg(long)]
    direction: String,
    /// Motion name for the record
    #[arg(long)]
    motion: String,
    /// Method name for the record
    #[arg(long)]
    method: String,
    /// Placement name for the record
    #[arg(long, default_value = "regressed")]
    placement: String,
    /// Training-pair label for the record: dense or keyposes
    #[arg(long, default_value = "dense")]
    training: String,
    /// Output JSON record (stdout when omitted)
    #[arg(short, long)]
    out: Option<PathBuf>,
}

fn main() -> ExitCode {
    let args = Args::parse();
    run_stage("evaluate", || {
        args.common.init()?;
        let pred = MeshSequence::load_dir(&args.prediction)?;
        let truth = MeshSequence::load_dir(&args.truth)?;
        let (rms_pose_m, rms_placed_m) =
            rms_errors(&pred, &truth).with_context(|| args.prediction.display().to_string())?;
        let record = EvalRecord {
            direction: args.direction.clone(),
            motion: args.motion.clone(),
            method: args.method.clone(),
            placement: args.placement.clone(),
            training: args.training.clone(),
            rms_pose_m,
            rms_placed_m,
            frames: pred.n_frames(),
        };
        let text = serde_json::to_string_pretty(&record)?;
        match &args.out {
            Some(p) => mesh_core::atomic::write_bytes_atomic(p, text.as_bytes())?,
            None => println!("{text}"),
        }
        Ok(())
    })
}
