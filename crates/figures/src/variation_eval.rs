//! The `variation-eval` stage: a variation model measured on its group: GPDM vs PCA reconstruction
//! (3DV fig. 4), guided vs unguided latent blending (fig. 7b) and the latent plots (figs. 3, 5).

use std::path::PathBuf;

use anyhow::Context;
use clap::Parser;
use mesh_core::artifact::Artifact;
use mesh_core::cli::CommonArgs;
use serde::Serialize;

use variation::evaluate::evaluate;
use variation::group::Group;
use variation::train::VariationModel;

use crate::variation_plots::write_eval_plots;

/// Measure a variation model: GPDM vs PCA reconstruction (fig. 4), guided vs unguided latent blending (fig. 7b), latent plots (figs. 3, 5)
#[derive(Parser, Debug, Serialize)]
#[command(
    name = "variation-eval",
    version,
    after_help = "e.g.: variation-eval --model work/locomotion.model --group work/locomotion.group --plots out/variation/plots --out work/locomotion-eval.json"
)]
pub struct Params {
    #[command(flatten)]
    #[serde(skip)]
    pub common: CommonArgs,
    /// Trained model (kind variation-model, from gpdm-train)
    #[arg(long)]
    pub model: PathBuf,
    /// The prealigned group the model was trained on
    #[arg(long)]
    pub group: PathBuf,
    /// Folder for the latent-trajectory plots (PNG)
    #[arg(long)]
    pub plots: Option<PathBuf>,
    /// Output report (JSON)
    #[arg(short, long)]
    pub out: PathBuf,
}

/// Writes the JSON report (and the plots into `--plots` when asked).
pub fn run(p: &Params) -> anyhow::Result<()> {
    let model = VariationModel::load(&p.model)?;
    let group = Group::load(&p.group)?;
    variation::trained_on::check(&model, &group)
        .with_context(|| format!("{} with {}", p.model.display(), p.group.display()))?;
    let spin = mesh_core::cli::spinner(
        &format!("variation-eval: {} sequences x {} parts", model.sequences.len(), model.parts.len()),
        &p.common,
    );
    let (mut report, figures) = evaluate(&model, &group, p.plots.is_some(), p.common.seed)?;
    if let (Some(dir), Some(figures)) = (&p.plots, &figures) {
        report.plots = write_eval_plots(dir, &report, figures)?;
    }
    spin.finish_and_clear();
    mesh_core::atomic::write_bytes_atomic(
        &p.out,
        (serde_json::to_string_pretty(&report)? + "\n").as_bytes(),
    )?;
    Ok(())
}
