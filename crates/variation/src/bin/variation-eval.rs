use std::path::PathBuf;
use std::process::ExitCode;

use clap::Parser;
use mesh_core::artifact::Artifact;
use mesh_core::cli::{run_stage, CommonArgs};
use variation::evaluate::evaluate;
use variation::group::Group;
use variation::train::VariationModel;

/// Measure a variation model: GPDM vs PCA reconstruction (fig. 4), guided vs unguided latent blending (fig. 7b), latent plots (figs. 3, 5)
#[derive(Parser, Debug)]
#[command(
    name = "variation-eval",
    version,
    after_help = "e.g.: variation-eval --model work/locomotion.model --group work/locomotion.group --plots out/variation/plots --out work/locomotion-eval.json"
)]
struct Args {
    #[command(flatten)]
    common: CommonArgs,
    /// Trained model (kind variation-model, from gpdm-train)
    #[arg(long)]
    model: PathBuf,
    /// The prealigned group the model was trained on
    #[arg(long)]
    group: PathBuf,
    /// Folder for the latent-trajectory plots (PNG)
    #[arg(long)]
    plots: Option<PathBuf>,
    /// Output report (JSON)
    #[arg(short, long)]
    out: PathBuf,
}

fn main() -> ExitCode {
    let args = mesh_core::cli::parse::<Args>();
    run_stage("variation-eval", || {
        args.common.init()?;
        let model = VariationModel::load(&args.model)?;
        let group = Group::load(&args.group)?;
        let spin = mesh_core::cli::spinner(
            &format!("variation-eval: {} sequences x {} parts", model.sequences.len(), model.parts.len()),
            &args.common,
        );
        let report = evaluate(&model, &group, args.plots.as_deref(), args.common.seed)?;
        spin.finish_and_clear();
        mesh_core::atomic::write_bytes_atomic(
            &args.out,
            (serde_json::to_string_pretty(&report)? + "\n").as_bytes(),
        )?;
        Ok(())
    })
}
