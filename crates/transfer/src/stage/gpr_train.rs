//! The `gpr-train` stage: the source-to-target GP regression per body part and for the rigid
//! displacement (CVPR eqs. 8-13), or a baseline, from a direction's training pairs.

use std::path::PathBuf;

use anyhow::{bail, Context};
use clap::Parser;
use gp::gpr::{GprOptions, PAPER_NOISE_VAR};
use gp::sparse_gpr::Sparsity;
use mesh_core::artifact::{Artifact, Header};
use mesh_core::cli::CommonArgs;
use mesh_core::part_merge;
use serde::{Deserialize, Serialize};

use crate::gpr_model::{
    train_orientation, train_piece, train_rows, FixedHyperparameters, GprModel, MeanFunction, MeanPrior, MeanPriors, Method,
    OrientationOptions, PairFiles, Regression, RegressorReport, Templates, TrainingRows, DISPLACEMENT, MEAN_RIDGE,
};
use crate::cross_validation::{cross_validate, Candidate, CrossValidation, FoldUnit, Folds, HeldOut, Hyperparameters, MotionError};
use crate::limb_orientation;
use crate::model_config::{self, ConfigName, OrientationWeight, Overrides, Settings, AUTO_ORIENTATION_WEIGHTS};
use crate::training_rows::PairData;
use capture::part_pca::PcaModel;

