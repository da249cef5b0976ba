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

use crate::frames::{frames_per_block, read_frames, write_frames, FrameBlocks};
use nalgebra::Vector3;
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
    // Each part's frames: a frame directory read a block at a time, or one mesh file.
    enum Part {
        Dir(FrameBlocks),
        File(Vec<Vector3<f64>>),
    }
    let mut parts = Vec::new();
    for &k in &order {
        let name = &seg.parts[k].name;
        let dir = p.parts.join(name);
        let (part, path, n_vertices) = if dir.is_dir() {
            let b = FrameBlocks::open(&dir)?;
            let n = b.n_vertices;
            (Part::Dir(b), dir, n)
        } else {
            let path = p.parts.join(format!("{name}.ply"));
            let mut f = read_frames(&path)?;
            let n = f.frames[0].len();
            (Part::File(f.frames.swap_remove(0)), path, n)
        };
        if n_vertices != seg.parts[k].vertices.len() {
            bail!(
                "{}: {n_vertices} vertices but part '{name}' has {}",
                path.display(),
                seg.parts[k].vertices.len()
            );
        }
        parts.push(part);
    }
    let count = |part: &Part| match part {
        Part::Dir(b) => b.n_frames(),
        Part::File(_) => 1,
    };
    let n_frames = count(&parts[0]);
    if let Some(part) = parts.iter().find(|part| count(part) != n_frames) {
        bail!("part inputs disagree on the number of frames ({} vs {n_frames})", count(part));
    }
    let bar = mesh_core::cli::progress_bar(n_frames as u64, "stitch: frames", &p.common);
    let mut stitch_block = |range: std::ops::Range<usize>| -> anyhow::Result<Vec<Vec<Vector3<f64>>>> {
        let frames: Vec<Vec<Vec<Vector3<f64>>>> = parts
            .iter()
            .map(|part| match part {
                Part::Dir(b) => b.block(range.clone()),
                Part::File(v) => Ok(vec![v.clone()]),
            })
            .collect::<Result<_, _>>()?;
        range
            .clone()
            .enumerate()
            .map(|(j, i)| {
                bar.inc(1);
                let frame: Vec<_> = frames.iter().map(|part| part[j].clone()).collect();
                Ok(stitcher.stitch(&frame).with_context(|| format!("frame {i}"))?.vertices)
            })
            .collect()
    };
    if !matches!(parts[0], Part::Dir(_)) {
        let out = stitch_block(0..1)?;
        bar.finish_and_clear();
        write_frames(&p.out, &template.faces, out, false)?;
        return Ok(());
    }
    let writer = mesh_core::io::ply_frames::PlyFrames::new(template.vertices.len(), &template.faces);
    let block = frames_per_block(template.vertices.len());
    writer.write_dir_streamed(&p.out, None, |push| {
        for start in (0..n_frames).step_by(block) {
            let stitched = stitch_block(start..(start + block).min(n_frames)).map_err(|e| mesh_core::Error::invalid(format!("{e:#}")))?;
            stitched.iter().try_for_each(|f| push(f))?;
        }
        Ok(())
    })?;
    bar.finish_and_clear();
    Ok(())
}
