//! `gpdm-train`: one GPDM per body part on the group's time-aligned sequences (originals and
//! pre-blended `Y_w`), sharing one latent space per part with no dynamics across sequence
//! boundaries (3DV §5, eqs. 3-7; numerics in the `gpdm` crate).
//!
//! Defaults follow the paper (d = 3, PCA start, α_k = β_k = 1, noise variances 0.1) plus the
//! the deviations of docs/DEVIATIONS.md, which make 3DV eq. 7 well-posed: a pose-noise floor of 1e-6 m² (the noise-free
//! fit has no minimum), a dynamics-noise floor [`DYN_NOISE_FLOOR`], a weak log-normal factor on
//! β1..β3 and the latent scale fixed at unit mean square (`gpdm::model` module doc). The fit is
//! one joint L-BFGS run (memory [`LBFGS_MEMORY`]) that stops by convergence: relative decrease
//! below [`VALUE_TOLERANCE`] per iteration over a 10-iteration window, or ‖∇‖∞ ≤ 1e-3. Parts are trained in
//! parallel.

use gpdm::optim::{train as fit, Schedule, TrainOptions, TrainReport};
use gpdm::{Gpdm, GpdmConfig};
use mesh_core::artifact::Artifact;
use mesh_core::part_merge::{PartReports, Partitioned};
use mesh_core::rigid::RigidMotion;
use mesh_core::{Error, Result};
use nalgebra::{DMatrix, Vector3};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::contacts::Contacts;
use crate::frame_stride;
use crate::group::{Group, PartDef};
use crate::part_data::{self, DisplacementScale};
use crate::reference::{Landmarks, Reference};
use crate::turns_and_tears::CaptureLimits;

/// One part's model.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PartModel {
    pub part: PartDef,
    /// The template part: decoded poses are in its frame.
    pub reference: Vec<Vector3<f64>>,
    pub gpdm: Gpdm,
}

/// What a sampled sequence needs besides the latents.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SequenceInfo {
    pub name: String,
    /// For a pre-blended sequence, its weight between the motions of `blend_of`.
    pub blend: Option<f64>,
    /// For a pre-blended sequence, the indices of the two motions it blends (w = 0, w = 1).
    pub blend_of: Option<(usize, usize)>,
    /// World pose of the first frame: decoded motions start here.
    pub start_pose: RigidMotion,
    pub contacts: Option<Contacts>,
    /// What the post-processes read of the sequence's meshes ([`crate::reference`]).
    pub reference: Reference,
}

/// The trained variation model of one movement group.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct VariationModel {
    pub group: String,
    pub subject: String,
    pub fps: f64,
    pub up: Vector3<f64>,
    pub template: Vec<Vector3<f64>>,
    pub faces: Vec<[u32; 3]>,
    /// Part 0 is the torso; its poses carry the scaled displacement.
    pub parts: Vec<PartModel>,
    pub scale: DisplacementScale,
    pub sequences: Vec<SequenceInfo>,
    pub pair: Option<(usize, usize)>,
    /// Capture frames per training step of the GPDMs ([`crate::frame_stride`]; 1: every frame).
    pub stride: usize,
    /// Capture frames per training sequence (the GPDMs hold
    /// `frame_stride::kept_count(frames, stride)` of them).
    pub frames: usize,
    /// How fast the captures turn and how long their edges get, which the variations are held
    /// to ([`crate::turns_and_tears`], [`crate::turn_limit`]).
    pub capture_limits: CaptureLimits,
}

impl Artifact for VariationModel {
    const KIND: &'static str = "variation-model";
    const VERSION: u32 = 6;

    /// A valid body (`group::check_body`); per part a reference of its vertex count and a
    /// valid GPDM with one latent trajectory per training sequence, each of the
    /// `frame_stride::kept_count(frames, stride)` training steps; a stride >= 1; contacts of
    /// `frames` entries; reference trajectories of `frames` entries ([`Reference::check`]); the
    /// blend pair among the sequences.
    fn validate(&self) -> std::result::Result<(), String> {
        let defs: Vec<PartDef> = self.parts.iter().map(|p| p.part.clone()).collect();
        self.check(&defs)
    }
}

/// A piece (`gpdm-train --part NAME`) is the model holding that part alone.
impl Partitioned for VariationModel {
    const PIECE_KIND: &'static str = "variation-model-part";
    type Body = VariationModel;

