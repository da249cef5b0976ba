//! `gpr-train`: the GP regression model of the transfer (CVPR §5, eqs. 8-13).
//!
//! For every body part `k`, a multi-output GP maps the source subject's part-`k`
//! PCA coefficients to the target subject's part-`k` coefficients (CVPR eq. 8: one GP
//! per output column, all sharing the kernel and its hyperparameters); one more
//! GP maps the source's rigid displacement 6-vector to the target's (paper §4,
//! "Rigid Transformation"). Training pairs are the dense correspondences of
//! `dtw-densify` (CVPR eq. 7), or only the key-poses (`--keyposes-only`).
//!
//! Methods (paper §7 comparisons):
//! - `gpr-nn` (the paper): neural-network kernel, CVPR eq. 10;
//! - `gpr-se`, `gpr-linear`: squared-exponential and linear kernels;
//! - `keypose-affine`: Semantic Deformation Transfer (Baran et al. 2009) on the
//!   key-pose pairs only, per part (`gp::affine_keypose`);
//! - `whole-body`: `gpr-nn` on a single-part PCA (`pca-fit --whole-body`).
//!
//! Deviations (documented for the report):
//! - The displacement GP is always a `gpr-nn` GP (also for `keypose-affine`,
//!   which has no displacement model in Baran et al.), so that the methods
//!   differ only in the pose mapping.
//! - The displacement outputs are divided by their RMS before training
//!   (`y_scale`, undone at prediction), so that the paper's `σn² = 0.1` is a
//!   noise level relative to the signal: per-frame displacements are a few
//!   centimetres, and an absolute `σn² = 0.1 m²` would flatten the regression
//!   to zero.
//! - Frame rates: see [`target_step`].

use gp::affine_keypose::AffineKeypose;
use gp::affine_mean::AffineMean;
use gp::gpr::{Gpr, GprOptions, TrainReport};
use gp::kernel::Kernel;
use mesh_core::artifact::Artifact;
use mesh_core::part_merge::Partitioned;
use mesh_core::rigid::{integrate, RigidMotion};
use mesh_core::{Error, Result};
use std::path::PathBuf;

pub use capture::choices::{MeanFunction, Method};
use capture::align::{AlignedMotion, CaptureInfo};
use capture::motion_stream::read_frames;
use capture::part_pca::FrameEncoder;
use crate::densify::Correspondences;
use crate::limb_orientation::{self, LimbMap, LimbOrientation};
use capture::part_pca::PcaModel;
use nalgebra::{DMatrix, Vector6};
use serde::{Deserialize, Serialize};

/// The kernel of `method`'s pose GPs (`None` for the affine baseline). Starting
/// hyperparameters are replaced by `gp::gpr::initial_kernel` when training.
/// `nn_bias` selects the NN kernel with the bias input (R&W eq. 4.29):
/// CVPR eq. 10 as printed has none, which makes every function of the GP odd,
/// `f(-x) = -f(x)` (asin is odd), so it cannot learn even components of a
/// mapping between centred PCA coefficients.
pub fn method_kernel(method: Method, nn_bias: bool) -> Option<Kernel> {
    match method {
        Method::GprNn | Method::WholeBody => Some(Kernel::NeuralNetwork {
            l: 1.0,
            sigma_f: 1.0,
            bias: nn_bias,
        }),
        Method::GprSe => Some(Kernel::SquaredExponential {
            l: 1.0,
            sigma_f: 1.0,
        }),
        Method::GprLinear => Some(Kernel::Linear { sigma_f: 1.0 }),
        Method::KeyposeAffine => None,
    }
}

/// What the ridge of the affine mean shrinks the map toward.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "kebab-case")]
pub enum MeanPrior {
    /// Zero: plain ridge regression.
    #[default]
    Zero,
    /// The linear map the two subjects' part shapes predict (`crate::geometric_prior`).
    Geometric,
}

/// A prior map for each part's affine mean (e.g. [`crate::geometric_prior::part_priors`]) and
/// how it enters: as the ridge's target, and mixed into the fitted map.
#[derive(Clone, Copy, Debug)]
pub struct MeanPriors<'a> {
    /// One `(d + 1) x p` map per part.
    pub maps: &'a [DMatrix<f64>],
    /// The ridge shrinks the fit toward the map (otherwise toward zero).
    pub ridge_toward: bool,
    /// The stored mean is `(1 - weight) · fit + weight · map`; the part's GP is trained on the
    /// residuals of the fit.
    pub weight: f64,
}

/// Weight of the geometric prior in each part's affine mean (`gpr-train --prior-weight`):
/// measured on the demo, holdout and tiny sets (docs/RESULTS.md, study 2).
pub const PRIOR_WEIGHT: f64 = 0.25;

/// Relative ridge of the affine mean (`gp::affine_mean`): it shrinks the map along the
/// input directions the training poses barely span, where an unseen motion's pose would
/// otherwise be extrapolated on noise (docs/RESULTS.md, study 2: 1e-6 to 3e-4 measured on
/// both benchmark sets; 1e-5 lowers the pose error on both).
pub const MEAN_RIDGE: f64 = 1e-5;

/// The mapping of one part's coefficients (or of the displacement).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum Regressor {
    /// `mean(x) + y_scale · gp(x)`: a GP trained on the residuals of the (optional) affine
    /// mean, divided by `y_scale`.
    Gp {
        gpr: Gpr,
        y_scale: f64,
        mean: Option<AffineMean>,
    },
    Affine(AffineKeypose),
}

impl Regressor {
    /// Internal consistency of a regressor read from a file (its GP, affine mean and scale
    /// agree in dimensions, every number finite), with `dims` = (inputs, outputs) when they
    /// are known. The error is the problem.
    fn validate(&self, dims: Option<(usize, usize)>) -> std::result::Result<(), String> {
        let (d, p) = match self {
            Regressor::Gp { gpr, y_scale, mean } => {
                gpr.validate()?;
                if !(y_scale.is_finite() && *y_scale > 0.0) {
                    return Err(format!("output scale {y_scale} is not a finite positive number"));
                }
                let (d, p) = (gpr.input_dim(), gpr.output_dim());
                if let Some(m) = mean {
                    m.validate(d, p)?;
                }
                (d, p)
            }
            Regressor::Affine(a) => {
                a.validate()?;
                (a.source_keys.ncols(), a.target_keys.ncols())
            }
        };
        match dims {
            Some(want) if want != (d, p) => Err(format!("maps {d} inputs to {p} outputs, expected {} to {}", want.0, want.1)),
            _ => Ok(()),
        }
    }

