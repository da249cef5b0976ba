//! Learning curves of the pose regression (CVPR §7, figures 7-9): RMS
//! per-vertex error on the training subset and on a held-out 30 % of the
//! frame pairs, against the training-set size.
//!
//! - Figure 7: kernels (NN, SE, linear) and the affine key-pose baseline,
//!   training subsets drawn at random;
//! - figure 8: the same four methods, training subsets initialised with all
//!   key-pose pairs, then random pairs;
//! - figure 9: per-part GPs versus one whole-body GP (NN kernel) at equal
//!   total dimensions (the paper: "for equivalent total number of input and
//!   output dimensions"; e.g. 5 parts x 20 components against 100 whole-body
//!   components).
//!
//! **Pairs.** The paper's curves use fully annotated frame correspondences
//! ([`Correspondence::True`]: `train[k].correspondences` of `set.json`, one
//! per source frame); [`Correspondence::Dtw`] uses the DTW-densified pairs of
//! `dtw-densify` instead (what the transfer is trained on).
//!
//! **Split.** The pairs of all training motions are shuffled with ChaCha8
//! from `--seed`; key-pose pairs always stay on the training side and 30 % of
//! the others are held out. Training subsets of increasing size are prefixes
//! of one shuffled order of the training side (figure 8: key-poses first), so
//! they are nested.
//!
//! **Error.** Against the target's *true* aligned part meshes, so a perfect
//! regressor scores the PCA truncation error, not 0 (as the paper's curves).
//! With `x` a true part row, `c = W (x - μ)` its coefficients (orthonormal
//! rows `W`) and `ĉ` the prediction, `x - (μ + Wᵀ ĉ) = Wᵀ (c - ĉ) + r` with the
//! truncation residual `r = x - μ - Wᵀ c` orthogonal to the rows of `W`, hence
//! `|x - decode(ĉ)|² = |c - ĉ|² + |r|²` exactly: the per-vertex RMS is
//! `sqrt(Σ_rows Σ_parts (|Δc_k|² + |r_k|²) / (rows · Σ_parts n_k))` with `n_k`
//! the part's vertex count (vertices on overlap bands count once per part).
//! The `pca-truncation` curve is that error for `ĉ = c`. The displacement GP
//! is not part of these curves.
//!
//! **Affine baseline.** Fitted on the training subset's pairs, every pair a
//! key-pose (Baran et al.'s affine span grows with the subset, as in the
//! paper, where it "performs particularly poorly" on large dense sets).

use std::path::Path;

use gp::gpr::GprOptions;
use mesh_core::capture_set::SetSpec;
use mesh_core::{Error, Result};
use nalgebra::DMatrix;
use rand::seq::SliceRandom;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use crate::gpr_model::{train, GprModel, MeanFunction, Method, PairData, TrainingSet, MEAN_RIDGE};
use capture::align::{AlignedMotion, CaptureInfo};
use capture::motion_stream::read_encoded_with_truncation;
use capture::part_pca::{EncodedFrames, PcaModel};

/// Which frame pairs the curves learn from and are tested on.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Correspondence {
    /// The set's ground-truth correspondences (`set.json`, `train[k].correspondences`).
    True,
    /// The DTW-densified pairs (`dtw-densify`).
    Dtw,
}

impl Correspondence {
    pub fn name(&self) -> &'static str {
        match self {
            Correspondence::True => "true",
            Correspondence::Dtw => "dtw",
        }
    }
}

/// Which training rows a curve uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Rows {
    /// Random pairs.
    Dense,
    /// All key-pose pairs first, then random pairs.
    KeyposesFirst,
}

/// One curve of the figures.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Curve {
    pub method: Method,
    pub rows: Rows,
    /// Per-part GPs (false: whole body).
    pub parts: bool,
}

impl Curve {
    pub fn label(&self) -> String {
        let rows = match self.rows {
            Rows::Dense => "dense",
            Rows::KeyposesFirst => "keyposes-first",
        };
        let body = if self.parts { "parts" } else { "whole-body" };
        format!("{} {rows} {body}", self.method.name())
    }
}

const fn curve(method: Method, rows: Rows, parts: bool) -> Curve {
    Curve {
        method,
        rows,
        parts,
    }
}

