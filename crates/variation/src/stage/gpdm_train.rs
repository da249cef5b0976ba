//! The `gpdm-train` stage: one GPDM per body part (3DV eqs. 1-7) from a prealigned group.

use std::path::PathBuf;

use clap::Parser;
use gpdm::optim::{Exit, Schedule};
use mesh_core::artifact::Artifact;
use mesh_core::cli::CommonArgs;
use mesh_core::part_merge::{self, PartReports};
use serde::Serialize;

use crate::group::Group;
use crate::train::{train_selected, training_report, TrainConfig, VariationModel};

/// Learn one GPDM per body part (shared latent space per part) from a prealigned movement group
#[derive(Parser, Debug, Serialize)]
#[command(
    name = "gpdm-train",
    version,
    after_help = "e.g.: gpdm-train --group out/work/variation/locomotion.group --out out/work/variation/locomotion.model --report out/work/variation/locomotion-train.json"
)]
pub struct Params {
    #[command(flatten)]
    #[serde(skip)]
    pub common: CommonArgs,
    /// Prealigned group (kind variation-group, from prealign)
    #[arg(long)]
    pub group: PathBuf,
    /// Latent dimension d
    #[arg(long, default_value_t = 3)]
    pub latent_dim: usize,
    /// Lower bound on the pose-noise variance 1/α3 in m² (0 = none)
    #[arg(long, default_value_t = 1e-6)]
    pub noise_floor: f64,
    /// Lower bound on the dynamics-noise variance 1/β4 in squared latent units (0 = none; without
    /// it 1/β4 collapses on some parts and HMC returns copies of the source)
    #[arg(long, default_value_t = crate::train::DYN_NOISE_FLOOR)]
    pub dyn_noise_floor: f64,
    /// Weight of the dynamics term in the objective: paper (3DV eq. 7 as printed) or balanced
    /// (the dynamics density raised to D/d, so the latent trajectories are shaped by the
    /// dynamics as much as by the poses)
    #[arg(long, value_enum, default_value_t = gpdm::DynamicsWeight::default())]
    pub dynamics_weight: gpdm::DynamicsWeight,
    /// Alternating rounds of (X, α) and β-only L-BFGS phases (0 = one joint fit, the default)
    #[arg(long, default_value_t = 0)]
    pub rounds: usize,
    /// L-BFGS iterations per phase (with --rounds > 0)
    #[arg(long, default_value_t = 200)]
    pub iters: usize,
    /// L-BFGS iteration limit of the joint fit: it bounds a part's training time (most fits stop
    /// by convergence first)
    #[arg(long, default_value_t = crate::train::MAX_ITERATIONS)]
    pub max_iter: usize,
    /// Convergence: the fit stops when the objective decreased by less than this fraction of
    /// its value per iteration over the last 10 (or ‖∇‖∞ ≤ 1e-3)
    #[arg(long, value_name = "TOL", default_value_t = crate::train::VALUE_TOLERANCE)]
    pub value_tolerance: f64,
    /// Training frames: exact (every frame, the paper's fit; cost grows as N³) or strided (every
    /// s-th frame, s from --fit-rate, --min-fit-frames and --max-fit-frames; sampling
    /// interpolates back to the capture's rate)
    #[arg(long, value_enum, default_value_t = crate::train::Fit::default())]
    pub fit: crate::train::Fit,
    /// With --fit strided: frame rate the dynamics are learned at (stride round(fps / rate))
    #[arg(long, value_name = "FPS", default_value_t = crate::train::FIT_RATE)]
    pub fit_rate: f64,
    /// With --fit strided: the stride is lowered (down to every frame) until one part's
    /// training frames (all sequences) are at least this many, so a short clip keeps enough
    /// frames to learn its dynamics
    #[arg(long, value_name = "N", default_value_t = crate::train::MIN_FIT_FRAMES)]
    pub min_fit_frames: usize,
    /// With --fit strided: the stride is raised until one part's training frames (all
    /// sequences) are at most this many, so the cost stays bounded whatever the capture length
    #[arg(long, value_name = "N", default_value_t = crate::train::MAX_FIT_FRAMES)]
    pub max_fit_frames: usize,
    /// Train only this part (a part name of the group) and write it alone, as kind
    /// variation-model-part (its --report of that part alone): `merge-parts` joins the parts
    /// (and their reports) into the whole model
    #[arg(long)]
    #[serde(skip)]
    pub part: Option<String>,
    /// Output artifact (kind variation-model; variation-model-part with --part)
    #[arg(short, long)]
    pub out: PathBuf,
    /// Training report (JSON: objective, hyperparameters, time per part)
    #[arg(long)]
    pub report: Option<PathBuf>,
}

