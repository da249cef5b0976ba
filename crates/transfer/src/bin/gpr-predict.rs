use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

use anyhow::{bail, Context};
use clap::Parser;
use mesh_core::artifact::Artifact;
use mesh_core::cli::{run_stage, CommonArgs};
use mesh_core::segmentation::Segmentation;
use mesh_core::sequence::MeshSequence;
use capture::align::AlignedMotion;
use transfer::gpr_model::GprModel;
use capture::part_pca::PcaModel;
use transfer::placement::Placement;
use transfer::predict::transfer_motion;
use transfer::reconstruct::{Reconstructor, Surface};

/// Transfer an aligned source motion to the target subject with a trained model: PLY frames in world coordinates
#[derive(Parser, Debug)]
#[command(
    name = "gpr-predict",
    version,
    after_help = "e.g.: gpr-predict --model work/A-to-B/gpr-nn.model --source-pca work/A/pca.model --target-pca work/B/pca.model \\\n        --target-template set/B/walk/000000.ply work/A/punch.aligned --out out/transfer/A-to-B/punch/gpr-nn"
)]
struct Args {
    #[command(flatten)]
    common: CommonArgs,
    /// Trained model (from gpr-train)
    #[arg(long)]
    model: PathBuf,
    /// PCA model of the model's source subject (the one it was trained with)
    #[arg(long)]
    source_pca: PathBuf,
    /// PCA model of the model's target subject
    #[arg(long)]
    target_pca: PathBuf,
    /// Target template mesh (gives the output's faces)
    #[arg(long)]
    target_template: PathBuf,
    /// How the poses are placed in the world
    #[arg(long, value_enum, default_value_t = Placement::ScaledSource)]
    placement: Placement,
    /// Surface reconstruction after PCA decoding (paper §6): `assemble` averages overlaps,
    /// `correct` applies §6.1 first, `correct-stitch` also stitches along optimal loops (§6.2)
    #[arg(long, value_enum, default_value_t = Surface::Assemble)]
    surface: Surface,
    /// Target segmentation (from segment; needed unless --surface assemble)
    #[arg(long, required_if_eq_any([("surface", "correct"), ("surface", "correct-stitch"), ("surface", "stitch")]))]
    segmentation: Option<PathBuf>,
    /// Target's aligned training motions: the correction's training part meshes (repeatable)
    #[arg(long = "target-training", required_if_eq_any([("surface", "correct"), ("surface", "correct-stitch")]))]
    target_training: Vec<PathBuf>,
    /// Nearest training part meshes blended by the correction (the paper's M)
    #[arg(short = 'm', long, default_value_t = surface::correct::DEFAULT_NEIGHBOURS as u16, value_parser = clap::value_parser!(u16).range(1..))]
    neighbours: u16,
    /// Use every n-th training frame for the correction
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u16).range(1..))]
    correct_stride: u16,
    /// Do not clean up foot skating (by default each placed frame is shifted horizontally,
    /// smoothly in time, so that where the source has a foot down the target's sole moves as the
    /// source's does, scaled: planted feet stay planted; the pose is unchanged)
    #[arg(long)]
    no_footskate: bool,
    /// Smoothness λ of the foot-skating correction (weight of its second differences against
    /// the contact residuals; larger: smoother root, feet pinned less tightly)
    #[arg(long, default_value_t = transfer::feet::SMOOTHNESS)]
    footskate_smoothness: f64,
    /// Aligned source motion (from align)
    motion: PathBuf,
    /// Output folder of PLY frames 000000.ply, ... (the target's topology, one frame per source frame)
    #[arg(short, long)]
    out: PathBuf,
    /// Also write timings (frames per second of the prediction) as JSON
    #[arg(long)]
    timing: Option<PathBuf>,
    /// Also write per-frame confidence as JSON: per part, the GP's predictive variance over
    /// its prior variance and the distance to the nearest training input (docs/FORMATS.md)
    #[arg(long)]
    confidence: Option<PathBuf>,
}

