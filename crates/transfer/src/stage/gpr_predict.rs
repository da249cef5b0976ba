//! The `gpr-predict` stage: an aligned source motion transferred to the target subject with a
//! trained model (CVPR eq. 12 per part and for the displacement), decoded, placed and optionally
//! corrected and stitched (CVPR §6), written as PLY frames in world coordinates.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{bail, Context};
use clap::Parser;
use mesh_core::artifact::Artifact;
use mesh_core::cli::CommonArgs;
use mesh_core::segmentation::Segmentation;
use serde::Serialize;

use crate::gpr_model::GprModel;
use crate::placement::Placement;
use crate::predict::{transfer_motion, SourceMotion, Streaming};
use crate::reconstruct::{training_part_meshes, Reconstructor, Stride, Surface};
use capture::part_pca::PcaModel;

/// Transfer an aligned source motion to the target subject with a trained model: PLY frames in world coordinates
#[derive(Parser, Debug, Serialize)]
#[command(
    name = "gpr-predict",
    version,
    after_help = "e.g.: gpr-predict --model work/A-to-B/gpr-nn.model --source-pca work/A/pca.model --target-pca work/B/pca.model \\\n        --target-template set/B/walk/000000.ply work/A/punch.aligned --out out/transfer/A-to-B/punch/gpr-nn"
)]
pub struct Params {
    #[command(flatten)]
    #[serde(skip)]
    pub common: CommonArgs,
    /// Trained model (from gpr-train)
    #[arg(long)]
    pub model: PathBuf,
    /// PCA model of the model's source subject (the one it was trained with)
    #[arg(long)]
    pub source_pca: PathBuf,
    /// PCA model of the model's target subject
    #[arg(long)]
    pub target_pca: PathBuf,
    /// Target template mesh (gives the output's faces)
    #[arg(long)]
    pub target_template: PathBuf,
    /// How the poses are placed in the world
    #[arg(long, value_enum, default_value_t = Placement::PREDICT_DEFAULT)]
    pub placement: Placement,
    /// Surface reconstruction after PCA decoding (paper §6): `assemble` averages overlaps,
    /// `correct` applies §6.1 first, `correct-stitch` also stitches along optimal loops (§6.2)
    #[arg(long, value_enum, default_value_t = Surface::Assemble)]
    pub surface: Surface,
    /// Target segmentation (from segment; needed unless --surface assemble)
    #[arg(long, required_if_eq_any([("surface", "correct"), ("surface", "correct-stitch"), ("surface", "stitch")]))]
    pub segmentation: Option<PathBuf>,
    /// Target's aligned training motions: the correction's training part meshes (repeatable)
    #[arg(long = "target-training", required_if_eq_any([("surface", "correct"), ("surface", "correct-stitch")]))]
    pub target_training: Vec<PathBuf>,
    /// Nearest training part meshes blended by the correction (the paper's M)
    #[arg(short = 'm', long, default_value_t = surface::correct::DEFAULT_NEIGHBOURS as u16, value_parser = clap::value_parser!(u16).range(1..))]
    pub neighbours: u16,
    /// Use every n-th training frame for the correction (default: every frame while their
    /// part meshes fit in --memory-budget, else every 2nd, 4th, ...: the smallest that fits)
    #[arg(long, value_parser = clap::value_parser!(u16).range(1..))]
    pub correct_stride: Option<u16>,
    /// Do not clean up foot skating (by default each placed frame is shifted horizontally,
    /// smoothly in time, so that where the source has a foot down the target's sole moves as the
    /// source's does, scaled: planted feet stay planted; the pose is unchanged)
    #[arg(long)]
    pub no_footskate: bool,
    /// Smoothness λ of the foot-skating correction (weight of its second differences against
    /// the contact residuals; larger: smoother root, feet pinned less tightly)
    #[arg(long, default_value_t = crate::feet::SMOOTHNESS)]
    pub footskate_smoothness: f64,
    /// Do not put planted feet on the floor (by default, where the source has a foot down, the
    /// target's leg is deformed, hip seam fixed, so that its lowest point is at the height of the
    /// template's, smoothly in time; the root is not moved, but under `--placement regressed` or
    /// `blended`, whose root height drifts, the whole body is first lowered or raised onto the
    /// floor and the legs take what is left)
    #[arg(long)]
    pub no_foot_height: bool,
    /// Aligned source motion (from align)
    pub motion: PathBuf,
    /// Output folder of PLY frames 000000.ply, ... (the target's topology, one frame per source frame)
    #[arg(short, long)]
    pub out: PathBuf,
    /// With --surface correct-stitch: also write the corrected parts merged by averaging (what
    /// --surface correct writes) to this folder, from the same correction
    #[arg(long)]
    pub corrected_out: Option<PathBuf>,
    /// Memory in MiB for each store that grows with the data: the transferred frames (made a
    /// block at a time and held until the feet clean-up is solved: in memory while they fit,
    /// beyond it in a scratch file beside the output), and with --surface correct*, the
    /// correction's training part meshes (see --correct-stride) and its cached factorisations
    /// (least recently used rebuilt when needed). Only the stride changes the output
    #[arg(long, value_name = "MIB", default_value_t = mesh_core::cli::DEFAULT_MEMORY_BUDGET_MIB)]
    pub memory_budget: usize,
    /// Also write timings (frames per second of the prediction) as JSON
    #[arg(long)]
    pub timing: Option<PathBuf>,
    /// Also write per-frame confidence as JSON: per part, the GP's predictive variance over
    /// its prior variance and the distance to the nearest training input (docs/FORMATS.md)
    #[arg(long)]
    pub confidence: Option<PathBuf>,
}