    /// As [`VariationModel::validate`] for one part, whose parent (an index into the whole
    /// model's parts) is not checked.
    fn validate_body(body: &VariationModel) -> std::result::Result<(), String> {
        match body.parts.as_slice() {
            [p] => body.check(&[PartDef { parent: None, ..p.part.clone() }]),
            parts => Err(format!("{} parts in a piece, expected 1", parts.len())),
        }
    }

    /// The parts of the bodies in order; everything else must be equal.
    fn join(parts: &[String], bodies: Vec<VariationModel>) -> std::result::Result<VariationModel, String> {
        let mut bodies = bodies.into_iter();
        let mut whole = bodies.next().ok_or("no parts")?;
        let mut joined = std::mem::take(&mut whole.parts);
        for (mut b, name) in bodies.zip(&parts[1..]) {
            let own = std::mem::take(&mut b.parts);
            if b != whole {
                return Err(format!("part '{name}' was trained on another group, body, stride or sequences"));
            }
            joined.extend(own);
        }
        whole.parts = joined;
        match whole.parts.iter().zip(parts).find(|(p, n)| p.part.name != **n) {
            Some((p, n)) => Err(format!("the piece of part '{n}' holds part '{}'", p.part.name)),
            None => Ok(whole),
        }
    }
}

/// `gpdm-train --report`: the group, the configuration, the displacement scale and the stride,
/// then one entry per part (JSON: [`training_report`]).
impl PartReports for VariationModel {
    type Report = serde_json::Value;

    fn report_part(report: &serde_json::Value) -> std::result::Result<String, String> {
        match report["parts"].as_array().map(Vec::as_slice) {
            Some([one]) => one["part"].as_str().map(str::to_string).ok_or_else(|| "its part has no name".to_string()),
            Some(many) => Err(format!("a report of {} parts, not of one piece's part", many.len())),
            None => Err("no \"parts\" list: not a gpdm-train report".to_string()),
        }
    }

    /// The parts' entries in order; everything else must be equal.
    fn join_reports(reports: Vec<serde_json::Value>) -> std::result::Result<serde_json::Value, String> {
        let mut reports = reports.into_iter();
        let mut whole = reports.next().ok_or("no reports")?;
        let mut parts = whole["parts"].take();
        for mut r in reports {
            let own = r["parts"].take();
            if r != whole {
                return Err(format!("the report of part '{}' is of another group or configuration", own[0]["part"]));
            }
            if let (Some(all), Some(own)) = (parts.as_array_mut(), own.as_array()) {
                all.extend(own.iter().cloned());
            }
        }
        whole["parts"] = parts;
        Ok(whole)
    }

    fn report_text(report: &serde_json::Value) -> serde_json::Result<String> {
        Ok(serde_json::to_string_pretty(report)? + "\n")
    }
}

/// The `gpdm-train --report` of a training of `group` under `cfg` (JSON): the group's name, the
/// configuration, the model's displacement scale and stride, and per trained part its size,
/// time, hyperparameters and optimiser summary.
pub fn training_report(
    group: &str,
    cfg: &TrainConfig,
    scale: &DisplacementScale,
    stride: usize,
    reports: &[PartTrainReport],
) -> serde_json::Result<serde_json::Value> {
    let parts: Vec<_> = reports
        .iter()
        .map(|r| {
            serde_json::json!({
                "part": r.part, "frames": r.frames, "pose_dim": r.pose_dim, "seconds": r.seconds,
                "alpha": r.alpha, "beta": r.beta, "initial_value": r.report.initial_value,
                "final_value": r.report.final_value, "evaluations": r.report.evaluations,
                "iterations": r.report.history.len().saturating_sub(1),
                "beta_log_sd": cfg.gpdm.beta_log_sd, "fixed_latent_scale": cfg.gpdm.fixed_latent_scale,
                "exits": r.report.exits, "max_jitter": r.report.max_jitter,
            })
        })
        .collect();
    Ok(serde_json::json!({ "group": group, "config": serde_json::to_value(cfg)?, "scale": serde_json::to_value(scale)?,
        "stride": stride, "parts": parts }))
}