fn main() -> ExitCode {
    let args = mesh_core::cli::parse::<Args>();
    run_stage("gpr-predict", || {
        args.common.init()?;
        let model = GprModel::load(&args.model)?;
        let (src_pca, tgt_pca) = (
            PcaModel::load(&args.source_pca)?,
            PcaModel::load(&args.target_pca)?,
        );
        for (pca, path) in [(&src_pca, &args.source_pca), (&tgt_pca, &args.target_pca)] {
            let names: Vec<&String> = pca.parts.iter().map(|p| &p.name).collect();
            if names
                .iter()
                .map(|s| s.as_str())
                .ne(model.part_names.iter().map(|s| s.as_str()))
            {
                bail!(
                    "{}: parts {:?} differ from the model's {:?}",
                    path.display(),
                    names,
                    model.part_names
                );
            }
        }
        let motion = AlignedMotion::load(&args.motion)?;
        let template = mesh_core::io::read_mesh(&args.target_template)?;
        if template.n_vertices() != tgt_pca.n_vertices {
            bail!(
                "{}: {} vertices but the target PCA model was fitted on {}",
                args.target_template.display(),
                template.n_vertices(),
                tgt_pca.n_vertices
            );
        }
        let faces = template.faces;
        let mut recon = match (&args.surface, &args.segmentation) {
            (Surface::Assemble, _) | (_, None) => None,
            (surface, Some(seg_path)) => {
                let seg = Segmentation::load(seg_path)?;
                let training = args
                    .target_training
                    .iter()
                    .map(AlignedMotion::load)
                    .collect::<Result<Vec<_>, _>>()?;
                let refs: Vec<&AlignedMotion> = training.iter().collect();
                Some(
                    Reconstructor::new(
                        &tgt_pca,
                        &seg,
                        &faces,
                        &refs,
                        *surface,
                        args.neighbours.into(),
                        args.correct_stride.into(),
                    )
                    .with_context(|| seg_path.display().to_string())?
                    .with_progress(mesh_core::cli::progress_bar(
                        0,
                        "gpr-predict: surface",
                        &args.common,
                    )),
                )
            }
        };
        let t0 = Instant::now();
        let result = transfer_motion(
            &model,
            &src_pca,
            &tgt_pca,
            &motion,
            args.placement,
            recon.as_mut(),
            (!args.no_footskate).then_some(args.footskate_smoothness),
        )
        .with_context(|| args.motion.display().to_string())?;
        let total = t0.elapsed().as_secs_f64();
        if let Some(w) = &result.blend_weights {
            let mean = w.iter().sum::<f64>() / w.len().max(1) as f64;
            let max = w.iter().cloned().fold(0.0, f64::max);
            mesh_core::info!(
                "blended placement: scaled-source weight mean {mean:.3}, max {max:.3}"
            );
        }
        if let Some(p) = &result.planted {
            mesh_core::info!(
                "foot skating: {} frames with a planted foot, root shifted by at most {:.3} m",
                p.planted_frames,
                p.max_shift_m
            );
        }
        if let Some(path) = &args.confidence {
            let xs = src_pca.encode(&motion)?;
            let xd = transfer::predict::displacement_matrix(&motion.displacements);
            let c = transfer::confidence::confidence(&model, &xs, &xd)
                .with_context(|| args.motion.display().to_string())?;
            mesh_core::atomic::write_bytes_atomic(path, serde_json::to_string(&c)?.as_bytes())?;
        }
        let t1 = Instant::now();
        // One output frame per source frame: the sequence plays at the source's rate, which
        // gpr-train records in the model's header.
        let (_, _, model_header) = mesh_core::artifact::read_header(&args.model)?;
        let fps = model_header.params.get("source_fps").and_then(|f| f.as_f64());
        MeshSequence::new(faces, result.frames).write_dir_at(&args.out, fps)?;
        let write = t1.elapsed().as_secs_f64();
        let n = motion.n_frames() as f64;
        mesh_core::info!(
            "{} frames: encode {:.4} s, GP {:.4} s ({:.0} frames/s), decode+assemble {:.4} s, total {:.4} s, PLY writing {:.3} s",
            n,
            result.timing.encode_s,
            result.timing.gp_s,
            n / result.timing.gp_s.max(1e-12),
            result.timing.decode_s,
            total,
            write
        );
        if let Some(path) = &args.timing {
            let json = serde_json::json!({
                "frames": motion.n_frames(), "encode_s": result.timing.encode_s, "gp_s": result.timing.gp_s,
                "gp_frames_per_s": n / result.timing.gp_s.max(1e-12), "decode_assemble_s": result.timing.decode_s,
                "total_s": total, "frames_per_s_without_writing": n / total.max(1e-12), "ply_write_s": write,
            });
            mesh_core::atomic::write_bytes_atomic(
                path,
                serde_json::to_string_pretty(&json)?.as_bytes(),
            )?;
        }
        Ok(())
    })
}
