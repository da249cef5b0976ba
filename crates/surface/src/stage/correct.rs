//! The `correct` stage: predicted part meshes corrected with the rotations towards their nearest
//! training meshes (CVPR §6.1).

use std::path::PathBuf;

use anyhow::bail;
use clap::Parser;
use mesh_core::cli::CommonArgs;
use rayon::prelude::*;
use serde::Serialize;

use crate::correct::{Corrector, DEFAULT_NEIGHBOURS};
use crate::frames::{check_same_topology, read_frames, write_frames};

/// Correct predicted part meshes with the rotations towards their nearest training meshes (transfer paper §6.1)
#[derive(Parser, Debug, Serialize)]
#[command(
    name = "correct",
    version,
    after_help = "e.g.: correct --training work/B/parts/left-arm work/pred/left-arm --out work/corrected/left-arm"
)]
pub struct Params {
    #[command(flatten)]
    #[serde(skip)]
    pub common: CommonArgs,
    /// Predicted part: a mesh file, or a directory of frames
    pub prediction: PathBuf,
    /// Directory of the training meshes of the same part (000000.ply, ...), same topology
    #[arg(long)]
    pub training: PathBuf,
    /// Number of nearest training meshes blended (the paper's M)
    #[arg(short = 'm', long, default_value_t = DEFAULT_NEIGHBOURS as u16, value_parser = clap::value_parser!(u16).range(1..))]
    pub neighbours: u16,
    /// Output mesh file, or directory when the prediction is a directory
    #[arg(short, long)]
    pub out: PathBuf,
}

/// Writes the corrected part (a mesh, or a folder of frames like the prediction).
pub fn run(p: &Params) -> anyhow::Result<()> {
    let training = read_frames(&p.training)?;
    if !training.is_dir {
        bail!(
            "{}: --training must be a directory of frames",
            p.training.display()
        );
    }
    let pred = read_frames(&p.prediction)?;
    check_same_topology(&training, &p.training, &pred, &p.prediction)?;
    let corrector = Corrector::new(training.faces.clone(), training.frames)?;
    let bar = mesh_core::cli::progress_bar(pred.frames.len() as u64, "correct: frames", &p.common);
    let out: Vec<_> = pred
        .frames
        .par_iter()
        .map(|frame| {
            let c = corrector.correct(frame, p.neighbours as usize);
            bar.inc(1);
            c
        })
        .collect::<Result<_, _>>()?;
    bar.finish_and_clear();
    write_frames(&p.out, &pred.faces, out, pred.is_dir)?;
    Ok(())
}