/// The curves of figures 7, 8 and 9 (figure 9 shares figure 7's gpr-nn curve).
pub const CURVES: [Curve; 9] = [
    curve(Method::GprNn, Rows::Dense, true),
    curve(Method::GprSe, Rows::Dense, true),
    curve(Method::GprLinear, Rows::Dense, true),
    curve(Method::KeyposeAffine, Rows::Dense, true),
    curve(Method::GprNn, Rows::KeyposesFirst, true),
    curve(Method::GprSe, Rows::KeyposesFirst, true),
    curve(Method::GprLinear, Rows::KeyposesFirst, true),
    curve(Method::KeyposeAffine, Rows::KeyposesFirst, true),
    curve(Method::WholeBody, Rows::Dense, false),
];

/// Curve label of the PCA truncation floor (a perfect regressor).
pub fn truncation_label(parts: bool) -> String {
    format!(
        "pca-truncation {}",
        if parts { "parts" } else { "whole-body" }
    )
}

/// One point of one curve.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CurvePoint {
    pub direction: String,
    /// [`Correspondence::name`].
    pub pairs: String,
    pub curve: String,
    pub n_train: usize,
    /// Total number of target PCA components (sum over parts).
    pub components: usize,
    pub train_rms_m: f64,
    pub test_rms_m: f64,
}

/// One training pair in coefficients, with the PCA truncation residuals of
/// both motions' frames.
#[derive(Clone, Debug)]
pub struct ResidualPair {
    pub data: PairData,
    /// `source_residual[part][frame]`: `|r|²` (m², summed over the part's vertices).
    pub source_residual: Vec<Vec<f64>>,
    pub target_residual: Vec<Vec<f64>>,
}

impl ResidualPair {
    /// Swaps source and target (the reverse direction).
    pub fn reversed(self) -> ResidualPair {
        ResidualPair {
            data: self.data.reversed(),
            source_residual: self.target_residual,
            target_residual: self.source_residual,
        }
    }
}

/// Squared truncation residual `|x - decode(encode(x))|²` of every part of
/// every frame of `motion`: `result[part][frame]`.
pub fn truncation_residuals(pca: &PcaModel, motion: &AlignedMotion) -> Result<Vec<Vec<f64>>> {
    let rows = pca.part_rows(motion)?;
    let coeffs = pca.encode_rows(&rows)?;
    pca.truncation(&rows, &coeffs)
}

/// Fails unless every frame pair and key-pose lies within motions of `source_frames` and
/// `target_frames` frames.
fn check_frame_pairs(source_frames: usize, target_frames: usize, pairs: &[[usize; 2]], keyposes: &[[usize; 2]]) -> Result<()> {
    match pairs.iter().chain(keyposes).find(|[i, j]| *i >= source_frames || *j >= target_frames) {
        Some([i, j]) => Err(Error::invalid(format!(
            "frame pair ({i}, {j}) outside the motions ({source_frames} and {target_frames} frames)"
        ))),
        None => Ok(()),
    }
}

/// Encodes one training pair (set order: `source` of the set's source
/// subject) with the two subjects' PCA models.
pub fn encode_pair(
    source: &AlignedMotion,
    target: &AlignedMotion,
    pairs: &[[usize; 2]],
    keyposes: &[[usize; 2]],
    source_pca: &PcaModel,
    target_pca: &PcaModel,
) -> Result<ResidualPair> {
    check_frame_pairs(source.n_frames(), target.n_frames(), pairs, keyposes)?;
    Ok(ResidualPair {
        data: PairData {
            source_coeffs: source_pca.encode(source)?,
            target_coeffs: target_pca.encode(target)?,
            source_disp: source.displacements.clone(),
            target_disp: target.displacements.clone(),
            pairs: pairs.to_vec(),
            keyposes: keyposes.to_vec(),
        },
        source_residual: truncation_residuals(source_pca, source)?,
        target_residual: truncation_residuals(target_pca, target)?,
    })
}