/// Train the source-to-target GP regression per body part and for the rigid displacement (CVPR eqs. 8-13)
#[derive(Parser, Debug, Serialize)]
#[command(
    name = "gpr-train",
    version,
    after_help = "e.g.: gpr-train --source-pca work/A/pca.model --target-pca work/B/pca.model \\\n        --pair work/A/walk.aligned work/B/walk.aligned work/pairs/walk.corr --method gpr-nn --out work/A-to-B/gpr-nn.model"
)]
pub struct Params {
    #[command(flatten)]
    #[serde(skip)]
    pub common: CommonArgs,
    /// PCA model (from pca-fit) of this direction's source subject
    #[arg(long)]
    pub source_pca: PathBuf,
    /// PCA model of this direction's target subject (same part names)
    #[arg(long)]
    pub target_pca: PathBuf,
    /// A training pair as in the set: aligned motion of the set's source subject, of its target subject, and their correspondences (repeat per pair)
    #[arg(long, num_args = 3, value_names = ["SET_SOURCE", "SET_TARGET", "CORR"], required = true, action = clap::ArgAction::Append)]
    pub pair: Vec<PathBuf>,
    /// Train the reverse direction (set target -> set source): --source-pca is then the set target's
    #[arg(long)]
    pub reverse: bool,
    /// Transfer method (whole-body: gpr-nn on whole-body PCA models; keypose-affine: Baran et
    /// al.'s affine key-pose maps for every part and the displacement, no limb orientation)
    #[arg(long, value_enum, default_value_t = Method::GprNn)]
    pub method: Method,
    /// Train on the key-pose pairs only (instead of the dense DTW pairs)
    #[arg(long)]
    pub keyposes_only: bool,
    /// Neural-network kernel with the bias input (R&W eq. 4.29); eq. 10 as printed has none, which limits the GP to odd functions
    #[arg(long)]
    pub nn_bias: bool,
    /// Named configuration (docs/studies/10-cross-validation.md): `default` (--mean both: the
    /// average of `affine-mean` and `zero-mean`), `affine-mean` (affine mean, prior weight 0.25,
    /// limb orientation 0.5), `no-prior` (--prior-weight 0), `affine-only` (no prior, no limb
    /// orientation), `zero-mean` (--mean zero, limb orientation), `paper` (zero mean, no limb
    /// orientation: CVPR's model); `auto` cross-validates the ones that turn the limbs (`default`,
    /// `affine-mean`, `no-prior`, `zero-mean`) and keeps `default` unless another is better on
    /// the held-out motions by more than a standard error (docs/studies/47-mean-ensemble.md),
    /// after choosing their orientation weight as `--orientation-weight auto` does.
    /// Explicit flags override the configuration's values
    #[arg(long, value_enum, default_value_t = ConfigName::Default, value_name = "NAME")]
    pub config: ConfigName,
    /// Estimate the pose error on a new motion by cross-validation on the training motions
    /// (needs two or more pairs; `--config auto` always does): `cross_validation` in the header
    /// and the report
    #[arg(long)]
    pub cross_validate: bool,
    /// What each cross-validation fold holds out: `halves` (each half of each motion, the other
    /// half trained on) or `motions` (each whole motion: a pessimistic estimate, far above the
    /// error measured on new motions; docs/studies/10-cross-validation.md)
    #[arg(long, value_enum, default_value_t = FoldUnit::Halves, value_name = "UNIT")]
    pub cv_folds: FoldUnit,
    /// Hyperparameters of the models that leave a motion out: `fixed` keeps the full model's
    /// (optimistic for the zero-mean GP); `refit` learns them again on the other motions (up to 3.3x
    /// the cost; docs/studies/10-cross-validation.md)
    #[arg(long, value_enum, default_value_t = Hyperparameters::Fixed, value_name = "HOW")]
    pub cv_hyperparameters: Hyperparameters,
    /// A model already trained on these pairs with this configuration: its GPs' hyperparameters
    /// are kept, not learnt again (the same model, without the optimisation; the pipeline's
    /// cross-validation task reuses the model it trained). Not with `--config auto`
    #[arg(long, value_name = "MODEL")]
    pub hyperparameters_from: Option<PathBuf>,
    /// JSON report: the cross-validated errors (pooled and per motion) of every
    /// configuration tried, and the one kept
    #[arg(long)]
    pub report: Option<PathBuf>,
    /// Mean function of the GPs: `affine` = least-squares affine map, GP on the residuals;
    /// `zero` = the paper's zero-mean GP (CVPR eq. 11); `both` = each part's GP trained both
    /// ways and the two predictions averaged [default: the configuration's, both]
    #[arg(long, value_enum)]
    pub mean: Option<MeanFunction>,
    /// Relative ridge of the affine mean (shrinks the map along input directions the training
    /// poses barely span; 1e-6 is the plain least-squares fit)
    #[arg(long, default_value_t = MEAN_RIDGE)]
    pub mean_ridge: f64,
    /// What the ridge shrinks the affine mean toward: `zero`, or `geometric` = the map the two
    /// subjects' part shapes predict (transfer::geometric_prior)
    #[arg(long, value_enum, default_value_t = MeanPrior::Zero)]
    pub mean_prior: MeanPrior,
    /// Weight of the geometric prior mixed into each part's affine mean (0: the fitted map alone).
    /// The default suits five training motions; with eight or more, 0 measured better on every
    /// benchmark set (docs/studies/09-training-coverage.md) [default: the configuration's, 0.25]
    #[arg(long, value_name = "W")]
    pub prior_weight: Option<f64>,
    /// How far each limb is turned from the orientation the pose GP predicts toward the one a
    /// map of the source limb's orientation predicts (transfer::limb_orientation; 0: the
    /// paper's model, no turn); `auto`: of 0.5, 0.3 and 0 the one with the lowest error when
    /// each whole training motion is held out (needs two or more pairs; recorded as
    /// `orientation_weight_choice`; docs/studies/48-orientation-weight.md) [default: `auto`
    /// with `--config auto`, else the configuration's, 0.5]
    #[arg(long, value_name = "W|auto")]
    pub orientation_weight: Option<OrientationWeight>,
    /// Limbs whose orientation is measured relative to their attachment, the root part's region
    /// around their joint (an arm's shoulder girdle), instead of the root part's whole frame
    /// (comma-separated limb names, e.g. `arm_l,arm_r`; ignored by the whole-body method;
    /// default: none, docs/studies/06-limb-orientation.md)
    #[arg(long, value_delimiter = ',', value_name = "PARTS")]
    pub attached_limbs: Vec<String>,
    /// Observation-noise variance σn² (the paper's 0.1; the starting value with --learn-noise)
    #[arg(long, default_value_t = PAPER_NOISE_VAR)]
    pub noise_var: f64,
    /// Also learn σn² by maximising the marginal likelihood (the paper fixes it)
    #[arg(long)]
    pub learn_noise: bool,
    /// Sparse GP (Titsias' bound) with at most M inducing inputs chosen by greedy variance
    /// selection; `auto` (default): the exact GP of CVPR eqs. 8-13 up to 1024 pairs, 256
    /// inducing inputs above (a lab's minutes of training motion train in minutes, not hours);
    /// `exact`: the exact GP at any size
    #[arg(long, value_name = "M|auto|exact", default_value_t = Sparsity::Auto)]
    #[serde(serialize_with = "as_text")]
    pub sparse: Sparsity,
    /// Maximum conjugate-gradient iterations per GP
    #[arg(long, default_value_t = 100)]
    pub max_iter: usize,
    /// Train only this part's regressor (a part name of the PCA models, or `displacement`) and
    /// write it alone, as kind gpr-model-part: `merge-parts` joins them into the whole model
    #[arg(long)]
    #[serde(skip)]
    pub part: Option<String>,
    /// Output artifact (kind gpr-model; gpr-model-part with --part)
    #[arg(short, long)]
    pub out: PathBuf,
}