    /// Mapped outputs for the rows of `xs`.
    pub fn predict(&self, xs: &DMatrix<f64>) -> Result<DMatrix<f64>> {
        let out = match self {
            Regressor::Gp { gpr, y_scale, mean } => gpr.predict_mean(xs).and_then(|g| {
                let g = g * *y_scale;
                match mean {
                    Some(m) => m.predict(xs).map(|m| m + g),
                    None => Ok(g),
                }
            }),
            Regressor::Affine(a) => a.predict(xs),
        };
        out.map_err(|e| Error::invalid(e.to_string()))
    }
}

/// The mean of `mean_fn` (relative ridge `ridge`) fitted on `(x, y)` and the residuals the GP
/// is trained on.
fn fit_mean(
    mean_fn: MeanFunction,
    ridge: f64,
    prior: Option<&DMatrix<f64>>,
    x: &DMatrix<f64>,
    y: &DMatrix<f64>,
    notes: &mut Vec<String>,
) -> Result<(Option<AffineMean>, DMatrix<f64>)> {
    match mean_fn {
        MeanFunction::Zero => Ok((None, y.clone())),
        MeanFunction::Affine => {
            let m = AffineMean::fit_toward(x, y, ridge, prior, notes)
                .map_err(|e| Error::invalid(e.to_string()))?;
            let r = y - m.predict(x).map_err(|e| Error::invalid(e.to_string()))?;
            Ok((Some(m), r))
        }
    }
}

/// What training one regressor did (printed with `-v`, kept in the model).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RegressorReport {
    /// Part name, or `displacement`.
    pub name: String,
    pub kernel: Option<Kernel>,
    /// Optimiser exit state (`None`: not optimised, e.g. the affine baseline).
    pub exit: Option<String>,
    pub iterations: usize,
    pub initial_lml: f64,
    /// Log marginal likelihood, or Titsias' lower bound on it for a sparse GP.
    pub lml: f64,
    /// Inducing-input count of a sparse GP (`None`: exact GP or no GP).
    pub inducing: Option<usize>,
    /// Numerical notes (Cholesky jitter retries).
    pub notes: Vec<String>,
}

impl RegressorReport {
    fn from_train(name: &str, gpr: &Gpr, r: &TrainReport) -> Self {
        RegressorReport {
            name: name.to_string(),
            kernel: Some(gpr.kernel),
            exit: r.exit.map(|e| e.label().to_string()),
            iterations: r.iterations,
            initial_lml: r.initial_lml,
            lml: r.lml,
            inducing: gpr.sparse().map(|s| s.inducing().nrows()),
            notes: r.notes.clone(),
        }
    }

    /// One line for logs.
    pub fn line(&self) -> String {
        match (&self.kernel, &self.exit) {
            (Some(k), exit) => format!(
                "{}: kernel {:?}, {} {:.3} -> {:.3}, {} iterations, exit: {}",
                self.name,
                k,
                match self.inducing {
                    Some(m) => format!("sparse bound ({m} inducing inputs)"),
                    None => "log marginal likelihood".to_string(),
                },
                self.initial_lml,
                self.lml,
                self.iterations,
                exit.as_deref().unwrap_or("not optimised")
            ),
            (None, _) => format!("{}: affine key-pose mapping (no optimisation)", self.name),
        }
    }
}

/// A trained transfer model (artifact kind `gpr-model`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GprModel {
    pub method: Method,
    /// Part names, in the order of the PCA models the model was trained with.
    pub part_names: Vec<String>,
    pub parts: Vec<Regressor>,
    pub displacement: Regressor,
    /// Number of training pairs (rows) of the pose regressions.
    pub n_train: usize,
    /// Target frames per source frame `q = fps_target / fps_source`.
    pub frame_ratio: f64,
    pub keyposes_only: bool,
    /// NN kernel with the bias input (see [`Method::kernel`]).
    pub nn_bias: bool,
    /// Mean function of the GPs.
    pub mean: MeanFunction,
    pub reports: Vec<RegressorReport>,
    /// Limb orientation maps applied after the pose GPs (`None`: the paper's model).
    pub orientation: Option<LimbOrientation>,
    /// The source and target PCA models' template hashes (`PcaModel::template_sha256`):
    /// `gpr-predict` refuses PCA models of other templates. Empty when trained in memory.
    pub templates: Templates,
}

/// SHA-256 (hex) of the source and target templates a transfer model was trained with.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Templates {
    pub source: String,
    pub target: String,
}

impl Templates {
    /// The template hashes of the two PCA models.
    pub fn of(source_pca: &PcaModel, target_pca: &PcaModel) -> Templates {
        Templates { source: source_pca.template_sha256.clone(), target: target_pca.template_sha256.clone() }
    }

    /// Fails unless the PCA models were fitted on the templates the model was trained with
    /// (an unrecorded hash passes).
    pub fn check(&self, source_pca: &PcaModel, target_pca: &PcaModel) -> Result<()> {
        capture::part_pca::check_same_template(
            &source_pca.template_sha256,
            &self.source,
            "the source PCA model was fitted on",
            "the transfer model was trained with",
        )?;
        capture::part_pca::check_same_template(
            &target_pca.template_sha256,
            &self.target,
            "the target PCA model was fitted on",
            "the transfer model was trained with",
        )
    }
}

impl Artifact for GprModel {
    const KIND: &'static str = "gpr-model";
    const VERSION: u32 = 6;

    /// One regressor per part name, each internally consistent (GP weights, inducing inputs,
    /// affine mean and key-poses agree in dimensions; finite positive kernel parameters), a
    /// displacement regressor from 6 to 6 values, a finite positive frame ratio.
    fn validate(&self) -> std::result::Result<(), String> {
        if self.parts.len() != self.part_names.len() || self.parts.is_empty() {
            return Err(format!("{} part regressors for {} part names", self.parts.len(), self.part_names.len()));
        }
        for (name, r) in self.part_names.iter().zip(&self.parts) {
            r.validate(None).map_err(|e| format!("part '{name}': {e}"))?;
        }
        self.displacement
            .validate(Some((6, 6)))
            .map_err(|e| format!("displacement: {e}"))?;
        if let Some(o) = &self.orientation {
            o.validate(self.parts.len())?;
        }
        if !(self.frame_ratio.is_finite() && self.frame_ratio > 0.0) {
            return Err(format!("frame ratio {} is not a finite positive number", self.frame_ratio));
        }
        Ok(())
    }
}

