//! The `hmc-sample` stage end to end: variations of every training sequence and of requested
//! blends ([`crate::sample`]), decoded to meshes ([`crate::reconstruct`]), written as PLY
//! sequences `<out>/<label>/var<k>/NNNNNN.ply`, and measured against their source
//! ([`crate::metrics`]): the training sequence, or for a blend the non-linear mesh blend of the
//! pair at that weight. Post-processes, on by default, follow the decoding: [`grounding`]
//! (vertical) then [`footskate`] (horizontal root shift), both driven by the DTW correspondence
//! of each variation to its source, then [`foot_height`] (each sole at the source's height, swing
//! feet at least at its clearance) and [`foot_lock`] (planted soles pinned by their legs). The
//! clean-ups follow the source's contacts completed at the clip's ends
//! ([`foot_lock::close_clip_ends`]).

use std::path::Path;

use mesh_core::{Error, Result};
use nalgebra::Vector3;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::blend_guide::{self, BlendGuide};
use crate::contacts::Contacts;
use crate::diversity;
use crate::foot_height;
use crate::foot_lock;
use crate::footskate;
use crate::frame_writer::{VariationFormat, VariationWriter};
use crate::grounding::{self, FloorContact};
use crate::group::{blend_name, blend_sequences_at, Group, GroupSequence, PartDef};
use crate::latent_smoothing;
use crate::metrics::{self, Stats};
use crate::motion_matching::MatchOptions;
use crate::reconstruct::{Assembly, Decoder};
use crate::reference::{Landmarks, Reference};
use crate::sample::{
    blend_bounding, blend_entries, blend_variations, default_hmc, matched_blend_variations, mix, ChainStats, HmcStart,
    Sampler, Variations,
};
use crate::train::VariationModel;
use crate::turns_and_tears::{CaptureLimits, TurnsAndTears};
use crate::variant_cache::VariantCache;
pub use crate::synth_report::{SequenceReport, SynthReport};

/// Settings of [`run`].
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct SynthConfig {
    /// Variations per sequence.
    pub n: usize,
    /// Blend weights w* to synthesise (besides the training sequences).
    pub blends: Vec<f64>,
    pub seed: u64,
    /// Draw poses from 3DV eq. 11 instead of the mean (eq. 12).
    pub sample_poses: bool,
    pub assembly: Assembly,
    /// Trajectory sampler (HMC, the paper's, by default).
    #[serde(default)]
    pub sampler: Sampler,
    /// Settings of `Sampler::MotionMatching` ([`crate::motion_matching`]).
    #[serde(default)]
    pub motion_matching: MatchOptions,
    /// κ: every one-step variance of the sampled dynamics is κ σ²_X (1: the model's).
    #[serde(default = "one")]
    pub variance_scale: f64,
    pub burn_in: usize,
    /// Where every HMC chain starts (the paper's mean prediction by default).
    #[serde(default)]
    pub hmc_start: HmcStart,
    pub thin: usize,
    pub target_accept: f64,
    /// Ground every variation on its source ([`crate::grounding`]); on by default.
    #[serde(default = "yes")]
    pub grounding: bool,
    /// Turn every variation onto its source's course ([`crate::course`]), before grounding;
    /// on by default.
    #[serde(default = "yes")]
    pub course: bool,
    /// Pin planted feet by a horizontal root correction ([`crate::footskate`]), after
    /// grounding; on by default. Needs the source's contact annotations.
    #[serde(default = "yes")]
    pub footskate: bool,
    /// Weight λ of the correction's second differences ([`footskate::SMOOTHNESS`]).
    #[serde(default = "footskate_smoothness")]
    pub footskate_smoothness: f64,
    /// After the root clean-up, pin each planted sole by deforming its leg
    /// ([`crate::foot_lock`]); on by default.
    #[serde(default = "yes")]
    pub foot_lock: bool,
    /// How the foot lock eases in and out of each contact ([`foot_lock::Ease`]).
    #[serde(default)]
    pub foot_ease: foot_lock::Ease,
    /// After the root clean-up, bring each sole to the source's height at the matched frame
    /// (planted) or at least to its clearance (swing) by deforming its leg
    /// ([`crate::foot_height`]); on by default.
    #[serde(default = "yes")]
    pub foot_height: bool,
    /// Last, slow every variation where it turns faster than the captures' spin bounds
    /// ([`crate::turn_limit`], the model's capture limits); on by default.
    #[serde(default = "yes")]
    pub turn_limit: bool,
    /// Measure every sequence against its source ([`SequenceReport`]); off, the report's
    /// `sequences` is empty (a query that only wants meshes skips most of the cost).
    #[serde(default = "yes")]
    pub statistics: bool,
    /// Gaussian σ in frames of the temporal smoothing of every sampled latent trajectory
    /// before decoding ([`crate::latent_smoothing`]; `hmc-sample` uses
    /// [`crate::latent_smoothing::DEFAULT_SIGMA`]); 0 leaves them as sampled.
    #[serde(default)]
    pub latent_smoothing: f64,
    /// What to synthesise: None (every training sequence and the blends `blends` of the
    /// model's pair, the pipeline's default) or one [`Query`].
    #[serde(default)]
    pub query: Option<Query>,
    /// Frames per variation (None: the capture's length). Longer than the capture follows the
    /// learned dynamics past its end; shorter cuts.
    #[serde(default)]
    pub frames: Option<usize>,
    /// How each variation is written (a folder of PLY frames by default).
    #[serde(default)]
    pub frame_format: VariationFormat,
    /// What a blend's variations follow: the blend of the captures made per query, or the
    /// model's references of the nearest learned weights interpolated ([`crate::blend_guide`]).
    #[serde(default)]
    pub blend_guide: BlendGuide,
}

