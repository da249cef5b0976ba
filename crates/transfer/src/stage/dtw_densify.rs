//! The `dtw-densify` stage: one training pair's key-pose correspondences made dense by DTW on
//! the Bayesian-linear-regression association cost (CVPR eqs. 1-7).

use std::path::PathBuf;

use anyhow::{bail, Context};
use clap::Parser;
use mesh_core::artifact::Artifact;
use mesh_core::capture_set::SetSpec;
use mesh_core::cli::CommonArgs;
use serde::Serialize;

use crate::densify::{densify, path_error, Correspondences, PAPER_SIGMA2};
use capture::motion_stream::read_encoded;
use capture::part_pca::PcaModel;

/// Densify one training pair's key-pose correspondences by DTW on a Bayesian-linear-regression cost
#[derive(Parser, Debug, Serialize)]
#[command(
    name = "dtw-densify",
    version,
    after_help = "e.g.: dtw-densify --set set --motion walk --source-pca work/A/pca.model --target-pca work/B/pca.model \\\n        work/A/walk.aligned work/B/walk.aligned --out work/pairs/walk.corr"
)]
pub struct Params {
    #[command(flatten)]
    #[serde(skip)]
    pub common: CommonArgs,
    /// Capture-set folder (its set.json: key-poses and, if present, true correspondences)
    #[arg(long)]
    pub set: PathBuf,
    /// Training pair, by its source motion's name
    #[arg(long)]
    pub motion: String,
    /// Source subject's PCA model
    #[arg(long)]
    pub source_pca: PathBuf,
    /// Target subject's PCA model
    #[arg(long)]
    pub target_pca: PathBuf,
    /// Observation noise variance σ² of the key-pose regression (CVPR eq. 1)
    #[arg(long, default_value_t = PAPER_SIGMA2)]
    pub sigma2: f64,
    /// Aligned source motion
    pub source: PathBuf,
    /// Aligned target motion
    pub target: PathBuf,
    /// Output artifact (kind correspondences)
    #[arg(short, long)]
    pub out: PathBuf,
    /// Write the path's distance to the set's true correspondences (when present) as JSON
    #[arg(long)]
    pub report: Option<PathBuf>,
}

/// Writes the correspondences (and the `--report`); the header records `p`, `set.json`, both
/// PCA models and both motions. Holds each motion's PCA coefficients, never its frames.
pub fn run(p: &Params) -> anyhow::Result<()> {
    let set_json = p.set.join("set.json");
    let set = SetSpec::load(&set_json)?;
    let Some(pair) = set.train.iter().find(|t| t.source == p.motion) else {
        bail!("{}: no training pair with source motion '{}'", set_json.display(), p.motion);
    };
    let (src_pca, tgt_pca) = (PcaModel::load(&p.source_pca)?, PcaModel::load(&p.target_pca)?);
    let src_names: Vec<&str> = src_pca.parts.iter().map(|q| q.name.as_str()).collect();
    let tgt_names: Vec<&str> = tgt_pca.parts.iter().map(|q| q.name.as_str()).collect();
    if src_names != tgt_names {
        bail!("{}: parts {:?} differ from the target's {:?}", p.source_pca.display(), src_names, tgt_names);
    }
    // The cost compares frames by their PCA coefficients: each motion is encoded as it is read,
    // and neither is held.
    let (xs, _, src_sha) = read_encoded(&p.source, &src_pca)?;
    let (ys, tgt, tgt_sha) = read_encoded(&p.target, &tgt_pca)?;
    let pairs = densify(&xs, &ys, &pair.keyposes, p.sigma2).with_context(|| set_json.display().to_string())?;
    let result = Correspondences {
        source_motion: pair.source.clone(),
        target_motion: pair.target.clone(),
        keyposes: pair.keyposes.clone(),
        pairs,
    };
    let header = p
        .common
        .header("dtw-densify", env!("CARGO_PKG_VERSION"))
        .with_params(p)?
        .with_input(&set_json)?
        .with_input(&p.source_pca)?
        .with_input(&p.target_pca)?
        .with_input_hashed(&p.source, src_sha)
        .with_input_hashed(&p.target, tgt_sha);
    result.save(&p.out, &header)?;
    if let Some(report) = &p.report {
        let target_fps = tgt.capture.require_fps().with_context(|| p.target.display().to_string())?;
        let truth: Option<Vec<[usize; 2]>> = pair
            .extra
            .get("correspondences")
            .map(|v| serde_json::from_value(v.clone()))
            .transpose()
            .with_context(|| format!("{}: pair '{}': bad correspondences", set_json.display(), p.motion))?;
        let json = serde_json::json!({
            "pair": p.motion,
            "pairs": result.pairs.len(),
            "error_vs_truth": truth.map(|t| path_error(&result.pairs, &t, target_fps)),
        });
        mesh_core::atomic::write_bytes_atomic(report, serde_json::to_string_pretty(&json)?.as_bytes())?;
    }
    Ok(())
}
