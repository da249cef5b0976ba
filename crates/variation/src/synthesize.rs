//! The `hmc-sample` stage end to end: variations of every training sequence and of requested
//! blends ([`crate::sample`]), decoded to meshes ([`crate::reconstruct`]), written as PLY
//! sequences `<out>/<label>/var<k>/NNNNNN.ply`, and measured against their source
//! ([`crate::metrics`]): the training sequence, or for a blend the non-linear mesh blend of the
//! pair at that weight.

use std::path::Path;

use mesh_core::sequence::MeshSequence;
use mesh_core::{Error, Result};
use nalgebra::Vector3;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::grounding::{self, FloorContact};
use crate::group::{blend_name, blend_sequences, Group};
use crate::metrics::{self, Stats};
use crate::reconstruct::{Assembly, Decoder};
use crate::sample::{
    blend_variations, default_hmc, mix, sequence_variations, ChainStats, Variations,
};
use crate::train::VariationModel;

/// Settings of [`run`].
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct SynthConfig {
    /// Variations per sequence.
    pub n: usize,
    /// Blend weights w* to synthesise (besides the training sequences).
    pub blends: Vec<f64>,
    pub seed: u64,
    /// Draw poses from eq. 11 instead of the mean (eq. 12).
    pub sample_poses: bool,
    pub assembly: Assembly,
    pub burn_in: usize,
    pub thin: usize,
    pub target_accept: f64,
    /// Ground every variation on its source ([`crate::grounding`]); on by default.
    #[serde(default = "yes")]
    pub grounding: bool,
}

fn yes() -> bool {
    true
}

/// Statistics of one synthesised sequence's variations.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct SequenceReport {
    pub label: String,
    pub blend: Option<f64>,
    pub frames: usize,
    /// Mean per-vertex distance of each variation to the source, world coordinates (m).
    pub distance_to_source_m: Vec<f64>,
    /// The same after rigidly aligning every frame to the template: pose only (m).
    pub pose_distance_to_source_m: Vec<f64>,
    /// Distance to the source's pose manifold whatever the timing
    /// ([`metrics::nearest_frame_distance`], frames aligned to the template; m): small when a
    /// variation stays on the source's cycle.
    pub manifold_distance_m: Vec<f64>,
    /// Mean |i − j| along the DTW path between variation and source (frames).
    pub timing_offset_frames: Vec<f64>,
    /// Mean per-vertex distance between pairs of variations (m).
    pub pairwise_distance_m: Stats,
    /// Mean relative edge-length change against the template: variations, and the source.
    pub edge_distortion: Vec<f64>,
    pub source_edge_distortion: f64,
    /// Foot sliding (m per contact frame pair): variations and source.
    pub foot_sliding_m: Vec<Option<f64>>,
    pub source_foot_sliding_m: Option<f64>,
    /// Largest depth of each variation's lowest point below the floor (the source's lowest
    /// point), after grounding when on (m; [`grounding::floor_contact`]).
    #[serde(default)]
    pub penetration_m: Vec<f64>,
    /// Largest height of each variation's lowest point above the floor over frames whose
    /// DTW-matched source frame is in contact (m).
    #[serde(default)]
    pub floating_m: Vec<f64>,
    /// The same two before grounding.
    #[serde(default)]
    pub ungrounded_penetration_m: Vec<f64>,
    #[serde(default)]
    pub ungrounded_floating_m: Vec<f64>,
}

/// Everything `hmc-sample` reports.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct SynthReport {
    pub group: String,
    pub config: SynthConfig,
    pub chains: Vec<ChainStats>,
    pub accept_rate: Stats,
    pub sequences: Vec<SequenceReport>,
    pub notes: Vec<String>,
    pub seconds_sampling: f64,
    pub seconds_decoding: f64,
}

/// Sole vertices of the model's template (both feet, [`metrics::soles`]).
fn model_soles(model: &VariationModel) -> Vec<Vec<u32>> {
    metrics::soles(
        &model
            .parts
            .iter()
            .map(|p| p.part.clone())
            .collect::<Vec<_>>(),
        &model.template,
        &model.up,
        0.015,
    )
}

/// Contact height (m) for foot sliding and floating: a foot within it of the ground touches.
const CONTACT_HEIGHT: f64 = 0.02;

/// [`grounding::floor_contact`] of a variation against its source (lowest points of all
/// vertices, DTW-matched frames).
fn floor_contact(
    v: &[Vec<Vector3<f64>>],
    source: &[Vec<Vector3<f64>>],
    model: &VariationModel,
) -> FloorContact {
    grounding::floor_contact(
        &grounding::lowest(v, &[], &model.up),
        &grounding::lowest(source, &[], &model.up),
        &grounding::correspondence(v, source, &model.template),
        CONTACT_HEIGHT,
    )
}