/// `--sparse` as written on the command line (`exact`, `auto` or M).
fn as_text<S: serde::Serializer>(s: &Sparsity, ser: S) -> Result<S::Ok, S::Error> {
    ser.serialize_str(&s.to_string())
}

/// Writes the model (and the `--report`); the header records `p` (the configuration's flag
/// values where no flag was given) plus the frame rates read from the pairs (`source_fps`,
/// `target_fps`: `gpr-predict` reads the first), both PCA models and every pair file, and with
/// `--cross-validate`, `--report` or `--config auto`, `cross_validation`
/// ([`CrossValidationReport`]). With `--part` only that regressor is trained, written as a
/// piece (`mesh_core::part_merge`).
pub fn run(p: &Params) -> anyhow::Result<()> {
    let method = p.method;
    let (src_pca, tgt_pca) = (
        PcaModel::load(&p.source_pca)?,
        PcaModel::load(&p.target_pca)?,
    );
    let names = part_names(p, &src_pca, &tgt_pca)?;
    // The pieces of a model: its parts' regressors, then the displacement's.
    let units: Vec<String> = names.iter().cloned().chain([DISPLACEMENT.to_string()]).collect();
    let unit = selected_unit(p, &names, &units)?;
    if method == Method::WholeBody && names.len() != 1 {
        mesh_core::warn!(
            "method whole-body with a {}-part PCA model (expected pca-fit --whole-body)",
            names.len()
        );
    }
    let mut configs = configurations(p)?;
    // `--config auto` chooses the orientation weight too, unless one is given.
    let choose_weight = matches!((p.orientation_weight, p.config), (Some(OrientationWeight::Auto), _) | (None, ConfigName::Auto))
        && method != Method::KeyposeAffine;
    let cross_validated = p.cross_validate || p.report.is_some() || configs.len() > 1;
    let given = given_hyperparameters(p, &names, configs.len())?;
    // The files are in the set's order (set source, set target); the PCA models are in
    // the direction's order.
    let (set_source_pca, set_target_pca) = if p.reverse {
        (&tgt_pca, &src_pca)
    } else {
        (&src_pca, &tgt_pca)
    };
    let LoadedPairs { mut pairs, held_out, pair_hashes, fps: (set_source_fps, set_target_fps) } =
        load_pairs(p, set_source_pca, set_target_pca)?;
    if (cross_validated || choose_weight) && pairs.len() < 2 {
        return Err(mesh_core::Error::invalid(format!("cross-validation needs two or more --pair, got {}", pairs.len())).into());
    }
    let (source_fps, target_fps) = if p.reverse {
        (set_target_fps, set_source_fps)
    } else {
        (set_source_fps, set_target_fps)
    };
    let opts = GprOptions {
        noise_var: p.noise_var,
        learn_noise: p.learn_noise,
        sparse: p.sparse,
        cg: gp::optim::CgOptions {
            max_iter: p.max_iter,
            ..Default::default()
        },
        ..Default::default()
    };
    let ratio = target_fps / source_fps;
    let start = std::time::Instant::now();
    // A misspelt limb is refused before the GPs are trained.
    limb_orientation::frames(&tgt_pca, &p.attached_limbs)?;
    let ridge_toward = p.mean_prior == MeanPrior::Geometric;
    let maps = configs
        .iter()
        .any(|(_, s)| s.mean != MeanFunction::Zero && (ridge_toward || s.prior_weight > 0.0))
        .then(|| crate::geometric_prior::part_priors(&src_pca, &tgt_pca));
    let trainer = Trainer { p, names: &names, src_pca: &src_pca, tgt_pca: &tgt_pca, maps: maps.as_deref(), opts: &opts, given: given.as_ref() };
    let provenance = Provenance { p, source_fps, target_fps, pair_hashes: &pair_hashes };
    // The rows are gathered once for the regressions and the limb orientation; the pairs'
    // coefficients are not needed after that unless motions are left out (at 10^5 pairs each
    // is hundreds of MB).
    let n_pairs = pairs.len();
    let rows = TrainingRows::new(method, &names, &pairs, ratio, p.keyposes_only)?;
    if !cross_validated && !choose_weight {
        pairs = Vec::new();
    }
    if let Some(unit) = unit {
        let (_, chosen) = configs[0];
        let spin = mesh_core::cli::spinner(
            &format!("gpr-train: {}, {} pairs", units[unit], n_pairs),
            &p.common,
        );
        let piece = trainer.piece(&rows, unit, &chosen)?;
        spin.finish_and_clear();
        log_report(&piece.report);
        part_merge::save_piece::<GprModel>(&p.out, &provenance.header(&chosen, None, None)?, &units, unit, piece)?;
        return Ok(());
    }
    let spin = mesh_core::cli::spinner(
        &format!(
            "gpr-train: {} parts + displacement, {} pairs{}",
            names.len(),
            n_pairs,
            if configs.len() > 1 { format!(", {} configurations", configs.len()) } else { String::new() }
        ),
        &p.common,
    );
    let mut models = trainer.models(&rows, &configs)?;
    drop(rows);
    let trained_s = start.elapsed().as_secs_f64();
    let weight_choice = match choose_weight {
        true => {
            let choice = trainer.choose_orientation_weight(&configs[0].1, &models[0], &pairs, &held_out, ratio)?;
            for ((_, s), m) in configs.iter_mut().zip(models.iter_mut()) {
                s.orientation_weight = choice.weight;
                m.orientation = m.orientation.take().filter(|_| choice.weight > 0.0).map(|o| limb_orientation::LimbOrientation { weight: choice.weight, ..o });
            }
            mesh_core::info!(
                "orientation weight {} kept of {} (cross-validated pose error {}, whole motions held out)",
                choice.weight,
                choice.candidates.iter().map(|c| c.weight.to_string()).collect::<Vec<_>>().join(", "),
                choice.candidates.iter().map(|c| format!("{:.4} m", c.cv_rms_pose_m)).collect::<Vec<_>>().join(", ")
            );
            Some(choice)
        }
        false => None,
    };
    let cv = match cross_validated {
        true => Some(trainer.cross_validation(&configs, &models, &pairs, &held_out, ratio)?),
        false => None,
    };
    spin.finish_and_clear();
    let chosen = cv.as_ref().map_or(0, |cv| cv.chosen_index);
    let model = models.swap_remove(chosen);
    mesh_core::info!(
        "trained {} on {} pairs in {:.3} s{}",
        method.name(),
        model.n_train,
        trained_s,
        match &cv {
            Some(cv) => format!(
                ", cross-validated on {} motions ({}) in {:.3} s: configuration {}, cross-validated pose error {:.4} m",
                n_pairs,
                cv.folds.name(),
                start.elapsed().as_secs_f64() - trained_s,
                cv.config.name(),
                cv.cv_rms_pose_m
            ),
            None => String::new(),
        }
    );
    model.reports.iter().for_each(log_report);
    let header = provenance.header(&configs[chosen].1, cv.as_ref(), weight_choice.as_ref())?;
    // The report first: the model's presence says both are complete.
    if let (Some(r), Some(cv)) = (&p.report, &cv) {
        let text = serde_json::to_string_pretty(cv)? + "\n";
        mesh_core::atomic::write_bytes_atomic(r, text.as_bytes())?;
    }
    model.save(&p.out, &header)?;
    Ok(())
}

