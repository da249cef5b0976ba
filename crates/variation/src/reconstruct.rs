//! Pose reconstruction of sampled latent trajectories (paper §6, eqs. 11-13) and assembly of the
//! body: every part's pose from its GP (mean, eq. 12, or a draw from eq. 11), the parts merged
//! into one template mesh, the result rigidly aligned to the template (the same normalisation
//! `transfer::align` applied to the training frames), then placed in the world by integrating
//! the predicted displacements from the source sequence's starting pose.
//!
//! Merging: [`Assembly::Stitch`] is the paper's (child aligned to parent on the overlap band,
//! optimal boundary loop, Poisson merge: `surface::stitch::Stitcher`); [`Assembly::Average`]
//! aligns each child to its parent on the band and averages vertices shared by several parts
//! (as `transfer::assemble`), about 100 times cheaper, used for bulk decoding and statistics.

use gpdm::predict::Predictor;
use mesh_core::rigid::{procrustes, RigidMotion};
use mesh_core::{Error, Result};
use nalgebra::{DMatrix, Vector3, Vector6};
use rand::Rng;
use serde::{Deserialize, Serialize};

use crate::group::PartDef;
use crate::part_data::{split_torso, unflatten};
use crate::train::VariationModel;

/// How parts are merged into one mesh.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Assembly {
    Stitch,
    Average,
}

/// Decoded parts of one trajectory: `parts[k][t]` part `k`'s vertices at frame `t` (template
/// part frame) and the per-frame displacement 6-vectors.
pub struct DecodedParts {
    pub parts: Vec<Vec<Vec<Vector3<f64>>>>,
    pub displacements: Vec<[f64; 6]>,
    /// Per frame `[height, body-frame up axis]` (see [`crate::part_data`]).
    pub gravity: Vec<[f64; 4]>,
}

/// Factorised predictors of every part, plus the averaging plan.
pub struct Decoder<'a> {
    pub model: &'a VariationModel,
    pub predictors: Vec<Predictor>,
    /// Per child part: (its local index, parent's local index) of every band vertex.
    bands: Vec<Vec<(usize, usize)>>,
    coverage: Vec<u32>,
}

impl<'a> Decoder<'a> {
    /// Factorises every part's kernels; jitter notes go to `notes`.
    pub fn new(model: &'a VariationModel, notes: &mut Vec<String>) -> Result<Self> {
        let predictors = model
            .parts
            .iter()
            .map(|p| {
                let pr = Predictor::new(&p.gpdm)
                    .map_err(|e| Error::invalid(format!("part '{}': {e}", p.part.name)))?;
                notes.extend(
                    pr.notes
                        .iter()
                        .map(|n| format!("part '{}': {n}", p.part.name)),
                );
                Ok(pr)
            })
            .collect::<Result<Vec<_>>>()?;
        let parts: Vec<&PartDef> = model.parts.iter().map(|p| &p.part).collect();
        let n = model.template.len();
        let mut coverage = vec![0u32; n];
        parts
            .iter()
            .flat_map(|p| &p.vertices)
            .for_each(|&v| coverage[v as usize] += 1);
        if let Some(v) = coverage.iter().position(|&c| c == 0) {
            return Err(Error::invalid(format!("template vertex {v} is in no part")));
        }
        let mut bands = vec![Vec::new()];
        for (k, p) in parts.iter().enumerate().skip(1) {
            let q = p.parent.filter(|&q| q < k).ok_or_else(|| {
                Error::invalid(format!("part '{}' has no earlier parent", p.name))
            })?;
            let mut local = vec![usize::MAX; n];
            parts[q]
                .vertices
                .iter()
                .enumerate()
                .for_each(|(i, &v)| local[v as usize] = i);
            let band: Vec<(usize, usize)> = p
                .vertices
                .iter()
                .enumerate()
                .filter(|(_, &v)| local[v as usize] != usize::MAX)
                .map(|(i, &v)| (i, local[v as usize]))
                .collect();
            if band.len() < 3 {
                return Err(Error::invalid(format!(
                    "part '{}' shares {} vertices with its parent (need 3)",
                    p.name,
                    band.len()
                )));
            }
            bands.push(band);
        }
        Ok(Decoder {
            model,
            predictors,
            bands,
            coverage,
        })
    }

    /// Part poses for the latent trajectories `latents[k]` (T × d each): the mean (eq. 12) or,
    /// with `rng`, a draw from eq. 11.
    pub fn part_poses<R: Rng + ?Sized>(
        &self,
        latents: &[DMatrix<f64>],
        mut rng: Option<&mut R>,
    ) -> Result<DecodedParts> {
        if latents.len() != self.predictors.len() {
            return Err(Error::invalid(format!(
                "{} latent trajectories for {} parts",
                latents.len(),
                self.predictors.len()
            )));
        }
        let mut parts = Vec::with_capacity(latents.len());
        let mut displacements = Vec::new();
        let mut gravity = Vec::new();
        for (k, (pr, x)) in self.predictors.iter().zip(latents).enumerate() {
            let y = pr
                .reconstruct(x, rng.as_deref_mut())
                .map_err(|e| Error::invalid(format!("part {k}: {e}")))?;
            let mut frames = Vec::with_capacity(y.nrows());
            // Column-major storage: transpose once so that every frame is contiguous.
            let yt = y.transpose();
            let dim = yt.nrows();
            for t in 0..y.nrows() {
                let row = &yt.as_slice()[t * dim..(t + 1) * dim];
                if k == 0 {
                    let (v, d, g) = split_torso(row, self.model.scale);
                    frames.push(v);
                    displacements.push(d);
                    gravity.push(g);
                } else {
                    frames.push(unflatten(row));
                }
            }
            parts.push(frames);
        }
        Ok(DecodedParts {
            parts,
            displacements,
            gravity,
        })
    }

