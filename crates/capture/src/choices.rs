//! The transfer stages' named choices: the GP method, the mean function, the placement of the
//! transferred poses and the model's named configuration. They live below the stages so that `plan`, which writes the stages'
//! command lines, names them without depending on the transfer crate.

use clap::ValueEnum;
use serde::{Deserialize, Serialize};

/// The transfer methods compared in the paper (§7).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, ValueEnum)]
#[serde(rename_all = "kebab-case")]
pub enum Method {
    GprNn,
    GprSe,
    GprLinear,
    KeyposeAffine,
    WholeBody,
}

impl Method {
    pub const ALL: [Method; 5] = [
        Method::GprNn,
        Method::GprSe,
        Method::GprLinear,
        Method::KeyposeAffine,
        Method::WholeBody,
    ];

    /// The name used on the command line, in file paths and in results.json.
    pub fn name(&self) -> &'static str {
        match self {
            Method::GprNn => "gpr-nn",
            Method::GprSe => "gpr-se",
            Method::GprLinear => "gpr-linear",
            Method::KeyposeAffine => "keypose-affine",
            Method::WholeBody => "whole-body",
        }
    }

    pub fn from_name(name: &str) -> Option<Method> {
        Method::ALL.into_iter().find(|m| m.name() == name)
    }
}

/// The mean function of the GPs (CVPR eq. 11 assumes a zero mean).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "kebab-case")]
pub enum MeanFunction {
    /// An affine map fitted by least squares, the GP on the residuals (`gp::affine_mean`):
    /// far from the training inputs the prediction degrades to the linear mapping.
    #[default]
    Affine,
    /// Zero mean (the paper): far from the data the prediction falls back to the PCA mean.
    Zero,
    /// Both: each part's GP trained twice, on the affine mean's residuals and with zero mean,
    /// and the two predictions averaged (an ensemble of the two models; the displacement is
    /// the affine mean's): far from the data the prediction falls back halfway from the
    /// linear mapping toward the PCA mean.
    Both,
}

/// Which per-frame displacement places the transferred poses.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, ValueEnum)]
#[serde(rename_all = "kebab-case")]
pub enum Placement {
    /// The source displacement, translation scaled by the height ratio
    ScaledSource,
    /// The displacement GP's prediction (the paper)
    Regressed,
    /// Regressed, falling back to scaled-source where the GP's variance is high
    Blended,
}

impl Placement {
    /// `gpr-predict --placement`'s default, and so `make transfer`'s: the scaled source
    /// displacement (the paper regresses it; docs/studies/04-placement.md).
    pub const PREDICT_DEFAULT: Placement = Placement::ScaledSource;

    pub fn name(&self) -> &'static str {
        match self {
            Placement::Regressed => "regressed",
            Placement::ScaledSource => "scaled-source",
            Placement::Blended => "blended",
        }
    }
}

/// Which correspondences a transfer model was trained on, as recorded with its errors.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, ValueEnum)]
#[serde(rename_all = "kebab-case")]
pub enum Correspondences {
    /// Every frame pair of the DTW-densified training pairs
    #[default]
    Dense,
    /// The key-pose pairs only (`gpr-train --keyposes-only`)
    Keyposes,
}

impl Correspondences {
    pub fn name(&self) -> &'static str {
        match self {
            Correspondences::Dense => "dense",
            Correspondences::Keyposes => "keyposes",
        }
    }
}

/// A configuration's name on the command line.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize, ValueEnum)]
#[serde(rename_all = "kebab-case")]
pub enum ConfigName {
    /// Choose the limb orientation weight, then try the candidates and keep `default` unless
    /// another is clearly better by its cross-validated errors (`transfer::cross_validation::keep`).
    Auto,
    /// The defaults: the average of `affine-mean` and `zero-mean` (`--mean both`).
    #[default]
    Default,
    /// The affine mean with the geometric prior mixed in, limb orientation.
    AffineMean,
    /// `affine-mean` without the geometric prior (`--prior-weight 0`).
    NoPrior,
    /// The affine mean and its GP alone: no prior, no limb orientation.
    AffineOnly,
    /// The paper's zero-mean GP (CVPR eq. 11), with the limb orientation.
    ZeroMean,
    /// The paper's model: zero mean, NN kernel, σn² = 0.1, no prior, no limb orientation.
    Paper,
}

impl ConfigName {
    /// The name as written on the command line.
    pub fn name(self) -> &'static str {
        match self {
            ConfigName::Auto => "auto",
            ConfigName::Default => "default",
            ConfigName::AffineMean => "affine-mean",
            ConfigName::NoPrior => "no-prior",
            ConfigName::AffineOnly => "affine-only",
            ConfigName::ZeroMean => "zero-mean",
            ConfigName::Paper => "paper",
        }
    }
}

