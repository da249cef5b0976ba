//! The `hmc-sample` stage: variations of every training motion and of blends, sampled by Hybrid
//! Monte Carlo in the GPDM latent spaces (3DV §5) and written as meshes.

use std::path::PathBuf;

use anyhow::Context;
use clap::Parser;
use mesh_core::artifact::Artifact;
use mesh_core::cli::CommonArgs;
use serde::Serialize;

use crate::blend_guide::BlendGuide;
use crate::frame_writer::VariationFormat;
use crate::group::Group;
use crate::memory_budget;
use crate::motion_matching::{Examples, MatchOptions, Start as MatchStart};
use crate::reconstruct::Assembly;
use crate::sample::{HmcStart, Sampler};
use crate::synthesize::{run_with_progress, Query, SynthConfig};
use crate::train::VariationModel;
use crate::variant_cache::VariantCache;

/// Sample variations of every training motion and of blends by HMC in the GPDM latent spaces and write them as meshes
#[derive(Parser, Debug, Serialize)]
#[command(
    name = "hmc-sample",
    version,
    after_help = "e.g.: hmc-sample --seed 0 -n 5 --blends 0.25,0.75 --group work/locomotion.group --model work/locomotion.model --out out/variation/locomotion --report work/locomotion-samples.json\n      hmc-sample --model work/locomotion.model --motion walk -n 20 --frame-count 300 --seed 7 --out out/walk20\n      hmc-sample --model work/locomotion.model --blend walk:run --weight 0.3 -n 10 --sampler ancestral --out out/blend03"
)]
pub struct Params {
    #[command(flatten)]
    #[serde(skip)]
    pub common: CommonArgs,
    /// Trained model (kind variation-model, from gpdm-train)
    #[arg(long)]
    pub model: PathBuf,
    /// The prealigned group the model was trained on: the captures the statistics compare with
    /// and exact blend guides are made from (without it: every query from the model alone)
    #[arg(long)]
    pub group: Option<PathBuf>,
    /// Variations per sequence
    #[arg(short, long, default_value_t = 5, value_parser = at_least(1))]
    pub n: usize,
    /// Only variations of this training sequence (a motion of the group, or a pre-blend
    /// `blend-<w>`), instead of every sequence and the --blends
    #[arg(long, conflicts_with = "blend")]
    pub motion: Option<String>,
    /// Only variations of the blend of two motions of the group, `A:B` at --weight (guided by
    /// that pair's nearest pre-blended weights on each side, by the two motions' own variants
    /// for a pair without pre-blends)
    #[arg(long, value_name = "A:B", requires = "weight", value_parser = super::parse_pair)]
    #[serde(serialize_with = "pair_as_text")]
    pub blend: Option<(String, String)>,
    /// Weight w* in [0, 1] of the --blend (0: A, 1: B)
    #[arg(short, long, value_name = "W", requires = "blend")]
    pub weight: Option<f64>,
    /// What a blend's variations follow (heading, heights, matched frames, contacts of its
    /// source): exact (the two captures' meshes blended at --weight per query, which needs
    /// --group) or stored (the model's references of the nearest learned weights on each side,
    /// interpolated; docs/DEVIATIONS.md) [default: exact with --group, stored without]
    #[arg(long, value_enum)]
    pub blend_guide: Option<BlendGuide>,
    /// Frames per variation [default: the capture's length]; longer follows the dynamics on
    /// past the capture's end, shorter cuts
    #[arg(long, value_name = "N", value_parser = at_least(2))]
    pub frame_count: Option<usize>,
    /// Blend weights w* in [0, 1] to synthesise, comma-separated (empty: none)
    #[arg(long, default_value = "0.25,0.75", value_parser = parse_weights)]
    pub blends: Weights,
    /// Draw poses from the predictive distribution (3DV eq. 11) instead of its mean (eq. 12)
    #[arg(long)]
    pub sample_poses: bool,
    /// How parts are merged: feather (children aligned on their bands, then weights ramping
    /// smoothly from parent to child across each band: the seams of stitch at a quarter of its
    /// time, docs/DEVIATIONS.md), stitch (the paper's optimal-boundary Poisson stitching, per
    /// frame) or average (shared vertices averaged uniformly). With feather or average and mean
    /// poses the poses decode through kernel bases, fused with the merge
    #[arg(long, value_enum, default_value_t = Assembly::Feather)]
    pub assembly: Assembly,
    /// Trajectory sampler: hmc (the paper's Hybrid Monte Carlo), ancestral (independent draws
    /// of the same density kept on the learned data, one forward pass each; burn-in and thinning
    /// do not apply) or motion-matching (a training-free baseline: generative motion matching,
    /// GenMM, over every part's learned latent points jointly, the queried sequence's patches
    /// matched coarse to fine from a random phase of its cycle; no new poses, and copies of the
    /// source where the learned trajectories are no closed cycles, e.g. jumps; the --match-*
    /// settings apply, the HMC ones and --variance-scale do not;
    /// docs/studies/39-motion-matching-baseline.md)
    #[arg(long, value_enum, default_value_t = Sampler::Hmc)]
    pub sampler: Sampler,
    /// With --sampler motion-matching: the sequences matched against, own (the queried one) or
    /// group (every sequence of the group, started from the queried one)
    #[arg(long, value_enum, default_value_t = Examples::Own)]
    pub match_examples: Examples,
    /// With --sampler motion-matching: noise added to the coarsest start, in units of each
    /// part's spread (a patch's many coordinates average it out: on the demo set 0 to 3 give the
    /// same variations)
    #[arg(long, default_value_t = MatchOptions::default().noise)]
    pub match_noise: f64,
    /// With --sampler motion-matching: patch length in training steps (the same at every level)
    #[arg(long, default_value_t = MatchOptions::default().patch, value_parser = at_least(1))]
    pub match_patch: usize,
    /// With --sampler motion-matching: α of GenMM's completeness normalisation (each example
    /// patch's distances divided by α plus its distance to the nearest synthesis patch, so
    /// unused example patches are preferred; GenMM uses 0.01); 0: plain nearest neighbours
    #[arg(long, default_value_t = MatchOptions::default().alpha.unwrap_or(0.0))]
    pub match_alpha: f64,
    /// With --sampler motion-matching: how the coarsest level starts, phase (the queried
    /// trajectory from a random point of its first half, replayed past its end, with noise),
    /// shuffle (random crops of the examples end to end: their pieces recombined; seams may
    /// spin) or source (the queried trajectory with noise, GenMM's: on short captures the
    /// variations are copies of their source)
    #[arg(long, value_enum, default_value_t = MatchStart::Phase)]
    pub match_start: MatchStart,
    /// With --sampler motion-matching: most pyramid levels (each half the previous one's length;
    /// fewer when a level would hold less than one patch)
    #[arg(long, default_value_t = MatchOptions::default().levels, value_parser = at_least(1))]
    pub match_levels: usize,
    /// Scale κ of every one-step variance of the sampled dynamics (1: the model's density, as in
    /// the paper; below 1: trajectories closer to the learned dynamics, less frame-to-frame jitter)
    #[arg(long, default_value_t = crate::sample::VARIANCE_SCALE)]
    pub variance_scale: f64,
    /// Where every HMC chain starts: mean (the mean prediction, 3DV eq. 8, as in the paper)
    /// or ancestral (an exact draw of the sampled density: stationary from the start, so a
    /// short burn-in suffices; docs/DEVIATIONS.md)
    #[arg(long, value_enum, default_value_t = HmcStart::Mean)]
    pub hmc_start: HmcStart,
    /// HMC burn-in iterations (step size adapted) [default: 200 with --hmc-start mean, 50 with
    /// ancestral]
    #[arg(long)]
    pub burn_in: Option<usize>,
    /// Keep one HMC iteration in THIN
    #[arg(long, default_value_t = 10, value_parser = at_least(1))]
    pub thin: usize,
    /// Target acceptance rate during burn-in
    #[arg(long, default_value_t = 0.7)]
    pub target_accept: f64,
    /// Do not ground the variations (by default each frame is shifted vertically, smoothly in
    /// time, so that its soles follow the source's at the DTW-matched frame)
    #[arg(long)]
    pub no_grounding: bool,
    /// Do not keep the variations on their sources' course (by default each frame is turned
    /// about the vertical, slowly in time, so that its heading follows the source's at the
    /// DTW-matched frame; the sway within a stride is the variation's own)
    #[arg(long)]
    pub no_course: bool,
    /// Do not clean up foot skating (by default each frame is shifted horizontally, smoothly in
    /// time, so that feet planted in the source at the DTW-matched frame stay put; a foot on
    /// the source's floor at the clip's first or last frame counts as planted there)
    #[arg(long)]
    pub no_footskate: bool,
    /// Smoothness λ of the foot-skating correction (weight of its second differences against
    /// the contact residuals; larger: smoother root, feet pinned less tightly)
    #[arg(long, default_value_t = crate::footskate::SMOOTHNESS)]
    pub footskate_smoothness: f64,
    /// Do not lock planted feet by deforming the legs (by default, after the root clean-up,
    /// each planted sole's remaining slide is removed by shifting its leg, weighted from the
    /// sole up to the hip, by 10 cm at most)
    #[arg(long)]
    pub no_foot_lock: bool,
    /// How the foot lock eases in before and out after each contact: flight (offset where both
    /// feet take off or land together, within 4 frames: a jump; position for every other step),
    /// position (the sole's position blended from its free path to the planted spot, so it
    /// lands and lifts off from rest) or offset (the planted offset faded, the free path's
    /// speed kept up to the contact)
    #[arg(long, value_enum, default_value_t = crate::foot_lock::Ease::Flight)]
    pub foot_ease: crate::foot_lock::Ease,
    /// Do not set the feet's heights by deforming the legs (by default, after the root
    /// clean-up, each planted sole is brought to the source's height at the matched frame and
    /// each swing foot raised to at least the source's clearance, by 5 cm at most)
    #[arg(long)]
    pub no_foot_height: bool,
    /// Do not slow the variations where they turn faster than the captures (by default, last,
    /// each step between frames that turns the whole body or its heading faster than 1.25x the
    /// captures' fastest is spread over more frames, interpolated; the variation keeps its
    /// frame count and ends a little earlier in the motion)
    #[arg(long)]
    pub no_turn_limit: bool,
    /// Smooth every sampled latent trajectory in time with a Gaussian of SIGMA frames before
    /// decoding (first point kept; 0 = off: the trajectories as sampled). Two frames by
    /// default with hmc and ancestral: the sampled trajectories jitter frame to frame, which
    /// decoded turns the body faster than any capture; 0 with motion-matching, whose
    /// trajectories are averages of learned points and do not jitter (smoothed, a run's swift
    /// latent steps are cut short)
    #[arg(long, value_name = "SIGMA")]
    pub latent_smoothing: Option<f64>,
    /// Output folder: <out>/<sequence>/var<k>/NNNNNN.ply, or with --frame-format pc2
    /// <out>/<sequence>/var<k>.obj + var<k>.pc2
    #[arg(short, long)]
    pub out: PathBuf,
    /// How each variation is written: ply (a folder of binary PLY frames) or pc2 (its first
    /// frame as OBJ plus a float32 point cache, a quarter of the bytes)
    #[arg(long, value_enum, default_value_t = VariationFormat::Ply)]
    pub frame_format: VariationFormat,
    /// Statistics against the sources (JSON); without it they are not computed. Those that
    /// compare with the captures need --group: without it the report says they were skipped
    #[arg(long)]
    pub report: Option<PathBuf>,
    /// Sample a --blend's guiding variants again instead of reading and keeping them beside
    /// the model (by default the variants of the learned weights bounding --weight are sampled
    /// once per setting and kept in <model>.variants/, which later blend queries read;
    /// docs/FORMATS.md)
    #[arg(long)]
    pub no_variant_cache: bool,
}

