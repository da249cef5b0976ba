//! What `hmc-sample` reports ([`crate::synthesize::run`]): per synthesised sequence, its
//! variations measured against their source, and the run's chains, timings and notes.

use serde::{Deserialize, Serialize};

use crate::diversity::Diversity;
use crate::metrics::Stats;
use crate::sample::ChainStats;
use crate::synthesize::SynthConfig;
use crate::turns_and_tears::{CaptureLimits, TurnsAndTears};

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
    /// ([`crate::metrics::nearest_frame_distance`], frames aligned to the template; m): small when a
    /// variation stays on the source's cycle.
    pub manifold_distance_m: Vec<f64>,
    /// Mean |i − j| along the DTW path between variation and source (frames).
    pub timing_offset_frames: Vec<f64>,
    /// Each variation's pace: its [`crate::metrics::pose_speed`] over the source's (1: as lively as
    /// the source; a trajectory that settles toward a point gives a fraction).
    #[serde(default)]
    pub pose_speed_ratio: Vec<f64>,
    /// Each variation's horizontal travel along the source's, as a fraction of the source's
    /// ([`crate::metrics::travel_ratio`]; None where the source stays in place).
    #[serde(default)]
    pub travel_ratio: Vec<Option<f64>>,
    /// Mean per-vertex distance between pairs of variations (m).
    pub pairwise_distance_m: Stats,
    /// Mean relative edge-length change against the template: variations, and the source.
    pub edge_distortion: Vec<f64>,
    pub source_edge_distortion: f64,
    /// Foot sliding (m per contact frame pair): variations and source.
    pub foot_sliding_m: Vec<Option<f64>>,
    pub source_foot_sliding_m: Option<f64>,
    /// Largest depth of each variation's lowest point below the floor (the source's lowest
    /// point), after grounding when on (m; [`crate::grounding::floor_contact`]).
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
    /// Foot sliding before the foot-skating clean-up (after grounding; m per frame).
    #[serde(default)]
    pub raw_foot_sliding_m: Vec<Option<f64>>,
    /// Foot sliding on annotated contacts ([`crate::metrics::contact_sliding`]): variations after and
    /// before the clean-up (the source's annotations at the DTW-matched frames), and the
    /// source on its own annotations. Empty / None without annotations.
    #[serde(default)]
    pub contact_sliding_m: Vec<Option<f64>>,
    #[serde(default)]
    pub raw_contact_sliding_m: Vec<Option<f64>>,
    #[serde(default)]
    pub source_contact_sliding_m: Option<f64>,
    /// Largest horizontal root correction of each variation by the clean-up (m).
    #[serde(default)]
    pub footskate_max_m: Vec<f64>,
    /// Coverage, global and local diversity of the variations against the source
    /// ([`crate::diversity`]).
    #[serde(default)]
    pub diversity: Option<Diversity>,
    /// For a blend: the two learned weights whose variants were blended, the nearest on each
    /// side of `blend` among the pair's pre-blends and its captured motions (0 and 1); equal
    /// when `blend` is a learned weight.
    #[serde(default)]
    pub guided_from: Option<(f64, f64)>,
    /// Per variation, its frames that turn faster or stretch an edge further than the
    /// captures ever do ([`crate::turns_and_tears`]; `SynthReport::capture_limits`).
    #[serde(default)]
    pub turns_and_tears: Vec<TurnsAndTears>,
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
    /// Decoding, grounding, clean-ups, writing and statistics together (wall, s).
    pub seconds_decoding: f64,
    /// Writing the PLY files, summed over the parallel per-variation tasks (s; wall time of
    /// each task's writes), and computing the statistics (wall, s).
    #[serde(default)]
    pub seconds_writing: f64,
    #[serde(default)]
    pub seconds_statistics: f64,
    /// With the fast decoding (`--average`, mean poses): the largest certified bound on any
    /// pose coordinate's error against exact decoding over the sampled latent points (m);
    /// None with exact decoding.
    #[serde(default)]
    pub decoding_bound_m: Option<f64>,
    /// The captures' fastest turn and longest edge, which every sequence's
    /// `turns_and_tears` is held to (None without statistics).
    #[serde(default)]
    pub capture_limits: Option<CaptureLimits>,
}
