//! The `transfer-eval` stage: per-vertex RMS error of a transferred sequence against its ground
//! truth (pose-aligned and as placed) and, given the contacts, the soles' sliding; given the
//! source motion and both PCA models, the sliding and floor offset on the source's contacts
//! (all that is measured without truth); with `--time-normalise`, against a reference
//! performance of another length instead ([`crate::reference_score`]).

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

use capture::align::AlignedMotion;
use capture::part_pca::PcaModel;
use nalgebra::Vector3;

use crate::evaluate::{foot_sliding, rms_errors_per_frame, without_truth, EvalRecord, SourceMeasures};

/// Per-vertex RMS error of a transferred sequence against its ground truth (pose-aligned and as placed), foot sliding and floor offset
#[derive(Parser, Debug, Serialize)]
#[command(
    name = "transfer-eval",
    version,
    after_help = "e.g.: transfer-eval out/transfer/A-to-B/punch/gpr-nn set/truth/B/punch --direction 'A->B' --motion punch --method gpr-nn --out out/eval/A-to-B/punch/gpr-nn.json\n      \
                  transfer-eval out/transfer/A-to-B/punch/gpr-nn --source-motion work/A/punch.aligned --source-pca work/A/pca.model --target-pca work/B/pca.model \\\n        \
                  --direction 'A->B' --motion punch --method gpr-nn --out eval.json     # without truth\n      \
                  transfer-eval pred/back set/reference/sorceress/back --time-normalise --template set/sorceress/walk/000000.ply --direction 'sarge->sorceress' --motion back --method gpr-nn"
)]
pub struct Params {
    #[command(flatten)]
    #[serde(skip)]
    pub common: CommonArgs,
    /// Transferred sequence folder (from gpr-predict)
    pub prediction: PathBuf,
    /// Ground-truth folder (same frame count and topology), or with --time-normalise a reference
    /// performance (any frame count) [default: none: the record holds the measures on the
    /// source's contacts, which need --source-motion]
    #[arg(required_unless_present = "source_motion")]
    pub truth: Option<PathBuf>,
    /// TRUTH is a reference performance: the target performing the motion its own way, timed
    /// differently. Each frame is compared with the reference at the same fraction of its
    /// length, and along the frames' least-cost alignment (`dtw_rms_pose_m`, timing-free); with
    /// --template, the template held still is scored too (`still_rms_pose_m`,
    /// `still_dtw_rms_pose_m`)
    #[arg(long, conflicts_with = "contacts", requires = "truth")]
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
    /// The aligned source motion the prediction transfers (align): foot sliding and floor offset on
    /// its contacts, detected on its meshes (needs --source-pca and --target-pca)
    #[arg(long, value_name = "ALIGNED", requires_all = ["source_pca", "target_pca"])]
    pub source_motion: Option<PathBuf>,
    /// Per-part PCA model of the source (its leg parts give the source's soles)
    #[arg(long)]
    pub source_pca: Option<PathBuf>,
    /// Per-part PCA model of the target (its leg parts give the soles, its template the floor)
    #[arg(long)]
    pub target_pca: Option<PathBuf>,
    /// Output JSON record (stdout when omitted)
    #[arg(short, long)]
    pub out: Option<PathBuf>,
}

/// Writes the JSON record to `--out`, or prints it on stdout.
pub fn run(p: &Params) -> anyhow::Result<()> {
    let pred = MeshSequence::load_dir(&p.prediction)?;
    let source = match &p.source_motion {
        Some(m) => source_measures(p, m, &pred)?,
        None => SourceMeasures::default(),
    };
    let Some(truth_dir) = &p.truth else {
        let record = EvalRecord {
            foot_sliding_m: source.foot_sliding_m,
            source_foot_sliding_m: source.source_foot_sliding_m,
            floor_offset_m: source.floor_offset_m,
            ..record(p, &pred, None, None, Vec::new())
        };
        return write(p, &record);
    };
    let truth = MeshSequence::load_dir(truth_dir)?;
    if p.time_normalise {
        return write(p, &reference_record(p, &pred, &truth)?);
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
        foot_sliding_m,
        truth_foot_sliding_m,
        floor_offset_m: source.floor_offset_m,
        ..record(p, &pred, Some(rms_pose_m), Some(rms_placed_m), frame_pose_m)
    };
    write(p, &record)
}

/// The record's labels and errors, without foot measures.
fn record(p: &Params, pred: &MeshSequence, pose: Option<f64>, placed: Option<f64>, frames: Vec<f64>) -> EvalRecord {
    EvalRecord {
        direction: p.direction.clone(),
        motion: p.motion.clone(),
        method: p.method.clone(),
        placement: p.placement.name().to_string(),
        training: p.correspondences.name().to_string(),
        rms_pose_m: pose,
        rms_placed_m: placed,
        frames: pred.n_frames(),
        foot_sliding_m: None,
        truth_foot_sliding_m: None,
        source_foot_sliding_m: None,
        floor_offset_m: None,
        frame_pose_m: frames,
        reference_frames: None,
        still_rms_pose_m: None,
        dtw_rms_pose_m: None,
        still_dtw_rms_pose_m: None,
    }
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
        reference_frames: Some(reference.n_frames()),
        still_rms_pose_m: s.still_rms_pose_m,
        dtw_rms_pose_m: s.dtw_rms_pose_m,
        still_dtw_rms_pose_m: s.still_dtw_rms_pose_m,
        ..record(p, pred, Some(s.rms_pose_m), Some(s.rms_placed_m), s.frame_pose_m)
    })
}

fn write(p: &Params, record: &EvalRecord) -> anyhow::Result<()> {
    let text = serde_json::to_string_pretty(record)?;
    match &p.out {
        Some(path) => mesh_core::atomic::write_bytes_atomic(path, text.as_bytes())?,
        None => println!("{text}"),
    }
    Ok(())
}

/// Sliding and floor offset of `pred` on the contacts of the source motion at `motion`.
fn source_measures(p: &Params, motion: &std::path::Path, pred: &MeshSequence) -> anyhow::Result<SourceMeasures> {
    let (Some(sp), Some(tp)) = (&p.source_pca, &p.target_pca) else {
        anyhow::bail!("--source-motion needs --source-pca and --target-pca");
    };
    let source = AlignedMotion::load(motion)?;
    let (source_pca, target_pca) = (PcaModel::load(sp)?, PcaModel::load(tp)?);
    let up = Vector3::from(source.capture.up);
    let Some(found) = crate::feet::source_contacts(&source_pca, &source) else {
        mesh_core::info!("{}: no two leg parts or no frame rate: no contacts", motion.display());
        return Ok(SourceMeasures::default());
    };
    let Some(target) = crate::feet::TargetFeet::of(&target_pca, &up) else {
        mesh_core::info!("{}: the target has no two leg parts: no soles", tp.display());
        return Ok(SourceMeasures::default());
    };
    without_truth(pred, &target, &found.contacts, (&found.world, &found.soles), &up)
        .with_context(|| p.prediction.display().to_string())
}
