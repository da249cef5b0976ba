use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{bail, Context};
use clap::Parser;
use mesh_core::cli::{run_stage, CommonArgs};
use rayon::prelude::*;
use surface::blend::{linear_blend, Blender};
use surface::frames::{check_same_topology, read_frames, write_frames};

/// Blend two poses (or two time-aligned sequences) of one subject: rotations by log/exp, stretch linearly, Poisson solve
#[derive(Parser, Debug)]
#[command(
    name = "blend",
    version,
    after_help = "e.g.: blend set/A/walk/000010.ply set/A/run/000012.ply --weight 0.5 --out out/blend.ply\n      blend work/A/walk work/A/run --weight 0.3 --rest set/A/walk/000000.ply --out out/walk-run"
)]
struct Args {
    #[command(flatten)]
    common: CommonArgs,
    /// First pose: a mesh file, or a directory of frames
    a: PathBuf,
    /// Second pose, same topology (a directory needs as many frames as `a`)
    b: PathBuf,
    /// Weight of `b` in [0, 1] (0 gives `a`, 1 gives `b`)
    #[arg(short, long, default_value_t = 0.5, value_name = "W")]
    weight: f64,
    /// Rest mesh the deformation gradients are measured from [default: first frame of `a`]
    #[arg(long)]
    rest: Option<PathBuf>,
    /// Linear vertex blending instead (the baseline)
    #[arg(long)]
    linear: bool,
    /// Output mesh file, or directory when the inputs are directories
    #[arg(short, long)]
    out: PathBuf,
}

fn main() -> ExitCode {
    let args = mesh_core::cli::parse::<Args>();
    run_stage("blend", || {
        args.common.init()?;
        if !(0.0..=1.0).contains(&args.weight) {
            bail!("--weight must be in [0, 1], got {}", args.weight);
        }
        let (a, b) = (read_frames(&args.a)?, read_frames(&args.b)?);
        check_same_topology(&a, &args.a, &b, &args.b)?;
        if a.frames.len() != b.frames.len() {
            bail!(
                "{}: {} frames but {} has {}",
                args.b.display(),
                b.frames.len(),
                args.a.display(),
                a.frames.len()
            );
        }
        let rest = match &args.rest {
            Some(p) => {
                let r = read_frames(p)?;
                check_same_topology(&a, &args.a, &r, p)?;
                r.frames.into_iter().next().expect("at least one frame")
            }
            None => a.frames[0].clone(),
        };
        let w = args.weight;
        let out: Vec<_> = if args.linear {
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
        write_frames(&args.out, &a.faces, out, a.is_dir)?;
        Ok(())
    })
}
