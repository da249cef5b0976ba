//! The pipelines' options: the variables `pipelines/transfer.mk` and `pipelines/variation.mk`
//! take (README, "Pipelines"), as one clap struct. Values that only travel to a stage's command
//! line are kept as the text given, so the command is the one a user would type.

use std::path::PathBuf;

use clap::{Args, ValueEnum};
use crate::flag::{flag, GprPredict};
use serde::Serialize;
pub use capture::align::AlignFrame;
pub use capture::choices::{ConfigName, MeanFunction, Method};
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
    /// The model's named configuration (CONFIG): `gpr-train --config NAME` for every model;
    /// `paper` also runs the rest of the pipeline as the paper does ([`TransferOptions::paper`])
    /// [default: gpr-train's]
    #[arg(long, value_enum, value_name = "NAME")]
    pub config: Option<ConfigName>,
    /// Transfer methods (TRANSFER_METHODS); gpr-nn with key-poses only is always added
    /// [default: the configuration's, [`TransferOptions::methods`]]
    #[arg(long, num_args = 1.., value_parser = parse_method)]
    pub methods: Vec<Method>,
    /// align --frame (ALIGN_FRAME) [default: the configuration's, else align's]
    #[arg(long, value_enum)]
    pub align_frame: Option<AlignFrame>,
    /// pca-fit --part-alignment (PART_ALIGNMENT) [default: pca-fit's]
    #[arg(long, value_enum, default_value_t = PartAlignment::default(), hide_default_value = true)]
    pub part_alignment: PartAlignment,
    /// gpr-predict --placement of every method (PLACEMENT); gpr-nn is also placed the other ways
    /// [default: the configuration's, else gpr-predict's]
    #[arg(long, value_enum)]
    pub placement: Option<Placement>,
    /// gpr-train --mean of every model (GPR_MEAN); unset: the configuration's (the default
    /// configuration's is both)
    #[arg(long, value_enum)]
    pub gpr_mean: Option<MeanFunction>,
    /// Further gpr-train flags for every model, one string (GPR_TRAIN_FLAGS)
    #[arg(long, default_value = "", allow_hyphen_values = true, value_name = "FLAGS")]
    pub gpr_train_flags: String,
    /// pca-fit --components per part (PCA_COMPONENTS); the whole body gets parts x this
    /// [default: pca-fit's]
    #[arg(long, value_name = "K")]
    pub pca_components: Option<usize>,
}

impl TransferOptions {
    /// `CONFIG=paper`: the paper's pipeline (CVPR §4-6) besides its model (`gpr-train --config
    /// paper`): poses aligned on the whole mesh (`align --frame body`), placed by the regressed
    /// displacement, no foot clean-ups, and every method of its comparison (CVPR fig. 7).
    pub fn paper(&self) -> bool {
        self.config == Some(ConfigName::Paper)
    }

    /// The methods run: TRANSFER_METHODS, or the configuration's. Under `paper`, the paper's
    /// comparison: the three kernels, the key-pose baseline and the whole body. Otherwise the
    /// kernel rows are left out: with the affine mean the three kernels' residual GPs give
    /// transfers a few millimetres apart or equal (docs/DEFAULTS.md), so gpr-nn stands for them.
    pub fn methods(&self) -> Vec<Method> {
        if !self.methods.is_empty() {
            self.methods.clone()
        } else if self.paper() {
            Method::ALL.to_vec()
        } else {
            vec![Method::GprNn, Method::KeyposeAffine, Method::WholeBody]
        }
    }

    /// The alignment frame: ALIGN_FRAME, else the whole body under `paper`, else align's default.
    pub fn align_frame(&self) -> AlignFrame {
        self.align_frame.unwrap_or(if self.paper() { AlignFrame::Body } else { AlignFrame::default() })
    }

    /// The placement of every method: PLACEMENT, else the regressed displacement under `paper`,
    /// else gpr-predict's default.
    pub fn placement(&self) -> Placement {
        self.placement.unwrap_or(if self.paper() { Placement::Regressed } else { Placement::PREDICT_DEFAULT })
    }

    /// Components per part: PCA_COMPONENTS, else pca-fit's default.
    pub fn pca_components(&self) -> usize {
        self.pca_components.unwrap_or(capture::stage::pca_fit::COMPONENTS)
    }

    /// Flags of every `gpr-predict`: under `paper`, no foot-skating clean-up and no foot height.
    pub fn predict_flags(&self) -> Vec<String> {
        if self.paper() { vec![flag!(GprPredict, no_footskate), flag!(GprPredict, no_foot_height)] } else { Vec::new() }
    }
}

/// `make variation`'s options (pipelines/variation.mk).
#[derive(Args, Clone, Debug, PartialEq, Serialize)]
pub struct VariationOptions {
    /// prealign --subject-name (VARIATION_SUBJECT) [default: the set's source subject]
    #[arg(long)]
    pub variation_subject: Option<String>,
    /// A movement group and its motions, `NAME=M1,M2` (VARIATION_GROUPS, VARIATION_MOTIONS_<g>); repeat
    /// [default: locomotion=walk,run,turn_left,turn_right, prealigned with --gait-cycles, and
    /// jump=jump,cmu_jump; a set's missing motions are left out]
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
            ("locomotion".into(), "walk,run,turn_left,turn_right".into()),
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
