//! The `blend` stage: two poses (or two time-aligned sequences) of one subject blended by their
//! deformation gradients, rotations by log/exp and stretch linearly, then a Poisson solve.

use std::path::PathBuf;

use anyhow::{bail, Context};
use clap::Parser;
use mesh_core::cli::CommonArgs;
use rayon::prelude::*;
use serde::Serialize;

use crate::blend::{linear_blend, Blender};
use crate::frames::{check_same_topology, read_frames, write_frames};

/// Blend two poses (or two time-aligned sequences) of one subject: rotations by log/exp, stretch linearly, Poisson solve
#[derive(Parser, Debug, Serialize)]
#[command(
    name = "blend",
    version,
    after_help = "e.g.: blend set/A/walk/000010.ply set/A/run/000012.ply --weight 0.5 --out out/blend.ply\n      blend work/A/walk work/A/run --weight 0.3 --rest set/A/walk/000000.ply --out out/walk-run"
)]
pub struct Params {
    #[command(flatten)]
    #[serde(skip)]
    pub common: CommonArgs,
    /// First pose: a mesh file, or a directory of frames
    pub a: PathBuf,
    /// Second pose, same topology (a directory needs as many frames as `a`)
    pub b: PathBuf,
    /// Weight of `b` in [0, 1] (0 gives `a`, 1 gives `b`)
    #[arg(short, long, default_value_t = 0.5, value_name = "W")]
    pub weight: f64,
    /// Rest mesh the deformation gradients are measured from [default: first frame of `a`]
    #[arg(long)]
    pub rest: Option<PathBuf>,
    /// Linear vertex blending instead (the baseline)
    #[arg(long)]
    pub linear: bool,
    /// Output mesh file, or directory when the inputs are directories
    #[arg(short, long)]
    pub out: PathBuf,
}

/// Writes the blend (a mesh, or a folder of frames when the inputs are folders).
pub fn run(p: &Params) -> anyhow::Result<()> {
    if !(0.0..=1.0).contains(&p.weight) {
        bail!("--weight must be in [0, 1], got {}", p.weight);
    }
    let (a, b) = (read_frames(&p.a)?, read_frames(&p.b)?);
    check_same_topology(&a, &p.a, &b, &p.b)?;
    if a.frames.len() != b.frames.len() {
        bail!(
            "{}: {} frames but {} has {}",
            p.b.display(),
            b.frames.len(),
            p.a.display(),
            a.frames.len()
        );
    }
    let rest = match &p.rest {
        Some(path) => {
            let r = read_frames(path)?;
            check_same_topology(&a, &p.a, &r, path)?;
            r.frames.into_iter().next().expect("at least one frame")
        }
        None => a.frames[0].clone(),
    };
    let w = p.weight;
    let out: Vec<_> = if p.linear {
        a.frames
            .iter()
            .zip(&b.frames)
            .map(|(p, q)| linear_blend(p, q, w))
            .collect()
    } else {
        let blender = Blender::new(rest, a.faces.clone()).context("rest mesh")?;
        a.frames
            .par_iter()
            .zip(&b.frames)
            .map(|(p, q)| blender.blend(p, q, w))
            .collect::<Result<_, _>>()?
    };
    write_frames(&p.out, &a.faces, out, a.is_dir)?;
    Ok(())
}