/// One request against a trained model.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Query {
    /// Variations of one training sequence, by name (a motion or a pre-blend `blend-<w>`).
    Motion(String),
    /// Variations of the blend at weight `w` ∈ [0, 1] of any two captured motions `a` (w = 0)
    /// and `b` (w = 1) of the group: guided by the learned pre-blends of that pair where the
    /// group has them (the nearest pre-blended weight on each side of `w`), else the
    /// endpoints' variants interpolated ([`crate::sample::blend_entries`]).
    Blend { a: String, b: String, w: f64 },
}

fn footskate_smoothness() -> f64 {
    footskate::SMOOTHNESS
}

fn one() -> f64 {
    1.0
}

fn yes() -> bool {
    true
}

/// The landmarks of the model's body ([`Landmarks::of`]).
fn model_landmarks(model: &VariationModel) -> Landmarks {
    let defs: Vec<PartDef> = model.parts.iter().map(|p| p.part.clone()).collect();
    Landmarks::of(&model.template, &model.faces, &defs, &model.up)
}

/// Certified bound (m) on every pose coordinate of the kernel-basis decoding at the training
/// latent points (`Decoder::with_pose_basis`); at the sampled points the bound is evaluated
/// and reported (`SynthReport::decoding_bound_m`).
pub const BASIS_TOLERANCE_M: f64 = 2e-7;

/// Contact height (m) for foot sliding and floating: a foot within it of the ground touches.
const CONTACT_HEIGHT: f64 = 0.02;

/// [`grounding::floor_contact`] of a variation against its job's source (lowest points of all
/// vertices, DTW-matched frames `matches`).
fn floor_contact(
    v: &[Vec<Vector3<f64>>],
    job: &Job,
    matches: &[f64],
    model: &VariationModel,
) -> FloorContact {
    grounding::floor_contact(
        &grounding::lowest(v, &[], &model.up),
        &job.reference.lowest,
        matches,
        CONTACT_HEIGHT,
    )
}

/// One decoded variation with what the post-processes saw and did.
struct Decoded {
    meshes: Vec<Vec<Vector3<f64>>>,
    /// DTW-matched source frame of every frame.
    matches: Vec<f64>,
    ungrounded: FloorContact,
    /// Foot sliding before the clean-up (geometric, annotated), measured for the statistics.
    raw_sliding: (Option<f64>, Option<f64>),
    /// Contacts transferred from the source (None without annotations).
    contacts: Option<Contacts>,
    footskate_max: f64,
    /// Certified bound on the basis decoding's error at this variation's latent points (m).
    bound: Option<f64>,
    /// Steps the turn limit spread over more than one frame ([`crate::turn_limit`]).
    slowed_steps: usize,
}

impl Decoded {
    /// Slows the meshes where they turn faster than `limits` allow ([`crate::turn_limit`]),
    /// the per-frame matches and contacts following the frames' new times.
    fn limit_turns(&mut self, core: &[u32], up: &Vector3<f64>, limits: &CaptureLimits) {
        let Some(times) = crate::turn_limit::limit(&mut self.meshes, core, up, limits) else { return };
        self.slowed_steps = crate::turn_limit::slowed_steps(&times);
        if !self.matches.is_empty() {
            self.matches = times.iter().map(|&u| crate::turn_limit::value_at(&self.matches, u)).collect();
        }
        if let Some(c) = self.contacts.as_mut().filter(|c| !c.is_empty()) {
            *c = times.iter().map(|&u| crate::turn_limit::nearest(c, u)).collect();
        }
    }
}

