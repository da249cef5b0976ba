//! The `transfer-eval` stage: per-vertex RMS error of a transferred sequence against its ground
//! truth (pose-aligned and as placed) and, given the contacts, the soles' sliding; with
//! `--time-normalise`, against a reference performance of another length instead
//! ([`crate::reference_score`]).

use std::path::PathBuf;

use anyhow::Context;
use capture::choices::{Correspondences, Placement};
use clap::Parser;
use mesh_core::artifact::Artifact;
use mesh_core::capture_set::SubjectSpec;
use mesh_core::cli::CommonArgs;
use mesh_core::segmentation::Segmentation;
use mesh_core::sequence::MeshSequence;
use serde::Serialize;

use crate::evaluate::{foot_sliding, rms_errors_per_frame, EvalRecord};

/// Per-vertex RMS error of a transferred sequence against its ground truth (pose-aligned and as placed)
#[derive(Parser, Debug, Serialize)]
#[command(
    name = "transfer-eval",
    version,
    after_help = "e.g.: transfer-eval out/transfer/A-to-B/punch/gpr-nn set/truth/B/punch --direction 'A->B' --motion punch --method gpr-nn --out out/eval/A-to-B/punch/gpr-nn.json\n\
                  e.g.: transfer-eval pred/back set/reference/sorceress/back --time-normalise --template set/sorceress/walk/000000.ply --direction 'sarge->sorceress' --motion back --method gpr-nn"
)]
pub struct Params {
    #[command(flatten)]
    #[serde(skip)]
    pub common: CommonArgs,
    /// Transferred sequence folder (from gpr-predict)
    pub prediction: PathBuf,
    /// Ground-truth folder (same frame count and topology), or with --time-normalise a reference
    /// performance (any frame count)
    pub truth: PathBuf,
    /// TRUTH is a reference performance: the target performing the motion its own way, timed
    /// differently.
    /// Each frame is compared with the reference at the same fraction of its length; with
    /// --template, the template held still is scored too (`still_rms_pose_m`)
    #[arg(long, conflicts_with = "contacts")]
    pub time_normalise: bool,
    /// Direction label for the record, e.g. A->B
    #[arg(long)]
    pub direction: String,
    /// Motion name for the record
    #[arg(long)]
    pub motion: String,
    /// Method name for the record
    #[arg(long)]
    pub method: String,
    /// Placement of the prediction, for the record
    #[arg(long, value_enum, default_value_t = Placement::Regressed)]
    pub placement: Placement,
    /// Correspondences the model was trained on, for the record
    #[arg(long, value_enum, default_value_t = Correspondences::Dense)]
    pub correspondences: Correspondences,
    /// The target's subject.json: foot sliding is measured on its `truth_contacts` of --motion
    /// (needs --segmentation and --template)
    #[arg(long, requires_all = ["segmentation", "template"])]
    pub contacts: Option<PathBuf>,
    /// The target's segmentation (its leg parts give the soles)
    #[arg(long)]
    pub segmentation: Option<PathBuf>,
    /// The target's template mesh (rest pose: the soles are its lowest leg vertices; with
    /// --time-normalise, the pose held still for the baseline score)
    #[arg(long)]
    pub template: Option<PathBuf>,
    /// Output JSON record (stdout when omitted)
    #[arg(short, long)]
    pub out: Option<PathBuf>,
}

/// Writes the JSON record to `--out`, or prints it on stdout.
pub fn run(p: &Params) -> anyhow::Result<()> {
    let pred = MeshSequence::load_dir(&p.prediction)?;
    let truth = MeshSequence::load_dir(&p.truth)?;
    if p.time_normalise {
        return write_record(p, reference_record(p, &pred, &truth)?);
    }
    let (rms_pose_m, rms_placed_m, frame_pose_m) = rms_errors_per_frame(&pred, &truth)
        .with_context(|| p.prediction.display().to_string())?;
    let (mut foot_sliding_m, mut truth_foot_sliding_m) = (None, None);
    if let (Some(spec_path), Some(seg_path), Some(tpl_path)) =
        (&p.contacts, &p.segmentation, &p.template)
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
            seg.parts.iter().map(|part| (part.name.as_str(), part.vertices.as_slice())).collect();
        let soles = mesh_core::feet::soles(&legs, &template.vertices, &up, mesh_core::feet::SOLE_TOLERANCE);
        if let Some(c) = mesh_core::contacts::from_subject_field(
            &spec,
            "truth_contacts",
            &p.motion,
            truth.n_frames(),
        )
        .with_context(|| spec_path.display().to_string())?
        {
            (foot_sliding_m, truth_foot_sliding_m) = foot_sliding(&pred, &truth, &soles, &c, &up)
                .with_context(|| p.prediction.display().to_string())?;
        }
    }
    let record = EvalRecord {
        direction: p.direction.clone(),
        motion: p.motion.clone(),
        method: p.method.clone(),
        placement: p.placement.name().to_string(),
        training: p.correspondences.name().to_string(),
        rms_pose_m,
        rms_placed_m,
        frames: pred.n_frames(),
        foot_sliding_m,
        truth_foot_sliding_m,
        frame_pose_m,
        reference_frames: None,
        still_rms_pose_m: None,
    };
    write_record(p, record)
}

/// The record of `--time-normalise`: time-normalised errors and the still baseline.
fn reference_record(p: &Params, pred: &MeshSequence, reference: &MeshSequence) -> anyhow::Result<EvalRecord> {
    let rest = match &p.template {
        Some(path) => Some(mesh_core::io::read_mesh(path)?.vertices),
        None => None,
    };
    let s = crate::reference_score::score_against_reference(pred, reference, rest.as_deref())
        .with_context(|| p.prediction.display().to_string())?;
    Ok(EvalRecord {
        direction: p.direction.clone(),
        motion: p.motion.clone(),
        method: p.method.clone(),
        placement: p.placement.name().to_string(),
        training: p.correspondences.name().to_string(),
        rms_pose_m: s.rms_pose_m,
        rms_placed_m: s.rms_placed_m,
        frames: pred.n_frames(),
        foot_sliding_m: None,
        truth_foot_sliding_m: None,
        frame_pose_m: s.frame_pose_m,
        reference_frames: Some(reference.n_frames()),
        still_rms_pose_m: s.still_rms_pose_m,
    })
}

/// Writes `record` to `--out`, or prints it on stdout.
fn write_record(p: &Params, record: EvalRecord) -> anyhow::Result<()> {
    let text = serde_json::to_string_pretty(&record)?;
    match &p.out {
        Some(path) => mesh_core::atomic::write_bytes_atomic(path, text.as_bytes())?,
        None => println!("{text}"),
    }
    Ok(())
}