    /// Aligns children to parents on the bands and averages shared vertices (one frame).
    pub fn assemble_average(&self, parts: &[&[Vector3<f64>]]) -> Vec<Vector3<f64>> {
        let n = self.model.template.len();
        let mut sum = vec![Vector3::zeros(); n];
        let mut placed: Vec<Vec<Vector3<f64>>> = Vec::with_capacity(parts.len());
        for (k, p) in self.model.parts.iter().enumerate() {
            let pts = if k == 0 {
                parts[0].to_vec()
            } else {
                let q = p.part.parent.expect("checked in new");
                let src: Vec<Vector3<f64>> =
                    self.bands[k].iter().map(|&(i, _)| parts[k][i]).collect();
                let dst: Vec<Vector3<f64>> =
                    self.bands[k].iter().map(|&(_, j)| placed[q][j]).collect();
                procrustes(&src, &dst, None).apply_all(parts[k])
            };
            for (x, &v) in pts.iter().zip(&p.part.vertices) {
                sum[v as usize] += x;
            }
            placed.push(pts);
        }
        sum.iter()
            .zip(&self.coverage)
            .map(|(s, &c)| s / c as f64)
            .collect()
    }

    /// Merged body frames (template-aligned) of decoded parts.
    pub fn assemble(
        &self,
        decoded: &DecodedParts,
        how: Assembly,
    ) -> Result<Vec<Vec<Vector3<f64>>>> {
        let n_frames = decoded.displacements.len();
        let mut stitcher = match how {
            // A single part needs no merging.
            Assembly::Stitch if self.model.parts.len() > 1 => {
                let parts = self
                    .model
                    .parts
                    .iter()
                    .map(|p| surface::stitch::Part {
                        vertices: p.part.vertices.clone(),
                        parent: p.part.parent,
                    })
                    .collect();
                let layout = surface::stitch::PartLayout::new(
                    self.model.template.len(),
                    self.model.faces.clone(),
                    parts,
                )?;
                Some(surface::stitch::Stitcher::new(layout))
            }
            _ => None,
        };
        (0..n_frames)
            .map(|t| {
                let body = match stitcher.as_mut() {
                    Some(s) => {
                        let parts: Vec<Vec<Vector3<f64>>> =
                            decoded.parts.iter().map(|p| p[t].clone()).collect();
                        s.stitch(&parts)?.vertices
                    }
                    None => {
                        let parts: Vec<&[Vector3<f64>]> =
                            decoded.parts.iter().map(|p| p[t].as_slice()).collect();
                        self.assemble_average(&parts)
                    }
                };
                Ok(procrustes(&body, &self.model.template, None).apply_all(&body))
            })
            .collect()
    }

    /// Full decoding: part poses, assembly, displacement integration from `start`.
    pub fn decode<R: Rng + ?Sized>(
        &self,
        latents: &[DMatrix<f64>],
        start: &RigidMotion,
        how: Assembly,
        rng: Option<&mut R>,
    ) -> Result<Vec<Vec<Vector3<f64>>>> {
        let decoded = self.part_poses(latents, rng)?;
        let body = self.assemble(&decoded, how)?;
        Ok(place(
            &body,
            &decoded.displacements,
            &decoded.gravity,
            &self.model.up,
            start,
        ))
    }
}

/// World frames: `P_0 = start`, `P_t = G_t(P_{t−1} ∘ D_t)` (the first displacement is
/// ignored), where `G_t` is the gravity correction (deviation, see [`crate::part_data`]): the
/// smallest world rotation about the body origin taking the pose's body-frame up axis to the
/// decoded one, then the height set to the decoded height. Heading and horizontal travel stay
/// integrated. With `gravity` empty, plain integration.
pub fn place(
    body: &[Vec<Vector3<f64>>],
    displacements: &[[f64; 6]],
    gravity: &[[f64; 4]],
    up: &Vector3<f64>,
    start: &RigidMotion,
) -> Vec<Vec<Vector3<f64>>> {
    let mut poses = Vec::with_capacity(body.len());
    let mut cur = *start;
    for t in 0..body.len() {
        if t > 0 {
            cur = cur.compose(&RigidMotion::from_6vec(&Vector6::from_row_slice(
                &displacements[t],
            )));
            if let Some(g) = gravity.get(t) {
                let u = Vector3::new(g[1], g[2], g[3]);
                if u.norm() > 1e-9 {
                    // World direction the decoded body-up axis currently points to; rotate it onto `up`.
                    let now = cur.rotation * u.normalize();
                    if let Some(q) = nalgebra::Rotation3::rotation_between(&now, up) {
                        cur.rotation = q * cur.rotation;
                    }
                }
                cur.translation += up * (g[0] - cur.translation.dot(up));
            }
        }
        poses.push(cur);
    }
    body.iter()
        .zip(&poses)
        .map(|(f, p)| p.apply_all(f))
        .collect()
}