/// Writes the frames (and the `--timing` and `--confidence` JSON when asked); the folder's
/// `rate.json` is the source frame rate recorded in the model's header.
pub fn run(p: &Params) -> anyhow::Result<()> {
    if p.corrected_out.is_some() && p.surface != Surface::CorrectStitch {
        bail!("--corrected-out needs --surface correct-stitch (the other outputs are one folder)");
    }
    let model = GprModel::load(&p.model)?;
    let (src_pca, tgt_pca) = (
        PcaModel::load(&p.source_pca)?,
        PcaModel::load(&p.target_pca)?,
    );
    check_models(p, &model, &src_pca, &tgt_pca)?;
    let t0 = Instant::now();
    let motion = SourceMotion::read(&p.motion, &src_pca)?;
    let encode_s = t0.elapsed().as_secs_f64();
    let faces = target_faces(p, &tgt_pca)?;
    let (mut recon, correct_stride) = reconstructor(p, &tgt_pca, &faces)?;
    let transfer_start = Instant::now();
    let mut result = transfer_motion(
        &model,
        &src_pca,
        &tgt_pca,
        &motion,
        p.placement,
        recon.as_mut(),
        &crate::feet::CleanUp {
            footskate: !p.no_footskate,
            foot_height: !p.no_foot_height,
            smoothness: p.footskate_smoothness,
            faces: &faces,
        },
        &Streaming {
            output: &p.out,
            corrected_output: p.corrected_out.as_deref(),
            block: capture::part_pca::frames_per_block(tgt_pca.n_vertices),
            memory_budget: p.memory_budget.saturating_mul(1 << 20),
        },
    )
    .with_context(|| p.motion.display().to_string())?;
    if let Some(r) = &recon {
        r.finish();
    }
    // Encoding, prediction and surface, as the timing reports them (not the models' reading).
    let total = encode_s + transfer_start.elapsed().as_secs_f64();
    if let Some(w) = &result.blend_weights {
        let mean = w.iter().sum::<f64>() / w.len().max(1) as f64;
        let max = w.iter().cloned().fold(0.0, f64::max);
        mesh_core::info!(
            "blended placement: scaled-source weight mean {mean:.3}, max {max:.3}"
        );
    }
    if let Some(planted) = &result.planted {
        mesh_core::info!(
            "foot skating: {} frames with a planted foot, root shifted by at most {:.3} m",
            planted.planted_frames,
            planted.max_shift_m
        );
        if planted.max_body_drop_m > 0.0 {
            mesh_core::info!("foot height: the regressed root lowered or raised by at most {:.3} m", planted.max_body_drop_m);
        }
    }
    if let Some(path) = &p.confidence {
        let xd = crate::predict::displacement_matrix(&motion.info.displacements);
        let c = crate::confidence::confidence(&model, &motion.coefficients, &xd)
            .with_context(|| p.motion.display().to_string())?;
        mesh_core::atomic::write_bytes_atomic(path, serde_json::to_string(&c)?.as_bytes())?;
    }
    let t1 = Instant::now();
    let fps = output_rate(p, &motion)?;
    let writer = mesh_core::io::ply_frames::PlyFrames::new(tgt_pca.n_vertices, &faces);
    let outputs = [(p.corrected_out.as_ref(), result.corrected_frames.as_mut()), (Some(&p.out), Some(&mut result.frames))];
    for (dir, frames) in outputs {
        let (Some(dir), Some(frames)) = (dir, frames) else { continue };
        let bar = mesh_core::cli::stage_progress(frames.n_frames() as u64, "frames written");
        writer.write_dir_streamed(dir, fps, |push| frames.for_each(&mut |f| {
            bar.inc(1);
            push(f)
        }))?;
        bar.finish_and_clear();
    }
    let seconds = Seconds { encode: encode_s, total, write: t1.elapsed().as_secs_f64() };
    report_timing(p, motion.n_frames(), &seconds, &result.timing, recon.as_ref(), correct_stride)
}

