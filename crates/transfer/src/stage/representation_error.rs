//! The `representation-error` stage: a subject's own truth frames rebuilt through part PCA and
//! each surface method, to separate the representation's error from the regression's.

use std::path::PathBuf;

use capture::align::{align_motion_on, AlignedMotion};
use capture::part_pca::{fit, PartAlignment};
use clap::Parser;
use gp::pca::Components;
use mesh_core::artifact::Artifact;
use mesh_core::cli::CommonArgs;
use mesh_core::io::read_mesh;
use mesh_core::segmentation::Segmentation;
use mesh_core::sequence::MeshSequence;
use serde::Serialize;

use crate::reconstruct::{Reconstructor, Surface};
use crate::representation::{rebuilt_error, truncation_rms, RepresentationRow};

/// Diagnose the representation error: a subject's own truth frames through part PCA and each surface method
#[derive(Parser, Debug, Serialize)]
#[command(
    name = "representation-error",
    version,
    after_help = "e.g.: representation-error --template set/B/walk/000000.ply --segmentation work/B/parts.seg --truth set/truth/B/punch work/B/*.aligned --out work/B/representation.json"
)]
pub struct Params {
    #[command(flatten)]
    #[serde(skip)]
    pub common: CommonArgs,
    /// Template mesh of the subject
    #[arg(long)]
    pub template: PathBuf,
    /// Segmentation artifact from `segment`
    #[arg(long)]
    pub segmentation: PathBuf,
    /// Truth frame directory of the subject (a motion not used for training)
    #[arg(long)]
    pub truth: PathBuf,
    /// Components per part
    #[arg(long, default_value_t = 20)]
    pub components: usize,
    /// Nearest training meshes of the correction
    #[arg(short = 'm', long, default_value_t = 3)]
    pub neighbours: usize,
    /// Aligned training motions of the subject
    #[arg(required = true)]
    pub motions: Vec<PathBuf>,
    /// Output JSON (rows and per-part truncation errors)
    #[arg(short, long)]
    pub out: PathBuf,
}

/// Writes the rows and the per-part truncation errors as JSON.
pub fn run(p: &Params) -> anyhow::Result<()> {
    let template = read_mesh(&p.template)?;
    let seg = Segmentation::load(&p.segmentation)?;
    let motions = p
        .motions
        .iter()
        .map(AlignedMotion::load)
        .collect::<Result<Vec<_>, _>>()?;
    let refs: Vec<&AlignedMotion> = motions.iter().collect();
    let anchor = refs.first().map(|m| m.anchor.clone()).unwrap_or_default();
    let truth = align_motion_on(&template, &MeshSequence::load_dir(&p.truth)?, &anchor)?;
    let mut rows = Vec::new();
    let mut truncation = serde_json::Map::new();
    // 2 alignments x 4 surface methods x with and without PCA.
    let bar = mesh_core::cli::progress_bar(16, "representation-error: reconstructions", &p.common);
    for alignment in [PartAlignment::Body, PartAlignment::Part] {
        let (pca, _) = fit(
            &template.vertices,
            &seg,
            &refs,
            Components::Count(p.components),
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
                p.neighbours,
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
            recon.finish();
        }
    }
    bar.finish_and_clear();
    let json = serde_json::json!({"truth": p.truth, "components": p.components, "rows": rows, "truncation_rms_m": truncation});
    mesh_core::atomic::write_bytes_atomic(
        &p.out,
        serde_json::to_string_pretty(&json)?.as_bytes(),
    )?;
    Ok(())
}