/// The hyperparameters of `--hyperparameters-from`'s model, checked against this training: one
/// configuration, the same method and part names.
fn given_hyperparameters(p: &Params, names: &[String], n_configs: usize) -> anyhow::Result<Option<FixedHyperparameters>> {
    let Some(path) = &p.hyperparameters_from else {
        return Ok(None);
    };
    if n_configs != 1 {
        return Err(mesh_core::Error::invalid("--hyperparameters-from fixes one configuration's GPs: not with --config auto").into());
    }
    let model = GprModel::load(path)?;
    if model.method != p.method || model.part_names != names {
        return Err(mesh_core::Error::file(
            path,
            format!("a {} model of parts {:?}, not {} of {:?}", model.method.name(), model.part_names, p.method.name(), names),
        )
        .into());
    }
    Ok(Some(FixedHyperparameters::of(&model)?))
}

/// The source PCA model's part names, which the target's must equal.
fn part_names(p: &Params, src_pca: &PcaModel, tgt_pca: &PcaModel) -> anyhow::Result<Vec<String>> {
    let names: Vec<String> = src_pca.parts.iter().map(|p| p.name.clone()).collect();
    let tgt_names: Vec<String> = tgt_pca.parts.iter().map(|p| p.name.clone()).collect();
    if names != tgt_names {
        bail!(
            "{}: parts {:?} differ from the target's {:?}",
            p.source_pca.display(),
            names,
            tgt_names
        );
    }
    Ok(names)
}