/// Fails unless both PCA models have the model's parts and are the ones it was trained with.
fn check_models(p: &Params, model: &GprModel, src_pca: &PcaModel, tgt_pca: &PcaModel) -> anyhow::Result<()> {
    for (pca, path) in [(src_pca, &p.source_pca), (tgt_pca, &p.target_pca)] {
        let names: Vec<&String> = pca.parts.iter().map(|part| &part.name).collect();
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
    model
        .templates
        .check(src_pca, tgt_pca)
        .with_context(|| format!("{} with {} and {}", p.model.display(), p.source_pca.display(), p.target_pca.display()))?;
    Ok(())
}

/// The faces of `--target-template`, once it is checked to be the target PCA model's template.
fn target_faces(p: &Params, tgt_pca: &PcaModel) -> anyhow::Result<Vec<[u32; 3]>> {
    let template = mesh_core::io::read_mesh(&p.target_template)?;
    capture::part_pca::check_same_template(
        &mesh_core::artifact::sha256_file(&p.target_template)?,
        &tgt_pca.template_sha256,
        "this file is",
        "the target PCA model was fitted on",
    )
    .with_context(|| p.target_template.display().to_string())?;
    if template.n_vertices() != tgt_pca.n_vertices {
        bail!(
            "{}: {} vertices but the target PCA model was fitted on {}",
            p.target_template.display(),
            template.n_vertices(),
            tgt_pca.n_vertices
        );
    }
    Ok(template.faces)
}

/// The surface step `--surface` asks for (none to assemble the parts), and with a correction
/// the stride of the training frames it uses.
fn reconstructor(p: &Params, tgt_pca: &PcaModel, faces: &[[u32; 3]]) -> anyhow::Result<(Option<Reconstructor>, Option<usize>)> {
    let (surface, seg_path) = match (&p.surface, &p.segmentation) {
        (Surface::Assemble, _) | (_, None) => return Ok((None, None)),
        (surface, Some(seg_path)) => (*surface, seg_path),
    };
    let seg = Segmentation::load(seg_path)?;
    // The correction's training part meshes, read a frame at a time: the training
    // motions are never held whole. Stitching alone uses none.
    let corrected = matches!(surface, Surface::Correct | Surface::CorrectStitch);
    let paths = if corrected { p.target_training.as_slice() } else { &[] };
    let budget = p.memory_budget.saturating_mul(1 << 20);
    let stride = match p.correct_stride {
        Some(n) => Stride::Every(n.into()),
        None => Stride::Within(budget),
    };
    let (training, used) = training_part_meshes(tgt_pca, paths, stride)?;
    if used > 1 && p.correct_stride.is_none() {
        mesh_core::warn!(
            "the target's training part meshes do not fit in --memory-budget {} MiB: the correction uses every {used}th training frame (--correct-stride or a larger budget to choose)",
            p.memory_budget
        );
    }
    let recon = Reconstructor::with_training_meshes(tgt_pca, &seg, faces, training, surface, p.neighbours.into())
        .with_context(|| seg_path.display().to_string())?
        .with_corrected_assembly(p.corrected_out.is_some())
        .with_correction_cache(budget)
        .with_progress(mesh_core::cli::progress_bar(0, "gpr-predict: surface", &p.common));
    Ok((Some(recon), corrected.then_some(used)))
}

/// The output's frame rate: one output frame per source frame, so the sequence plays at the
/// source motion's rate. A model trained on source motions of another rate learnt
/// displacements per frame of that rate, which a warning says.
fn output_rate(p: &Params, motion: &SourceMotion) -> anyhow::Result<Option<f64>> {
    let fps = (motion.info.capture.fps > 0.0).then_some(motion.info.capture.fps);
    let (_, _, model_header) = mesh_core::artifact::read_header(&p.model)?;
    if let (Some(fps), Some(trained)) = (fps, model_header.params.get("source_fps").and_then(|f| f.as_f64())) {
        if fps != trained {
            mesh_core::warn!(
                "{}: {fps} fps, the model's source motions {trained} fps: its displacements are per frame of those",
                p.motion.display()
            );
        }
    }
    Ok(fps)
}

/// Wall times of a transfer (s): encoding the source, encoding to surface (`total`), writing.
struct Seconds {
    encode: f64,
    total: f64,
    write: f64,
}

/// Logs the transfer's timing (`-v`) and writes `--timing`.
fn report_timing(
    p: &Params,
    frames: usize,
    seconds: &Seconds,
    timing: &crate::predict::Timing,
    recon: Option<&Reconstructor>,
    correct_stride: Option<usize>,
) -> anyhow::Result<()> {
    let (encode_s, total, write) = (seconds.encode, seconds.total, seconds.write);
    let n = frames as f64;
    mesh_core::info!(
        "{} frames: encode {:.4} s, GP {:.4} s ({:.0} frames/s), decode+assemble {:.4} s, total {:.4} s, PLY writing {:.3} s",
        n,
        encode_s,
        timing.gp_s,
        n / timing.gp_s.max(1e-12),
        timing.decode_s,
        total,
        write
    );
    let surface = recon.map(|r| r.timing());
    if let Some(t) = &surface {
        let s = t.nearest_s + t.correct_s + t.merge_s;
        mesh_core::info!(
            "surface: {} frames in {s:.3} s ({:.1} frames/s): nearest meshes {:.3} s, correction {:.3} s, merge {:.3} s",
            t.frames,
            t.frames as f64 / s.max(1e-12),
            t.nearest_s,
            t.correct_s,
            t.merge_s
        );
    }
    if let Some(path) = &p.timing {
        let mut json = serde_json::json!({
            "frames": frames, "encode_s": encode_s, "gp_s": timing.gp_s,
            "gp_frames_per_s": n / timing.gp_s.max(1e-12), "decode_assemble_s": timing.decode_s,
            "total_s": total, "frames_per_s_without_writing": n / total.max(1e-12), "ply_write_s": write,
            "unstitched_frames": recon.map_or(0, |r| r.unstitched_frames()),
            "correct_stride": correct_stride,
            "factorisations": recon.map_or(0, |r| r.factorisations()),
        });
        if let Some(t) = surface {
            json["surface_s"] = serde_json::to_value(t)?;
        }
        mesh_core::atomic::write_bytes_atomic(
            path,
            serde_json::to_string_pretty(&json)?.as_bytes(),
        )?;
    }
    Ok(())
}