/// Writes the `--report` (if asked) and the model; the header records `p`, the training configuration
/// derived from it (`config`) and the group. With `--part` only that part is trained, written
/// as a piece (`mesh_core::part_merge`).
pub fn run(p: &Params) -> anyhow::Result<()> {
    let group = Group::load(&p.group)?;
    let mut cfg = TrainConfig::default();
    cfg.gpdm.latent_dim = p.latent_dim;
    cfg.gpdm.pose_noise_floor = (p.noise_floor > 0.0).then_some(p.noise_floor);
    cfg.gpdm.dyn_noise_floor = (p.dyn_noise_floor > 0.0).then_some(p.dyn_noise_floor);
    cfg.gpdm.dynamics_weight = p.dynamics_weight;
    if p.rounds > 0 {
        cfg.options.schedule = Schedule::Alternate {
            rounds: p.rounds,
            iters: p.iters,
        };
    }
    cfg.options.lbfgs.max_iter = p.max_iter;
    if !(p.value_tolerance >= 0.0 && p.value_tolerance.is_finite()) {
        anyhow::bail!("--value-tolerance {}: must be a finite number >= 0", p.value_tolerance);
    }
    cfg.options.lbfgs.value_tol = p.value_tolerance;
    cfg.fit(p.fit, p.fit_rate, p.min_fit_frames, p.max_fit_frames)?;
    let names: Vec<String> = group.parts.iter().map(|q| q.name.clone()).collect();
    let only = match &p.part {
        Some(name) => Some(part_merge::select(&names, name, &p.group)?),
        None => None,
    };
    let bar = mesh_core::cli::progress_bar(
        if only.is_some() { 1 } else { group.parts.len() as u64 },
        "gpdm-train: parts",
        &p.common,
    );
    let (model, reports) = train_selected(&group, &cfg, only, &|_| bar.inc(1))?;
    bar.finish_and_clear();
    if model.stride > 1 {
        mesh_core::info!(
            "dynamics learned every {} frames ({:.1} fps of {:.1})",
            model.stride,
            model.fps / model.stride as f64,
            model.fps
        );
    }
    for r in &reports {
        mesh_core::info!(
            "{}: {} frames x {} dims, objective {:.4e} -> {:.4e} in {:.1} s",
            r.part,
            r.frames,
            r.pose_dim,
            r.report.initial_value,
            r.report.final_value,
            r.seconds
        );
        if let Some(e) = r
            .report
            .exits
            .last()
            .filter(|e| !matches!(e, Exit::GradientTolerance | Exit::ValueTolerance))
        {
            mesh_core::warn!("{}: L-BFGS stopped by {e:?}, not by convergence", r.part);
        }
        if r.report.max_jitter > 0.0 {
            mesh_core::warn!(
                "{}: Cholesky needed jitter {:e} at the optimum",
                r.part,
                r.report.max_jitter
            );
        }
    }
    let mut params = serde_json::to_value(p)?;
    params["config"] = serde_json::to_value(&cfg)?;
    let header = p
        .common
        .header("gpdm-train", env!("CARGO_PKG_VERSION"))
        .with_input(&p.group)?
        .with_params(&params)?;
    let (scale, stride) = (model.scale, model.stride);
    // The report first: the model's presence says both are complete.
    if let Some(report) = &p.report {
        let json = training_report(&group.name, &cfg, &scale, stride, &reports)?;
        mesh_core::atomic::write_bytes_atomic(report, VariationModel::report_text(&json)?.as_bytes())?;
    }
    match only {
        Some(k) => part_merge::save_piece::<VariationModel>(&p.out, &header, &names, k, model)?,
        None => model.save(&p.out, &header)?,
    }
    Ok(())
}