/// The coefficients and displacements of one training pair of motions, with
/// the frame pairs to learn from.
#[derive(Clone, Debug)]
pub struct PairData {
    /// Source coefficients per part (`F_s x m_k`).
    pub source_coeffs: Vec<DMatrix<f64>>,
    /// Target coefficients per part (`F_t x m_k`).
    pub target_coeffs: Vec<DMatrix<f64>>,
    /// Source displacements `D_i` (align.rs), one per source frame.
    pub source_disp: Vec<[f64; 6]>,
    /// Target displacements, one per target frame.
    pub target_disp: Vec<[f64; 6]>,
    /// Dense `(source frame, target frame)` pairs.
    pub pairs: Vec<[usize; 2]>,
    /// Key-pose pairs (a subset of the path).
    pub keyposes: Vec<[usize; 2]>,
}

impl PairData {
    /// Swaps source and target (the B->A direction uses the A->B path reversed).
    pub fn reversed(self) -> PairData {
        let swap = |v: Vec<[usize; 2]>| v.into_iter().map(|[i, j]| [j, i]).collect();
        PairData {
            source_coeffs: self.target_coeffs,
            target_coeffs: self.source_coeffs,
            source_disp: self.target_disp,
            target_disp: self.source_disp,
            pairs: swap(self.pairs),
            keyposes: swap(self.keyposes),
        }
    }
}

/// A `--pair` as [`PairFiles::read_encoded`] reads it.
pub struct EncodedPair {
    /// The pair in the set's order.
    pub data: PairData,
    /// Capture records of the set's source and target motions.
    pub captures: [CaptureInfo; 2],
    /// SHA-256 of the three files, in the command line's order.
    pub sha256: [String; 3],
}

/// One training pair as the stages name it on the command line (`--pair SOURCE TARGET CORR`):
/// the aligned motions of the set's source and target subjects and their correspondences.
pub struct PairFiles {
    pub source: AlignedMotion,
    pub target: AlignedMotion,
    pub corr: Correspondences,
    paths: [PathBuf; 2],
}

impl PairFiles {
    /// Loads the three files of one `--pair` (exactly three paths).
    pub fn load(files: &[PathBuf]) -> Result<PairFiles> {
        let [s, t, c] = files else {
            return Err(Error::invalid("--pair takes three files"));
        };
        Ok(PairFiles {
            source: AlignedMotion::load(s)?,
            target: AlignedMotion::load(t)?,
            corr: Correspondences::load(c)?,
            paths: [s.clone(), t.clone()],
        })
    }

    /// One `--pair` read and encoded in one pass per file, without holding its motions: the
    /// set's source motion encoded with `source_pca` and its target motion with `target_pca`
    /// frame block by frame block as they are decoded (`capture::part_pca::FrameEncoder`, the
    /// coefficients of [`PairFiles::encode`] to the bit), the three files in parallel. Returns
    /// the pair in set order, the two motions' capture records and each file's SHA-256 (in the
    /// files' order) for the output's input records, computed in the same pass.
    pub fn read_encoded(files: &[PathBuf], source_pca: &PcaModel, target_pca: &PcaModel) -> Result<EncodedPair> {
        let [s, t, c] = files else {
            return Err(Error::invalid("--pair takes three files"));
        };
        let encoded = |path: &PathBuf, pca: &PcaModel| {
            let mut enc = FrameEncoder::new(pca);
            let (info, sha) = read_frames(path, |f| enc.push(f))?;
            let coeffs = enc.finish(&info.capture.template_sha256).map_err(|e| Error::file(path, e.to_string()))?;
            Ok::<_, Error>((coeffs, info, sha))
        };
        let ((source, target), corr) = rayon::join(
            || rayon::join(|| encoded(s, source_pca), || encoded(t, target_pca)),
            || Correspondences::load_hashed(c),
        );
        let ((source_coeffs, source, hs), (target_coeffs, target, ht), (corr, hc)) = (source?, target?, corr?);
        Ok(EncodedPair {
            data: PairData {
                source_coeffs,
                target_coeffs,
                source_disp: source.displacements,
                target_disp: target.displacements,
                pairs: corr.pairs,
                keyposes: corr.keyposes,
            },
            captures: [source.capture, target.capture],
            sha256: [hs, ht, hc],
        })
    }

    /// The pair in coefficients: the set's source motion encoded with `source_pca`, its
    /// target motion with `target_pca` (set order; [`PairData::reversed`] for B->A).
    pub fn encode(&self, source_pca: &PcaModel, target_pca: &PcaModel) -> Result<PairData> {
        let coeffs = |pca: &PcaModel, m: &AlignedMotion, path: &PathBuf| {
            pca.encode(m).map_err(|e| Error::file(path, e.to_string()))
        };
        Ok(PairData {
            source_coeffs: coeffs(source_pca, &self.source, &self.paths[0])?,
            target_coeffs: coeffs(target_pca, &self.target, &self.paths[1])?,
            source_disp: self.source.displacements.clone(),
            target_disp: self.target.displacements.clone(),
            pairs: self.corr.pairs.clone(),
            keyposes: self.corr.keyposes.clone(),
        })
    }
}

/// Stacked regression problems: per part `(X_k, Y_k)` and the displacement `(X_d, Y_d)`.
#[derive(Clone, Debug)]
pub struct TrainingSet {
    pub x_parts: Vec<DMatrix<f64>>,
    pub y_parts: Vec<DMatrix<f64>>,
    pub x_disp: DMatrix<f64>,
    pub y_disp: DMatrix<f64>,
}

