//! The `correct` stage: predicted part meshes corrected with the rotations towards their nearest
//! training meshes (CVPR §6.1).

use std::path::PathBuf;

use anyhow::bail;
use clap::Parser;
use mesh_core::cli::CommonArgs;
use rayon::prelude::*;
use serde::Serialize;

use crate::correct::{Corrector, DEFAULT_NEIGHBOURS};
use crate::frames::{frames_per_block, read_frames, write_frames, FrameBlocks};

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
    /// Memory in MiB for each store that grows with the data: the training meshes (every 2nd,
    /// 4th, ... frame when every frame would not fit) and their cached factorisations (least
    /// recently used rebuilt when needed: the same output). The prediction is read, corrected
    /// and written a block of frames at a time
    #[arg(long, value_name = "MIB", default_value_t = mesh_core::cli::DEFAULT_MEMORY_BUDGET_MIB)]
    pub memory_budget: usize,
}

/// Writes the corrected part (a mesh, or a folder of frames like the prediction).
pub fn run(p: &Params) -> anyhow::Result<()> {
    if !p.training.is_dir() {
        bail!("{}: --training must be a directory of frames", p.training.display());
    }
    let budget = p.memory_budget.saturating_mul(1 << 20);
    let training = FrameBlocks::open(&p.training)?;
    let (meshes, stride) = training.strided_within(budget)?;
    if stride > 1 {
        mesh_core::warn!(
            "{}: {} training frames do not fit in --memory-budget {} MiB: every {stride}th is used",
            p.training.display(),
            training.n_frames(),
            p.memory_budget
        );
    }
    let mut corrector = Corrector::new(training.faces.clone(), meshes)?;
    corrector.set_cache_limit(budget);
    let check = |n_vertices: usize, faces: &[[u32; 3]]| -> anyhow::Result<()> {
        if n_vertices != training.n_vertices || faces != training.faces.as_slice() {
            bail!(
                "{}: topology differs from {} ({n_vertices} vs {} vertices, {} vs {} faces)",
                p.prediction.display(),
                p.training.display(),
                training.n_vertices,
                faces.len(),
                training.faces.len()
            );
        }
        Ok(())
    };
    let m = p.neighbours as usize;
    if !p.prediction.is_dir() {
        let pred = read_frames(&p.prediction)?;
        check(pred.frames[0].len(), &pred.faces)?;
        let out = vec![corrector.correct(&pred.frames[0], m)?];
        write_frames(&p.out, &pred.faces, out, false)?;
        return Ok(());
    }
    let pred = FrameBlocks::open(&p.prediction)?;
    check(pred.n_vertices, &pred.faces)?;
    let bar = mesh_core::cli::progress_bar(pred.n_frames() as u64, "correct: frames", &p.common);
    let writer = mesh_core::io::ply_frames::PlyFrames::new(pred.n_vertices, &pred.faces);
    let block = frames_per_block(pred.n_vertices);
    writer.write_dir_streamed(&p.out, None, |push| {
        for start in (0..pred.n_frames()).step_by(block) {
            let frames = pred.block(start..(start + block).min(pred.n_frames()))?;
            let corrected: Vec<_> = frames
                .par_iter()
                .map(|frame| {
                    let c = corrector.correct(frame, m);
                    bar.inc(1);
                    c
                })
                .collect::<Result<_, _>>()?;
            corrected.iter().try_for_each(|f| push(f))?;
        }
        Ok(())
    })?;
    bar.finish_and_clear();
    Ok(())
}
