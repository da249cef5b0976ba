//! The stages of variation synthesis (Boukhayma & Boyer, "Controllable Variation Synthesis for
//! Surface Motion Capture", 3DV 2017).
//!
//! Data flows one way: capture set -> [`prealign`] (contact-guided DTW of one movement group to a
//! reference after cutting locomotion to whole [`gait`] cycles, [`contacts`] from the subject description, pre-blended `Y_w` sequences, §7) ->
//! [`part_data`] (per-part pose vectors, §4) -> [`train`] (one GPDM per part, §5) -> [`sample`]
//! (mean prediction + HMC over latent trajectories, §6; latent blending, §7, of variants a blend query
//! keeps beside the model: [`variant_cache`]) -> [`reconstruct`]
//! (3DV eqs. 11-13, stitching, displacement integration) -> [`grounding`] (feet on the source's floor, a
//! post-process; the post-processes read the source's [`reference`] trajectories, stored in the model) -> [`footskate`] (planted feet kept in place by a root shift, a post-process) ->
//! [`foot_lock`] (the rest of each planted sole's slide absorbed by its leg) -> [`metrics`],
//! [`turns_and_tears`] (frames that spin or tear past the captures' own figures); [`evaluate`]
//! measures a model (3DV figs. 4 and 7b, the plots' data);
//! [`synthesize`] runs the query end to end and [`synth_report`] holds what it reports.

pub mod blend_guide;
pub mod contacts;
pub mod course;
pub mod diversity;
pub mod evaluate;
pub mod foot_height;
pub mod foot_lock;
pub mod footskate;
pub mod frame_stride;
pub mod frame_writer;
pub mod gait;
pub mod grounding;
pub mod group;
pub mod latent_smoothing;
pub mod local_linear;
pub mod memory_budget;
pub mod metrics;
pub mod motion_matching;
pub mod part_data;
pub mod prealign;
pub mod reconstruct;
pub mod reference;
pub mod sample;
pub mod stage;
pub mod synth_report;
pub mod synthesize;
pub mod train;
pub mod trained_on;
pub mod turn_limit;
pub mod turns_and_tears;
pub mod variant_cache;
