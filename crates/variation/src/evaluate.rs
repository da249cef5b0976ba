//! `variation-eval`: the model-level figures of the 3DV paper (figs. 3-5, 7b) and the mean prediction.
//!
//! - **Fig. 4**: reconstruction error of the training poses, GPDM (3DV eq. 12 at the learned
//!   latent points, interpolated to every captured frame when trained at a stride) against
//!   PCA with the same dimension d on the training rows, as the mean per-vertex distance in
//!   each part's template frame (torso displacement columns excluded).
//! - **Fig. 7b**: for w ∈ {0.25, 0.75}, the non-linear mesh blend `Y_w` of the pair is the
//!   truth; the latent interpolation *guided* by the learned intermediate trajectory
//!   (`blend_pair` of the bounding learned trajectories, e.g. X₁ and X_0.5) and the *unguided*
//!   one (`(1 − w) X₁ + w X₂`) are decoded (3DV eq. 12) and compared per frame with the truth.
//! - **Mean prediction**: from each training sequence's first latent point, the mean
//!   dynamics (3DV eqs. 8-10) over the sequence length, decoded, against the sequence: shows
//!   whether the learned dynamics stay on the cycle (a test of the noise floor).
//! - Latent plots' data ([`EvalFigures`], drawn by the `figures` crate): figs. 3 and 5; fig. 6 (each learned pre-blend `X_w` against
//!   the linear interpolation `(1 − w) X₁ + w X₂`, per part) and fig. 7a (at w = 0.25, first part:
//!   the unguided and the guided interpolations of fig. 7b with the trajectories they come from).

use gp::pca::{Components, Pca};
use gpdm::blend::blend_pair;
use gpdm::hmc::HmcOptions;
use mesh_core::{Error, Result};
use nalgebra::DMatrix;
use serde::{Deserialize, Serialize};

use crate::group::{blend_sequences, Group};
use crate::metrics::mean_row_distance;
use crate::part_data;
use crate::reconstruct::Decoder;
use crate::sample::{sequence_variations, Sampler};
use crate::train::VariationModel;

/// Fig. 4 entry of one part.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct ReconstructionError {
    pub part: String,
    pub vertices: usize,
    pub gpdm_m: f64,
    pub pca_m: f64,
}

/// Fig. 7b for one weight.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct LatentBlendError {
    pub w: f64,
    /// Bounding learned weights used by the guided interpolation.
    pub guided_from: (f64, f64),
    /// Mean per-vertex distance to the non-linear blend, per frame (all parts, vertex-weighted).
    pub guided_per_frame_m: Vec<f64>,
    pub unguided_per_frame_m: Vec<f64>,
    pub guided_m: f64,
    pub unguided_m: f64,
}

/// Mean-prediction tracking of one sequence.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct MeanPrediction {
    pub sequence: String,
    /// Mean per-vertex distance (all parts) between the decoded mean prediction and the data.
    pub error_m: f64,
}

/// Everything `variation-eval` reports.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct EvalReport {
    pub group: String,
    pub latent_dim: usize,
    pub reconstruction: Vec<ReconstructionError>,
    pub reconstruction_gpdm_m: f64,
    pub reconstruction_pca_m: f64,
    pub latent_blend: Vec<LatentBlendError>,
    pub mean_prediction: Vec<MeanPrediction>,
    pub plots: Vec<String>,
}

fn vertex_count(model: &VariationModel, k: usize) -> usize {
    model.parts[k].part.vertices.len()
}

/// Decoded part rows (`T × D_k`) of latent trajectories, one per part.
fn decode_rows(dec: &Decoder, latents: &[DMatrix<f64>]) -> Result<Vec<DMatrix<f64>>> {
    dec.predictors
        .iter()
        .zip(latents)
        .map(|(p, x)| p.pose_mean(x).map_err(|e| Error::invalid(e.to_string())))
        .collect()
}

fn weighted(model: &VariationModel, per_part: &[f64]) -> f64 {
    let n: usize = (0..model.parts.len()).map(|k| vertex_count(model, k)).sum();
    per_part
        .iter()
        .enumerate()
        .map(|(k, e)| e * vertex_count(model, k) as f64)
        .sum::<f64>()
        / n.max(1) as f64
}