/// A count of at least `min` (a smaller one means nothing: a usage error).
fn at_least(min: u64) -> clap::builder::RangedU64ValueParser<usize> {
    clap::builder::RangedU64ValueParser::<usize>::new().range(min..)
}

/// `--blend` as written on the command line (`A:B`), or `null`.
fn pair_as_text<S: serde::Serializer>(pair: &Option<(String, String)>, ser: S) -> Result<S::Ok, S::Error> {
    match pair {
        Some((a, b)) => ser.serialize_str(&format!("{a}:{b}")),
        None => ser.serialize_none(),
    }
}

/// Comma-separated weights; the empty string is an empty list.
#[derive(Clone, Debug, Serialize)]
#[serde(transparent)]
pub struct Weights(pub Vec<f64>);

fn parse_weights(s: &str) -> Result<Weights, String> {
    s.split(',')
        .map(str::trim)
        .filter(|w| !w.is_empty())
        .map(|w| {
            w.parse::<f64>()
                .map_err(|_| format!("'{w}' is not a number"))
        })
        .collect::<Result<_, _>>()
        .map(Weights)
}

/// Writes the variations as PLY frames (and the `--report` statistics when asked).
pub fn run(p: &Params) -> anyhow::Result<()> {
    // The two inputs are read side by side, then checked against each other.
    let (model, group) = rayon::join(
        || VariationModel::load_hashed(&p.model),
        || p.group.as_ref().map(Group::load).transpose(),
    );
    let ((model, model_sha256), group) = (model?, group?);
    if let (Some(group), Some(path)) = (&group, &p.group) {
        crate::trained_on::check(&model, group)
            .with_context(|| format!("{} with {}", p.model.display(), path.display()))?;
    }
    // The query's size against the machine's memory, before anything of that size is allocated.
    let frames = p.frame_count.unwrap_or(model.n_frames());
    let needed = memory_budget::bytes_needed(p.n, frames, model.template.len(), rayon::current_num_threads());
    memory_budget::check(p.n, frames, needed, memory_budget::physical_memory())?;
    let cfg = SynthConfig {
        n: p.n,
        blends: p.blends.0.clone(),
        seed: p.common.seed,
        sample_poses: p.sample_poses,
        assembly: p.assembly,
        sampler: p.sampler,
        motion_matching: MatchOptions {
            examples: p.match_examples,
            noise: p.match_noise,
            patch: p.match_patch,
            alpha: (p.match_alpha != 0.0).then_some(p.match_alpha),
            start: p.match_start,
            levels: p.match_levels,
            ..MatchOptions::default()
        },
        variance_scale: p.variance_scale,
        burn_in: p.burn_in.unwrap_or(p.hmc_start.default_burn_in()),
        hmc_start: p.hmc_start,
        thin: p.thin,
        target_accept: p.target_accept,
        grounding: !p.no_grounding,
        course: !p.no_course,
        footskate: !p.no_footskate,
        footskate_smoothness: p.footskate_smoothness,
        foot_lock: !p.no_foot_lock,
        foot_ease: p.foot_ease,
        foot_height: !p.no_foot_height,
        turn_limit: !p.no_turn_limit,
        // The statistics against the sources are the report's content: skipped without one.
        statistics: p.report.is_some(),
        latent_smoothing: p.latent_smoothing.unwrap_or(match p.sampler {
            Sampler::MotionMatching => 0.0,
            _ => crate::latent_smoothing::DEFAULT_SIGMA,
        }),
        query: match (&p.motion, &p.blend, p.weight) {
            (Some(m), _, _) => Some(Query::Motion(m.clone())),
            (None, Some((a, b)), Some(w)) => Some(Query::Blend {
                a: a.clone(),
                b: b.clone(),
                w,
            }),
            _ => None,
        },
        frames: p.frame_count,
        frame_format: p.frame_format,
        blend_guide: p.blend_guide.unwrap_or(match group {
            Some(_) => BlendGuide::Exact,
            None => BlendGuide::Stored,
        }),
    };
    // A blend query's guiding variants are kept beside the model, for this build's sampler.
    let cache = match (&cfg.query, p.no_variant_cache, cfg.sampler) {
        (Some(Query::Blend { .. }), false, Sampler::Hmc | Sampler::Ancestral) => {
            Some(VariantCache::beside(&p.model, model_sha256, crate::variant_cache::this_build()?))
        }
        _ => None,
    };
    // Sampling first (a spinner), then one step per synthesised sequence.
    let bar = mesh_core::cli::progress_bar(0, "hmc-sample: sampling", &p.common);
    bar.enable_steady_tick(std::time::Duration::from_millis(200));
    let report = run_with_progress(&model, group.as_ref(), &cfg, &p.out, cache.as_ref(), &|done, total| {
        if done == 0 {
            bar.set_length(total as u64);
            bar.set_message("hmc-sample: sequences");
        }
        bar.set_position(done as u64);
    })?;
    bar.finish_and_clear();
    for n in &report.notes {
        mesh_core::warn!("{n}");
    }
    mesh_core::info!(
        "HMC acceptance {:.2} (min {:.2}, max {:.2})",
        report.accept_rate.mean,
        report.accept_rate.min,
        report.accept_rate.max
    );
    if let Some(path) = &p.report {
        mesh_core::atomic::write_bytes_atomic(
            path,
            (serde_json::to_string_pretty(&report)? + "\n").as_bytes(),
        )?;
    }
    Ok(())
}