impl TrainingSet {
    pub fn len(&self) -> usize {
        self.x_disp.nrows()
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The rows `rows` of every problem.
    pub fn subset(&self, rows: &[usize]) -> TrainingSet {
        let pick = |m: &DMatrix<f64>| m.select_rows(rows.iter());
        TrainingSet {
            x_parts: self.x_parts.iter().map(pick).collect(),
            y_parts: self.y_parts.iter().map(pick).collect(),
            x_disp: pick(&self.x_disp),
            y_disp: pick(&self.y_disp),
        }
    }
}

/// The target's rigid displacement over **one source frame interval** ending
/// at target frame `j`, from per-target-frame displacements `disp` and the
/// frame ratio `q = fps_target / fps_source`.
///
/// With `c = ceil(q)` (`c = q` when `q` is an integer), the displacements of
/// target frames `j-c+1 ..= j` are composed (frames before 1 are the identity:
/// `D_0 = 0`). When `q` is not an integer (or `q < 1`), the composed 6-vector
/// is scaled by `q / c`: a first-order approximation of scaling the twist of
/// the motion, exact for straight-line translation at constant speed and for
/// rotation about a fixed axis without translation.
pub fn target_step(disp: &[[f64; 6]], j: usize, q: f64) -> [f64; 6] {
    let c = q.ceil().max(1.0) as usize;
    let first = (j + 1).saturating_sub(c);
    let steps: Vec<RigidMotion> = (first..=j)
        .map(|f| RigidMotion::from_6vec(&Vector6::from_column_slice(&disp[f])))
        .collect();
    let composed = *integrate(&RigidMotion::identity(), &steps)
        .last()
        .expect("integrate returns the start");
    let v = composed.to_6vec() * (q / c as f64);
    v.into()
}

/// Stacks the training rows of all pairs: pose rows for every dense pair (or
/// key-pose pair when `keyposes_only`), displacement rows `(D^s_i, target_step(j))`.
pub fn training_set(
    pairs: &[PairData],
    frame_ratio: f64,
    keyposes_only: bool,
) -> Result<TrainingSet> {
    let n_parts = pairs.first().map_or(0, |p| p.source_coeffs.len());
    if pairs.is_empty() || n_parts == 0 {
        return Err(Error::invalid("no training pairs or no parts"));
    }
    let mut rows: Vec<(usize, usize, usize)> = Vec::new();
    for (p, pair) in pairs.iter().enumerate() {
        if pair.source_coeffs.len() != n_parts || pair.target_coeffs.len() != n_parts {
            return Err(Error::invalid(format!(
                "training pair {p}: part counts differ"
            )));
        }
        let (fs, ft) = (pair.source_disp.len(), pair.target_disp.len());
        let chosen = if keyposes_only {
            &pair.keyposes
        } else {
            &pair.pairs
        };
        for &[i, j] in chosen {
            if i >= fs || j >= ft {
                return Err(Error::invalid(format!(
                    "training pair {p}: frame pair ({i}, {j}) outside the motions ({fs} and {ft} frames)"
                )));
            }
            rows.push((p, i, j));
        }
    }
    if rows.is_empty() {
        return Err(Error::invalid("no training frame pairs"));
    }
    let n = rows.len();
    let gather = |dim: usize, get: &dyn Fn(usize, usize, usize, usize) -> f64| {
        DMatrix::from_fn(n, dim, |r, c| {
            let (p, i, j) = rows[r];
            get(p, i, j, c)
        })
    };
    let mut x_parts = Vec::with_capacity(n_parts);
    let mut y_parts = Vec::with_capacity(n_parts);
    for k in 0..n_parts {
        let ms = pairs[0].source_coeffs[k].ncols();
        let mt = pairs[0].target_coeffs[k].ncols();
        x_parts.push(gather(ms, &|p, i, _, c| pairs[p].source_coeffs[k][(i, c)]));
        y_parts.push(gather(mt, &|p, _, j, c| pairs[p].target_coeffs[k][(j, c)]));
    }
    let steps: Vec<[f64; 6]> = rows
        .iter()
        .map(|&(p, _, j)| target_step(&pairs[p].target_disp, j, frame_ratio))
        .collect();
    let x_disp = gather(6, &|p, i, _, c| pairs[p].source_disp[i][c]);
    let y_disp = DMatrix::from_fn(n, 6, |r, c| steps[r][c]);
    Ok(TrainingSet {
        x_parts,
        y_parts,
        x_disp,
        y_disp,
    })
}

fn rms(m: &DMatrix<f64>) -> f64 {
    (m.norm_squared() / m.len().max(1) as f64).sqrt()
}

/// Trains the GP of `method` on every part, with `opts`. `keys` gives the
/// key-pose rows for the affine baseline.
fn train_parts(
    method: Method,
    nn_bias: bool,
    mean_fn: MeanFunction,
    mean_ridge: f64,
    mean_priors: Option<MeanPriors>,
    names: &[String],
    data: &TrainingSet,
    keys: &TrainingSet,
    opts: &GprOptions,
) -> Result<(Vec<Regressor>, Vec<RegressorReport>)> {
    match method_kernel(method, nn_bias) {
        Some(kernel) => {
            let mut means = Vec::new();
            let mut problems: Vec<(DMatrix<f64>, DMatrix<f64>)> = Vec::new();
            let mut mean_notes = Vec::new();
            for (k, name) in names.iter().enumerate() {
                let mut notes = Vec::new();
                let toward = mean_priors.filter(|p| p.ridge_toward).map(|p| &p.maps[k]);
                let (mut m, r) = fit_mean(mean_fn, mean_ridge, toward, &data.x_parts[k], &data.y_parts[k], &mut notes)
                    .map_err(|e| Error::invalid(format!("part '{name}': {e}")))?;
                if let (Some(mean), Some(p)) = (m.as_mut(), mean_priors) {
                    if p.weight > 0.0 {
                        if p.maps[k].shape() != mean.w.shape() {
                            return Err(Error::invalid(format!(
                                "part '{name}': prior map of shape {:?} for a mean of shape {:?}",
                                p.maps[k].shape(),
                                mean.w.shape()
                            )));
                        }
                        mean.w = &mean.w * (1.0 - p.weight) + &p.maps[k] * p.weight;
                    }
                }
                means.push(m);
                mean_notes.push(notes);
                problems.push((data.x_parts[k].clone(), r));
            }
            let trained = gp::gpr::train_many(kernel, &problems, opts);
            let mut regs = Vec::new();
            let mut reports = Vec::new();
            for (((name, t), mean), notes) in names.iter().zip(trained).zip(means).zip(mean_notes) {
                let (gpr, r) = t.map_err(|e| Error::invalid(format!("part '{name}': {e}")))?;
                let mut report = RegressorReport::from_train(name, &gpr, &r);
                report.notes.extend(notes);
                reports.push(report);
                regs.push(Regressor::Gp { gpr, y_scale: 1.0, mean });
            }
            Ok((regs, reports))
        }
        None => {
            let mut regs = Vec::new();
            let mut reports = Vec::new();
            for (k, name) in names.iter().enumerate() {
                let a = AffineKeypose::fit(&keys.x_parts[k], &keys.y_parts[k])
                    .map_err(|e| Error::invalid(format!("part '{name}': {e}")))?;
                regs.push(Regressor::Affine(a));
                reports.push(RegressorReport {
                    name: name.clone(),
                    kernel: None,
                    exit: None,
                    iterations: 0,
                    initial_lml: f64::NAN,
                    lml: f64::NAN,
                    inducing: None,
                    notes: Vec::new(),
                });
            }
            Ok((regs, reports))
        }
    }
}

/// Trains the displacement GP (`gpr-nn` on the residuals of `mean_fn`, scaled to unit RMS).
pub fn train_displacement(
    data: &TrainingSet,
    nn_bias: bool,
    mean_fn: MeanFunction,
    mean_ridge: f64,
    opts: &GprOptions,
) -> Result<(Regressor, RegressorReport)> {
    let mut notes = Vec::new();
    let (mean, resid) = fit_mean(mean_fn, mean_ridge, None, &data.x_disp, &data.y_disp, &mut notes)
        .map_err(|e| Error::invalid(format!("displacement: {e}")))?;
    let y_scale = rms(&resid).max(1e-9);
    let y = &resid / y_scale;
    let (gpr, r) = Gpr::train(
        Kernel::NeuralNetwork {
            l: 1.0,
            sigma_f: 1.0,
            bias: nn_bias,
        },
        &data.x_disp,
        &y,
        opts,
    )
    .map_err(|e| Error::invalid(format!("displacement: {e}")))?;
    let mut report = RegressorReport::from_train("displacement", &gpr, &r);
    report.notes.extend(notes);
    Ok((Regressor::Gp { gpr, y_scale, mean }, report))
}

/// Trains a transfer model: the pose mapping of `method` per part and the
/// displacement GP. `part_names` are the parts of both PCA models (equal).
/// `nn_bias`: see [`method_kernel`]; `mean_ridge`: the affine mean's relative ridge
/// ([`MEAN_RIDGE`] by default); `mean_priors`: prior maps for the parts' affine means
/// ([`MeanPriors`]; `None`: the ridge shrinks toward zero and nothing is mixed in).
#[allow(clippy::too_many_arguments)]
pub fn train(
    method: Method,
    nn_bias: bool,
    mean_fn: MeanFunction,
    mean_ridge: f64,
    mean_priors: Option<MeanPriors>,
    part_names: &[String],
    pairs: &[PairData],
    frame_ratio: f64,
    keyposes_only: bool,
    opts: &GprOptions,
) -> Result<GprModel> {
    let rows = TrainingRows::new(method, part_names, pairs, frame_ratio, keyposes_only)?;
    let regression = Regression { method, nn_bias, mean: mean_fn, mean_ridge, mean_priors, opts };
    train_rows(&regression, part_names, &rows)
}

/// How every regressor of a model is trained ([`train_rows`], [`train_piece`]): the method, the
/// NN kernel's bias input, the mean function with its ridge and priors, the GP options.
#[derive(Clone, Copy)]
pub struct Regression<'a> {
    pub method: Method,
    pub nn_bias: bool,
    pub mean: MeanFunction,
    pub mean_ridge: f64,
    pub mean_priors: Option<MeanPriors<'a>>,
    pub opts: &'a GprOptions,
}