/// Part `k`'s captured rows of training sequence `s` (every frame, template part frame).
fn capture_rows(model: &VariationModel, group: &Group, k: usize, s: usize) -> DMatrix<f64> {
    let part = &model.parts[k].part;
    let r = part_data::reference(&model.template, part);
    part_data::part_rows(&group.sequences[s].motion, part, &r)
}

/// The latent plots' data, drawn by the `figures` crate's `variation-eval` (figs. 4 and 7b are
/// drawn from the [`EvalReport`]): file name, title and named trajectories of each.
#[derive(Clone, Debug)]
pub struct EvalFigures {
    /// Fig. 3 per part, then fig. 6 per part and fig. 7a.
    pub latent: Vec<LatentFigure>,
    /// Fig. 5: HMC variations of the first sequence's first part.
    pub variations: LatentFigure,
}

/// Runs the evaluation; with `figures`, also the latent plots' data (the report's `plots` stay
/// empty: the files are named by whoever draws them).
pub fn evaluate(
    model: &VariationModel,
    group: &Group,
    figures: bool,
    seed: u64,
) -> Result<(EvalReport, Option<EvalFigures>)> {
    if group.sequences.len() != model.sequences.len() || group.n_frames() != model.n_frames() {
        return Err(Error::invalid(
            "the group does not match the model (train the model from this group)",
        ));
    }
    let mut notes = Vec::new();
    let dec = Decoder::new(model, &mut notes)?;
    let d = model.parts[0].gpdm.config.latent_dim;
    let reconstruction = reconstruction_errors(model, group, &dec, d)?;
    let reconstruction_gpdm_m = weighted(
        model,
        &reconstruction.iter().map(|r| r.gpdm_m).collect::<Vec<_>>(),
    );
    let reconstruction_pca_m = weighted(
        model,
        &reconstruction.iter().map(|r| r.pca_m).collect::<Vec<_>>(),
    );
    // Fig. 7b (and the latent plots of figs. 6 and 7a, drawn below with the others).
    let mut blend_figs = preblend_figures(model);
    let latent_blend = latent_blend_errors(model, group, &dec, &mut blend_figs)?;
    let mean_prediction = mean_prediction_errors(model, group, &dec)?;
    let figures = match figures {
        true => Some(latent_figures(model, &dec, seed, blend_figs)?),
        false => None,
    };
    let report = EvalReport {
        group: model.group.clone(),
        latent_dim: d,
        reconstruction,
        reconstruction_gpdm_m,
        reconstruction_pca_m,
        latent_blend,
        mean_prediction,
        plots: Vec::new(),
    };
    Ok((report, figures))
}

/// A latent plot: its file name, title and named trajectories.
pub type LatentFigure = (String, String, Vec<(String, DMatrix<f64>)>);

/// Fig. 4: per part, the training meshes reconstructed by the GPDM (3DV eq. 12 at the learned
/// latent points, brought to the capture's rate, against every captured frame) and by a PCA of
/// the same dimension `d` on the training rows.
fn reconstruction_errors(model: &VariationModel, group: &Group, dec: &Decoder, d: usize) -> Result<Vec<ReconstructionError>> {
    let mut reconstruction = Vec::new();
    for (k, pm) in model.parts.iter().enumerate() {
        let g = &pm.gpdm;
        let nv = vertex_count(model, k);
        let mut sum = 0.0;
        for s in 0..model.sequences.len() {
            let rec = dec.predictors[k]
                .pose_mean(&model.latents(s)[k])
                .map_err(|e| Error::invalid(e.to_string()))?;
            let truth = capture_rows(model, group, k, s);
            sum += mean_row_distance(&rec, &truth, nv) * truth.nrows() as f64;
        }
        let frames = (model.sequences.len() * model.n_frames()).max(1) as f64;
        let mut y = g.y.clone();
        for mut row in y.row_iter_mut() {
            row += g.y_mean.transpose();
        }
        let pca = Pca::fit(&y, Components::Count(d)).map_err(|e| Error::invalid(e.to_string()))?;
        let pr = pca
            .decode(&pca.encode(&y).map_err(|e| Error::invalid(e.to_string()))?)
            .map_err(|e| Error::invalid(e.to_string()))?;
        reconstruction.push(ReconstructionError {
            part: pm.part.name.clone(),
            vertices: nv,
            gpdm_m: sum / frames,
            pca_m: mean_row_distance(&pr, &y, nv),
        });
    }
    Ok(reconstruction)
}