impl VariationModel {
    /// [`Artifact::validate`] with `defs` standing for the parts' definitions.
    fn check(&self, defs: &[PartDef]) -> std::result::Result<(), String> {
        crate::group::check_body(&self.template, &self.faces, &self.up, self.fps, defs)?;
        if self.stride == 0 || self.frames == 0 || self.sequences.is_empty() {
            return Err(format!("stride {}, {} frames, {} sequences", self.stride, self.frames, self.sequences.len()));
        }
        let c = &self.capture_limits;
        if ![c.max_turn_deg, c.max_edge_m, c.max_course_turn_deg, c.max_heading_turn_deg].iter().all(|v| v.is_finite() && *v >= 0.0) {
            return Err(format!("capture limits {c:?}: every figure must be a finite number >= 0"));
        }
        let steps = frame_stride::kept_count(self.frames, self.stride);
        for p in &self.parts {
            let what = |e: String| format!("part '{}': {e}", p.part.name);
            if p.reference.len() != p.part.vertices.len() {
                return Err(what(format!("{} reference points for {} vertices", p.reference.len(), p.part.vertices.len())));
            }
            p.gpdm.validate().map_err(what)?;
            if p.gpdm.seq_lens.len() != self.sequences.len() || p.gpdm.seq_lens.iter().any(|&l| l != steps) {
                return Err(what(format!(
                    "latent trajectories of {:?} steps for {} sequences of {steps}",
                    p.gpdm.seq_lens,
                    self.sequences.len()
                )));
            }
        }
        if let Some(s) = self.sequences.iter().find(|s| s.contacts.as_ref().is_some_and(|c| c.len() != self.frames)) {
            return Err(format!("sequence '{}': contacts of other than {} frames", s.name, self.frames));
        }
        // Leg heights are stored for every sequence or for none (a body without two legs).
        let legs = self.sequences.iter().any(|s| !s.reference.leg_lowest.is_empty());
        for s in &self.sequences {
            s.reference
                .check(self.frames, self.template.len(), legs)
                .map_err(|e| format!("sequence '{}': {e}", s.name))?;
        }
        let blends: Vec<(Option<f64>, Option<(usize, usize)>)> =
            self.sequences.iter().map(|s| (s.blend, s.blend_of)).collect();
        crate::group::check_blends(&blends)?;
        crate::group::check_pair(self.pair, self.sequences.len())
    }
}

impl VariationModel {
    /// Index of the training sequence named `name`.
    pub fn index(&self, name: &str) -> Option<usize> {
        self.sequences.iter().position(|s| s.name == name)
    }
    /// Training sequence `s`'s learned latent trajectory for every part, at the capture's rate
    /// (interpolated between the training steps when the stride is above 1).
    pub fn latents(&self, s: usize) -> Vec<DMatrix<f64>> {
        self.model_latents(s)
            .iter()
            .map(|x| frame_stride::upsample(x, self.stride, self.frames))
            .collect()
    }
    /// Training sequence `s`'s learned latent trajectory for every part, one row per training
    /// step (every `stride` capture frames).
    pub fn model_latents(&self, s: usize) -> Vec<DMatrix<f64>> {
        self.parts
            .iter()
            .map(|p| p.gpdm.sequence_latent(s).expect("sequence index in range"))
            .collect()
    }
    /// Capture frames per training sequence.
    pub fn n_frames(&self) -> usize {
        self.frames
    }
    /// Latent trajectories sampled at the training steps, brought to `frames` capture frames.
    pub fn to_capture_rate(&self, x: &[DMatrix<f64>], frames: usize) -> Vec<DMatrix<f64>> {
        x.iter()
            .map(|x| frame_stride::upsample(x, self.stride, frames))
            .collect()
    }
}

/// Default lower bound on the dynamics-noise variance 1/β4 (latent units², latents start at
/// unit variance). Without it 1/β4 collapses to ~1e-8 on some parts of the demo locomotion
/// (arm, legs), HMC's step size adapts down to ~1e-5 and those parts' samples are copies of
/// the source.
pub const DYN_NOISE_FLOOR: f64 = 1e-3;

/// Which frames train the GPDMs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum Fit {
    /// Every captured frame (the paper's fit; cost N³ per objective evaluation).
    Exact,
    /// Every s-th frame ([`crate::frame_stride`]): dynamics at about [`FIT_RATE`] fps, with at
    /// least [`MIN_FIT_FRAMES`] and at most [`MAX_FIT_FRAMES`] training frames per part (the
    /// default: docs/DEVIATIONS.md).
    #[default]
    Strided,
}

