use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::bail;
use clap::Parser;
use mesh_core::artifact::Artifact;
use mesh_core::cli::{run_stage, CommonArgs};
use mesh_core::segmentation::Segmentation;
use mesh_core::sequence::MeshSequence;
use transfer::quality::measure;

/// Seam, closedness, part volume and edge-length statistics of predicted sequences against the truth (paper §6)
#[derive(Parser, Debug)]
#[command(
    name = "surface-quality",
    version,
    after_help = "e.g.: surface-quality --segmentation work/B/parts.seg --truth set/truth/B/punch out/transfer/A-to-B/punch/gpr-nn out/transfer/A-to-B/punch/gpr-nn+correct --out quality.json"
)]
struct Args {
    #[command(flatten)]
    common: CommonArgs,
    /// Segmentation artifact of the target (from segment)
    #[arg(long)]
    segmentation: PathBuf,
    /// Truth frame directory
    #[arg(long)]
    truth: PathBuf,
    /// Predicted frame directories (the target's topology, as many frames as the truth)
    #[arg(required = true)]
    predictions: Vec<PathBuf>,
    /// Output JSON: one record per prediction
    #[arg(short, long)]
    out: PathBuf,
}

fn main() -> ExitCode {
    let args = mesh_core::cli::parse::<Args>();
    run_stage("surface-quality", || {
        args.common.init()?;
        let seg = Segmentation::load(&args.segmentation)?;
        let truth = MeshSequence::load_dir(&args.truth)?;
        if truth.n_vertices() != seg.n_vertices {
            bail!(
                "{}: {} vertices but the segmentation has {}",
                args.truth.display(),
                truth.n_vertices(),
                seg.n_vertices
            );
        }
        let mut recs = Vec::new();
        let bar = mesh_core::cli::progress_bar(args.predictions.len() as u64, "surface-quality: predictions", &args.common);
        for p in &args.predictions {
            let pred = MeshSequence::load_dir(p)?;
            if pred.faces != truth.faces || pred.n_frames() != truth.n_frames() {
                bail!(
                    "{}: topology or frame count differs from {}",
                    p.display(),
                    args.truth.display()
                );
            }
            let q = measure(&truth.faces, &seg, &pred.frames, &truth.frames);
            recs.push(serde_json::json!({"prediction": p, "quality": q}));
            bar.inc(1);
        }
        bar.finish_and_clear();
        mesh_core::atomic::write_bytes_atomic(
            &args.out,
            serde_json::to_string_pretty(&recs)?.as_bytes(),
        )?;
        Ok(())
    })
}
