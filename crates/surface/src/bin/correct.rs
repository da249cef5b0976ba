use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::bail;
use clap::Parser;
use mesh_core::cli::{run_stage, CommonArgs};
use rayon::prelude::*;
use surface::correct::{Corrector, DEFAULT_NEIGHBOURS};
use surface::frames::{check_same_topology, read_frames, write_frames};

/// Correct predicted part meshes with the rotations towards their nearest training meshes (transfer paper §6.1)
#[derive(Parser, Debug)]
#[command(
    name = "correct",
    version,
    after_help = "e.g.: correct --training work/B/parts/left-arm work/pred/left-arm --out work/corrected/left-arm"
)]
struct Args {
    #[command(flatten)]
    common: CommonArgs,
    /// Predicted part: a mesh file, or a directory of frames
    prediction: PathBuf,
    /// Directory of the training meshes of the same part (000000.ply, ...), same topology
    #[arg(long)]
    training: PathBuf,
    /// Number of nearest training meshes blended (the paper's M)
    #[arg(short = 'm', long, default_value_t = DEFAULT_NEIGHBOURS as u16, value_parser = clap::value_parser!(u16).range(1..))]
    neighbours: u16,
    /// Output mesh file, or directory when the prediction is a directory
    #[arg(short, long)]
    out: PathBuf,
}

fn main() -> ExitCode {
    let args = mesh_core::cli::parse::<Args>();
    run_stage("correct", || {
        args.common.init()?;
        let training = read_frames(&args.training)?;
        if !training.is_dir {
            bail!(
                "{}: --training must be a directory of frames",
                args.training.display()
            );
        }
        let pred = read_frames(&args.prediction)?;
        check_same_topology(&training, &args.training, &pred, &args.prediction)?;
        let corrector = Corrector::new(training.faces.clone(), training.frames)?;
        let bar = mesh_core::cli::progress_bar(pred.frames.len() as u64, "correct: frames", &args.common);
        let out: Vec<_> = pred
            .frames
            .par_iter()
            .map(|p| {
                let c = corrector.correct(p, args.neighbours as usize);
                bar.inc(1);
                c
            })
            .collect::<Result<_, _>>()?;
        bar.finish_and_clear();
        write_frames(&args.out, &pred.faces, out, pred.is_dir)?;
        Ok(())
    })
}