/// Fig. 6: the learned trajectory of each pre-blend of the model's pair against the linear
/// interpolation of the pair's trajectories at the same weight, per part (none without a pair).
fn preblend_figures(model: &VariationModel) -> Vec<LatentFigure> {
    let mut blend_figs = Vec::new();
    let Some((a, b)) = model.pair else {
        return blend_figs;
    };
    for (k, pm) in model.parts.iter().enumerate() {
        let (xa, xb) = (&model.latents(a)[k], &model.latents(b)[k]);
        let mut series = vec![
            (model.sequences[a].name.clone(), xa.clone()),
            (model.sequences[b].name.clone(), xb.clone()),
        ];
        for (i, info) in model.sequences.iter().enumerate() {
            // The pre-blends of the pair (a group may pre-blend other pairs too).
            if let (Some(w), true) = (info.blend, info.blend_of == Some((a, b))) {
                series.push((format!("linear w = {w}"), xa * (1.0 - w) + xb * w));
                series.push((format!("learned pre-blend w = {w}"), model.latents(i)[k].clone()));
            }
        }
        if series.len() > 2 {
            blend_figs.push((
                format!("fig6-preblend-{}.png", pm.part.name),
                format!("{}: pre-blended trajectory vs linear interpolation ({})", model.group, pm.part.name),
                series,
            ));
        }
    }
    blend_figs
}

/// Fig. 7b: at w = 0.25 and 0.75, the latent interpolation guided by the learned pre-blends and
/// the unguided one, decoded, against the non-linear mesh blend, per frame; fig. 7a's latent
/// plot of the first part is added to `blend_figs`.
fn latent_blend_errors(
    model: &VariationModel,
    group: &Group,
    dec: &Decoder,
    blend_figs: &mut Vec<LatentFigure>,
) -> Result<Vec<LatentBlendError>> {
    let mut latent_blend = Vec::new();
    let Some((a, b)) = model.pair else {
        return Ok(latent_blend);
    };
    let learned = crate::sample::blend_entries(model, a, b);
    let blender = surface::blend::Blender::new(group.template.clone(), group.faces.clone())?;
    for w in [0.25, 0.75] {
        let i2 = learned
            .iter()
            .position(|&(v, _)| v > w)
            .unwrap_or(learned.len() - 1);
        let (lo, hi) = (learned[i2 - 1], learned[i2]);
        let truth = blend_sequences(
            &blender,
            &group.sequences[a],
            &group.sequences[b],
            w,
            &group.up,
            &group.root_point(),
        )?;
        let xa = model.latents(a);
        let xb = model.latents(b);
        let (xl, xh) = (model.latents(lo.1), model.latents(hi.1));
        let guided: Vec<DMatrix<f64>> = (0..model.parts.len())
            .map(|k| blend_pair(&xl[k], lo.0, &xh[k], hi.0, w))
            .collect();
        let unguided: Vec<DMatrix<f64>> = (0..model.parts.len())
            .map(|k| &xa[k] * (1.0 - w) + &xb[k] * w)
            .collect();
        if w == 0.25 && (lo.1, hi.1) != (a, b) {
            // Fig. 7a: the two interpolations at w of the first part.
            let pm = &model.parts[0];
            blend_figs.push((
                format!("fig7a-interpolation-{w}-{}.png", pm.part.name),
                format!("{}: X_{w} guided vs unguided ({})", model.group, pm.part.name),
                vec![
                    (model.sequences[a].name.clone(), xa[0].clone()),
                    (model.sequences[b].name.clone(), xb[0].clone()),
                    (format!("learned w = {}", hi.0), xh[0].clone()),
                    (format!("unguided w = {w} (from w = 0, 1)"), unguided[0].clone()),
                    (format!("guided w = {w} (from w = {}, {})", lo.0, hi.0), guided[0].clone()),
                ],
            ));
        }
        let (rg, ru) = (decode_rows(&dec, &guided)?, decode_rows(&dec, &unguided)?);
        let t_n = truth.motion.n_frames();
        let mut gpf = vec![0.0; t_n];
        let mut upf = vec![0.0; t_n];
        let total: usize = (0..model.parts.len()).map(|k| vertex_count(model, k)).sum();
        for (k, pm) in model.parts.iter().enumerate() {
            let r = part_data::reference(&model.template, &pm.part);
            let yt = part_data::part_rows(&truth.motion, &pm.part, &r);
            let nv = vertex_count(model, k);
            for t in 0..t_n {
                let one = |m: &DMatrix<f64>| {
                    mean_row_distance(
                        &m.rows(t, 1).into_owned(),
                        &yt.rows(t, 1).into_owned(),
                        nv,
                    )
                };
                gpf[t] += one(&rg[k]) * nv as f64 / total as f64;
                upf[t] += one(&ru[k]) * nv as f64 / total as f64;
            }
        }
        let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len().max(1) as f64;
        latent_blend.push(LatentBlendError {
            w,
            guided_from: (lo.0, hi.0),
            guided_m: mean(&gpf),
            unguided_m: mean(&upf),
            guided_per_frame_m: gpf,
            unguided_per_frame_m: upf,
        });
    }
    Ok(latent_blend)
}

