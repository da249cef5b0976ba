use std::path::PathBuf;
use std::process::ExitCode;

use clap::Parser;
use gp::pca::Components;
use mesh_core::artifact::Artifact;
use mesh_core::cli::{run_stage, CommonArgs};
use mesh_core::io::read_mesh;
use mesh_core::segmentation::Segmentation;
use capture::align::AlignedMotion;
use capture::part_pca;

/// Fit a PCA per body part on a subject's aligned training motions
#[derive(Parser, Debug)]
#[command(
    name = "pca-fit",
    version,
    after_help = "e.g.: pca-fit --template set/A/walk/000000.ply --parts work/A/parts.seg work/A/*.aligned --out work/A/pca.model"
)]
struct Args {
    #[command(flatten)]
    common: CommonArgs,
    /// Template mesh of the subject
    #[arg(long)]
    template: PathBuf,
    /// Segmentation artifact from `segment` (omit with --whole-body)
    #[arg(long, required_unless_present = "whole_body")]
    parts: Option<PathBuf>,
    /// Treat the whole body as one part (the paper's comparison)
    #[arg(long)]
    whole_body: bool,
    /// Components per part (the paper uses 20)
    #[arg(long, default_value_t = 20, conflicts_with = "variance")]
    components: usize,
    /// Keep the fewest components explaining this fraction of variance instead
    #[arg(long)]
    variance: Option<f64>,
    /// How each part is aligned before PCA: `body` = cut from the whole-body-aligned frames
    /// (assembly averages overlaps); `part` = also Procrustes per part (assembly re-orients
    /// children on their overlap band)
    #[arg(long, value_enum, default_value_t = part_pca::PartAlignment::Body)]
    part_alignment: part_pca::PartAlignment,
    /// Aligned training motions (artifacts from `align`)
    #[arg(required = true)]
    motions: Vec<PathBuf>,
    /// Output artifact (kind pca-model)
    #[arg(short, long)]
    out: PathBuf,
    /// Also write per-part explained variance and reconstruction error as JSON
    #[arg(long)]
    report: Option<PathBuf>,
}

fn main() -> ExitCode {
    let args = mesh_core::cli::parse::<Args>();
    run_stage("pca-fit", || {
        args.common.init()?;
        let template = read_mesh(&args.template)?;
        let parts = match &args.parts {
            Some(p) if !args.whole_body => Segmentation::load(p)?,
            _ => part_pca::whole_body(template.n_vertices()),
        };
        let motions = args
            .motions
            .iter()
            .map(AlignedMotion::load)
            .collect::<Result<Vec<_>, _>>()?;
        let choice = match args.variance {
            Some(r) => Components::ExplainedVariance(r),
            None => Components::Count(args.components),
        };
        let refs: Vec<&AlignedMotion> = motions.iter().collect();
        let (model, report) = part_pca::fit_with_progress(
            &template.vertices,
            &parts,
            &refs,
            choice,
            args.part_alignment,
            &mesh_core::cli::stage_progress(0, "parts fitted"),
        )?;
        let mut header = args
            .common
            .header("pca-fit", env!("CARGO_PKG_VERSION"))
            .with_params(&serde_json::json!({"components": args.components, "variance": args.variance, "whole_body": args.whole_body, "part_alignment": format!("{:?}", args.part_alignment)}))?
            .with_input(&args.template)?;
        if let (Some(p), false) = (&args.parts, args.whole_body) {
            header = header.with_input(p)?;
        }
        for m in &args.motions {
            header = header.with_input(m)?;
        }
        model.save(&args.out, &header)?;
        if let Some(r) = &args.report {
            let text = serde_json::to_string_pretty(&report)?;
            mesh_core::atomic::write_bytes_atomic(r, text.as_bytes())?;
        }
        Ok(())
    })
}
