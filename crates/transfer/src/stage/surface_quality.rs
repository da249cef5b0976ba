//! The `surface-quality` stage: seam, closedness, part volume and edge-length statistics of
//! predicted sequences against the truth (CVPR §6).

use std::path::PathBuf;

use anyhow::bail;
use clap::Parser;
use mesh_core::artifact::Artifact;
use mesh_core::cli::CommonArgs;
use mesh_core::segmentation::Segmentation;
use mesh_core::sequence::MeshSequence;
use serde::Serialize;

use crate::quality::measure;

/// Seam, closedness, part volume and edge-length statistics of predicted sequences against the truth (paper §6)
#[derive(Parser, Debug, Serialize)]
#[command(
    name = "surface-quality",
    version,
    after_help = "e.g.: surface-quality --segmentation work/B/parts.seg --truth set/truth/B/punch out/transfer/A-to-B/punch/gpr-nn out/transfer/A-to-B/punch/gpr-nn+correct --out quality.json"
)]
pub struct Params {
    #[command(flatten)]
    #[serde(skip)]
    pub common: CommonArgs,
    /// Segmentation artifact of the target (from segment)
    #[arg(long)]
    pub segmentation: PathBuf,
    /// Truth frame directory
    #[arg(long)]
    pub truth: PathBuf,
    /// Predicted frame directories (the target's topology, as many frames as the truth)
    #[arg(required = true)]
    pub predictions: Vec<PathBuf>,
    /// Output JSON: one record per prediction
    #[arg(short, long)]
    pub out: PathBuf,
}

/// Writes one JSON record per prediction.
pub fn run(p: &Params) -> anyhow::Result<()> {
    let seg = Segmentation::load(&p.segmentation)?;
    let truth = MeshSequence::load_dir(&p.truth)?;
    if truth.n_vertices() != seg.n_vertices {
        bail!(
            "{}: {} vertices but the segmentation has {}",
            p.truth.display(),
            truth.n_vertices(),
            seg.n_vertices
        );
    }
    let mut recs = Vec::new();
    let bar = mesh_core::cli::progress_bar(p.predictions.len() as u64, "surface-quality: predictions", &p.common);
    for path in &p.predictions {
        let pred = MeshSequence::load_dir(path)?;
        if pred.faces != truth.faces || pred.n_frames() != truth.n_frames() {
            bail!(
                "{}: topology or frame count differs from {}",
                path.display(),
                p.truth.display()
            );
        }
        let q = measure(&truth.faces, &seg, &pred.frames, &truth.frames);
        recs.push(serde_json::json!({"prediction": path, "quality": q}));
        bar.inc(1);
    }
    bar.finish_and_clear();
    mesh_core::atomic::write_bytes_atomic(
        &p.out,
        serde_json::to_string_pretty(&recs)?.as_bytes(),
    )?;
    Ok(())
}