/// A sequence to synthesise: label, blend weight, latent variations, the source's reference
/// trajectories and meshes, start pose and the source's contacts.
struct Job {
    label: String,
    blend: Option<f64>,
    vars: Variations,
    /// What the post-processes read of the source ([`crate::reference`]).
    reference: Reference,
    /// The source's lowest height of each leg per frame ([`Reference::leg`]; empty without legs).
    source_legs: [Vec<f64>; 2],
    /// The source's meshes, for the statistics against it (None without the group).
    source: Option<Vec<Vec<Vector3<f64>>>>,
    start: mesh_core::rigid::RigidMotion,
    contacts: Option<Contacts>,
    /// The contacts the clean-ups follow: `contacts` completed at the clip's ends
    /// ([`foot_lock::close_clip_ends`]) where the legs are known.
    cleanup_contacts: Option<Contacts>,
    /// The source's lowest height over all frames (its floor).
    floor: f64,
    /// For a blend, the learned weights that guide it ([`SequenceReport::guided_from`]).
    guided_from: Option<(f64, f64)>,
}

impl Job {
    fn new(
        label: String,
        blend: Option<f64>,
        vars: Variations,
        reference: Reference,
        source: Option<Vec<Vec<Vector3<f64>>>>,
        start: mesh_core::rigid::RigidMotion,
        contacts: Option<Contacts>,
    ) -> Job {
        Job {
            label,
            blend,
            vars,
            source_legs: [reference.leg(0), reference.leg(1)],
            floor: reference.floor(),
            reference,
            source,
            start,
            cleanup_contacts: contacts.clone(),
            contacts,
            guided_from: None,
        }
    }
}

/// The learned weights of `entries` ([`blend_entries`], sorted) nearest to `w` on each side.
fn bounding(entries: &[(f64, usize)], w: f64) -> Option<(f64, f64)> {
    let lo = entries.iter().rev().find(|e| e.0 <= w)?.0;
    let hi = entries.iter().find(|e| e.0 >= w)?.0;
    Some((lo, hi))
}

/// The post-processes of one decoded variation, in order: DTW correspondence to the source,
/// grounding, root clean-up, foot heights, foot lock (module doc).
struct Post<'a> {
    model: &'a VariationModel,
    cfg: &'a SynthConfig,
    feet: Option<&'a [Vec<u32>; 2]>,
    leg_weights: Option<&'a [Vec<(u32, f64)>; 2]>,
    /// Sole vertices of the geometric foot-sliding rule.
    soles: &'a [Vec<u32>],
    /// The root part's core (`group::root_core`): headings are measured on it.
    core: &'a [u32],
}

impl Post<'_> {
    /// The variation `m` of `job` post-processed, and its notes.
    fn run(
        &self,
        mut m: Vec<Vec<Vector3<f64>>>,
        job: &Job,
        matcher: &grounding::MatchSource,
    ) -> Result<(Decoded, Vec<String>)> {
        let (model, cfg) = (self.model, self.cfg);
        // Rigid shifts of the variation leave the (pose-normalised) DTW unchanged.
        let matches = matcher.matches(&m);
        if cfg.course {
            let sigma = crate::course::SIGMA_SECONDS * model.fps;
            crate::course::keep(&mut m, &job.reference.heading, &matches, self.core, &model.up, sigma);
        }
        let low = grounding::lowest(&m, &[], &model.up);
        let ungrounded =
            grounding::floor_contact(&low, &job.reference.lowest, &matches, CONTACT_HEIGHT);
        if cfg.grounding {
            // Ground on the lowest point of the whole body: sampled feet often point their toes
            // through the floor while the template soles sit at the right height.
            grounding::ground_on(
                &mut m,
                &low,
                &job.reference.lowest,
                &matches,
                &model.up,
                grounding::SIGMA_FRAMES,
            );
        }
        let contacts = job
            .contacts
            .as_ref()
            .map(|c| footskate::transfer_contacts(c, &matches));
        // The clean-ups' contacts: the source's completed at the clip's ends.
        let cleanup_contacts = job
            .cleanup_contacts
            .as_ref()
            .map(|c| footskate::transfer_contacts(c, &matches));
        let raw_sliding = (
            cfg.statistics
                .then(|| metrics::foot_sliding(&m, self.soles, &model.up, CONTACT_HEIGHT))
                .flatten(),
            match (cfg.statistics, &contacts, self.feet) {
                (true, Some(c), Some(f)) => metrics::contact_sliding(&m, f, c, &model.up),
                _ => None,
            },
        );
        let mut notes = Vec::new();
        let mut footskate_max = 0.0;
        if let (true, Some(c), Some(f)) = (cfg.footskate, &cleanup_contacts, self.feet) {
            let d = footskate::clean(
                &mut m,
                f,
                c,
                &model.up,
                cfg.footskate_smoothness,
                &mut notes,
            )?;
            footskate_max = d.iter().map(|v| v.norm()).fold(0.0, f64::max);
            if let (true, Some(legs)) = (cfg.foot_height, self.leg_weights) {
                foot_height::lift(&mut m, &job.source_legs, &matches, legs, c, &model.up);
            }
            if let (true, Some(legs)) = (cfg.foot_lock, self.leg_weights) {
                let c = match cfg.foot_height {
                    // The legs now follow the source's heights: extend each contact over the
                    // variation's own touches of the source's floor next to it.
                    true => {
                        let low = foot_lock::legs_above_floor(&m, legs, &model.up, job.floor);
                        foot_lock::grow_over_touches(c, &low, CONTACT_HEIGHT, foot_lock::EASE_FRAMES)
                    }
                    false => c.clone(),
                };
                foot_lock::lock(&mut m, legs, f, &c, &model.up, cfg.foot_ease);
            }
        }
        Ok((
            Decoded {
                meshes: m,
                matches,
                ungrounded,
                raw_sliding,
                contacts,
                footskate_max,
                bound: None,
                slowed_steps: 0,
            },
            notes,
        ))
    }
}