/// One training pair read from its aligned motions' files (`source` of the set's source
/// subject, `target` of its target), each in a single pass that encodes it with the subject's
/// per-part (`parts`) and whole-body (`whole`) models, `[source, target]` each: the pair as
/// [`encode_pair`] encodes it with the per-part and with the whole-body models (to the bit),
/// and the two motions' capture records. Holds a few frame blocks of each motion, never a
/// motion; a failure names the file.
pub fn read_pair(
    source: &Path,
    target: &Path,
    pairs: &[[usize; 2]],
    keyposes: &[[usize; 2]],
    parts: [&PcaModel; 2],
    whole: [&PcaModel; 2],
) -> Result<(ResidualPair, ResidualPair, [CaptureInfo; 2])> {
    let read = |path: &Path, k: usize| read_encoded_with_truncation(path, &[parts[k], whole[k]]);
    let (s, t) = rayon::join(|| read(source, 0), || read(target, 1));
    let ((s_enc, s_info, _), (t_enc, t_info, _)) = (s?, t?);
    check_frame_pairs(s_info.n_frames, t_info.n_frames, pairs, keyposes)?;
    let [s_parts, s_whole]: [EncodedFrames; 2] =
        s_enc.try_into().map_err(|_| Error::invalid("two encodings expected"))?;
    let [t_parts, t_whole]: [EncodedFrames; 2] =
        t_enc.try_into().map_err(|_| Error::invalid("two encodings expected"))?;
    let pair = |s: EncodedFrames, t: EncodedFrames| ResidualPair {
        data: PairData {
            source_coeffs: s.coefficients,
            target_coeffs: t.coefficients,
            source_disp: s_info.displacements.clone(),
            target_disp: t_info.displacements.clone(),
            pairs: pairs.to_vec(),
            keyposes: keyposes.to_vec(),
        },
        source_residual: s.truncation,
        target_residual: t.truncation,
    };
    Ok((pair(s_parts, t_parts), pair(s_whole, t_whole), [s_info.capture.clone(), t_info.capture.clone()]))
}

/// The key-poses and the true dense correspondences of the training pair
/// whose source motion is `motion` in `set` (`set_path` for messages).
pub fn true_correspondences(
    set: &SetSpec,
    set_path: &Path,
    motion: &str,
) -> Result<(Vec<[usize; 2]>, Vec<[usize; 2]>)> {
    let pair = set
        .train
        .iter()
        .find(|p| p.source == motion)
        .ok_or_else(|| {
            Error::file(
                set_path,
                format!("no training pair with source motion '{motion}'"),
            )
        })?;
    let value = pair.extra.get("correspondences").ok_or_else(|| {
        Error::file(
            set_path,
            format!("training pair '{motion}' has no 'correspondences' (true frame pairs)"),
        )
    })?;
    let corr: Vec<[usize; 2]> = serde_json::from_value(value.clone()).map_err(|e| {
        Error::file(
            set_path,
            format!("training pair '{motion}': bad correspondences: {e}"),
        )
    })?;
    if corr.is_empty() {
        return Err(Error::file(
            set_path,
            format!("training pair '{motion}': no correspondences"),
        ));
    }
    Ok((pair.keyposes.clone(), corr))
}

/// Total number of components of a PCA model (sum over parts).
pub fn total_components(pca: &PcaModel) -> usize {
    pca.parts.iter().map(|p| p.pca.n_components()).sum()
}

/// The training data of one direction, for per-part and whole-body PCA.
pub struct DirectionData {
    pub label: String,
    pub correspondence: Correspondence,
    pub parts: Vec<ResidualPair>,
    pub whole: Vec<ResidualPair>,
    /// Target vertex count of each part, and of the whole body.
    pub part_vertices: Vec<usize>,
    pub whole_vertices: usize,
    pub part_names: Vec<String>,
    pub frame_ratio: f64,
}

/// Row indices (in [`crate::gpr_model::training_set`] order, dense) of the
/// first occurrence of each key-pose pair.
pub fn key_rows(pairs: &[PairData]) -> Vec<usize> {
    let mut out = Vec::new();
    let mut offset = 0;
    for p in pairs {
        for k in &p.keyposes {
            if let Some(r) = p.pairs.iter().position(|q| q == k) {
                out.push(offset + r);
            }
        }
        offset += p.pairs.len();
    }
    out.sort_unstable();
    out.dedup();
    out
}

/// Seeded split of `n` rows: `(training side, held out)`; key rows stay on
/// the training side (at its front), 30 % of the other rows are held out.
pub fn split(n: usize, keys: &[usize], seed: u64) -> (Vec<usize>, Vec<usize>) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut others: Vec<usize> = (0..n).filter(|r| keys.binary_search(r).is_err()).collect();
    others.shuffle(&mut rng);
    let n_test = (others.len() as f64 * 0.3).round() as usize;
    let test = others[..n_test].to_vec();
    let mut train = keys.to_vec();
    train.shuffle(&mut rng);
    train.extend_from_slice(&others[n_test..]);
    (train, test)
}