fn measure(
    label: &str,
    blend: Option<f64>,
    vars: &[Vec<Vec<Vector3<f64>>>],
    ungrounded: &[FloorContact],
    source: &[Vec<Vector3<f64>>],
    model: &VariationModel,
) -> SequenceReport {
    let edges = metrics::edges(&model.faces);
    let soles = model_soles(model);
    let slide =
        |f: &[Vec<Vector3<f64>>]| metrics::foot_sliding(f, &soles, &model.up, CONTACT_HEIGHT);
    let source_pose = metrics::normalise(source, &model.template);
    let per: Vec<(f64, f64, f64, Option<f64>, f64, f64, FloorContact)> = vars
        .par_iter()
        .map(|v| {
            let pose = metrics::normalise(v, &model.template);
            (
                metrics::mean_vertex_distance(v, source),
                metrics::timing_offset(v, source, &model.template),
                metrics::edge_distortion(v, &model.template, &edges),
                slide(v),
                metrics::mean_vertex_distance(&pose, &source_pose),
                metrics::nearest_frame_distance(&pose, &source_pose, 2000),
                floor_contact(v, source, model),
            )
        })
        .collect();
    let mut pair = Vec::new();
    for i in 0..vars.len() {
        for j in i + 1..vars.len() {
            pair.push(metrics::mean_vertex_distance(&vars[i], &vars[j]));
        }
    }
    SequenceReport {
        label: label.to_string(),
        blend,
        frames: source.len(),
        distance_to_source_m: per.iter().map(|p| p.0).collect(),
        pose_distance_to_source_m: per.iter().map(|p| p.4).collect(),
        manifold_distance_m: per.iter().map(|p| p.5).collect(),
        timing_offset_frames: per.iter().map(|p| p.1).collect(),
        pairwise_distance_m: Stats::of(&pair),
        edge_distortion: per.iter().map(|p| p.2).collect(),
        source_edge_distortion: metrics::edge_distortion(source, &model.template, &edges),
        foot_sliding_m: per.iter().map(|p| p.3).collect(),
        source_foot_sliding_m: slide(source),
        penetration_m: per.iter().map(|p| p.6.penetration).collect(),
        floating_m: per.iter().map(|p| p.6.floating).collect(),
        ungrounded_penetration_m: ungrounded.iter().map(|c| c.penetration).collect(),
        ungrounded_floating_m: ungrounded.iter().map(|c| c.floating).collect(),
    }
}

/// Samples, decodes, writes and measures every sequence of `model` (sources from `group`).
pub fn run(
    model: &VariationModel,
    group: &Group,
    cfg: &SynthConfig,
    out: &Path,
) -> Result<SynthReport> {
    if group.sequences.len() != model.sequences.len() || group.n_frames() != model.n_frames() {
        return Err(Error::invalid(
            "the group does not match the model (train the model from this group)",
        ));
    }
    let mut notes = Vec::new();
    let dec = Decoder::new(model, &mut notes)?;
    let clock = std::time::Instant::now();
    let mut hmc = default_hmc(cfg.n.max(1), cfg.seed);
    hmc.burn_in = cfg.burn_in;
    hmc.thin = cfg.thin.max(1);
    hmc.target_accept = cfg.target_accept;
    let mut pools: Vec<Variations> = Vec::new();
    let mut chains = Vec::new();
    for s in 0..model.sequences.len() {
        let (v, st) = sequence_variations(&dec, s, &hmc)?;
        pools.push(v);
        chains.extend(st);
    }
    let mut jobs: Vec<(
        String,
        Option<f64>,
        Variations,
        Vec<Vec<Vector3<f64>>>,
        mesh_core::rigid::RigidMotion,
    )> = Vec::new();
    for (s, info) in model.sequences.iter().enumerate() {
        jobs.push((
            info.name.clone(),
            info.blend,
            pools[s].clone(),
            group.sequences[s].motion.world_frames(),
            info.start_pose,
        ));
    }
    if !cfg.blends.is_empty() {
        let (a, b) = model
            .pair
            .ok_or_else(|| Error::invalid("blends requested but the group has a single motion"))?;
        let blender = surface::blend::Blender::new(group.template.clone(), group.faces.clone())?;
        for &w in &cfg.blends {
            let vars = blend_variations(&dec, &pools, w, cfg.n, cfg.seed)?;
            let truth = blend_sequences(
                &blender,
                &group.sequences[a],
                &group.sequences[b],
                w,
                &group.up,
            )?;
            jobs.push((
                blend_name(w),
                Some(w),
                vars,
                truth.motion.world_frames(),
                model.sequences[a].start_pose,
            ));
        }
    }
    let seconds_sampling = clock.elapsed().as_secs_f64();
    let clock = std::time::Instant::now();
    let mut sequences = Vec::new();
    // Ground on the lowest point of the whole body: sampled feet often point their toes through
    // the floor while the template soles sit at the right height (h15, render check).
    let soles: Vec<u32> = Vec::new();
    for (j, (label, blend, vars, source, start)) in jobs.iter().enumerate() {
        let decoded: Vec<(Vec<Vec<Vector3<f64>>>, FloorContact)> = vars
            .par_iter()
            .enumerate()
            .map(|(k, latents)| {
                let mut rng =
                    ChaCha8Rng::seed_from_u64(mix(cfg.seed, 0xDEC0DE + j as u64, k as u64));
                let mut m = dec.decode(
                    latents,
                    start,
                    cfg.assembly,
                    cfg.sample_poses.then_some(&mut rng),
                )?;
                let before = floor_contact(&m, source, model);
                if cfg.grounding {
                    grounding::ground(
                        &mut m,
                        source,
                        &soles,
                        &model.template,
                        &model.up,
                        grounding::SIGMA_FRAMES,
                    );
                }
                Ok((m, before))
            })
            .collect::<Result<_>>()?;
        let (meshes, ungrounded): (Vec<_>, Vec<_>) = decoded.into_iter().unzip();
        for (k, m) in meshes.iter().enumerate() {
            MeshSequence::new(model.faces.clone(), m.clone())
                .write_dir(out.join(label).join(format!("var{k}")))?;
        }
        sequences.push(measure(label, *blend, &meshes, &ungrounded, source, model));
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
    })
}
