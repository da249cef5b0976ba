use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{bail, Context};
use clap::Parser;
use mesh_core::cli::{run_stage, CommonArgs};
use mesh_core::io::read_mesh;
use surface::frames::{read_frames, write_frames};
use mesh_core::artifact::Artifact;
use mesh_core::segmentation::Segmentation;
use surface::segmentation::part_layout;
use surface::stitch::Stitcher;

/// Stitch corrected part meshes into one mesh with the template's topology along optimal loops (transfer paper §6.2)
#[derive(Parser, Debug)]
#[command(
    name = "stitch",
    version,
    after_help = "e.g.: stitch work/corrected --segmentation work/B/parts.seg --template set/B/walk/000000.ply --out work/stitched"
)]
struct Args {
    #[command(flatten)]
    common: CommonArgs,
    /// Directory holding one `<part name>.ply` (one frame) or `<part name>/` frame directory per part
    parts: PathBuf,
    /// Segmentation artifact of the target template (from `segment`)
    #[arg(long)]
    segmentation: PathBuf,
    /// Target template mesh (its faces give the output topology)
    #[arg(long)]
    template: PathBuf,
    /// Output mesh file (single frames) or frame directory
    #[arg(short, long)]
    out: PathBuf,
}

fn main() -> ExitCode {
    let args = mesh_core::cli::parse::<Args>();
    run_stage("stitch", || {
        args.common.init()?;
        let seg = Segmentation::load(&args.segmentation)?;
        let template = read_mesh(&args.template)?;
        if template.vertices.len() != seg.n_vertices {
            bail!(
                "{}: {} vertices but the segmentation has {}",
                args.template.display(),
                template.vertices.len(),
                seg.n_vertices
            );
        }
        let order = seg
            .tree_order()
            .with_context(|| args.segmentation.display().to_string())?;
        let mut stitcher = Stitcher::new(
            part_layout(&seg, template.faces.clone())
                .with_context(|| args.segmentation.display().to_string())?,
        );
        let mut parts = Vec::new();
        for &k in &order {
            let name = &seg.parts[k].name;
            let dir = args.parts.join(name);
            let path = if dir.is_dir() {
                dir
            } else {
                args.parts.join(format!("{name}.ply"))
            };
            let f = read_frames(&path)?;
            if f.frames[0].len() != seg.parts[k].vertices.len() {
                bail!(
                    "{}: {} vertices but part '{name}' has {}",
                    path.display(),
                    f.frames[0].len(),
                    seg.parts[k].vertices.len()
                );
            }
            parts.push(f);
        }
        let n_frames = parts[0].frames.len();
        if let Some(p) = parts.iter().find(|p| p.frames.len() != n_frames) {
            bail!(
                "part inputs disagree on the number of frames ({} vs {n_frames})",
                p.frames.len()
            );
        }
        let mut out = Vec::with_capacity(n_frames);
        let bar = mesh_core::cli::progress_bar(n_frames as u64, "stitch: frames", &args.common);
        for i in 0..n_frames {
            bar.inc(1);
            let frame: Vec<_> = parts.iter().map(|p| p.frames[i].clone()).collect();
            out.push(
                stitcher
                    .stitch(&frame)
                    .with_context(|| format!("frame {i}"))?
                    .vertices,
            );
        }
        bar.finish_and_clear();
        write_frames(&args.out, &template.faces, out, parts[0].is_dir)?;
        Ok(())
    })
}
