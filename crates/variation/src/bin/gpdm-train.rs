use std::path::PathBuf;
use std::process::ExitCode;

use clap::Parser;
use gpdm::optim::{Exit, Schedule};
use mesh_core::artifact::Artifact;
use mesh_core::cli::{run_stage, CommonArgs};
use variation::group::Group;
use variation::train::{train_with_progress, TrainConfig};

/// Learn one GPDM per body part (shared latent space per part) from a prealigned movement group
#[derive(Parser, Debug)]
#[command(
    name = "gpdm-train",
    version,
    after_help = "e.g.: gpdm-train --group out/work/variation/locomotion.group --out out/work/variation/locomotion.model --report out/work/variation/locomotion-train.json"
)]
struct Args {
    #[command(flatten)]
    common: CommonArgs,
    /// Prealigned group (kind variation-group, from prealign)
    #[arg(long)]
    group: PathBuf,
    /// Latent dimension d
    #[arg(long, default_value_t = 3)]
    latent_dim: usize,
    /// Lower bound on the pose-noise variance 1/α3 in m² (0 = none)
    #[arg(long, default_value_t = 1e-6)]
    noise_floor: f64,
    /// Lower bound on the dynamics-noise variance 1/β4 in squared latent units (0 = none; without
    /// it 1/β4 collapses on some parts and HMC returns copies of the source)
    #[arg(long, default_value_t = variation::train::DYN_NOISE_FLOOR)]
    dyn_noise_floor: f64,
    /// Alternating rounds of (X, α) and β-only L-BFGS phases (0 = one joint fit, the default)
    #[arg(long, default_value_t = 0)]
    rounds: usize,
    /// L-BFGS iterations per phase (with --rounds > 0)
    #[arg(long, default_value_t = 200)]
    iters: usize,
    /// L-BFGS iteration limit of the joint fit (it normally stops by convergence first)
    #[arg(long, default_value_t = 10000)]
    max_iter: usize,
    /// Training frames: exact (every frame, the paper's fit; cost grows as N³) or strided (every
    /// s-th frame, s from --fit-rate and --max-fit-frames; sampling interpolates back to the
    /// capture's rate)
    #[arg(long, value_enum, default_value_t = variation::train::Fit::default())]
    fit: variation::train::Fit,
    /// With --fit strided: frame rate the dynamics are learned at (stride round(fps / rate))
    #[arg(long, value_name = "FPS", default_value_t = variation::train::FIT_RATE)]
    fit_rate: f64,
    /// With --fit strided: the stride is raised until one part's training frames (all
    /// sequences) are at most this many, so the cost stays bounded whatever the capture length
    #[arg(long, value_name = "N", default_value_t = variation::train::MAX_FIT_FRAMES)]
    max_fit_frames: usize,
    /// Output artifact (kind variation-model)
    #[arg(short, long)]
    out: PathBuf,
    /// Training report (JSON: objective, hyperparameters, time per part)
    #[arg(long)]
    report: Option<PathBuf>,
}

fn main() -> ExitCode {
    let args = mesh_core::cli::parse::<Args>();
    run_stage("gpdm-train", || {
        args.common.init()?;
        let group = Group::load(&args.group)?;
        let mut cfg = TrainConfig::default();
        cfg.gpdm.latent_dim = args.latent_dim;
        cfg.gpdm.pose_noise_floor = (args.noise_floor > 0.0).then_some(args.noise_floor);
        cfg.gpdm.dyn_noise_floor = (args.dyn_noise_floor > 0.0).then_some(args.dyn_noise_floor);
        if args.rounds > 0 {
            cfg.options.schedule = Schedule::Alternate {
                rounds: args.rounds,
                iters: args.iters,
            };
        }
        cfg.options.lbfgs.max_iter = args.max_iter;
        cfg.fit(args.fit, args.fit_rate, args.max_fit_frames)?;
        let bar = mesh_core::cli::progress_bar(
            group.parts.len() as u64,
            "gpdm-train: parts",
            &args.common,
        );
        let (model, reports) = train_with_progress(&group, &cfg, &|_| bar.inc(1))?;
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
        let header = args
            .common
            .header("gpdm-train", env!("CARGO_PKG_VERSION"))
            .with_input(&args.group)?
            .with_params(&cfg)?;
        model.save(&args.out, &header)?;
        if let Some(p) = &args.report {
            let light: Vec<_> = reports
                .iter()
                .map(|r| {
                    serde_json::json!({
                        "part": r.part, "frames": r.frames, "pose_dim": r.pose_dim, "seconds": r.seconds,
                        "alpha": r.alpha, "beta": r.beta, "initial_value": r.report.initial_value,
                        "final_value": r.report.final_value, "evaluations": r.report.evaluations,
                        "iterations": r.report.history.len() - 1,
                        "beta_log_sd": cfg.gpdm.beta_log_sd, "fixed_latent_scale": cfg.gpdm.fixed_latent_scale,
                        "exits": r.report.exits, "max_jitter": r.report.max_jitter,
                    })
                })
                .collect();
            let json = serde_json::json!({ "group": group.name, "config": cfg, "scale": model.scale,
                "stride": model.stride, "parts": light });
            mesh_core::atomic::write_bytes_atomic(
                p,
                (serde_json::to_string_pretty(&json)? + "\n").as_bytes(),
            )?;
        }
        Ok(())
    })
}
