//! The `paper-figure` stage: CVPR figure 3 (the BLR cost matrix of a training pair with its DTW
//! path), figure 5 (a body part before and after the §6.1 correction) and the per-frame confidence
//! of a transfer, one subcommand each.

use std::path::PathBuf;

use anyhow::{bail, Context};
use clap::{Args as ClapArgs, Parser, Subcommand};
use mesh_core::artifact::Artifact;
use mesh_core::capture_set::SetSpec;
use mesh_core::cli::CommonArgs;
use mesh_core::segmentation::Segmentation;
use mesh_core::sequence::MeshSequence;
use serde::Serialize;

use transfer::densify::PAPER_SIGMA2;
use crate::{
    correction_example, cost_and_path, load_confidence, load_eval, ConfidenceFigure, CostFigure,
    DEFAULT_EXTRAPOLATION_THRESHOLD,
};
use transfer::gpr_model::GprModel;
use transfer::learning_curves::true_correspondences;
use capture::motion_stream::read_encoded;
use capture::part_pca::PcaModel;
use transfer::reconstruct::{training_part_meshes, Stride};

/// The paper's figures 3 (BLR cost matrix with the DTW path) and 5 (a body part correction example), and the per-frame confidence of a transfer
#[derive(Parser, Debug, Serialize)]
#[command(
    name = "paper-figure",
    version,
    after_help = "e.g.: paper-figure cost-matrix --set set --motion walk --source-pca work/A/pca.model --target-pca work/B/pca.model \\\n        work/A/walk.aligned work/B/walk.aligned --out figures/fig3-walk.png\n      paper-figure correction --model work/models/A-to-B/gpr-nn.model --source-pca work/A/pca.model --target-pca work/B/pca.model \\\n        --segmentation work/B/parts.seg --target-training work/B/walk.aligned --truth set/truth/B/punch work/A/punch.aligned --out figures/fig5-punch.png\n      paper-figure confidence --confidence work/confidence/A-to-B/punch.json --eval work/eval/A-to-B/punch/gpr-nn.json --out figures/confidence-punch.png"
)]
pub struct Params {
    #[command(subcommand)]
    #[serde(flatten)]
    pub figure: Figure,
}

/// The figure drawn, recorded as `"figure": "<subcommand>"` beside its options.
#[derive(Subcommand, Debug, Serialize)]
#[serde(tag = "figure", rename_all = "kebab-case")]
pub enum Figure {
    /// CVPR figure 3: -log P_ij of one training pair (eqs. 1-6), the DTW path (eq. 7), key-poses and true pairs
    CostMatrix(CostArgs),
    /// CVPR figure 5: a predicted part before / after the §6.1 correction, and its nearest training meshes
    Correction(CorrectionArgs),
    /// Per frame: nearest distance and variance ratio of every part (gpr-predict --confidence), the pose error (evaluate)
    Confidence(ConfidenceArgs),
}

#[derive(ClapArgs, Debug, Serialize)]
pub struct CostArgs {
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
    /// Output PNG (an SVG is written next to it unless --no-svg)
    #[arg(short, long)]
    pub out: PathBuf,
    #[arg(long)]
    pub no_svg: bool,
}

#[derive(ClapArgs, Debug, Serialize)]
pub struct CorrectionArgs {
    #[command(flatten)]
    #[serde(skip)]
    pub common: CommonArgs,
    /// Transfer model (gpr-train)
    #[arg(long)]
    pub model: PathBuf,
    /// Source subject's PCA model
    #[arg(long)]
    pub source_pca: PathBuf,
    /// Target subject's PCA model
    #[arg(long)]
    pub target_pca: PathBuf,
    /// Target subject's segmentation (segment)
    #[arg(long)]
    pub segmentation: PathBuf,
    /// Target's aligned training motions: the correction's training part meshes (repeat)
    #[arg(long = "target-training", required = true)]
    pub target_training: Vec<PathBuf>,
    /// Memory for the training part meshes: every training frame while they fit, else every 2nd, 4th, ... (as gpr-predict)
    #[arg(long, value_name = "MIB", default_value_t = mesh_core::cli::DEFAULT_MEMORY_BUDGET_MIB)]
    pub memory_budget: usize,
    /// Nearest training part meshes blended by the correction (the paper's M)
    #[arg(short = 'm', long, default_value_t = surface::correct::DEFAULT_NEIGHBOURS)]
    pub neighbours: usize,
    /// Part to show [default: the part and frame farthest from every training mesh]
    #[arg(long)]
    pub part: Option<String>,
    /// Source frame to show [default: see --part]
    #[arg(long, value_name = "N")]
    pub source_frame: Option<usize>,
    /// The target's true sequence of the motion (folder of frames): drawn last, and scored in --report
    #[arg(long)]
    pub truth: Option<PathBuf>,
    /// Panel size in pixels
    #[arg(long, default_value_t = 360)]
    pub size: u32,
    /// View: front, side, three-quarter or AZIMUTH,ELEVATION
    #[arg(long, default_value = "three-quarter")]
    pub camera: String,
    /// Aligned source motion (align)
    pub motion: PathBuf,
    /// Output PNG
    #[arg(short, long)]
    pub out: PathBuf,
    /// Write the example's numbers (nearest distances, errors to the truth) as JSON
    #[arg(long)]
    pub report: Option<PathBuf>,
}