/// The statistics of `job`'s variations `decoded` against its source's meshes `source`.
fn measure(
    job: &Job,
    source: &[Vec<Vector3<f64>>],
    decoded: &[Decoded],
    model: &VariationModel,
    soles: &[Vec<u32>],
    limits: &CaptureLimits,
) -> SequenceReport {
    let (label, blend) = (&job.label, job.blend);
    let vars: Vec<&Vec<Vec<Vector3<f64>>>> = decoded.iter().map(|d| &d.meshes).collect();
    let edges = metrics::edges(&model.faces);
    let slide =
        |f: &[Vec<Vector3<f64>>]| metrics::foot_sliding(f, &soles, &model.up, CONTACT_HEIGHT);
    // Each variation's frames aligned to the template (pose only) once, for every pose figure
    // and its diversity cost matrix, then dropped.
    let source_pose = metrics::normalise(source, &model.template);
    let source_speed = metrics::pose_speed(&source_pose);
    type PerVariation = (f64, f64, f64, Option<f64>, f64, f64, FloorContact, nalgebra::DMatrix<f64>, f64, Option<f64>);
    let per: Vec<PerVariation> = decoded
        .par_iter()
        .map(|d| {
            let v = &d.meshes;
            let pose = metrics::normalise(v, &model.template);
            (
                metrics::mean_vertex_distance(v, source),
                metrics::timing_offset_aligned(&pose, &source_pose),
                metrics::edge_distortion(v, &model.template, &edges),
                slide(v),
                metrics::mean_vertex_distance(&pose, &source_pose),
                metrics::nearest_frame_distance(&pose, &source_pose, 2000),
                floor_contact(v, job, &d.matches, model),
                crate::prealign::pose_cost(&pose, &source_pose, 400),
                metrics::pose_speed(&pose) / source_speed.max(f64::MIN_POSITIVE),
                metrics::travel_ratio(v, source, &model.up),
            )
        })
        .collect();
    let pairs: Vec<(usize, usize)> = (0..vars.len())
        .flat_map(|i| (i + 1..vars.len()).map(move |j| (i, j)))
        .collect();
    let pair: Vec<f64> = pairs
        .par_iter()
        .map(|&(i, j)| metrics::mean_vertex_distance(vars[i], vars[j]))
        .collect();
    let contact_sliding = |f: &[Vec<Vector3<f64>>], c: &Option<Contacts>| {
        c.as_ref()
            .and_then(|c| metrics::contact_sliding(f, &soles, c, &model.up))
    };
    let costs: Vec<nalgebra::DMatrix<f64>> = per.iter().map(|p| p.7.clone()).collect();
    SequenceReport {
        label: label.to_string(),
        blend,
        frames: source.len(),
        distance_to_source_m: per.iter().map(|p| p.0).collect(),
        pose_distance_to_source_m: per.iter().map(|p| p.4).collect(),
        manifold_distance_m: per.iter().map(|p| p.5).collect(),
        timing_offset_frames: per.iter().map(|p| p.1).collect(),
        pose_speed_ratio: per.iter().map(|p| p.8).collect(),
        travel_ratio: per.iter().map(|p| p.9).collect(),
        pairwise_distance_m: Stats::of(&pair),
        edge_distortion: per.iter().map(|p| p.2).collect(),
        source_edge_distortion: metrics::edge_distortion(source, &model.template, &edges),
        foot_sliding_m: per.iter().map(|p| p.3).collect(),
        source_foot_sliding_m: slide(source),
        penetration_m: per.iter().map(|p| p.6.penetration).collect(),
        floating_m: per.iter().map(|p| p.6.floating).collect(),
        ungrounded_penetration_m: decoded.iter().map(|d| d.ungrounded.penetration).collect(),
        ungrounded_floating_m: decoded.iter().map(|d| d.ungrounded.floating).collect(),
        raw_foot_sliding_m: decoded.iter().map(|d| d.raw_sliding.0).collect(),
        contact_sliding_m: decoded
            .iter()
            .map(|d| contact_sliding(&d.meshes, &d.contacts))
            .collect(),
        raw_contact_sliding_m: decoded.iter().map(|d| d.raw_sliding.1).collect(),
        source_contact_sliding_m: contact_sliding(source, &job.contacts),
        footskate_max_m: decoded.iter().map(|d| d.footskate_max).collect(),
        diversity: Some(diversity::from_costs(&costs, source.len(), model.fps)),
        guided_from: job.guided_from,
        turns_and_tears: {
            let defs: Vec<crate::group::PartDef> = model.parts.iter().map(|p| p.part.clone()).collect();
            let core = crate::group::root_core(&defs, model.template.len());
            decoded
                .par_iter()
                .map(|d| TurnsAndTears { slowed_steps: d.slowed_steps, ..TurnsAndTears::of(&d.meshes, &edges, &core, &model.up, limits) })
                .collect()
        },
    }
}

