//! The `pca-fit` stage: a PCA per body part (or of the whole body) of a subject's aligned
//! training motions.

use std::path::PathBuf;

use clap::Parser;
use gp::pca::Components;
use mesh_core::artifact::{sha256_file, Artifact};
use mesh_core::cli::CommonArgs;
use mesh_core::io::read_mesh;
use mesh_core::part_merge::{self, PartReports};
use mesh_core::segmentation::Segmentation;
use serde::Serialize;

use crate::motion_stream::MotionFiles;
use crate::part_pca::{self, PcaModel};
use crate::streamed_pca;

/// `--components`' default: the paper's 20 per part (`make transfer` uses it unless
/// PCA_COMPONENTS is set).
pub const COMPONENTS: usize = gp::pca::PAPER_COMPONENTS;

/// Fit a PCA per body part on a subject's aligned training motions
#[derive(Parser, Debug, Serialize)]
#[command(
    name = "pca-fit",
    version,
    after_help = "e.g.: pca-fit --template set/A/walk/000000.ply --segmentation work/A/parts.seg work/A/*.aligned --out work/A/pca.model"
)]
pub struct Params {
    #[command(flatten)]
    #[serde(skip)]
    pub common: CommonArgs,
    /// Template mesh of the subject
    #[arg(long)]
    pub template: PathBuf,
    /// Segmentation artifact from `segment` (omit with --whole-body)
    #[arg(long, required_unless_present = "whole_body")]
    pub segmentation: Option<PathBuf>,
    /// Treat the whole body as one part (the paper's comparison)
    #[arg(long)]
    pub whole_body: bool,
    /// Components per part (the paper uses 20)
    #[arg(long, default_value_t = COMPONENTS, conflicts_with = "variance")]
    pub components: usize,
    /// Keep the fewest components explaining this fraction of variance instead
    #[arg(long)]
    pub variance: Option<f64>,
    /// How each part is aligned before PCA: `body` = cut from the whole-body-aligned frames
    /// (assembly averages overlaps); `part` = also Procrustes per part (assembly re-orients
    /// children on their overlap band)
    #[arg(long, value_enum, default_value_t = part_pca::PartAlignment::default())]
    pub part_alignment: part_pca::PartAlignment,
    /// Fit only this part (a name of the segmentation, `body` with --whole-body) and write it
    /// alone, as kind pca-model-part (its --report of that part alone): `merge-parts` joins the
    /// parts (and their reports) into the whole model
    #[arg(long)]
    #[serde(skip)]
    pub part: Option<String>,
    /// Memory for the training frames' rows and the matrices they are reduced to, in MiB:
    /// the rows are held while they fit in half of it, otherwise the motions are read again
    /// pass by pass (the same PCA to rounding, components up to sign); the model comes on top
    #[arg(long, value_name = "MIB", default_value_t = mesh_core::cli::DEFAULT_MEMORY_BUDGET_MIB)]
    pub memory_budget: usize,
    /// Aligned training motions (artifacts from `align`)
    #[arg(required = true)]
    pub motions: Vec<PathBuf>,
    /// Output artifact (kind pca-model)
    #[arg(short, long)]
    pub out: PathBuf,
    /// Also write per-part explained variance and reconstruction error as JSON
    #[arg(long)]
    pub report: Option<PathBuf>,
}

/// Writes the `--report` (if asked) and the PCA model; the header records `p`, the template, the
/// segmentation (unless `--whole-body`) and the motions. With `--part` the model holds that
/// part only, written as a piece (`mesh_core::part_merge`).
pub fn run(p: &Params) -> anyhow::Result<()> {
    let template = read_mesh(&p.template)?;
    let parts = match &p.segmentation {
        Some(seg) if !p.whole_body => Segmentation::load(seg)?,
        _ => part_pca::whole_body(template.n_vertices()),
    };
    let choice = match p.variance {
        Some(r) => Components::ExplainedVariance(r),
        None => Components::Count(p.components),
    };
    let template_sha256 = sha256_file(&p.template)?;
    let names: Vec<String> = parts.parts.iter().map(|q| q.name.clone()).collect();
    let only = match &p.part {
        Some(name) => {
            let source = match (&p.segmentation, p.whole_body) {
                (Some(seg), false) => seg,
                _ => &p.template,
            };
            Some(part_merge::select(&names, name, source)?)
        }
        None => None,
    };
    let (mut model, report) = streamed_pca::fit_streamed(
        &template.vertices,
        &parts,
        &mut MotionFiles::new(&p.motions, &template_sha256),
        choice,
        p.part_alignment,
        only,
        p.memory_budget.saturating_mul(1 << 20),
        &mesh_core::cli::stage_progress(0, "parts fitted"),
    )?;
    model.template_sha256 = template_sha256;
    let mut header = p
        .common
        .header("pca-fit", env!("CARGO_PKG_VERSION"))
        .with_params(p)?
        .with_input(&p.template)?;
    if let (Some(seg), false) = (&p.segmentation, p.whole_body) {
        header = header.with_input(seg)?;
    }
    for m in &p.motions {
        header = header.with_input(m)?;
    }
    // The report first: the model's presence says both are complete.
    if let Some(r) = &p.report {
        let text = PcaModel::report_text(&report)?;
        mesh_core::atomic::write_bytes_atomic(r, text.as_bytes())?;
    }
    match only {
        Some(k) => part_merge::save_piece::<PcaModel>(&p.out, &header, &names, k, model)?,
        None => model.save(&p.out, &header)?,
    }
    Ok(())
}
