//! The `stitch` stage: corrected part meshes stitched into one mesh with the template's topology
//! along optimal loops (CVPR §6.2).

use std::path::PathBuf;

use anyhow::{bail, Context};
use clap::Parser;
use mesh_core::artifact::Artifact;
use mesh_core::cli::CommonArgs;
use mesh_core::io::read_mesh;
use mesh_core::segmentation::Segmentation;
use serde::Serialize;

use crate::frames::{read_frames, write_frames};
use crate::segmentation::part_layout;
use crate::stitch::Stitcher;

/// Stitch corrected part meshes into one mesh with the template's topology along optimal loops (transfer paper §6.2)
#[derive(Parser, Debug, Serialize)]
#[command(
    name = "stitch",
    version,
    after_help = "e.g.: stitch work/corrected --segmentation work/B/parts.seg --template set/B/walk/000000.ply --out work/stitched"
)]
pub struct Params {
    #[command(flatten)]
    #[serde(skip)]
    pub common: CommonArgs,
    /// Directory holding one `<part name>.ply` (one frame) or `<part name>/` frame directory per part
    pub parts: PathBuf,
    /// Segmentation artifact of the target template (from `segment`)
    #[arg(long)]
    pub segmentation: PathBuf,
    /// Target template mesh (its faces give the output topology)
    #[arg(long)]
    pub template: PathBuf,
    /// Output mesh file (single frames) or frame directory
    #[arg(short, long)]
    pub out: PathBuf,
}

/// Writes the stitched mesh (or frame folder, when the parts are frame folders).
pub fn run(p: &Params) -> anyhow::Result<()> {
    let seg = Segmentation::load(&p.segmentation)?;
    let template = read_mesh(&p.template)?;
    if template.vertices.len() != seg.n_vertices {
        bail!(
            "{}: {} vertices but the segmentation has {}",
            p.template.display(),
            template.vertices.len(),
            seg.n_vertices
        );
    }
    let order = seg
        .tree_order()
        .with_context(|| p.segmentation.display().to_string())?;
    let mut stitcher = Stitcher::new(
        part_layout(&seg, template.faces.clone())
            .with_context(|| p.segmentation.display().to_string())?,
    );
    let mut parts = Vec::new();
    for &k in &order {
        let name = &seg.parts[k].name;
        let dir = p.parts.join(name);
        let path = if dir.is_dir() {
            dir
        } else {
            p.parts.join(format!("{name}.ply"))
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
    if let Some(part) = parts.iter().find(|part| part.frames.len() != n_frames) {
        bail!(
            "part inputs disagree on the number of frames ({} vs {n_frames})",
            part.frames.len()
        );
    }
    let mut out = Vec::with_capacity(n_frames);
    let bar = mesh_core::cli::progress_bar(n_frames as u64, "stitch: frames", &p.common);
    for i in 0..n_frames {
        bar.inc(1);
        let frame: Vec<_> = parts.iter().map(|part| part.frames[i].clone()).collect();
        out.push(
            stitcher
                .stitch(&frame)
                .with_context(|| format!("frame {i}"))?
                .vertices,
        );
    }
    bar.finish_and_clear();
    write_frames(&p.out, &template.faces, out, parts[0].is_dir)?;
    Ok(())
}
