//! The `segment` stage: a subject's template cut into overlapping parts along its curves.

use std::path::PathBuf;

use anyhow::Context;
use clap::Parser;
use mesh_core::artifact::Artifact;
use mesh_core::capture_set::SubjectSpec;
use mesh_core::cli::CommonArgs;
use mesh_core::io::read_mesh;
use serde::Serialize;

/// Cut a subject's template into overlapping body parts along the curves of its subject.json
#[derive(Parser, Debug, Serialize)]
#[command(
    name = "segment",
    version,
    after_help = "e.g.: segment set/A/subject.json --template set/A/walk/000000.ply --out work/A/parts.seg"
)]
pub struct Params {
    #[command(flatten)]
    #[serde(skip)]
    pub common: CommonArgs,
    /// The subject's subject.json (part tree and curves)
    pub subject: PathBuf,
    /// Template mesh the curve indices refer to
    #[arg(long)]
    pub template: PathBuf,
    /// Output artifact (kind segmentation)
    #[arg(short, long)]
    pub out: PathBuf,
}

/// Writes the segmentation; the header records `p` and both inputs' hashes.
pub fn run(p: &Params) -> anyhow::Result<()> {
    let subject = SubjectSpec::load(&p.subject)?;
    let template = read_mesh(&p.template)?;
    let parts = mesh_core::segmentation::segment(&template, &subject)
        .with_context(|| p.subject.display().to_string())?;
    let header = p
        .common
        .header("segment", env!("CARGO_PKG_VERSION"))
        .with_params(p)?
        .with_input(&p.subject)?
        .with_input(&p.template)?;
    parts.save(&p.out, &header)?;
    Ok(())
}
