use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{bail, Context};
use clap::Parser;
use gp::gpr::{GprOptions, PAPER_NOISE_VAR};
use mesh_core::artifact::Artifact;
use mesh_core::cli::{run_stage, CommonArgs};
use transfer::gpr_model::{PairData, PairFiles};
use transfer::learning_curves::{plot_all, run_direction, sizes, write_csv, DirectionData};
use transfer::part_pca::PcaModel;

/// Learning curves of the pose regression, both directions (paper figures 7-9): CSV, PNG and SVG plots
#[derive(Parser, Debug)]
#[command(
    name = "learning-curves",
    version,
    after_help = "e.g.: learning-curves --source-pca work/A/pca.model --target-pca work/B/pca.model --source-whole work/A/pca-whole.model \\\n        --target-whole work/B/pca-whole.model --source-fps 25 --target-fps 50 \\\n        --pair work/A/walk.aligned work/B/walk.aligned work/pairs/walk.corr --out out/learning-curves"
)]
struct Args {
    #[command(flatten)]
    common: CommonArgs,
    /// Per-part PCA model of the set's source subject
    #[arg(long)]
    source_pca: PathBuf,
    /// Per-part PCA model of the set's target subject
    #[arg(long)]
    target_pca: PathBuf,
    /// Whole-body PCA model of the source subject (pca-fit --whole-body)
    #[arg(long)]
    source_whole: PathBuf,
    /// Whole-body PCA model of the target subject
    #[arg(long)]
    target_whole: PathBuf,
    #[arg(long)]
    source_fps: f64,
    #[arg(long)]
    target_fps: f64,
    /// Source subject name (for the direction labels)
    #[arg(long, default_value = "A")]
    source_name: String,
    /// Target subject name
    #[arg(long, default_value = "B")]
    target_name: String,
    /// A training pair as in the set: aligned source motion, aligned target motion, correspondences (repeat)
    #[arg(long, num_args = 3, value_names = ["SET_SOURCE", "SET_TARGET", "CORR"], required = true, action = clap::ArgAction::Append)]
    pair: Vec<PathBuf>,
    /// Largest training subset (pairs)
    #[arg(long, default_value_t = 300)]
    max_train: usize,
    /// Number of training-subset sizes
    #[arg(long, default_value_t = 6)]
    steps: usize,
    /// Neural-network kernel with the bias input (R&W eq. 4.29); eq. 10 as printed has none, which limits the GP to odd functions
    #[arg(long)]
    nn_bias: bool,
    /// Observation-noise variance σn²
    #[arg(long, default_value_t = PAPER_NOISE_VAR)]
    noise_var: f64,
    /// Maximum conjugate-gradient iterations per GP
    #[arg(long, default_value_t = 50)]
    max_iter: usize,
    /// Output folder: learning_curves.csv and <direction>-fig{7,8,9}-*.png/.svg
    #[arg(short, long)]
    out: PathBuf,
}

fn main() -> ExitCode {
    let args = Args::parse();
    run_stage("learning-curves", || {
        args.common.init()?;
        let load = |p: &PathBuf| PcaModel::load(p);
        let (sp, tp, sw, tw) = (
            load(&args.source_pca)?,
            load(&args.target_pca)?,
            load(&args.source_whole)?,
            load(&args.target_whole)?,
        );
        let names: Vec<String> = sp.parts.iter().map(|p| p.name.clone()).collect();
        if tp.parts.iter().map(|p| &p.name).ne(names.iter()) {
            bail!(
                "{}: the part names differ from the source's {:?}",
                args.target_pca.display(),
                names
            );
        }
        let (mut parts, mut whole) = (Vec::new(), Vec::new());
        for files in args.pair.chunks(3) {
            let pair = PairFiles::load(files)?;
            parts.push(pair.encode(&sp, &tp)?);
            whole.push(pair.encode(&sw, &tw)?);
        }
        let opts = GprOptions {
            noise_var: args.noise_var,
            cg: gp::optim::CgOptions {
                max_iter: args.max_iter,
                ..Default::default()
            },
            ..Default::default()
        };
        let n_keys = parts.iter().map(|p| p.keyposes.len()).sum::<usize>();
        let n_rows = parts.iter().map(|p| p.pairs.len()).sum::<usize>();
        let train_max = args
            .max_train
            .min(n_rows - (n_rows.saturating_sub(n_keys) as f64 * 0.3).round() as usize);
        let train_sizes = sizes(n_keys.max(10), train_max, args.steps);
        let forward = DirectionData {
            label: format!("{}->{}", args.source_name, args.target_name),
            part_vertices: tp.parts.iter().map(|p| p.vertices.len()).collect(),
            whole_vertices: tw.n_vertices,
            part_names: names.clone(),
            frame_ratio: args.target_fps / args.source_fps,
            parts: parts.clone(),
            whole: whole.clone(),
        };
        let reverse = DirectionData {
            label: format!("{}->{}", args.target_name, args.source_name),
            part_vertices: sp.parts.iter().map(|p| p.vertices.len()).collect(),
            whole_vertices: sw.n_vertices,
            part_names: names,
            frame_ratio: args.source_fps / args.target_fps,
            parts: parts.into_iter().map(PairData::reversed).collect(),
            whole: whole.into_iter().map(PairData::reversed).collect(),
        };
        let mut points = Vec::new();
        for d in [&forward, &reverse] {
            let t = std::time::Instant::now();
            points.extend(run_direction(
                d,
                &train_sizes,
                args.nn_bias,
                &opts,
                args.common.seed,
            )?);
            mesh_core::info!(
                "{}: sizes {:?} in {:.1} s",
                d.label,
                train_sizes,
                t.elapsed().as_secs_f64()
            );
        }
        std::fs::create_dir_all(&args.out).with_context(|| args.out.display().to_string())?;
        let plots = plot_all(&args.out, &points)?;
        mesh_core::info!("wrote {} plots", plots.len());
        write_csv(&args.out.join("learning_curves.csv"), &points)?;
        Ok(())
    })
}