#[derive(ClapArgs, Debug, Serialize)]
pub struct ConfidenceArgs {
    #[command(flatten)]
    #[serde(skip)]
    pub common: CommonArgs,
    /// Confidence JSON of one transferred motion (gpr-predict --confidence)
    #[arg(long)]
    pub confidence: PathBuf,
    /// Evaluate record of the same motion (transfer-eval --out): adds the per-frame pose error panel
    #[arg(long)]
    pub eval: Option<PathBuf>,
    /// Shade the frames where some body part's nearest distance is at least this
    #[arg(long, default_value_t = DEFAULT_EXTRAPOLATION_THRESHOLD)]
    pub threshold: f64,
    /// Title [default: direction, motion and method of --eval]
    #[arg(long)]
    pub title: Option<String>,
    /// Output PNG (an SVG is written next to it unless --no-svg)
    #[arg(short, long)]
    pub out: PathBuf,
    #[arg(long)]
    pub no_svg: bool,
}

fn confidence(a: &ConfidenceArgs) -> anyhow::Result<()> {
    if !(a.threshold.is_finite() && a.threshold >= 0.0) {
        bail!("--threshold {}: expected a non-negative number", a.threshold);
    }
    let conf = load_confidence(&a.confidence)?;
    let eval = a.eval.as_ref().map(|p| load_eval(p, conf.frames, &a.confidence)).transpose()?;
    let fig = ConfidenceFigure::new(&conf, eval.as_ref(), a.title.clone(), a.threshold);
    mesh_core::info!("{}", fig.caption);
    if eval.is_some() {
        match fig.correlation {
            Some(r) => mesh_core::info!("pearson r = {r:.4} over {} frames", fig.frames),
            None => mesh_core::info!("pearson r undefined over {} frames (a constant series)", fig.frames),
        }
    }
    let svg = a.out.with_extension("svg");
    fig.write(&a.out, (!a.no_svg).then_some(svg.as_path()))?;
    Ok(())
}

fn cost_matrix(a: &CostArgs) -> anyhow::Result<()> {
    let set_json = a.set.join("set.json");
    let set = SetSpec::load(&set_json)?;
    let Some(pair) = set.train.iter().find(|p| p.source == a.motion) else {
        bail!("{}: no training pair with source motion '{}'", set_json.display(), a.motion);
    };
    let truth = true_correspondences(&set, &set_json, &a.motion).ok().map(|t| t.1);
    let (sp, tp) = (PcaModel::load(&a.source_pca)?, PcaModel::load(&a.target_pca)?);
    let (xs, _, _) = read_encoded(&a.source, &sp)?;
    let (ys, _, _) = read_encoded(&a.target, &tp)?;
    let (cost, path) = cost_and_path(&xs, &ys, &pair.keyposes, a.sigma2).with_context(|| set_json.display().to_string())?;
    let fig = CostFigure {
        title: format!("{} / {}: -log P_ij (eqs. 1-6), DTW path (eq. 7)", pair.source, pair.target),
        cost,
        path,
        keyposes: pair.keyposes.clone(),
        truth,
    };
    let svg = a.out.with_extension("svg");
    fig.write(&a.out, (!a.no_svg).then_some(svg.as_path()))?;
    Ok(())
}

fn correction(a: &CorrectionArgs) -> anyhow::Result<()> {
    let Some(view) = render::camera::View::parse(&a.camera) else {
        bail!("--camera {}: expected front, side, three-quarter or AZIMUTH,ELEVATION", a.camera);
    };
    let model = GprModel::load(&a.model)?;
    let (sp, tp) = (PcaModel::load(&a.source_pca)?, PcaModel::load(&a.target_pca)?);
    let seg = Segmentation::load(&a.segmentation)?;
    let budget = Stride::Within(a.memory_budget.saturating_mul(1 << 20));
    let (training, stride) = training_part_meshes(&tp, &a.target_training, budget)?;
    if stride > 1 {
        mesh_core::warn!(
            "the target's training part meshes do not fit in --memory-budget {} MiB: the correction uses every {stride}th training frame",
            a.memory_budget
        );
    }
    let (coeffs, source, _) = read_encoded(&a.motion, &sp)?;
    let truth = a.truth.as_ref().map(MeshSequence::load_dir).transpose()?;
    let (fig, report) = correction_example(
        &model,
        &coeffs,
        &source.displacements,
        &tp,
        &seg,
        training,
        a.part.as_deref(),
        a.source_frame,
        a.neighbours,
        truth.as_ref().map(|t| t.frames.as_slice()),
    )
    .with_context(|| a.motion.display().to_string())?;
    mesh_core::info!("{}", serde_json::to_string(&report)?);
    fig.render(a.size, &view).write_png(&a.out)?;
    if let Some(r) = &a.report {
        mesh_core::atomic::write_bytes_atomic(r, serde_json::to_string_pretty(&report)?.as_bytes())?;
    }
    Ok(())
}

impl Params {
    /// The common flags of the chosen figure.
    pub fn common(&self) -> &CommonArgs {
        match &self.figure {
            Figure::CostMatrix(a) => &a.common,
            Figure::Correction(a) => &a.common,
            Figure::Confidence(a) => &a.common,
        }
    }
}

/// Draws the chosen figure (PNG, with an SVG beside it unless `--no-svg`; `correction` also
/// its `--report` JSON).
pub fn run(p: &Params) -> anyhow::Result<()> {
    match &p.figure {
        Figure::CostMatrix(a) => cost_matrix(a),
        Figure::Correction(a) => correction(a),
        Figure::Confidence(a) => confidence(a),
    }
}