/// Per sequence: the mean prediction from its first latent point, decoded, against its
/// captured frames.
fn mean_prediction_errors(model: &VariationModel, group: &Group, dec: &Decoder) -> Result<Vec<MeanPrediction>> {
    let mut mean_prediction = Vec::new();
    for (s, info) in model.sequences.iter().enumerate() {
        let lat = model.model_latents(s);
        let mut per = Vec::new();
        for k in 0..model.parts.len() {
            let x1: Vec<f64> = lat[k].row(0).iter().copied().collect();
            let steps = crate::frame_stride::covering_count(model.n_frames(), model.stride);
            let xm = dec.predictors[k]
                .mean_trajectory(&x1, steps)
                .map_err(|e| Error::invalid(e.to_string()))?;
            let xm = crate::frame_stride::upsample(&xm, model.stride, model.n_frames());
            let rec = dec.predictors[k]
                .pose_mean(&xm)
                .map_err(|e| Error::invalid(e.to_string()))?;
            let y = capture_rows(model, group, k, s);
            per.push(mean_row_distance(&rec, &y, vertex_count(model, k)));
        }
        mean_prediction.push(MeanPrediction {
            sequence: info.name.clone(),
            error_m: weighted(model, &per),
        });
    }
    Ok(mean_prediction)
}

/// The latent plots: fig. 3 (each part's learned trajectories), `blend_figs` (figs. 6 and 7a)
/// and fig. 5 (20 HMC variations of the first sequence, first part).
fn latent_figures(model: &VariationModel, dec: &Decoder, seed: u64, blend_figs: Vec<LatentFigure>) -> Result<EvalFigures> {
    let mut latent: Vec<LatentFigure> = model
        .parts
        .iter()
        .enumerate()
        .map(|(k, pm)| {
            let series = model.sequences.iter().enumerate().map(|(s, i)| (i.name.clone(), model.latents(s)[k].clone())).collect();
            let title = format!("{}: learned latent trajectories ({})", model.group, pm.part.name);
            (format!("fig3-latent-{}.png", pm.part.name), title, series)
        })
        .collect();
    latent.extend(blend_figs);
    let hmc = HmcOptions {
        n_samples: 20,
        burn_in: 200,
        thin: 10,
        seed,
        ..HmcOptions::default()
    };
    let (vars, _) = sequence_variations(dec, 0, Sampler::Hmc, 1.0, &hmc)?;
    let series: Vec<(String, DMatrix<f64>)> = vars
        .iter()
        .enumerate()
        .map(|(i, v)| (format!("var{i}"), v[0].clone()))
        .collect();
    let (sequence, part) = (&model.sequences[0].name, &model.parts[0].part.name);
    let variations = (
        format!("fig5-variations-{sequence}-{part}.png"),
        format!("{}: 20 HMC variations of {sequence} ({part})", model.group),
        series,
    );
    Ok(EvalFigures { latent, variations })
}
