use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Context;
use clap::Parser;
use mesh_core::cli::{run_stage, CommonArgs};
use mesh_core::artifact::Artifact;
use mesh_core::capture_set::SubjectSpec;
use mesh_core::segmentation::Segmentation;
use mesh_core::sequence::MeshSequence;
use capture::choices::{Correspondences, Placement};
use transfer::evaluate::{foot_sliding, rms_errors_per_frame, EvalRecord};

/// Per-vertex RMS error of a transferred sequence against its ground truth (pose-aligned and as placed)
#[derive(Parser, Debug)]
#[command(
    name = "transfer-eval",
    version,
    after_help = "e.g.: transfer-eval out/transfer/A-to-B/punch/gpr-nn set/truth/B/punch --direction 'A->B' --motion punch --method gpr-nn --out out/eval/A-to-B/punch/gpr-nn.json"
)]
struct Args {
    #[command(flatten)]
    common: CommonArgs,
    /// Transferred sequence folder (from gpr-predict)
    prediction: PathBuf,
    /// Ground-truth folder (same frame count and topology)
    truth: PathBuf,
    /// Direction label for the record, e.g. A->B
    #[arg(long)]
    direction: String,
    /// Motion name for the record
    #[arg(long)]
    motion: String,
    /// Method name for the record
    #[arg(long)]
    method: String,
    /// Placement of the prediction, for the record
    #[arg(long, value_enum, default_value_t = Placement::Regressed)]
    placement: Placement,
    /// Correspondences the model was trained on, for the record
    #[arg(long, value_enum, default_value_t = Correspondences::Dense)]
    correspondences: Correspondences,
    /// The target's subject.json: foot sliding is measured on its `truth_contacts` of --motion
    /// (needs --segmentation and --template)
    #[arg(long, requires_all = ["segmentation", "template"])]
    contacts: Option<PathBuf>,
    /// The target's segmentation (its leg parts give the soles)
    #[arg(long)]
    segmentation: Option<PathBuf>,
    /// The target's template mesh (rest pose: the soles are its lowest leg vertices)
    #[arg(long)]
    template: Option<PathBuf>,
    /// Output JSON record (stdout when omitted)
    #[arg(short, long)]
    out: Option<PathBuf>,
}

fn main() -> ExitCode {
    let args = mesh_core::cli::parse::<Args>();
    run_stage("transfer-eval", || {
        args.common.init()?;
        let pred = MeshSequence::load_dir(&args.prediction)?;
        let truth = MeshSequence::load_dir(&args.truth)?;
        let (rms_pose_m, rms_placed_m, frame_pose_m) = rms_errors_per_frame(&pred, &truth)
            .with_context(|| args.prediction.display().to_string())?;
        let (mut foot_sliding_m, mut truth_foot_sliding_m) = (None, None);
        if let (Some(spec_path), Some(seg_path), Some(tpl_path)) =
            (&args.contacts, &args.segmentation, &args.template)
        {
            let spec = SubjectSpec::load(spec_path)?;
            let up = spec.up_vector().with_context(|| {
                format!("{}: up axis '{}' is not one of ±x, ±y, ±z", spec_path.display(), spec.up)
            })?;
            let seg = Segmentation::load(seg_path)?;
            let template = mesh_core::io::read_mesh(tpl_path)?;
            if template.n_vertices() != seg.n_vertices {
                anyhow::bail!(
                    "{}: {} vertices but the segmentation was made for {}",
                    tpl_path.display(),
                    template.n_vertices(),
                    seg.n_vertices
                );
            }
            let legs: Vec<(&str, &[u32])> =
                seg.parts.iter().map(|p| (p.name.as_str(), p.vertices.as_slice())).collect();
            let soles = mesh_core::feet::soles(&legs, &template.vertices, &up, mesh_core::feet::SOLE_TOLERANCE);
            if let Some(c) = mesh_core::contacts::from_subject_field(
                &spec,
                "truth_contacts",
                &args.motion,
                truth.n_frames(),
            )
            .with_context(|| spec_path.display().to_string())?
            {
                (foot_sliding_m, truth_foot_sliding_m) = foot_sliding(&pred, &truth, &soles, &c, &up)
                    .with_context(|| args.prediction.display().to_string())?;
            }
        }
        let record = EvalRecord {
            direction: args.direction.clone(),
            motion: args.motion.clone(),
            method: args.method.clone(),
            placement: args.placement.name().to_string(),
            training: args.correspondences.name().to_string(),
            rms_pose_m,
            rms_placed_m,
            frames: pred.n_frames(),
            foot_sliding_m,
            truth_foot_sliding_m,
            frame_pose_m,
        };
        let text = serde_json::to_string_pretty(&record)?;
        match &args.out {
            Some(p) => mesh_core::atomic::write_bytes_atomic(p, text.as_bytes())?,
            None => println!("{text}"),
        }
        Ok(())
    })
}