/// Samples, decodes, writes and measures every sequence of `model`. The post-processes follow
/// the sources' reference trajectories stored in the model; `group`, the captures the model was
/// trained on, is needed for blends (their sources are blends of its meshes) and for the
/// statistics against the sources (skipped with a note without it).
pub fn run(
    model: &VariationModel,
    group: Option<&Group>,
    cfg: &SynthConfig,
    out: &Path,
) -> Result<SynthReport> {
    run_with_progress(model, group, cfg, out, None, &|_, _| {})
}

/// [`run`], calling `progress(done, total)` after the sampling (done = 0) and after each
/// synthesised sequence is written; the sampled variants are read from and kept in `cache`
/// when one is given ([`crate::variant_cache`]).
pub fn run_with_progress(
    model: &VariationModel,
    group: Option<&Group>,
    cfg: &SynthConfig,
    out: &Path,
    cache: Option<&VariantCache>,
    progress: &dyn Fn(usize, usize),
) -> Result<SynthReport> {
    check_inputs(model, group, cfg)?;
    let mut notes = Vec::new();
    // The statistics compare with the captured meshes, which only the group holds.
    let compare = cfg.statistics && group.is_some();
    if cfg.statistics && !compare {
        notes.push("statistics against the sources skipped: they need the captures (--group)".into());
    }
    // Mean poses merged by averaging decode through kernel bases, fused with the assembly
    // (`reconstruct::FusedDecoder`); eq. 11 draws and stitching decode exactly.
    let fast = cfg.assembly != Assembly::Stitch && !cfg.sample_poses;
    let dec = if fast {
        Decoder::with_pose_basis(model, BASIS_TOLERANCE_M, &mut notes)?.0
    } else {
        Decoder::new(model, &mut notes)?
    };
    let clock = std::time::Instant::now();
    let mut hmc = default_hmc(cfg.n.max(1), cfg.seed);
    hmc.burn_in = cfg.burn_in;
    hmc.start = cfg.hmc_start.chain_start();
    hmc.thin = cfg.thin.max(1);
    hmc.target_accept = cfg.target_accept;
    let frames = cfg.frames.unwrap_or(model.n_frames());
    let (wanted, blends) = sequences_and_blends(model, cfg)?;
    // The exact guide blends the two motions' captured meshes, and so do the statistics against
    // a blend's source: refused before any sampling without them.
    let exact = cfg.blend_guide == BlendGuide::Exact;
    let blend_group = match (blends.is_empty() || !(exact || compare), group) {
        (true, _) => None,
        (false, Some(g)) => Some(g),
        (false, None) => {
            return Err(Error::invalid(match cfg.query {
                Some(_) => "the exact blend guide is made from the captured meshes: give the group (--group), or --blend-guide stored",
                None => "the exact blend guide is made from the captured meshes: give the group (--group), --blend-guide stored, or no blends (--blends '')",
            }))
        }
    };
    // Every (sequence, part) chain is a task of one pool (each seeded by its own indices, so
    // the samples do not depend on the scheduling).
    let sampled: Vec<(Variations, Vec<ChainStats>)> = wanted
        .par_iter()
        .map(|&s| crate::variant_cache::variants(&dec, s, frames, cfg, &hmc, cache))
        .collect::<Result<_>>()?;
    let mut pools: Vec<Variations> = vec![Vec::new(); model.sequences.len()];
    let mut chains = Vec::new();
    for (&s, (v, st)) in wanted.iter().zip(sampled) {
        pools[s] = v;
        chains.extend(st);
    }
    let landmarks = model_landmarks(model);
    let mut jobs: Vec<Job> = Vec::new();
    if cfg.query.is_none() || matches!(cfg.query, Some(Query::Motion(_))) {
        for &s in &wanted {
            let info = &model.sequences[s];
            jobs.push(Job::new(
                info.name.clone(),
                info.blend,
                pools[s].clone(),
                info.reference.clone(),
                group.filter(|_| compare).map(|g| g.sequences[s].motion.world_frames()),
                info.start_pose,
                info.contacts.clone(),
            ));
        }
    }
    if !blends.is_empty() {
        let blend_sources = BlendSources { group: blend_group, exact, compare, frames, landmarks: &landmarks };
        jobs.extend(blend_jobs(model, cfg, &dec, &pools, &blends, &blend_sources)?);
    }
    for job in &mut jobs {
        for parts in &mut job.vars {
            for x in parts.iter_mut() {
                latent_smoothing::smooth_trajectory(x, cfg.latent_smoothing);
            }
        }
    }
    let seconds_sampling = clock.elapsed().as_secs_f64();
    progress(0, jobs.len());
    let clock = std::time::Instant::now();
    let mut sequences = Vec::new();
    let Landmarks { core, soles: all_soles, feet, leg_weights } = landmarks;
    // The stored leg heights are the legs' (a body without legs has none).
    if let Some(job) = jobs.iter().find(|j| j.reference.leg_lowest.is_empty() != leg_weights.is_none()) {
        return Err(Error::invalid(format!(
            "{}: the model's reference trajectories do not hold the body's leg heights (retrain the model)",
            job.label
        )));
    }
    if cfg.foot_lock && cfg.footskate && feet.is_some() && leg_weights.is_none() {
        notes.push("foot lock skipped: the segmentation has no left and right leg parts".into());
    }
    if cfg.footskate && feet.is_none() {
        notes.push("foot-skating clean-up skipped: no left and right soles found".into());
    }
    if leg_weights.is_some() {
        for job in &mut jobs {
            let Some(c) = &job.contacts else { continue };
            let low = job.reference.legs_above(job.floor);
            job.cleanup_contacts = Some(foot_lock::close_clip_ends(c, &low, CONTACT_HEIGHT));
        }
    }
    let fused = fast.then(|| dec.fused(cfg.assembly)).transpose()?;
    let writer = VariationWriter::new(cfg.frame_format, model.template.len(), &model.faces);
    let post = Post {
        model,
        cfg,
        feet: feet.as_ref(),
        leg_weights: leg_weights.as_ref(),
        soles: &all_soles,
        core: &core,
    };
    let (mut seconds_writing, mut seconds_statistics) = (0.0, 0.0);
    let capture_limits = group.filter(|_| compare).map(|_| model.capture_limits);
    let mut decoding_bound: Option<f64> = None;
    let output = Output { dec: &dec, fused: fused.as_ref(), writer: &writer, post: &post, out };
    for (j, job) in jobs.iter().enumerate() {
        if cfg.footskate && job.contacts.is_none() {
            notes.push(format!(
                "{}: the source has no contact annotations: foot-skating clean-up skipped",
                job.label
            ));
        }
        let done = output.write_job(j, job)?;
        let mut decoded = Vec::with_capacity(done.len());
        for (k, (d, n, written)) in done.into_iter().enumerate() {
            decoding_bound = match (decoding_bound, d.bound) {
                (Some(a), Some(b)) => Some(f64::max(a, b)),
                (a, b) => a.or(b),
            };
            notes.extend(n.into_iter().map(|n| format!("{} var{k}: {n}", job.label)));
            seconds_writing += written;
            decoded.push(d);
        }
        let stats_clock = std::time::Instant::now();
        if let (Some(limits), Some(source)) = (&capture_limits, &job.source) {
            sequences.push(measure(job, source, &decoded, model, &all_soles, limits));
        }
        seconds_statistics += stats_clock.elapsed().as_secs_f64();
        progress(j + 1, jobs.len());
    }
    let rates: Vec<f64> = chains.iter().map(|c| c.accept_rate).collect();
    Ok(SynthReport {
        group: model.group.clone(),
        config: cfg.clone(),
        accept_rate: Stats::of(&rates),
        chains,
        sequences,
        notes,
        seconds_sampling,
        seconds_decoding: clock.elapsed().as_secs_f64(),
        seconds_writing,
        seconds_statistics,
        decoding_bound_m: decoding_bound,
        capture_limits,
    })
}