/// The piece `--part` names among `units` (the parts, then the displacement), if given.
fn selected_unit(p: &Params, names: &[String], units: &[String]) -> anyhow::Result<Option<usize>> {
    let Some(name) = &p.part else {
        return Ok(None);
    };
    if names.iter().any(|n| n == DISPLACEMENT) {
        bail!("{}: a part is named '{DISPLACEMENT}', the name of the displacement regressor", p.source_pca.display());
    }
    if p.config == ConfigName::Auto || p.cross_validate || p.report.is_some() || p.orientation_weight == Some(OrientationWeight::Auto) {
        return Err(mesh_core::Error::invalid(
            "--config auto, --orientation-weight auto, --cross-validate and --report cross-validate whole models: not with --part",
        )
        .into());
    }
    Ok(Some(part_merge::select(units, name, &p.source_pca)?))
}

/// What the models are trained with: the stage's flags, the part names, both PCA models, the
/// parts' geometric priors (when some configuration uses them) and the GP options.
struct Trainer<'a> {
    p: &'a Params,
    names: &'a [String],
    src_pca: &'a PcaModel,
    tgt_pca: &'a PcaModel,
    maps: Option<&'a [nalgebra::DMatrix<f64>]>,
    opts: &'a GprOptions,
    /// `--hyperparameters-from`'s: the (one) configuration's GPs are conditioned with these.
    given: Option<&'a FixedHyperparameters>,
}