/// Default latent dimension d of every part's GPDM (the paper's is 3, `gpdm-train
/// --latent-dim 3`). With 3 a run's sampled trajectories settle toward a point: on the demo set
/// its variations cover 0.04 of the capture's ground at 0.52 of its pace; with 5, 0.99 at 0.85
/// (docs/studies/38-course-and-pace.md).
pub const LATENT_DIM: usize = 5;

/// Default frame rate of the strided fit (the 3DV paper's captures are 25 fps).
pub const FIT_RATE: f64 = 25.0;

/// Default bound on one part's training frames in the strided fit.
pub const MAX_FIT_FRAMES: usize = 240;

/// Default least number of one part's training frames in the strided fit: below it the stride
/// is lowered (down to every frame). Demo B's 104-frame jump at 50 fps kept 52 frames at 25 fps,
/// and its variations did not jump; with every frame they do
/// (docs/studies/24-short-clips.md).
pub const MIN_FIT_FRAMES: usize = 100;

/// Training settings.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TrainConfig {
    pub gpdm: GpdmConfig,
    pub options: TrainOptions,
    /// Frame rate the dynamics are learned at ([`crate::frame_stride`]): the stride is
    /// `round(fps / fit_rate)` (None: every frame, the paper's exact fit).
    #[serde(default)]
    pub fit_rate: Option<f64>,
    /// Least number of training frames of one part (all sequences): the stride is lowered
    /// until they are reached or the stride is 1 (None: no minimum).
    #[serde(default)]
    pub min_fit_frames: Option<usize>,
    /// Upper bound on the training frames of one part (all sequences): the stride is raised
    /// until they fit (None: no bound).
    #[serde(default)]
    pub max_fit_frames: Option<usize>,
}

/// L-BFGS memory of gpdm-train: on the N = 446, D = 15000 comparison problem 100 correction
/// pairs converge in ~2.5x fewer evaluations than the textbook 10; the two-loop
/// recursion costs O(memory · N d), negligible next to the O(N³) objective.
pub const LBFGS_MEMORY: usize = 100;

/// Relative decrease of the objective per iteration (over a 10-iteration window) below which
/// the fit stops. Demo B locomotion (50 fps, strided N = 222 per part): 1e-10 took 4016
/// evaluations on the torso, 1e-8 takes 1809 (320-1248 → 161-762 on the limbs) for the same
/// fig. 4 reconstruction (1.578 mm) and fig. 7b blend errors (1.724 / 1.972 mm) to 1 µm; 1e-7
/// (905) moves fig. 7b by 0.08-0.13 mm (docs/studies/12-gpdm-stopping-rule.md,
/// `fit_tolerance` in crates/studies).
pub const VALUE_TOLERANCE: f64 = 1e-8;

/// Iteration limit of the joint fit: with at most `max_fit_frames` frames per part the cost of one
/// evaluation is bounded, so this bounds a part's training whatever the capture's length (about
/// 2,000 × 1.6-2 ms on one core). The demo groups converge before it (the most, A's jump torso,
/// in 1,995 evaluations); on demo B's walk, run, dance_b group (612 frames, 204 per part) the torso
/// was still creeping at 10,000 (19.7 s), and stopping at 2,000 (3.3 s) gave fig. 4 2.70 mm
/// instead of 2.64, fig. 7b guided 10.12 / 8.15 mm instead of 9.46 / 9.22
/// (docs/studies/12-gpdm-stopping-rule.md).
pub const MAX_ITERATIONS: usize = 2000;

impl Default for TrainConfig {
    fn default() -> Self {
        let mut options = TrainOptions {
            schedule: Schedule::Joint,
            ..Default::default()
        };
        options.lbfgs.memory = LBFGS_MEMORY;
        options.lbfgs.value_tol = VALUE_TOLERANCE;
        options.lbfgs.value_window = 10;
        options.lbfgs.grad_tol = 1e-3;
        options.lbfgs.max_iter = MAX_ITERATIONS;
        options.lbfgs.max_evals = 20000;
        TrainConfig {
            gpdm: GpdmConfig {
                latent_dim: LATENT_DIM,
                dyn_noise_floor: Some(DYN_NOISE_FLOOR),
                ..Default::default()
            },
            options,
            fit_rate: Some(FIT_RATE),
            min_fit_frames: Some(MIN_FIT_FRAMES),
            max_fit_frames: Some(MAX_FIT_FRAMES),
        }
    }
}