/// The mean priors, if any, are one per part with a weight in `[0, 1]`.
fn check_priors(mean_priors: Option<MeanPriors>, part_names: &[String]) -> Result<()> {
    if let Some(p) = mean_priors {
        if p.maps.len() != part_names.len() {
            return Err(Error::invalid(format!("{} mean priors for {} parts", p.maps.len(), part_names.len())));
        }
        if !(0.0..=1.0).contains(&p.weight) {
            return Err(Error::invalid(format!("prior weight must be in [0, 1], got {}", p.weight)));
        }
    }
    Ok(())
}

/// [`train`] on rows already gathered (so that the limb orientation, [`train_orientation`],
/// fits on the same rows without gathering them again).
pub fn train_rows(regression: &Regression, part_names: &[String], rows: &TrainingRows) -> Result<GprModel> {
    let Regression { method, nn_bias, mean: mean_fn, mean_ridge, mean_priors, opts } = *regression;
    check_priors(mean_priors, part_names)?;
    rows.check_parts(part_names)?;
    let (data, keys) = (&rows.data, rows.keys());
    let (parts, disp) = rayon::join(
        || train_parts(method, nn_bias, mean_fn, mean_ridge, mean_priors, part_names, data, keys, opts),
        || train_displacement(data, nn_bias, mean_fn, mean_ridge, opts),
    );
    let (parts, mut reports) = parts?;
    let (displacement, disp_report) = disp?;
    reports.push(disp_report);
    Ok(GprModel {
        method,
        part_names: part_names.to_vec(),
        parts,
        displacement,
        n_train: rows.len(method),
        frame_ratio: rows.frame_ratio,
        keyposes_only: rows.keyposes_only,
        nn_bias,
        mean: mean_fn,
        reports,
        orientation: None,
        templates: Templates::default(),
    })
}

/// How `gpr-train` fits the limb orientation (`crate::limb_orientation`).
#[derive(Clone, Copy, Debug)]
pub struct OrientationOptions<'a> {
    /// The geodesic share of the turn toward the map's orientation (0: none).
    pub weight: f64,
    /// The limbs measured in their attachment's frame ([`limb_orientation::frames`]).
    pub attached: &'a [String],
}

/// The limb orientation of a model of `method` trained on `rows`, fitted on the rows its pose
/// regressions learn from (`crate::limb_orientation`); `None` when the weight is 0. With
/// `only`, the map of that part alone (the others `None`: [`train_piece`]'s).
pub fn train_orientation(
    method: Method,
    part_names: &[String],
    sets: &TrainingRows,
    source: &PcaModel,
    target: &PcaModel,
    options: &OrientationOptions,
    only: Option<usize>,
) -> Result<Option<LimbOrientation>> {
    let weight = options.weight;
    if !(0.0..=1.0).contains(&weight) {
        return Err(Error::invalid(format!("orientation weight must be in [0, 1], got {weight}")));
    }
    if weight == 0.0 {
        return Ok(None);
    }
    sets.check_parts(part_names)?;
    let rows = if method == Method::KeyposeAffine { sets.keys() } else { &sets.data };
    let frames = limb_orientation::frames(target, options.attached)?;
    let maps = (0..part_names.len())
        .map(|k| match only {
            Some(u) if u != k => Ok(None),
            _ => limb_orientation::fit_part(source, target, k, frames[k], &rows.x_parts, &rows.y_parts),
        })
        .collect::<Result<_>>()?;
    Ok(Some(LimbOrientation { weight, maps }))
}

/// The rows a model of `method` trains on, gathered once from the pairs: the dense or key-pose
/// rows, and the affine baseline's key-pose rows when they are other rows (not a copy: at 10^5
/// pairs the rows are hundreds of MB).
pub struct TrainingRows {
    data: TrainingSet,
    keys: Option<TrainingSet>,
    frame_ratio: f64,
    keyposes_only: bool,
}

