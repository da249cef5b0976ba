use std::path::PathBuf;
use std::process::ExitCode;

use clap::Parser;
use gp::pca::Components;
use mesh_core::artifact::Artifact;
use mesh_core::cli::{run_stage, CommonArgs};
use mesh_core::io::read_mesh;
use mesh_core::segmentation::Segmentation;
use mesh_core::sequence::MeshSequence;
use capture::align::{align_motion_on, AlignedMotion};
use capture::part_pca::{fit, PartAlignment};
use transfer::reconstruct::{Reconstructor, Surface};
use transfer::representation::{rebuilt_error, truncation_rms, RepresentationRow};

/// Diagnose the representation error: a subject's own truth frames through part PCA and each surface method
#[derive(Parser, Debug)]
#[command(
    name = "representation-error",
    version,
    after_help = "e.g.: representation-error --template set/B/walk/000000.ply --segmentation work/B/parts.seg --truth set/truth/B/punch work/B/*.aligned --out work/B/representation.json"
)]
struct Args {
    #[command(flatten)]
    common: CommonArgs,
    /// Template mesh of the subject
    #[arg(long)]
    template: PathBuf,
    /// Segmentation artifact from `segment`
    #[arg(long)]
    segmentation: PathBuf,
    /// Truth frame directory of the subject (a motion not used for training)
    #[arg(long)]
    truth: PathBuf,
    /// Components per part
    #[arg(long, default_value_t = 20)]
    components: usize,
    /// Nearest training meshes of the correction
    #[arg(short = 'm', long, default_value_t = 3)]
    neighbours: usize,
    /// Aligned training motions of the subject
    #[arg(required = true)]
    motions: Vec<PathBuf>,
    /// Output JSON (rows and per-part truncation errors)
    #[arg(short, long)]
    out: PathBuf,
}

fn main() -> ExitCode {
    let args = mesh_core::cli::parse::<Args>();
    run_stage("representation-error", || {
        args.common.init()?;
        let template = read_mesh(&args.template)?;
        let seg = Segmentation::load(&args.segmentation)?;
        let motions = args
            .motions
            .iter()
            .map(AlignedMotion::load)
            .collect::<Result<Vec<_>, _>>()?;
        let refs: Vec<&AlignedMotion> = motions.iter().collect();
        let anchor = refs.first().map(|m| m.anchor.clone()).unwrap_or_default();
        let truth = align_motion_on(&template, &MeshSequence::load_dir(&args.truth)?, &anchor)?;
        let mut rows = Vec::new();
        let mut truncation = serde_json::Map::new();
        // 2 alignments x 4 surface methods x with and without PCA.
        let bar = mesh_core::cli::progress_bar(16, "representation-error: reconstructions", &args.common);
        for alignment in [PartAlignment::Body, PartAlignment::Part] {
            let (pca, _) = fit(
                &template.vertices,
                &seg,
                &refs,
                Components::Count(args.components),
                alignment,
            )?;
            truncation.insert(
                format!("{alignment:?}"),
                serde_json::to_value(truncation_rms(&pca, &truth)?)?,
            );
            for surface in [
                Surface::Assemble,
                Surface::Stitch,
                Surface::Correct,
                Surface::CorrectStitch,
            ] {
                let mut recon = Reconstructor::new(
                    &pca,
                    &seg,
                    &template.faces,
                    &refs,
                    surface,
                    args.neighbours,
                    1,
                )?;
                for through_pca in [false, true] {
                    let e = rebuilt_error(&pca, &mut recon, &truth, through_pca)?;
                    bar.inc(1);
                    mesh_core::info!(
                        "{alignment:?} {surface:?} through_pca={through_pca}: rms_pose_m {e:.4}"
                    );
                    rows.push(RepresentationRow {
                        alignment: format!("{alignment:?}"),
                        surface: format!("{surface:?}"),
                        through_pca,
                        rms_pose_m: e,
                    });
                }
            }
        }
        bar.finish_and_clear();
        let json = serde_json::json!({"truth": args.truth, "components": args.components, "rows": rows, "truncation_rms_m": truncation});
        mesh_core::atomic::write_bytes_atomic(
            &args.out,
            serde_json::to_string_pretty(&json)?.as_bytes(),
        )?;
        Ok(())
    })
}
