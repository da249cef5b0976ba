//! The pipelines' options: the variables `pipelines/transfer.mk` and `pipelines/variation.mk`
//! take (README, "Pipelines"), as one clap struct. Values that only travel to a stage's command
//! line are kept as the text given, so the command is the one a user would type.

use std::path::PathBuf;

use clap::{Args, ValueEnum};
use serde::Serialize;
pub use capture::align::AlignFrame;
pub use capture::choices::{MeanFunction, Method};
pub use capture::part_pca::PartAlignment;
pub use capture::choices::Placement;

/// `gpr-train --method`, parsed by the stage's own names.
fn parse_method(s: &str) -> Result<Method, String> {
    Method::from_name(s).ok_or_else(|| {
        let names: Vec<&str> = Method::ALL.iter().map(|m| m.name()).collect();
        format!("unknown method '{s}' ({})", names.join(", "))
    })
}

/// The name clap shows for a value (its command-line spelling).
pub fn value_name<T: ValueEnum>(v: T) -> String {
    v.to_possible_value()
        .map(|p| p.get_name().to_string())
        .unwrap_or_default()
}

/// Where the pipelines read and write.
#[derive(Args, Clone, Debug, PartialEq, Serialize)]
pub struct Paths {
    /// Capture-set folder (docs/FORMATS.md)
    #[arg(long)]
    pub set: PathBuf,
    /// The pipelines' output folder (make's OUT): results under it, intermediates under OUT/work
    #[arg(long, value_name = "DIR")]
    pub pipeline_out: PathBuf,
}

/// `make transfer`'s options (pipelines/transfer.mk).
#[derive(Args, Clone, Debug, PartialEq, Serialize)]
pub struct TransferOptions {
    /// Transfer methods (TRANSFER_METHODS); gpr-nn with key-poses only is always added
    #[arg(long, num_args = 1.., value_parser = parse_method, default_values = ["gpr-nn", "gpr-se", "gpr-linear", "keypose-affine", "whole-body"])]
    pub methods: Vec<Method>,
    /// align --frame (ALIGN_FRAME) [default: align's]
    #[arg(long, value_enum, default_value_t = AlignFrame::default(), hide_default_value = true)]
    pub align_frame: AlignFrame,
    /// pca-fit --part-alignment (PART_ALIGNMENT) [default: pca-fit's]
    #[arg(long, value_enum, default_value_t = PartAlignment::default(), hide_default_value = true)]
    pub part_alignment: PartAlignment,
    /// gpr-predict --placement of every method (PLACEMENT); gpr-nn is also placed the other ways
    /// [default: gpr-predict's]
    #[arg(long, value_enum, default_value_t = Placement::PREDICT_DEFAULT, hide_default_value = true)]
    pub placement: Placement,
    /// gpr-train --mean of every model (GPR_MEAN); unset: the configuration's (gpr-train
    /// --config, in GPR_TRAIN_FLAGS; the default configuration's is affine)
    #[arg(long, value_enum)]
    pub gpr_mean: Option<MeanFunction>,
    /// Further gpr-train flags for every model, one string (GPR_TRAIN_FLAGS)
    #[arg(long, default_value = "", allow_hyphen_values = true, value_name = "FLAGS")]
    pub gpr_train_flags: String,
    /// pca-fit --components per part (PCA_COMPONENTS); the whole body gets parts x this
    #[arg(long, default_value_t = 20, value_name = "K")]
    pub pca_components: u32,
}

/// `make variation`'s options (pipelines/variation.mk).
#[derive(Args, Clone, Debug, PartialEq, Serialize)]
pub struct VariationOptions {
    /// prealign --subject-name (VARIATION_SUBJECT) [default: the set's source subject]
    #[arg(long)]
    pub variation_subject: Option<String>,
    /// A movement group and its motions, `NAME=M1,M2` (VARIATION_GROUPS, VARIATION_MOTIONS_<g>); repeat
    #[serde(rename = "variation_group")]
    #[arg(long = "variation-group", value_name = "NAME=MOTIONS", value_parser = parse_group)]
    pub groups: Vec<(String, String)>,
    /// Extra prealign flags of a group, `NAME=FLAGS` (VARIATION_PREALIGN_FLAGS_<g>); repeat
    #[arg(long = "prealign-flags", value_name = "NAME=FLAGS", allow_hyphen_values = true, value_parser = parse_group)]
    pub prealign_flags: Vec<(String, String)>,
    /// prealign --blend-weights (VARIATION_W)
    #[arg(long, default_value = "0.5", value_name = "W")]
    pub variation_w: String,
    /// hmc-sample --blends (VARIATION_BLENDS); a group of one motion is sampled without blends
    #[arg(long, default_value = "0.25,0.75", value_name = "W,...")]
    pub variation_blends: String,
    /// hmc-sample -n (VARIATION_N)
    #[arg(long, default_value_t = 5, value_name = "N")]
    pub variation_n: u32,
    /// hmc-sample and variation-eval --seed (VARIATION_SEED)
    #[arg(long, default_value_t = 0, value_name = "S")]
    pub variation_seed: u64,
    /// hmc-sample --variance-scale (VARIATION_VARIANCE_SCALE); unset: hmc-sample's own default
    #[arg(long, value_name = "X")]
    pub variation_variance_scale: Option<String>,
    /// Further gpdm-train flags, one string (VARIATION_TRAIN_FLAGS)
    #[arg(long, default_value = "", allow_hyphen_values = true, value_name = "FLAGS")]
    pub variation_train_flags: String,
    /// Further hmc-sample flags, one string (VARIATION_SAMPLE_FLAGS)
    #[arg(long, default_value = "", allow_hyphen_values = true, value_name = "FLAGS")]
    pub variation_sample_flags: String,
}

fn parse_group(s: &str) -> Result<(String, String), String> {
    match s.split_once('=') {
        Some((name, rest)) if !name.is_empty() => Ok((name.to_string(), rest.to_string())),
        _ => Err(format!("'{s}': expected NAME=VALUE")),
    }
}

impl VariationOptions {
    /// The groups the pipeline uses when none is given (pipelines/variation.mk's defaults).
    pub fn default_groups() -> Vec<(String, String)> {
        vec![
            ("locomotion".into(), "walk,run".into()),
            ("jump".into(), "jump,cmu_jump".into()),
        ]
    }

    /// The extra prealign flags of `group`, as words.
    pub fn prealign_words(&self, group: &str) -> Vec<String> {
        self.prealign_flags
            .iter()
            .filter(|(g, _)| g == group)
            .flat_map(|(_, f)| words(f))
            .collect()
    }
}

/// Whitespace-separated words of a flags string (as make splits a variable).
pub fn words(s: &str) -> Vec<String> {
    s.split_whitespace().map(str::to_string).collect()
}

/// Every option of both pipelines.
#[derive(Args, Clone, Debug, PartialEq, Serialize)]
pub struct PipelineOptions {
    #[command(flatten)]
    #[serde(flatten)]
    pub paths: Paths,
    #[command(flatten)]
    #[serde(flatten)]
    pub transfer: TransferOptions,
    #[command(flatten)]
    #[serde(flatten)]
    pub variation: VariationOptions,
}