/// Refuses a group that is not the model's and a latent smoothing that is no width.
fn check_inputs(model: &VariationModel, group: Option<&Group>, cfg: &SynthConfig) -> Result<()> {
    if let Some(group) = group {
        if group.sequences.len() != model.sequences.len() || group.n_frames() != model.n_frames() {
            return Err(Error::invalid(
                "the group does not match the model (train the model from this group)",
            ));
        }
    }
    if !(cfg.latent_smoothing >= 0.0 && cfg.latent_smoothing.is_finite()) {
        return Err(Error::invalid(format!(
            "latent smoothing σ = {} frames: must be a finite number >= 0",
            cfg.latent_smoothing
        )));
    }
    Ok(())
}

/// The model's sequences to sample and the blends `(a, b, w)` to make, for every sequence or
/// for the query.
#[allow(clippy::type_complexity)]
fn sequences_and_blends(model: &VariationModel, cfg: &SynthConfig) -> Result<(Vec<usize>, Vec<(usize, usize, f64)>)> {
    let index = |name: &str| {
        model.index(name).ok_or_else(|| {
            let names: Vec<&str> = model.sequences.iter().map(|s| s.name.as_str()).collect();
            Error::invalid(format!(
                "no sequence '{name}' in the model (it has {})",
                names.join(", ")
            ))
        })
    };
    Ok(match &cfg.query {
        None => {
            let blends = if cfg.blends.is_empty() {
                Vec::new()
            } else {
                let (a, b) = model.pair.ok_or_else(|| {
                    Error::invalid("blends requested but the group has a single motion")
                })?;
                cfg.blends.iter().map(|&w| (a, b, w)).collect()
            };
            ((0..model.sequences.len()).collect(), blends)
        }
        Some(Query::Motion(name)) => (vec![index(name)?], Vec::new()),
        Some(Query::Blend { a, b, w }) => {
            let (ia, ib) = (index(a)?, index(b)?);
            if ia == ib
                || model.sequences[ia].blend.is_some()
                || model.sequences[ib].blend.is_some()
            {
                return Err(Error::invalid(format!(
                    "blend '{a}:{b}': two different captured motions are needed"
                )));
            }
            if !(0.0..=1.0).contains(w) {
                return Err(Error::invalid(format!("blend weight {w} outside [0, 1]")));
            }
            // Only the two learned weights bounding w are sampled (one at a learned weight).
            let [lo, hi] = blend_bounding(model, ia, ib, *w);
            let used = if lo.1 == hi.1 { vec![lo.1] } else { vec![lo.1, hi.1] };
            (used, vec![(ia, ib, *w)])
        }
    })
}