impl TrainConfig {
    /// Selects the training frames: `Fit::Exact` clears the stride settings, `Fit::Strided`
    /// sets the rate and the frame bounds (the rate positive, the upper bound at least 2 and
    /// not below the lower; at least 2 per sequence is checked by [`train`]).
    pub fn fit(
        &mut self,
        fit: Fit,
        fit_rate: f64,
        min_fit_frames: usize,
        max_fit_frames: usize,
    ) -> Result<()> {
        match fit {
            Fit::Exact => {
                self.fit_rate = None;
                self.min_fit_frames = None;
                self.max_fit_frames = None;
            }
            Fit::Strided => {
                if !(fit_rate > 0.0 && fit_rate.is_finite()) {
                    return Err(Error::invalid(format!(
                        "fit rate {fit_rate} fps must be a positive number"
                    )));
                }
                if max_fit_frames < 2 {
                    return Err(Error::invalid(format!(
                        "max fit frames {max_fit_frames}: at least 2 are needed"
                    )));
                }
                if min_fit_frames > max_fit_frames {
                    return Err(Error::invalid(format!(
                        "min fit frames {min_fit_frames} above max fit frames {max_fit_frames}"
                    )));
                }
                self.fit_rate = Some(fit_rate);
                self.min_fit_frames = Some(min_fit_frames);
                self.max_fit_frames = Some(max_fit_frames);
            }
        }
        Ok(())
    }
}

/// Per-part training summary.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PartTrainReport {
    pub part: String,
    pub frames: usize,
    pub pose_dim: usize,
    pub seconds: f64,
    pub alpha: [f64; 3],
    pub beta: [f64; 4],
    pub report: TrainReport,
}

/// The stride [`train`] uses for `group` under `cfg` ([`frame_stride::stride_for`]).
pub fn fit_stride(group: &Group, cfg: &TrainConfig) -> usize {
    let sequences = group.sequences.len().max(1);
    let least = cfg.min_fit_frames.map(|m| m.div_ceil(sequences));
    let most = cfg.max_fit_frames.map(|m| m / sequences);
    frame_stride::stride_for(group.fps, cfg.fit_rate, group.n_frames(), least, most)
}

/// Per-part training matrices: `data[k][s]` is part `k`'s rows of sequence `s` at frames
/// `0, stride, 2·stride, …` (torso rows with the scaled per-capture-frame displacement and
/// gravity values), and the displacement scale.
pub fn training_data(group: &Group, stride: usize) -> (Vec<Vec<DMatrix<f64>>>, DisplacementScale) {
    let mut data: Vec<Vec<DMatrix<f64>>> = group
        .parts
        .par_iter()
        .map(|p| {
            let r = part_data::reference(&group.template, p);
            group
                .sequences
                .iter()
                .map(|s| {
                    frame_stride::strided_rows(&part_data::part_rows(&s.motion, p, &r), stride)
                })
                .collect()
        })
        .collect();
    let disp: Vec<Vec<[f64; 6]>> = group
        .sequences
        .iter()
        .map(|s| {
            if stride == 1 {
                part_data::model_displacements(&s.motion)
            } else {
                frame_stride::strided_displacements(&s.motion.displacements, stride)
            }
        })
        .collect();
    let scale = part_data::displacement_scale(&data[0], &disp);
    for ((m, d), s) in data[0].iter_mut().zip(&disp).zip(&group.sequences) {
        let grav = part_data::gravity(&s.motion, &group.up, &group.root_point());
        let grav: Vec<[f64; 4]> = frame_stride::kept_frames(grav.len(), stride)
            .into_iter()
            .map(|f| grav[f])
            .collect();
        *m = part_data::with_displacement(m, d, &grav, scale);
    }
    (data, scale)
}

/// Trains the model of `group`.
pub fn train(group: &Group, cfg: &TrainConfig) -> Result<(VariationModel, Vec<PartTrainReport>)> {
    train_with_progress(group, cfg, &|_| {})
}

/// [`train`], calling `part_done` with each part's name as its fit finishes (parts are
/// trained in parallel, so in any order).
pub fn train_with_progress(
    group: &Group,
    cfg: &TrainConfig,
    part_done: &(dyn Fn(&str) + Sync),
) -> Result<(VariationModel, Vec<PartTrainReport>)> {
    train_selected(group, cfg, None, part_done)
}