impl Trainer<'_> {
    /// One piece of configuration `chosen`'s model (`gpr-train --part`): a part's regressor and
    /// its limb orientation, or the displacement's.
    fn piece(&self, rows: &TrainingRows, unit: usize, chosen: &Settings) -> anyhow::Result<crate::gpr_piece::GprPiece> {
        let (p, names) = (self.p, self.names);
        let orientation = OrientationOptions { weight: chosen.orientation_weight, attached: &p.attached_limbs };
        let mut piece = train_piece(&regression_of(p, self.maps, self.opts, chosen, self.given), names, rows, unit)?;
        if unit < names.len() {
            let o = train_orientation(p.method, names, rows, self.src_pca, self.tgt_pca, &orientation, Some(unit))?;
            piece.orientation = o.and_then(|mut o| o.maps.swap_remove(unit));
        }
        piece.orientation_weight = chosen.orientation_weight;
        piece.templates = Templates::of(self.src_pca, self.tgt_pca);
        Ok(piece)
    }

    /// Every configuration's model on all the rows, in their order. Configurations that differ
    /// only in the prior's weight or the limb orientation have the same GPs (trained on the
    /// residuals of the same fitted mean): those are trained once and the others conditioned
    /// with their hyperparameters, which gives the same model. A `--mean both` configuration
    /// trained beside an affine-mean and a zero-mean one is conditioned with theirs.
    fn models(&self, rows: &TrainingRows, configs: &[(ConfigName, Settings)]) -> anyhow::Result<Vec<GprModel>> {
        let (p, names) = (self.p, self.names);
        // Averages last, so that the GPs they average are trained first.
        let mut order: Vec<usize> = (0..configs.len()).collect();
        order.sort_by_key(|&c| configs[c].1.mean == MeanFunction::Both);
        let mut models: Vec<Option<GprModel>> = vec![None; configs.len()];
        for c in order {
            let s = &configs[c].1;
            let twin = |mean: MeanFunction| configs.iter().zip(&models).find(|((_, t), m)| t.mean == mean && m.is_some()).and_then(|(_, m)| m.as_ref());
            let (fixed, reports) = match (s.mean, twin(s.mean), twin(MeanFunction::Affine), twin(MeanFunction::Zero)) {
                (_, Some(t), _, _) => (Some(FixedHyperparameters::of(t)?), Some(t.reports.clone())),
                (MeanFunction::Both, None, Some(a), Some(z)) => {
                    let (fa, fz) = (FixedHyperparameters::of(a)?, FixedHyperparameters::of(z)?);
                    let parts = fa.parts.into_iter().zip(fz.parts).map(|(a, z)| a.into_iter().chain(z).collect()).collect();
                    (Some(FixedHyperparameters { parts, displacement: fa.displacement }), Some(average_reports(names, a, z)))
                }
                _ => (None, None),
            };
            let fixed = fixed.as_ref().or(self.given);
            let mut model: GprModel = train_rows(&regression_of(p, self.maps, self.opts, s, fixed), names, rows)?;
            if let Some(reports) = reports {
                model.reports = reports;
            }
            let orientation = OrientationOptions { weight: s.orientation_weight, attached: &p.attached_limbs };
            model.orientation = train_orientation(p.method, names, rows, self.src_pca, self.tgt_pca, &orientation, None)?;
            model.templates = Templates::of(self.src_pca, self.tgt_pca);
            models[c] = Some(model);
        }
        Ok(models.into_iter().flatten().collect())
    }

    /// Leaves each motion of `pairs` out of every configuration (with its model's
    /// hyperparameters, `models`) and keeps the configuration of lowest error.
    fn cross_validation(
        &self,
        configs: &[(ConfigName, Settings)],
        models: &[GprModel],
        pairs: &[PairData],
        held_out: &[HeldOut],
        frame_ratio: f64,
    ) -> anyhow::Result<CrossValidationReport> {
        let p = self.p;
        let fixed = models.iter().map(FixedHyperparameters::of).collect::<mesh_core::Result<Vec<_>>>()?;
        let candidates: Vec<Candidate> = configs
            .iter()
            .zip(&fixed)
            .map(|((_, s), f)| Candidate {
                regression: regression_of(p, self.maps, self.opts, s, Some(f)),
                orientation: OrientationOptions { weight: s.orientation_weight, attached: &p.attached_limbs },
            })
            .collect();
        let errors = cross_validate(&self.folds(p.cv_folds, pairs, held_out, frame_ratio), &candidates)?;
        Ok(CrossValidationReport::choose(p.cv_folds, configs.iter().map(|(c, _)| *c).zip(errors).collect()))
    }

    /// The folds of `pairs` by `unit`, with the stage's options.
    fn folds<'b>(&'b self, unit: FoldUnit, pairs: &'b [PairData], held_out: &'b [HeldOut], frame_ratio: f64) -> Folds<'b> {
        Folds {
            unit,
            hyperparameters: self.p.cv_hyperparameters,
            pairs,
            held_out,
            frame_ratio,
            keyposes_only: self.p.keyposes_only,
            part_names: self.names,
            source_pca: self.src_pca,
            target_pca: self.tgt_pca,
        }
    }

    /// `--orientation-weight auto`: configuration `s` with each of [`AUTO_ORIENTATION_WEIGHTS`],
    /// its model's hyperparameters (`model`), each whole training motion held out; the weight of
    /// lowest pooled error is kept (the earliest on a tie).
    fn choose_orientation_weight(
        &self,
        s: &Settings,
        model: &GprModel,
        pairs: &[PairData],
        held_out: &[HeldOut],
        frame_ratio: f64,
    ) -> anyhow::Result<OrientationWeightChoice> {
        let p = self.p;
        let fixed = FixedHyperparameters::of(model)?;
        let candidates: Vec<Candidate> = AUTO_ORIENTATION_WEIGHTS
            .iter()
            .map(|&weight| Candidate {
                regression: regression_of(p, self.maps, self.opts, s, Some(&fixed)),
                orientation: OrientationOptions { weight, attached: &p.attached_limbs },
            })
            .collect();
        let errors = cross_validate(&self.folds(FoldUnit::Motions, pairs, held_out, frame_ratio), &candidates)?;
        let kept = (1..errors.len()).fold(0, |best, c| if errors[c].cv_rms_pose_m < errors[best].cv_rms_pose_m { c } else { best });
        Ok(OrientationWeightChoice {
            weight: AUTO_ORIENTATION_WEIGHTS[kept],
            folds: FoldUnit::Motions,
            candidates: AUTO_ORIENTATION_WEIGHTS
                .iter()
                .zip(errors)
                .map(|(&weight, e)| WeightError { weight, cv_rms_pose_m: e.cv_rms_pose_m, motions: e.motions })
                .collect(),
        })
    }
}

/// `--orientation-weight auto`'s record in the header (`orientation_weight_choice`): the weight
/// kept, what the folds held out, and every weight's cross-validated errors.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct OrientationWeightChoice {
    pub weight: f64,
    pub folds: FoldUnit,
    pub candidates: Vec<WeightError>,
}

/// One weight's cross-validated errors (metres): pooled and per held-out motion.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct WeightError {
    pub weight: f64,
    pub cv_rms_pose_m: f64,
    pub motions: Vec<MotionError>,
}

/// What a model's header records: the flags, the configuration kept and its cross-validation,
/// the direction's frame rates and every input's hash.
struct Provenance<'a> {
    p: &'a Params,
    source_fps: f64,
    target_fps: f64,
    pair_hashes: &'a [(&'a PathBuf, String)],
}