/// What the blends' jobs are made from: the group whose meshes are blended into their sources
/// (when the exact guide or the statistics need them), and the frames sampled.
struct BlendSources<'a> {
    group: Option<&'a Group>,
    exact: bool,
    compare: bool,
    frames: usize,
    landmarks: &'a Landmarks,
}

/// One job per blend `(a, b, w)`: its variations from the pools of the learned weights around
/// w (or matched, with motion matching), guided by the captures blended at w (every weight of a
/// pair from one decomposition of its frames) or by the model's stored references.
fn blend_jobs(
    model: &VariationModel,
    cfg: &SynthConfig,
    dec: &Decoder,
    pools: &[Variations],
    blends: &[(usize, usize, f64)],
    sources: &BlendSources,
) -> Result<Vec<Job>> {
    let mut truths: Vec<Option<GroupSequence>> = vec![None; blends.len()];
    let blender = match sources.group {
        Some(g) => Some(surface::blend::Blender::new(g.template.clone(), g.faces.clone())?),
        None => None,
    };
    for (i, &(a, b, _)) in blends.iter().enumerate() {
        let (Some(group), Some(blender)) = (sources.group, &blender) else { break };
        if truths[i].is_some() {
            continue;
        }
        let same: Vec<usize> = (i..blends.len())
            .filter(|&j| (blends[j].0, blends[j].1) == (a, b))
            .collect();
        let weights: Vec<f64> = same.iter().map(|&j| blends[j].2).collect();
        let made = blend_sequences_at(
            blender,
            &group.sequences[a],
            &group.sequences[b],
            &weights,
            &group.up,
            &group.root_point(),
        )?;
        for (j, t) in same.into_iter().zip(made) {
            truths[j] = Some(t);
        }
    }
    let mut jobs = Vec::new();
    for (&(a, b, w), truth) in blends.iter().zip(truths) {
        let vars = match cfg.sampler {
            Sampler::MotionMatching => matched_blend_variations(
                dec,
                (a, b),
                w,
                sources.frames,
                cfg.n,
                cfg.seed,
                &cfg.motion_matching,
            )?,
            _ => blend_variations(dec, pools, (a, b), w, cfg.n, cfg.seed)?,
        };
        let label = match cfg.query {
            None => blend_name(w),
            Some(_) => format!(
                "{}-{}-{w}",
                model.sequences[a].name, model.sequences[b].name
            ),
        };
        let frames = truth.as_ref().map(|t| t.motion.world_frames());
        let (reference, contacts) = match (sources.exact, &frames, truth) {
            (true, Some(f), Some(t)) => (Reference::of(f, &model.template, sources.landmarks, &model.up), t.contacts),
            _ => blend_guide::stored(model, a, b, w).map_err(Error::invalid)?,
        };
        let mut job = Job::new(
            label,
            Some(w),
            vars,
            reference,
            frames.filter(|_| sources.compare),
            model.sequences[a].start_pose,
            contacts,
        );
        job.guided_from = bounding(&blend_entries(model, a, b), w);
        if let Some((lo, hi)) = job.guided_from {
            mesh_core::info!("{}: variants of the learned weights {lo} and {hi} blended", job.label);
        }
        jobs.push(job);
    }
    Ok(jobs)
}