impl TrainingRows {
    /// The rows of `method` from `pairs` (target frame rate over source, `frame_ratio`), checked
    /// against `part_names`.
    pub fn new(
        method: Method,
        part_names: &[String],
        pairs: &[PairData],
        frame_ratio: f64,
        keyposes_only: bool,
    ) -> Result<Self> {
        if !(frame_ratio > 0.0 && frame_ratio.is_finite()) {
            return Err(Error::invalid(format!(
                "frame-rate ratio must be positive, got {frame_ratio}"
            )));
        }
        let data = training_set(pairs, frame_ratio, keyposes_only)?;
        let keys = if method == Method::KeyposeAffine && !keyposes_only {
            Some(training_set(pairs, frame_ratio, true)?)
        } else {
            None
        };
        let rows = TrainingRows { data, keys, frame_ratio, keyposes_only };
        rows.check_parts(part_names)?;
        Ok(rows)
    }

    /// The number of training rows (of the key-pose rows for the affine baseline).
    pub fn len(&self, method: Method) -> usize {
        if method == Method::KeyposeAffine { self.keys().len() } else { self.data.len() }
    }

    fn check_parts(&self, part_names: &[String]) -> Result<()> {
        if self.data.x_parts.len() != part_names.len() {
            return Err(Error::invalid(format!(
                "{} part names for {} parts of coefficients",
                part_names.len(),
                self.data.x_parts.len()
            )));
        }
        Ok(())
    }

    /// The key-pose rows of the affine baseline.
    fn keys(&self) -> &TrainingSet {
        self.keys.as_ref().unwrap_or(&self.data)
    }
}

/// The name of the displacement regressor among a model's pieces: `gpr-train --part
/// displacement` trains it alone.
pub const DISPLACEMENT: &str = "displacement";

/// One regressor of a [`GprModel`] (a part's, or the displacement's) with the model's shared
/// fields: what `gpr-train --part NAME` writes.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GprPiece {
    pub method: Method,
    pub regressor: Regressor,
    pub report: RegressorReport,
    pub n_train: usize,
    pub frame_ratio: f64,
    pub keyposes_only: bool,
    pub nn_bias: bool,
    pub mean: MeanFunction,
    /// The model's limb orientation weight (0: none) and this part's map (`None` for the
    /// root and the displacement).
    pub orientation_weight: f64,
    pub orientation: Option<LimbMap>,
    pub templates: Templates,
}

impl GprPiece {
    /// The fields every regressor of one model shares.
    fn shared(&self) -> (Method, usize, u64, bool, bool, MeanFunction, u64, &Templates) {
        (
            self.method,
            self.n_train,
            self.frame_ratio.to_bits(),
            self.keyposes_only,
            self.nn_bias,
            self.mean,
            self.orientation_weight.to_bits(),
            &self.templates,
        )
    }
}

/// The pieces of a model are its parts' regressors, then the displacement's ([`DISPLACEMENT`]).
impl Partitioned for GprModel {
    const PIECE_KIND: &'static str = "gpr-model-part";
    type Body = GprPiece;

    fn validate_body(body: &GprPiece) -> std::result::Result<(), String> {
        body.regressor.validate(None)?;
        if !(body.frame_ratio.is_finite() && body.frame_ratio > 0.0) {
            return Err(format!("frame ratio {} is not a finite positive number", body.frame_ratio));
        }
        if !(0.0..=1.0).contains(&body.orientation_weight) {
            return Err(format!("limb orientation weight {} is not in [0, 1]", body.orientation_weight));
        }
        if let Some(m) = &body.orientation {
            m.validate()?;
        }
        Ok(())
    }

    fn join(parts: &[String], mut bodies: Vec<GprPiece>) -> std::result::Result<GprModel, String> {
        let (last, names) = parts.split_last().ok_or("no parts")?;
        if last != DISPLACEMENT || names.is_empty() || bodies.len() != parts.len() {
            return Err(format!("the pieces of a model are its parts then '{DISPLACEMENT}', not {}", parts.join(", ")));
        }
        if let Some((b, name)) = bodies.iter().zip(parts).find(|(b, _)| b.shared() != bodies[0].shared()) {
            return Err(format!(
                "part '{name}' was trained with another method, frame ratio, mean or training set ({:?}, not {:?})",
                b.shared(),
                bodies[0].shared()
            ));
        }
        let disp = bodies.pop().expect("one body per part");
        let mut reports: Vec<RegressorReport> = bodies.iter().map(|b| b.report.clone()).collect();
        reports.push(disp.report);
        let orientation = (disp.orientation_weight > 0.0).then(|| LimbOrientation {
            weight: disp.orientation_weight,
            maps: bodies.iter().map(|b| b.orientation.clone()).collect(),
        });
        Ok(GprModel {
            method: disp.method,
            part_names: names.to_vec(),
            parts: bodies.into_iter().map(|b| b.regressor).collect(),
            displacement: disp.regressor,
            n_train: disp.n_train,
            frame_ratio: disp.frame_ratio,
            keyposes_only: disp.keyposes_only,
            nn_bias: disp.nn_bias,
            mean: disp.mean,
            reports,
            orientation,
            templates: disp.templates,
        })
    }
}

impl TrainingSet {
    /// Part `k`'s problem alone, with the displacement's.
    fn part(&self, k: usize) -> TrainingSet {
        TrainingSet {
            x_parts: vec![self.x_parts[k].clone()],
            y_parts: vec![self.y_parts[k].clone()],
            x_disp: self.x_disp.clone(),
            y_disp: self.y_disp.clone(),
        }
    }
}