impl Provenance<'_> {
    fn header(&self, chosen: &Settings, cv: Option<&CrossValidationReport>, weight: Option<&OrientationWeightChoice>) -> anyhow::Result<Header> {
        let p = self.p;
        let mut params = serde_json::to_value(p)?;
        params["mean"] = serde_json::to_value(chosen.mean)?;
        params["prior_weight"] = chosen.prior_weight.into();
        params["orientation_weight"] = chosen.orientation_weight.into();
        params["source_fps"] = self.source_fps.into();
        params["target_fps"] = self.target_fps.into();
        if let Some(cv) = cv {
            params["cross_validation"] = serde_json::to_value(cv)?;
        }
        if let Some(w) = weight {
            params["orientation_weight_choice"] = serde_json::to_value(w)?;
        }
        let mut header = p
            .common
            .header("gpr-train", env!("CARGO_PKG_VERSION"))
            .with_params(&params)?
            .with_input(&p.source_pca)?
            .with_input(&p.target_pca)?;
        if let Some(m) = &p.hyperparameters_from {
            header = header.with_input(m)?;
        }
        for (f, sha256) in self.pair_hashes {
            header.inputs.push(mesh_core::artifact::InputRecord { path: f.display().to_string(), sha256: sha256.clone() });
        }
        Ok(header)
    }
}

/// The configurations to train (`--config`, with the flags given explicitly applied; the
/// key-pose baseline without limb orientation), the weights checked.
fn configurations(p: &Params) -> anyhow::Result<Vec<(ConfigName, Settings)>> {
    let method = p.method;
    // Under `--orientation-weight auto` every configuration turns the limbs while the weight is
    // chosen (its maps are fitted), then takes the weight kept (`choose_orientation_weight`).
    let orientation_weight = match p.orientation_weight {
        Some(OrientationWeight::Fixed(w)) => Some(w),
        Some(OrientationWeight::Auto) => Some(limb_orientation::WEIGHT),
        None => None,
    };
    let overrides = Overrides { mean: p.mean, prior_weight: p.prior_weight, orientation_weight };
    if let Some(w) = p.prior_weight.filter(|w| !(0.0..=1.0).contains(w)) {
        return Err(mesh_core::Error::invalid(format!("--prior-weight must be in [0, 1], got {w}")).into());
    }
    if let Some(w) = orientation_weight.filter(|w| !(0.0..=1.0).contains(w)) {
        return Err(mesh_core::Error::invalid(format!("--orientation-weight must be in [0, 1], got {w}")).into());
    }
    // The key-pose baseline is Baran et al.'s model class throughout: no limb orientation.
    if method == Method::KeyposeAffine && orientation_weight.is_some_and(|w| w > 0.0) {
        mesh_core::warn!("method keypose-affine has no limb orientation: --orientation-weight is not used");
    }
    Ok(model_config::candidates(p.config)
        .into_iter()
        .filter_map(|c| model_config::settings(c, &overrides).map(|s| (c, s)))
        .map(|(c, s)| (c, if method == Method::KeyposeAffine { Settings { orientation_weight: 0.0, ..s } } else { s }))
        .collect())
}

/// The training pairs read: their coefficients, what leaving each out compares with, every
/// file's hash, and the set's source and target frame rates.
struct LoadedPairs<'a> {
    pairs: Vec<PairData>,
    held_out: Vec<HeldOut>,
    pair_hashes: Vec<(&'a PathBuf, String)>,
    fps: (f64, f64),
}

/// Every `--pair` read, hashed and encoded with the set's source and target PCA models.
fn load_pairs<'a>(p: &'a Params, set_source_pca: &PcaModel, set_target_pca: &PcaModel) -> anyhow::Result<LoadedPairs<'a>> {
    let mut pairs = Vec::new();
    let mut held_out = Vec::new();
    // Frame rates of the set's source and target subjects, from the aligned motions.
    let mut set_fps: Option<(f64, f64)> = None;
    // Every pair read, hashed and encoded in one pass per file, frames encoded as they are
    // decoded (no motion is ever held whole), in parallel (one file per thread), then checked
    // in the command line's order, so that the first bad pair is the one reported.
    let loaded: Vec<anyhow::Result<_>> = {
        use rayon::prelude::*;
        p.pair
            .par_chunks(3)
            .map(|files| {
                let pair = PairFiles::read_encoded(files, set_source_pca, set_target_pca)?;
                let fps = (
                    pair.captures[0].require_fps().with_context(|| files[0].display().to_string())?,
                    pair.captures[1].require_fps().with_context(|| files[1].display().to_string())?,
                );
                Ok((pair.data, fps, pair.sha256, pair.motion))
            })
            .collect()
    };
    let mut pair_hashes = Vec::new();
    for (files, item) in p.pair.chunks(3).zip(loaded) {
        let (data, fps, hashes, motion) = item?;
        if let Some(first) = set_fps.filter(|f| *f != fps) {
            bail!(
                "{}: frame rates {} and {} differ from the first pair's {} and {}",
                files[0].display(),
                fps.0,
                fps.1,
                first.0,
                first.1
            );
        }
        set_fps = Some(fps);
        pairs.push(if p.reverse { data.reversed() } else { data });
        // The direction's target motion: the truth of the pair's frames when it is left out.
        held_out.push(HeldOut { motion, truth: files[if p.reverse { 0 } else { 1 }].clone() });
        pair_hashes.extend(files.iter().zip(hashes));
    }
    let Some((set_source_fps, set_target_fps)) = set_fps else {
        bail!("no --pair given");
    };
    Ok(LoadedPairs { pairs, held_out, pair_hashes, fps: (set_source_fps, set_target_fps) })
}