/// [`train_with_progress`] of part `only` alone (an index into `group.parts`; `None`: every
/// part): the model then holds that part only, trained exactly as in the whole model (the
/// displacement scale still comes from the torso's rows).
pub fn train_selected(
    group: &Group,
    cfg: &TrainConfig,
    only: Option<usize>,
    part_done: &(dyn Fn(&str) + Sync),
) -> Result<(VariationModel, Vec<PartTrainReport>)> {
    if let Some(k) = only.filter(|&k| k >= group.parts.len()) {
        return Err(Error::invalid(format!("part index {k} of {} parts", group.parts.len())));
    }
    if group.sequences.is_empty() || group.parts.is_empty() {
        return Err(Error::invalid(format!(
            "group '{}' has no sequences or no parts",
            group.name
        )));
    }
    let stride = fit_stride(group, cfg);
    if frame_stride::kept_count(group.n_frames(), stride) < 2 {
        return Err(Error::invalid(format!(
            "group '{}': {} frames per sequence at stride {stride} leave fewer than 2 training steps",
            group.name,
            group.n_frames()
        )));
    }
    let (data, scale) = training_data(group, stride);
    let results: Vec<Result<(PartModel, PartTrainReport)>> = group
        .parts
        .par_iter()
        .zip(data.into_par_iter())
        .enumerate()
        .filter(|(k, _)| only.is_none_or(|o| o == *k))
        .map(|(_, (p, seqs))| {
            let clock = std::time::Instant::now();
            let err = |e: gpdm::GpdmError| Error::invalid(format!("part '{}': {e}", p.name));
            let mut g = Gpdm::new(&seqs, cfg.gpdm.clone()).map_err(err)?;
            let report = fit(&mut g, &cfg.options).map_err(err)?;
            let rep = PartTrainReport {
                part: p.name.clone(),
                frames: g.y.nrows(),
                pose_dim: g.y.ncols(),
                seconds: clock.elapsed().as_secs_f64(),
                alpha: g.alpha,
                beta: g.beta,
                report,
            };
            let reference = part_data::reference(&group.template, p);
            part_done(&p.name);
            Ok((
                PartModel {
                    part: p.clone(),
                    reference,
                    gpdm: g,
                },
                rep,
            ))
        })
        .collect();
    let mut parts = Vec::new();
    let mut reports = Vec::new();
    for r in results {
        let (m, rep) = r?;
        parts.push(m);
        reports.push(rep);
    }
    let landmarks = Landmarks::of(&group.template, &group.faces, &group.parts, &group.up);
    let sequences = group
        .sequences
        .par_iter()
        .map(|s| SequenceInfo {
            name: s.name.clone(),
            blend: s.blend,
            blend_of: s.blend_of,
            start_pose: s.motion.poses[0],
            contacts: s.contacts.clone(),
            reference: Reference::of(&s.motion.world_frames(), &group.template, &landmarks, &group.up),
        })
        .collect();
    let model = VariationModel {
        group: group.name.clone(),
        subject: group.subject.clone(),
        fps: group.fps,
        up: group.up,
        template: group.template.clone(),
        faces: group.faces.clone(),
        parts,
        scale,
        sequences,
        pair: group.pair,
        stride,
        frames: group.n_frames(),
        capture_limits: CaptureLimits::of_group(group),
    };
    Ok((model, reports))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_fit_sets_or_clears_the_stride_bounds_and_refuses_bad_ones() {
        let mut cfg = TrainConfig::default();
        cfg.fit(Fit::Exact, 25.0, 100, 240).unwrap();
        assert_eq!((cfg.fit_rate, cfg.min_fit_frames, cfg.max_fit_frames), (None, None, None));
        cfg.fit(Fit::Strided, 30.0, 50, 200).unwrap();
        assert_eq!((cfg.fit_rate, cfg.min_fit_frames, cfg.max_fit_frames), (Some(30.0), Some(50), Some(200)));
        for (rate, min, max, says) in [
            (0.0, 100, 240, "fit rate"),
            (f64::NAN, 100, 240, "fit rate"),
            (25.0, 1, 1, "at least 2"),
            (25.0, 300, 240, "above max fit frames"),
        ] {
            let err = cfg.fit(Fit::Strided, rate, min, max).unwrap_err().to_string();
            assert!(err.contains(says), "{err}");
        }
    }
}