/// Size of the training side of [`split`] for `n` rows with `keys` key rows.
pub fn train_side_len(n: usize, keys: usize) -> usize {
    n - (n.saturating_sub(keys) as f64 * 0.3).round() as usize
}

/// About `count` sizes from `min` to `max`, geometrically spaced, distinct.
pub fn sizes(min: usize, max: usize, count: usize) -> Vec<usize> {
    let (min, max) = (min.max(2).min(max), max.max(2));
    let mut out: Vec<usize> = (0..count.max(2))
        .map(|i| {
            let t = i as f64 / (count.max(2) - 1) as f64;
            (min as f64 * (max as f64 / min as f64).powf(t)).round() as usize
        })
        .collect();
    out.dedup();
    out
}

/// Per training row (in [`crate::gpr_model::training_set`] order, dense
/// pairs) the target's squared truncation residual of every part:
/// `result[part][row]`.
pub fn row_residuals(pairs: &[ResidualPair]) -> Vec<Vec<f64>> {
    let n_parts = pairs.first().map_or(0, |p| p.target_residual.len());
    (0..n_parts)
        .map(|k| {
            pairs
                .iter()
                .flat_map(|p| p.data.pairs.iter().map(move |&[_, j]| p.target_residual[k][j]))
                .collect()
        })
        .collect()
}

/// Per-vertex RMS error against the true parts: predicted coefficients
/// `pred`, true coefficients `truth` (per part, one row per pair), squared
/// truncation residuals `residual[part][row]` of the same rows, and each
/// part's vertex count (see the module documentation).
pub fn vertex_rms(
    pred: &[DMatrix<f64>],
    truth: &[DMatrix<f64>],
    residual: &[Vec<f64>],
    vertices: &[usize],
) -> f64 {
    let rows = truth.first().map_or(0, |t| t.nrows()).max(1) as f64;
    let sq: f64 = pred
        .iter()
        .zip(truth)
        .map(|(p, t)| (p - t).norm_squared())
        .sum::<f64>()
        + residual.iter().flatten().sum::<f64>();
    (sq / (rows * vertices.iter().sum::<usize>().max(1) as f64)).sqrt()
}

fn pick(residual: &[Vec<f64>], rows: &[usize]) -> Vec<Vec<f64>> {
    residual
        .iter()
        .map(|r| rows.iter().map(|&i| r[i]).collect())
        .collect()
}

fn model_error(
    model: &GprModel,
    data: &TrainingSet,
    residual: &[Vec<f64>],
    vertices: &[usize],
) -> Result<f64> {
    let pred = model
        .parts
        .iter()
        .zip(&data.x_parts)
        .map(|(r, x)| r.predict(x))
        .collect::<Result<Vec<_>>>()?;
    Ok(vertex_rms(&pred, &data.y_parts, residual, vertices))
}