/// The cross-validated errors of every configuration tried and the one kept: the header's
/// `cross_validation` and the `--report`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CrossValidationReport {
    /// The configuration kept: the first of `--config auto`'s order (`default`) unless another
    /// has a lower error on the held-out motions by more than a standard error
    /// ([`crate::cross_validation::keep`]).
    pub config: ConfigName,
    /// Its error pooled over every held-out frame (metres).
    pub cv_rms_pose_m: f64,
    /// What each fold held out.
    pub folds: FoldUnit,
    /// Its error per held-out motion.
    pub motions: Vec<MotionError>,
    /// Every configuration tried, in order, with its errors.
    pub candidates: Vec<CandidateError>,
    #[serde(skip)]
    chosen_index: usize,
}

/// One configuration's cross-validated errors.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CandidateError {
    pub config: ConfigName,
    #[serde(flatten)]
    pub errors: CrossValidation,
}

impl CrossValidationReport {
    /// Keeps the configuration [`crate::cross_validation::keep`] chooses.
    fn choose(folds: FoldUnit, candidates: Vec<(ConfigName, CrossValidation)>) -> Self {
        let errors: Vec<CrossValidation> = candidates.iter().map(|(_, e)| e.clone()).collect();
        let chosen_index = crate::cross_validation::keep(&errors);
        let (config, best) = candidates[chosen_index].clone();
        CrossValidationReport {
            config,
            cv_rms_pose_m: best.cv_rms_pose_m,
            folds,
            motions: best.motions,
            candidates: candidates.into_iter().map(|(config, errors)| CandidateError { config, errors }).collect(),
            chosen_index,
        }
    }
}

/// How the regressors of configuration `s` are trained: `maps` are the parts' geometric priors
/// (when some configuration uses them), `fixed` the hyperparameters to condition with.
fn regression_of<'a>(
    p: &Params,
    maps: Option<&'a [nalgebra::DMatrix<f64>]>,
    opts: &'a GprOptions,
    s: &Settings,
    fixed: Option<&'a FixedHyperparameters>,
) -> Regression<'a> {
    let ridge_toward = p.mean_prior == MeanPrior::Geometric;
    let priors = maps
        .filter(|_| s.mean != MeanFunction::Zero && (ridge_toward || s.prior_weight > 0.0))
        .map(|maps| MeanPriors { maps, ridge_toward, weight: s.prior_weight });
    Regression { method: p.method, nn_bias: p.nn_bias, mean: s.mean, mean_ridge: p.mean_ridge, mean_priors: priors, opts, fixed }
}

/// The reports of `--mean both`'s model averaging the GPs of `affine` and `zero` (part names
/// `names`): each part's two, and the affine model's displacement.
fn average_reports(names: &[String], affine: &GprModel, zero: &GprModel) -> Vec<RegressorReport> {
    let mut reports: Vec<RegressorReport> = names
        .iter()
        .zip(affine.reports.iter().zip(&zero.reports))
        .map(|(name, (a, z))| RegressorReport::average(name, a.clone(), z.clone()))
        .collect();
    reports.extend(affine.reports.get(names.len()).cloned());
    reports
}

/// Logs what training one regressor did (`-v`) and its numerical notes (an average's, its
/// members').
fn log_report(r: &RegressorReport) {
    mesh_core::info!("{}", r.line());
    for r in std::iter::once(r).chain(&r.members) {
        for n in &r.notes {
            mesh_core::warn!("{}: {n}", r.name);
        }
    }
}