/// [`train`] of one regressor: part `unit` (an index into `part_names`), or the displacement
/// when `unit == part_names.len()`; the regressor is trained exactly as in the whole model.
pub fn train_piece(regression: &Regression, part_names: &[String], rows: &TrainingRows, unit: usize) -> Result<GprPiece> {
    let Regression { method, nn_bias, mean: mean_fn, mean_ridge, mean_priors, opts } = *regression;
    check_priors(mean_priors, part_names)?;
    rows.check_parts(part_names)?;
    let (data, keys) = (&rows.data, rows.keys());
    let (regressor, report) = if unit < part_names.len() {
        let priors = mean_priors.map(|p| MeanPriors { maps: &p.maps[unit..=unit], ..p });
        let (mut regs, mut reports) = train_parts(
            method,
            nn_bias,
            mean_fn,
            mean_ridge,
            priors,
            &part_names[unit..=unit],
            &data.part(unit),
            &keys.part(unit),
            opts,
        )?;
        (regs.remove(0), reports.remove(0))
    } else if unit == part_names.len() {
        train_displacement(data, nn_bias, mean_fn, mean_ridge, opts)?
    } else {
        return Err(Error::invalid(format!("regressor {unit} of {} parts and the displacement", part_names.len())));
    };
    Ok(GprPiece {
        method,
        regressor,
        report,
        n_train: rows.len(method),
        frame_ratio: rows.frame_ratio,
        keyposes_only: rows.keyposes_only,
        nn_bias,
        mean: mean_fn,
        orientation_weight: 0.0,
        orientation: None,
        templates: Templates::default(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Pure translation at constant speed: one source interval is `q` target
    /// steps, for integer and fractional `q` (above and below 1).
    #[test]
    fn target_step_spans_one_source_interval() {
        let d = vec![
            [0.0; 6],
            [0.01, 0.0, 0.02, 0.0, 0.0, 0.0],
            [0.01, 0.0, 0.02, 0.0, 0.0, 0.0],
            [0.01, 0.0, 0.02, 0.0, 0.0, 0.0],
        ];
        for q in [2.0, 1.5, 0.8, 1.0, 3.0] {
            let s = target_step(&d, 3, q);
            assert!(
                (s[0] - 0.01 * q).abs() < 1e-12 && (s[2] - 0.02 * q).abs() < 1e-12,
                "q = {q}: {s:?}"
            );
        }
        // Pure rotation about a fixed axis composes exactly too.
        let r = vec![[0.0, 0.0, 0.0, 0.0, 0.1, 0.0]; 4];
        let s = target_step(&r, 3, 2.0);
        assert!((s[4] - 0.2).abs() < 1e-12 && s[3].abs() < 1e-12);
        // Near the start, frames before 0 count as the identity.
        assert!((target_step(&d, 1, 3.0)[0] - 0.01).abs() < 1e-12);
    }

    fn pair(f: usize, map: &dyn Fn(f64) -> f64) -> PairData {
        let xs = DMatrix::from_fn(f, 2, |i, c| ((i as f64) * 0.37 + c as f64).sin());
        let ys = DMatrix::from_fn(f, 3, |i, c| map(xs[(i, c % 2)]) * (c + 1) as f64);
        let disp: Vec<[f64; 6]> = (0..f)
            .map(|i| [0.01 * (i as f64 * 0.2).cos(), 0.0, 0.02, 0.0, 0.01, 0.0])
            .collect();
        PairData {
            source_coeffs: vec![xs],
            target_coeffs: vec![ys],
            source_disp: disp.clone(),
            target_disp: disp,
            pairs: (0..f).map(|i| [i, i]).collect(),
            keyposes: vec![[0, 0], [f / 2, f / 2], [f - 1, f - 1]],
        }
    }

    /// The prior weight mixes the fitted affine map with the prior map, and nothing else: at
    /// weight 0 the model is the one trained without a prior, at 1 the stored mean is the prior,
    /// at 0.25 a quarter of the way; the GP is the same in all three (trained on the fit's
    /// residuals). A weight outside [0, 1] or a prior per part missing is refused.
    #[test]
    fn prior_weight_mixes_the_fitted_map_with_the_prior() {
        let names = vec!["p".to_string()];
        let data = pair(60, &|x| 0.8 * x + 0.1 * x * x);
        let opts = GprOptions { noise_var: 1e-2, ..Default::default() };
        let prior = vec![DMatrix::from_fn(3, 3, |r, c| 0.1 * (r + 2 * c) as f64 - 0.3)];
        let with = |weight: f64| {
            let p = MeanPriors { maps: &prior, ridge_toward: false, weight };
            train(Method::GprNn, false, MeanFunction::Affine, MEAN_RIDGE, Some(p), &names, &[data.clone()], 1.0, false, &opts)
        };
        let plain = train(Method::GprNn, false, MeanFunction::Affine, MEAN_RIDGE, None, &names, &[data.clone()], 1.0, false, &opts).unwrap();
        let parts = |m: &GprModel| match &m.parts[0] {
            Regressor::Gp { gpr, mean: Some(mean), .. } => (gpr.clone(), mean.w.clone()),
            _ => panic!("expected a GP with an affine mean"),
        };
        let (gp0, fit) = parts(&plain);
        assert_eq!(with(0.0).unwrap(), plain);
        let (gp1, w1) = parts(&with(1.0).unwrap());
        assert!((&w1 - &prior[0]).abs().max() < 1e-15);
        let (gpq, wq) = parts(&with(0.25).unwrap());
        assert!((&wq - (&fit * 0.75 + &prior[0] * 0.25)).abs().max() < 1e-12);
        assert_eq!(gp1, gp0);
        assert_eq!(gpq, gp0);
        assert!(with(1.5).is_err());
        let none: Vec<DMatrix<f64>> = Vec::new();
        let p = MeanPriors { maps: &none, ridge_toward: false, weight: 0.25 };
        assert!(train(Method::GprNn, false, MeanFunction::Affine, MEAN_RIDGE, Some(p), &names, &[data], 1.0, false, &opts).is_err());
    }

    /// A trained model is valid and survives a save / load; each broken invariant of a model
    /// rewritten with a valid checksum is refused on load with its problem named.
    #[test]
    fn decoded_models_are_validated() {
        let names = vec!["p".to_string()];
        let data = pair(40, &|x| 0.8 * x + 0.1 * x * x);
        let opts = GprOptions { noise_var: 1e-2, ..Default::default() };
        let model = train(Method::GprNn, false, MeanFunction::Affine, MEAN_RIDGE, None, &names, &[data.clone()], 1.0, false, &opts).unwrap();
        let keyposes = train(Method::KeyposeAffine, false, MeanFunction::Affine, MEAN_RIDGE, None, &names, &[data], 1.0, false, &opts).unwrap();
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("m.model");
        let header = mesh_core::artifact::Header::new("test", "0");
        for m in [&model, &keyposes] {
            assert_eq!(m.validate(), Ok(()));
            m.save(&path, &header).unwrap();
            // (Field by field: the key-pose model's reports hold NaN, which is not equal to itself.)
            let back = GprModel::load(&path).unwrap();
            assert_eq!((&back.parts, &back.displacement, &back.part_names), (&m.parts, &m.displacement, &m.part_names));
        }
        let broken: Vec<(GprModel, &str)> = vec![
            (GprModel { part_names: vec![], ..model.clone() }, "1 part regressors for 0 part names"),
            (GprModel { frame_ratio: 0.0, ..model.clone() }, "frame ratio"),
            (GprModel { displacement: model.parts[0].clone(), ..model.clone() }, "displacement: maps 2 inputs to 3 outputs, expected 6 to 6"),
            (
                {
                    let mut m = model.clone();
                    if let Regressor::Gp { mean: Some(mean), .. } = &mut m.parts[0] {
                        mean.w = mean.w.rows(0, 2).into_owned();
                    }
                    m
                },
                "part 'p': affine mean of 2 x 3 for 2 inputs and 3 outputs",
            ),
            (
                {
                    let mut m = model.clone();
                    if let Regressor::Gp { y_scale, .. } = &mut m.parts[0] {
                        *y_scale = f64::NAN;
                    }
                    m
                },
                "output scale",
            ),
            (
                {
                    let mut m = keyposes.clone();
                    if let Regressor::Affine(a) = &mut m.parts[0] {
                        a.target_keys = a.target_keys.rows(0, 1).into_owned();
                    }
                    m
                },
                "key-poses",
            ),
            (
                GprModel { orientation: Some(LimbOrientation { weight: 0.5, maps: vec![None, None] }), ..model.clone() },
                "2 limb orientation maps for 1 parts",
            ),
            (
                GprModel { orientation: Some(LimbOrientation { weight: 1.5, maps: vec![None] }), ..model.clone() },
                "limb orientation weight 1.5",
            ),
            (
                GprModel { orientation: Some(LimbOrientation { weight: 0.5, maps: vec![Some(LimbMap { w: [[f64::NAN; 3]; 4], frame: limb_orientation::LimbFrame::Root })] }), ..model.clone() },
                "non-finite",
            ),
        ];
        for (bad, want) in broken {
            bad.save(&path, &header).unwrap();
            let e = GprModel::load(&path).unwrap_err().to_string();
            assert!(e.starts_with(&path.display().to_string()) && e.contains(want), "{e} (wanted '{want}')");
        }
    }

    /// `--sparse`: with enough inducing inputs for the training inputs (which lie on a curve:
    /// greedy selection stops once they are explained) the sparse model predicts as the exact
    /// one, through the same model type and the same confidence code.
    #[test]
    fn sparse_training_predicts_like_exact_through_the_same_model() {
        let names = vec!["p".to_string()];
        let data = pair(120, &|x| x.tanh() + 0.3 * x * x);
        let train_with = |sparse| {
            let opts = GprOptions { noise_var: 1e-2, sparse, ..Default::default() };
            train(Method::GprNn, true, MeanFunction::Affine, MEAN_RIDGE, None, &names, &[data.clone()], 1.0, false, &opts).unwrap()
        };
        let exact = train_with(gp::sparse_gpr::Sparsity::Exact);
        let sparse = train_with(gp::sparse_gpr::Sparsity::Inducing(60));
        assert!(sparse.reports[0].inducing.is_some_and(|m| m > 0 && m <= 60));
        assert_eq!(exact.reports[0].inducing, None);
        let xs = DMatrix::from_fn(7, 2, |i, c| (i as f64 * 0.9 + c as f64).cos());
        let (ye, ys) = (exact.parts[0].predict(&xs).unwrap(), sparse.parts[0].predict(&xs).unwrap());
        assert!((&ye - &ys).amax() < 1e-3 * ye.amax(), "{ye} vs {ys}");
        let disp = DMatrix::from_fn(7, 6, |i, c| 0.01 * ((i + c) as f64).sin());
        let c = crate::confidence::confidence(&sparse, &[xs], &disp).unwrap();
        assert!(c.variance_ratio["p"].as_ref().unwrap().iter().all(|v| (0.0..=1.0).contains(v)));
    }

    /// A linear map is learnt exactly by the linear-kernel GP (up to the
    /// noise's shrinkage), and a smooth non-linear one by the NN kernel.
    #[test]
    fn learns_known_maps_and_reverses() {
        let names = vec!["p".to_string()];
        let opts = GprOptions {
            noise_var: 1e-4,
            ..Default::default()
        };
        let lin = pair(60, &|x| 0.5 * x);
        let m = train(
            Method::GprLinear,
            false,
            MeanFunction::Zero,
            MEAN_RIDGE, None,
            &names,
            &[lin.clone()],
            1.0,
            false,
            &opts,
        )
        .unwrap();
        // Between two training samples on the input curve (i = 40.5).
        let (x0, x1) = ((0.37f64 * 40.5).sin(), (0.37f64 * 40.5 + 1.0).sin());
        let x = DMatrix::from_row_slice(1, 2, &[x0, x1]);
        let y = m.parts[0].predict(&x).unwrap();
        for (c, want) in [0.5 * x0, 2.0 * 0.5 * x1, 3.0 * 0.5 * x0]
            .iter()
            .enumerate()
        {
            assert!((y[c] - want).abs() < 1e-3, "{c}: {} vs {want}", y[c]);
        }
        // A smooth non-linear map with an even part: CVPR eq. 10 as printed (no
        // bias) can only represent odd functions and misses it; with the bias
        // input it is learnt.
        let nl = pair(80, &|x| x.tanh() + 0.3 * x * x);
        let want0 = x0.tanh() + 0.3 * x0 * x0;
        let odd = train(
            Method::GprNn,
            false,
            MeanFunction::Zero,
            MEAN_RIDGE, None,
            &names,
            &[nl.clone()],
            1.0,
            false,
            &opts,
        )
        .unwrap();
        let y_odd = odd.parts[0].predict(&x).unwrap()[0];
        let y_neg = odd.parts[0].predict(&(-&x)).unwrap()[0];
        assert!(
            (y_odd + y_neg).abs() < 1e-12,
            "no-bias NN GP is odd: {y_odd} {y_neg}"
        );
        let m = train(Method::GprNn, true, MeanFunction::Zero, MEAN_RIDGE, None, &names, &[nl], 1.0, false, &opts).unwrap();
        let y = m.parts[0].predict(&x).unwrap();
        assert!((y[0] - want0).abs() < 0.02, "{} vs {want0}", y[0]);
        assert!((y_odd - want0).abs() > 0.05, "{y_odd} vs {want0}");
        assert_eq!(m.n_train, 80);
        // The affine baseline uses the key-poses only.
        let m = train(
            Method::KeyposeAffine,
            false,
            MeanFunction::Zero,
            MEAN_RIDGE, None,
            &names,
            &[lin.clone()],
            1.0,
            false,
            &opts,
        )
        .unwrap();
        assert_eq!(m.n_train, 3);
        // Reversal swaps roles and pairs.
        let r = lin.clone().reversed();
        assert_eq!(r.source_coeffs[0], lin.target_coeffs[0]);
        assert_eq!(r.keyposes[1], [30, 30]);
    }
}
