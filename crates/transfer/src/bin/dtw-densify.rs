use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{bail, Context};
use clap::Parser;
use mesh_core::artifact::Artifact;
use mesh_core::capture_set::SetSpec;
use mesh_core::cli::{run_stage, CommonArgs};
use capture::align::AlignedMotion;
use transfer::densify::{densify, path_error, Correspondences, PAPER_SIGMA2};
use capture::part_pca::PcaModel;

/// Densify one training pair's key-pose correspondences by DTW on a Bayesian-linear-regression cost
#[derive(Parser, Debug)]
#[command(
    name = "dtw-densify",
    version,
    after_help = "e.g.: dtw-densify --set set --motion walk --source-pca work/A/pca.model --target-pca work/B/pca.model \\\n        work/A/walk.aligned work/B/walk.aligned --out work/pairs/walk.corr"
)]
struct Args {
    #[command(flatten)]
    common: CommonArgs,
    /// Capture-set folder (its set.json: key-poses and, if present, true correspondences)
    #[arg(long)]
    set: PathBuf,
    /// Training pair, by its source motion's name
    #[arg(long)]
    motion: String,
    /// Source subject's PCA model
    #[arg(long)]
    source_pca: PathBuf,
    /// Target subject's PCA model
    #[arg(long)]
    target_pca: PathBuf,
    /// Observation noise variance σ² of the key-pose regression (eq. 1)
    #[arg(long, default_value_t = PAPER_SIGMA2)]
    sigma2: f64,
    /// Aligned source motion
    source: PathBuf,
    /// Aligned target motion
    target: PathBuf,
    /// Output artifact (kind correspondences)
    #[arg(short, long)]
    out: PathBuf,
    /// Write the path's distance to the set's true correspondences (when present) as JSON
    #[arg(long)]
    report: Option<PathBuf>,
}

fn main() -> ExitCode {
    let args = mesh_core::cli::parse::<Args>();
    run_stage("dtw-densify", || {
        args.common.init()?;
        let set_json = args.set.join("set.json");
        let set = SetSpec::load(&set_json)?;
        let Some(pair) = set.train.iter().find(|p| p.source == args.motion) else {
            bail!("{}: no training pair with source motion '{}'", set_json.display(), args.motion);
        };
        let (src_pca, tgt_pca) = (PcaModel::load(&args.source_pca)?, PcaModel::load(&args.target_pca)?);
        let (src, tgt) = (AlignedMotion::load(&args.source)?, AlignedMotion::load(&args.target)?);
        let src_names: Vec<&str> = src_pca.parts.iter().map(|p| p.name.as_str()).collect();
        let tgt_names: Vec<&str> = tgt_pca.parts.iter().map(|p| p.name.as_str()).collect();
        if src_names != tgt_names {
            bail!("{}: parts {:?} differ from the target's {:?}", args.source_pca.display(), src_names, tgt_names);
        }
        let xs = src_pca.encode(&src).with_context(|| args.source.display().to_string())?;
        let ys = tgt_pca.encode(&tgt).with_context(|| args.target.display().to_string())?;
        let pairs = densify(&xs, &ys, &pair.keyposes, args.sigma2).with_context(|| set_json.display().to_string())?;
        let result = Correspondences {
            source_motion: pair.source.clone(),
            target_motion: pair.target.clone(),
            keyposes: pair.keyposes.clone(),
            pairs,
        };
        let header = args
            .common
            .header("dtw-densify", env!("CARGO_PKG_VERSION"))
            .with_params(&serde_json::json!({"pair": args.motion, "sigma2": args.sigma2}))?
            .with_input(&set_json)?
            .with_input(&args.source_pca)?
            .with_input(&args.target_pca)?
            .with_input(&args.source)?
            .with_input(&args.target)?;
        result.save(&args.out, &header)?;
        if let Some(report) = &args.report {
            let target_fps = tgt.capture.require_fps().with_context(|| args.target.display().to_string())?;
            let truth: Option<Vec<[usize; 2]>> = pair
                .extra
                .get("correspondences")
                .map(|v| serde_json::from_value(v.clone()))
                .transpose()
                .with_context(|| format!("{}: pair '{}': bad correspondences", set_json.display(), args.motion))?;
            let json = serde_json::json!({
                "pair": args.motion,
                "pairs": result.pairs.len(),
                "error_vs_truth": truth.map(|t| path_error(&result.pairs, &t, target_fps)),
            });
            mesh_core::atomic::write_bytes_atomic(report, serde_json::to_string_pretty(&json)?.as_bytes())?;
        }
        Ok(())
    })
}