/// All points of all [`CURVES`] (and the PCA truncation floors) for one
/// direction. `train_sizes` larger than the training side are skipped.
/// `nn_bias` and `mean`: as `gpr-train` ([`crate::gpr_model::train`]).
#[allow(clippy::too_many_arguments)]
pub fn run_direction(
    dir: &DirectionData,
    train_sizes: &[usize],
    nn_bias: bool,
    mean: MeanFunction,
    opts: &GprOptions,
    seed: u64,
) -> Result<Vec<CurvePoint>> {
    let plain = |v: &[ResidualPair]| v.iter().map(|p| p.data.clone()).collect::<Vec<_>>();
    let (parts_data, whole_data) = (plain(&dir.parts), plain(&dir.whole));
    let parts_set = crate::gpr_model::training_set(&parts_data, dir.frame_ratio, false)?;
    let whole_set = crate::gpr_model::training_set(&whole_data, dir.frame_ratio, false)?;
    if parts_set.len() != whole_set.len() {
        return Err(Error::invalid(
            "per-part and whole-body training sets differ in length",
        ));
    }
    let (parts_res, whole_res) = (row_residuals(&dir.parts), row_residuals(&dir.whole));
    let comps = |s: &TrainingSet| s.y_parts.iter().map(|y| y.ncols()).sum::<usize>();
    let keys = key_rows(&parts_data);
    let (train_side, held_out) = split(parts_set.len(), &keys, seed);
    let keys_first: Vec<usize> = {
        let mut k = keys.clone();
        k.extend(train_side.iter().filter(|r| keys.binary_search(r).is_err()));
        k
    };
    let dense_order: Vec<usize> = {
        let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x9e37_79b9_7f4a_7c15);
        let mut d = train_side.clone();
        d.shuffle(&mut rng);
        d
    };
    let point = |curve: String, n: usize, components: usize, train: f64, test: f64| CurvePoint {
        direction: dir.label.clone(),
        pairs: dir.correspondence.name().to_string(),
        curve,
        n_train: n,
        components,
        train_rms_m: train,
        test_rms_m: test,
    };
    let mut points = Vec::new();
    for curve in CURVES {
        let (set, residual, names, vertices): (&TrainingSet, &[Vec<f64>], Vec<String>, Vec<usize>) =
            if curve.parts {
                (
                    &parts_set,
                    &parts_res,
                    dir.part_names.clone(),
                    dir.part_vertices.clone(),
                )
            } else {
                (
                    &whole_set,
                    &whole_res,
                    vec!["body".to_string()],
                    vec![dir.whole_vertices],
                )
            };
        let test = set.subset(&held_out);
        let test_res = pick(residual, &held_out);
        for &n in train_sizes {
            if n > train_side.len() || (curve.rows == Rows::KeyposesFirst && n < keys.len()) {
                continue;
            }
            let rows: &[usize] = match curve.rows {
                Rows::Dense => &dense_order[..n],
                Rows::KeyposesFirst => &keys_first[..n],
            };
            let train_rows = set.subset(rows);
            let model = fit_on(
                curve.method,
                nn_bias,
                mean,
                &names,
                &train_rows,
                dir.frame_ratio,
                opts,
            )?;
            points.push(point(
                curve.label(),
                n,
                comps(set),
                model_error(&model, &train_rows, &pick(residual, rows), &vertices)?,
                model_error(&model, &test, &test_res, &vertices)?,
            ));
        }
    }
    // The floor: a perfect regressor on the same rows.
    for (parts, set, residual, vertices) in [
        (true, &parts_set, &parts_res, dir.part_vertices.clone()),
        (false, &whole_set, &whole_res, vec![dir.whole_vertices]),
    ] {
        let test = set.subset(&held_out);
        let test_err = vertex_rms(&test.y_parts, &test.y_parts, &pick(residual, &held_out), &vertices);
        for &n in train_sizes.iter().filter(|&&n| n <= train_side.len()) {
            let tr = set.subset(&dense_order[..n]);
            let train_err = vertex_rms(
                &tr.y_parts,
                &tr.y_parts,
                &pick(residual, &dense_order[..n]),
                &vertices,
            );
            points.push(point(truncation_label(parts), n, comps(set), train_err, test_err));
        }
    }
    Ok(points)
}

/// Trains the pose regressors of `method` on the rows of `set` (every row a
/// "key-pose", so that the affine baseline spans them all).
fn fit_on(
    method: Method,
    nn_bias: bool,
    mean: MeanFunction,
    names: &[String],
    set: &TrainingSet,
    ratio: f64,
    opts: &GprOptions,
) -> Result<GprModel> {
    let n = set.len();
    let one = PairData {
        source_coeffs: set.x_parts.clone(),
        target_coeffs: set.y_parts.clone(),
        source_disp: (0..n)
            .map(|r| std::array::from_fn(|c| set.x_disp[(r, c)]))
            .collect(),
        target_disp: vec![[0.0; 6]; n],
        pairs: (0..n).map(|r| [r, r]).collect(),
        keyposes: (0..n).map(|r| [r, r]).collect(),
    };
    train(method, nn_bias, mean, MEAN_RIDGE, None, names, &[one], ratio.max(1e-9), false, opts)
}

/// Writes the points as CSV.
pub fn write_csv(path: &Path, points: &[CurvePoint]) -> Result<()> {
    let mut text =
        String::from("direction,pairs,curve,n_train,components,train_rms_m,test_rms_m\n");
    for p in points {
        text.push_str(&format!(
            "{},{},{},{},{},{:.6},{:.6}\n",
            p.direction, p.pairs, p.curve, p.n_train, p.components, p.train_rms_m, p.test_rms_m
        ));
    }
    mesh_core::atomic::write_bytes_atomic(path, text.as_bytes())
}
