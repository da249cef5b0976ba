//! The `learning-curves` stage: the pose regression's error against the training-set size, both
//! directions, per part and whole body (CVPR figs. 7-9), as CSV and PNG/SVG plots.

use std::path::PathBuf;

use anyhow::{bail, Context};
use capture::part_pca::PcaModel;
use clap::Parser;
use gp::gpr::{GprOptions, PAPER_NOISE_VAR};
use mesh_core::artifact::Artifact;
use mesh_core::capture_set::SetSpec;
use mesh_core::cli::CommonArgs;
use serde::Serialize;

use transfer::densify::Correspondences;
use transfer::gpr_model::MeanFunction;
use transfer::learning_curves::{
    read_pair, run_direction, sizes, total_components, train_side_len, true_correspondences, write_csv,
    Correspondence, DirectionData,
};

use crate::learning_curve_plots::plot_all;

/// Learning curves of the pose regression, both directions (paper figures 7-9): CSV, PNG and SVG plots
#[derive(Parser, Debug, Serialize)]
#[command(
    name = "learning-curves",
    version,
    after_help = "e.g.: learning-curves --source-pca work/A/pca.model --target-pca work/B/pca.model --source-whole work/A/pca-whole.model \\\n        --target-whole work/B/pca-whole.model --set set --true-pair walk work/A/walk.aligned work/B/walk.aligned --out out/learning-curves\n      learning-curves --source-pca work/A/pca.model --target-pca work/B/pca.model --source-whole work/A/pca-whole.model \\\n        --target-whole work/B/pca-whole.model \\\n        --pair work/A/walk.aligned work/B/walk.aligned work/pairs/walk.corr --out out/learning-curves-dtw"
)]
pub struct Params {
    #[command(flatten)]
    #[serde(skip)]
    pub common: CommonArgs,
    /// Per-part PCA model of the set's source subject
    #[arg(long)]
    pub source_pca: PathBuf,
    /// Per-part PCA model of the set's target subject
    #[arg(long)]
    pub target_pca: PathBuf,
    /// Whole-body PCA model of the source subject (pca-fit --whole-body; fig. 9 compares it at the parts' total components)
    #[arg(long)]
    pub source_whole: PathBuf,
    /// Whole-body PCA model of the target subject
    #[arg(long)]
    pub target_whole: PathBuf,
    /// Source subject name (for the direction labels)
    #[arg(long, default_value = "A")]
    pub source_name: String,
    /// Target subject name
    #[arg(long, default_value = "B")]
    pub target_name: String,
    /// A training pair with DTW pairs: aligned source motion, aligned target motion, correspondences (repeat)
    #[arg(long, num_args = 3, value_names = ["SET_SOURCE", "SET_TARGET", "CORR"], action = clap::ArgAction::Append,
          required_unless_present = "true_pair", conflicts_with = "true_pair")]
    pub pair: Vec<PathBuf>,
    /// Capture-set folder (its set.json: key-poses and true correspondences of --true-pair)
    #[arg(long)]
    pub set: Option<PathBuf>,
    /// A training pair with the set's true correspondences: source motion name, aligned source motion, aligned target motion (repeat)
    #[arg(long, num_args = 3, value_names = ["MOTION", "SET_SOURCE", "SET_TARGET"], action = clap::ArgAction::Append, requires = "set")]
    pub true_pair: Vec<String>,
    /// Largest training subset (pairs)
    #[arg(long, default_value_t = 300)]
    pub max_train: usize,
    /// Number of training-subset sizes
    #[arg(long, default_value_t = 6)]
    pub steps: usize,
    /// Neural-network kernel with the bias input (R&W eq. 4.29); eq. 10 as printed has none, which limits the GP to odd functions
    #[arg(long)]
    pub nn_bias: bool,
    /// Mean function of the GPs: affine (the GP on its residuals) or zero (the paper's curves)
    #[arg(long, value_enum, default_value_t = MeanFunction::default())]
    pub mean: MeanFunction,
    /// Observation-noise variance σn²
    #[arg(long, default_value_t = PAPER_NOISE_VAR)]
    pub noise_var: f64,
    /// Maximum conjugate-gradient iterations per GP
    #[arg(long, default_value_t = 50)]
    pub max_iter: usize,
    /// Output folder: learning_curves.csv and <direction>-fig{7,8,9}-*.png/.svg
    #[arg(short, long)]
    pub out: PathBuf,
}

/// One training pair as named on the command line: aligned motions, frame pairs, key-poses.
struct PairInput {
    source: PathBuf,
    target: PathBuf,
    pairs: Vec<[usize; 2]>,
    keyposes: Vec<[usize; 2]>,
    what: String,
}