/// How a job's variations are decoded, cleaned up and written.
struct Output<'a, 'm> {
    dec: &'a Decoder<'m>,
    fused: Option<&'a crate::reconstruct::FusedDecoder<'a, 'm>>,
    writer: &'a VariationWriter,
    post: &'a Post<'m>,
    out: &'a Path,
}

impl Output<'_, '_> {
    /// Job `j`'s variations, one task each: decoded, cleaned up and written to its folder; the
    /// meshes are kept only for the statistics. Per variation: what it became, its notes and
    /// the seconds its writing took.
    fn write_job(&self, j: usize, job: &Job) -> Result<Vec<(Decoded, Vec<String>, f64)>> {
        let Output { dec, fused, writer, post, out } = *self;
        let (model, cfg) = (post.model, post.cfg);
        let matcher = job.reference.matcher(&model.template);
        let dir = out.join(&job.label);
        job
            .vars
            .par_iter()
            .enumerate()
            .map_init(
                || (crate::reconstruct::FusedScratch::default(), Vec::new(), Vec::new()),
                |(scratch, flat, spare), (k, latents)| {
                    let mut rng =
                        ChaCha8Rng::seed_from_u64(mix(cfg.seed, 0xDEC0DE + j as u64, k as u64));
                    let m = match fused {
                        // Mean poses merged by averaging: the fused kernel-basis decoder (one
                        // pass), its frames copied into the buffers of this thread's last
                        // variation when it kept none.
                        Some(f) => {
                            let nv = model.template.len();
                            let t_len = latents.first().map_or(0, |x| x.nrows());
                            flat.resize(t_len * nv, Vector3::zeros());
                            f.decode_average_into(latents, &job.start, scratch, flat)?;
                            let mut m: Vec<Vec<Vector3<f64>>> = std::mem::take(spare);
                            m.resize_with(t_len, Vec::new);
                            for (frame, c) in m.iter_mut().zip(flat.chunks_exact(nv.max(1))) {
                                frame.clear();
                                frame.extend_from_slice(c);
                            }
                            m
                        }
                        None => dec.decode(
                            latents,
                            &job.start,
                            cfg.assembly,
                            cfg.sample_poses.then_some(&mut rng),
                        )?,
                    };
                    let (mut d, notes) = post.run(m, job, &matcher)?;
                    // Last: the clean-ups turn the decoded frames less than they were sampled.
                    if cfg.turn_limit {
                        d.limit_turns(post.core, &model.up, &model.capture_limits);
                    }
                    if fused.is_some() && cfg.statistics {
                        d.bound = dec
                            .predictors
                            .iter()
                            .zip(latents)
                            .filter_map(|(pr, x)| pr.basis_error_bound(x))
                            .reduce(f64::max);
                    }
                    let clock = std::time::Instant::now();
                    writer.write(&dir, k, &d.meshes, Some(model.fps))?;
                    let written = clock.elapsed().as_secs_f64();
                    if !cfg.statistics {
                        *spare = std::mem::take(&mut d.meshes);
                    }
                    Ok((d, notes, written))
                },
            )
            .collect::<Result<_>>()
    }
}