fn pair_inputs(args: &Params) -> anyhow::Result<(Correspondence, Vec<PairInput>)> {
    if let Some(set_dir) = &args.set {
        let set_path = &set_dir.join("set.json");
        if !args.true_pair.is_empty() {
            let set = SetSpec::load(set_path)?;
            let mut out = Vec::new();
            for t in args.true_pair.chunks(3) {
                let (keyposes, pairs) = true_correspondences(&set, set_path, &t[0])?;
                out.push(PairInput {
                    source: PathBuf::from(&t[1]),
                    target: PathBuf::from(&t[2]),
                    pairs,
                    keyposes,
                    what: format!("{} (true pairs of {})", t[1], t[0]),
                });
            }
            return Ok((Correspondence::True, out));
        }
    }
    let mut out = Vec::new();
    for f in args.pair.chunks(3) {
        let corr = Correspondences::load(&f[2])?;
        out.push(PairInput {
            source: f[0].clone(),
            target: f[1].clone(),
            pairs: corr.pairs,
            keyposes: corr.keyposes,
            what: f[2].display().to_string(),
        });
    }
    Ok((Correspondence::Dtw, out))
}

/// Writes `learning_curves.csv` and the plots into `--out`.
pub fn run(p: &Params) -> anyhow::Result<()> {
    let (sp, tp) = (PcaModel::load(&p.source_pca)?, PcaModel::load(&p.target_pca)?);
    let (sw, tw) = (PcaModel::load(&p.source_whole)?, PcaModel::load(&p.target_whole)?);
    let names: Vec<String> = sp.parts.iter().map(|p| p.name.clone()).collect();
    if tp.parts.iter().map(|p| &p.name).ne(names.iter()) {
        bail!("{}: the part names differ from the source's {:?}", p.target_pca.display(), names);
    }
    let (correspondence, inputs) = pair_inputs(p)?;
    if inputs.is_empty() {
        bail!("no training pair given (--pair or --true-pair)");
    }
    let (mut parts, mut whole, mut rates) = (Vec::new(), Vec::new(), None);
    for input in &inputs {
        let (pair_parts, pair_whole, captures) =
            read_pair(&input.source, &input.target, &input.pairs, &input.keyposes, [&sp, &tp], [&sw, &tw])
                .with_context(|| input.what.clone())?;
        if rates.is_none() {
            let fps = |c: &capture::align::CaptureInfo| c.require_fps().with_context(|| input.what.clone());
            rates = Some((fps(&captures[0])?, fps(&captures[1])?));
        }
        parts.push(pair_parts);
        whole.push(pair_whole);
    }
    let Some((source_fps, target_fps)) = rates else {
        bail!("no training pair given (--pair or --true-pair)");
    };
    mesh_core::info!(
        "components: source {} in parts, {} whole body; target {} in parts, {} whole body; {} pairs",
        total_components(&sp),
        total_components(&sw),
        total_components(&tp),
        total_components(&tw),
        correspondence.name()
    );
    if total_components(&tp) != total_components(&tw) || total_components(&sp) != total_components(&sw) {
        mesh_core::warn!(
            "figure 9 compares unequal dimensions: parts {} / {}, whole body {} / {} (source / target)",
            total_components(&sp),
            total_components(&tp),
            total_components(&sw),
            total_components(&tw)
        );
    }
    let opts = GprOptions {
        noise_var: p.noise_var,
        cg: gp::optim::CgOptions { max_iter: p.max_iter, ..Default::default() },
        ..Default::default()
    };
    let n_keys = parts.iter().map(|p| p.data.keyposes.len()).sum::<usize>();
    let n_rows = parts.iter().map(|p| p.data.pairs.len()).sum::<usize>();
    let train_max = p.max_train.min(train_side_len(n_rows, n_keys));
    let train_sizes = sizes(n_keys.max(10), train_max, p.steps);
    let direction = |label: String, ratio: f64, vertices: &PcaModel, whole_vertices: usize, parts, whole| DirectionData {
        label,
        correspondence,
        part_vertices: vertices.parts.iter().map(|p| p.vertices.len()).collect(),
        whole_vertices,
        part_names: names.clone(),
        frame_ratio: ratio,
        parts,
        whole,
    };
    let forward = direction(
        format!("{}->{}", p.source_name, p.target_name),
        target_fps / source_fps,
        &tp,
        tw.n_vertices,
        parts.clone(),
        whole.clone(),
    );
    let reverse = direction(
        format!("{}->{}", p.target_name, p.source_name),
        source_fps / target_fps,
        &sp,
        sw.n_vertices,
        parts.into_iter().map(|p| p.reversed()).collect(),
        whole.into_iter().map(|p| p.reversed()).collect(),
    );
    let mut points = Vec::new();
    let bar = mesh_core::cli::progress_bar(2, "learning-curves: directions", &p.common);
    bar.enable_steady_tick(std::time::Duration::from_millis(200));
    for d in [&forward, &reverse] {
        let t = std::time::Instant::now();
        points.extend(run_direction(d, &train_sizes, p.nn_bias, p.mean, &opts, p.common.seed)?);
        bar.inc(1);
        mesh_core::info!("{}: sizes {:?} in {:.1} s", d.label, train_sizes, t.elapsed().as_secs_f64());
    }
    bar.finish_and_clear();
    std::fs::create_dir_all(&p.out).with_context(|| p.out.display().to_string())?;
    let plots = plot_all(&p.out, &points)?;
    mesh_core::info!("wrote {} plots", plots.len());
    write_csv(&p.out.join("learning_curves.csv"), &points)?;
    Ok(())
}
