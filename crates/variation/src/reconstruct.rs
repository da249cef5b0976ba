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
use mesh_core::rigid::{procrustes, rigid_from_moments, RigidMotion};
use mesh_core::{Error, Result};
use nalgebra::{DMatrix, Vector3, Vector6};
use rand::Rng;
use serde::{Deserialize, Serialize};

use crate::group::PartDef;
use crate::part_data::{extra_scale, split_torso, unflatten, TORSO_EXTRA};
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
    /// Exact predictor of the torso's extra columns when `predictors` use a basis.
    torso_extra: Option<Predictor>,
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
                Predictor::new(&p.gpdm)
                    .map_err(|e| Error::invalid(format!("part '{}': {e}", p.part.name)))
            })
            .collect::<Result<Vec<_>>>()?;
        Self::from_predictors(model, predictors, notes)
    }

    /// Like [`Decoder::new`], but every part decodes through the leading eigenvectors of its
    /// `K_Y` (`Predictor::with_kernel_basis`), with a certified error of at most `max_abs`
    /// (model units, metres: 1e-4 = 0.1 mm) per coordinate at the training latent points; the
    /// part bases are built in parallel. Returns the decoder and, per part, (rank, bound).
    pub fn with_pose_basis(
        model: &'a VariationModel,
        max_abs: f64,
        notes: &mut Vec<String>,
    ) -> Result<(Self, Vec<(usize, f64)>)> {
        use rayon::prelude::*;
        // The torso's displacement and gravity columns are integrated over the motion
        // ([`place`]): they are decoded exactly (10 columns, same kernel) so that basis errors
        // do not accumulate into the world placement, and the torso's basis covers its vertex
        // columns only (the scaled extra columns would dominate the bound's max_j ‖a_j‖).
        let columns = |g: &gpdm::Gpdm, from: usize, n: usize| {
            let mut c = g.clone();
            c.y = g.y.columns(from, n).into_owned();
            c.y_mean = g.y_mean.rows(from, n).into_owned();
            c
        };
        let torso = &model.parts[0].gpdm;
        let split = torso.y.ncols() > TORSO_EXTRA;
        let d0 = torso.y.ncols() - if split { TORSO_EXTRA } else { 0 };
        let torso_vertices = split.then(|| columns(torso, 0, d0));
        let built = model
            .parts
            .par_iter()
            .enumerate()
            .map(|(k, p)| {
                let g = match (&torso_vertices, k) {
                    (Some(t), 0) => t,
                    _ => &p.gpdm,
                };
                Predictor::with_kernel_basis(g, max_abs)
                    .map_err(|e| Error::invalid(format!("part '{}': {e}", p.part.name)))
            })
            .collect::<Result<Vec<_>>>()?;
        let info = built.iter().map(|b| (b.1, b.2)).collect();
        let predictors = built.into_iter().map(|b| b.0).collect();
        let mut dec = Self::from_predictors(model, predictors, notes)?;
        if split {
            let tail = columns(torso, d0, TORSO_EXTRA);
            dec.torso_extra =
                Some(Predictor::new(&tail).map_err(|e| Error::invalid(format!("torso: {e}")))?);
        }
        Ok((dec, info))
    }

    fn from_predictors(
        model: &'a VariationModel,
        predictors: Vec<Predictor>,
        notes: &mut Vec<String>,
    ) -> Result<Self> {
        for (p, pr) in model.parts.iter().zip(&predictors) {
            notes.extend(
                pr.notes
                    .iter()
                    .map(|n| format!("part '{}': {n}", p.part.name)),
            );
        }
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
            torso_extra: None,
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

/// Per-thread buffers of [`Decoder::decode_average_into`].
#[derive(Default)]
pub struct DecodeScratch {
    /// Part poses, D_k × T column-major (one frame per column).
    parts: Vec<Vec<f64>>,
    /// Per-vertex sums (3 per vertex) of the placed parts.
    sum: Vec<f64>,
    src: Vec<Vector3<f64>>,
    dst: Vec<Vector3<f64>>,
}

impl Decoder<'_> {
    /// The fast path of [`Decoder::decode`] with [`Assembly::Average`] and mean poses (eq. 12),
    /// for bulk decoding: part poses by one GEMM per part with every frame a contiguous column
    /// (`Predictor::pose_mean_cols`), then per frame one pass placing and averaging the parts
    /// and accumulating the body's moments against the template, and one pass applying the
    /// composed template alignment and world placement. Same result as `decode` up to
    /// rounding; no allocation per frame. Writes frame `t`'s body into
    /// `out[t·V..(t+1)·V]` (V template vertices).
    pub fn decode_average_into(
        &self,
        latents: &[DMatrix<f64>],
        start: &RigidMotion,
        scratch: &mut DecodeScratch,
        out: &mut [Vector3<f64>],
    ) -> Result<()> {
        let k_parts = self.predictors.len();
        if latents.len() != k_parts {
            return Err(Error::invalid(format!(
                "{} latent trajectories for {k_parts} parts",
                latents.len()
            )));
        }
        let t_len = latents[0].nrows();
        let nv = self.model.template.len();
        if latents.iter().any(|l| l.nrows() != t_len) || out.len() != t_len * nv {
            return Err(Error::invalid(
                "latent trajectories of different lengths or output of the wrong size",
            ));
        }
        scratch.parts.resize_with(k_parts, Vec::new);
        for (k, (pr, x)) in self.predictors.iter().zip(latents).enumerate() {
            let m = &mut scratch.parts[k];
            m.resize(pr.pose_dim() * t_len, 0.0);
            pr.pose_mean_cols(x, m)
                .map_err(|e| Error::invalid(format!("part {k}: {e}")))?;
        }
        let dims: Vec<usize> = self.predictors.iter().map(|p| p.pose_dim()).collect();
        // Displacement and gravity values (unscaled): the torso's last rows, or the exact
        // predictor of those columns when the torso decodes through a basis.
        let mut tail = Vec::new();
        let (src, stride, base) = match &self.torso_extra {
            Some(pr) => {
                tail.resize(TORSO_EXTRA * t_len, 0.0);
                pr.pose_mean_cols(&latents[0], &mut tail)
                    .map_err(|e| Error::invalid(format!("part 0: {e}")))?;
                (&tail[..], TORSO_EXTRA, 0)
            }
            None => (&scratch.parts[0][..], dims[0], dims[0] - TORSO_EXTRA),
        };
        let extra =
            |t: usize, k: usize| src[t * stride + base + k] / extra_scale(k, self.model.scale);
        let disp: Vec<[f64; 6]> = (0..t_len)
            .map(|t| std::array::from_fn(|k| extra(t, k)))
            .collect();
        let grav: Vec<[f64; 4]> = (0..t_len)
            .map(|t| std::array::from_fn(|k| extra(t, 6 + k)))
            .collect();
        let world = world_poses(t_len, &disp, &grav, &self.model.up, start);
        let tpl = &self.model.template;
        let cd = tpl.iter().sum::<Vector3<f64>>() / nv.max(1) as f64;
        scratch.sum.resize(3 * nv, 0.0);
        let mut placed: Vec<RigidMotion> = Vec::with_capacity(k_parts);
        for t in 0..t_len {
            let parts = &scratch.parts;
            let col = |k: usize| &parts[k][t * dims[k]..(t + 1) * dims[k]];
            let vtx = |c: &[f64], i: usize| Vector3::new(c[3 * i], c[3 * i + 1], c[3 * i + 2]);
            // Children aligned to their placed parents on the overlap bands.
            placed.clear();
            for (k, p) in self.model.parts.iter().enumerate() {
                if k == 0 {
                    placed.push(RigidMotion::identity());
                    continue;
                }
                let q = p.part.parent.expect("checked in new");
                let (ck, cq) = (col(k), col(q));
                scratch.src.clear();
                scratch.dst.clear();
                for &(i, j) in &self.bands[k] {
                    scratch.src.push(vtx(ck, i));
                    scratch.dst.push(placed[q].apply(&vtx(cq, j)));
                }
                placed.push(procrustes(&scratch.src, &scratch.dst, None));
            }
            // Sum of placed parts per vertex.
            let sum = &mut scratch.sum;
            sum.fill(0.0);
            for (k, p) in self.model.parts.iter().enumerate() {
                let c = col(k);
                let r = placed[k].rotation.matrix();
                let tr = placed[k].translation;
                for (i, &v) in p.part.vertices.iter().enumerate() {
                    let (x, y, z) = (c[3 * i], c[3 * i + 1], c[3 * i + 2]);
                    let s = &mut sum[3 * v as usize..3 * v as usize + 3];
                    for a in 0..3 {
                        s[a] += r[(a, 0)] * x + r[(a, 1)] * y + r[(a, 2)] * z + tr[a];
                    }
                }
            }
            // Average, and the moments of the template alignment (procrustes to the template:
            // H = Σ b_v (τ_v − τ̄)ᵀ since Σ (τ_v − τ̄) = 0).
            let mut cs = Vector3::zeros();
            let mut h = nalgebra::Matrix3::zeros();
            for (v, (s, &cov)) in sum.chunks_exact_mut(3).zip(&self.coverage).enumerate() {
                let inv = 1.0 / cov as f64;
                let b = Vector3::new(s[0] * inv, s[1] * inv, s[2] * inv);
                s.copy_from_slice(b.as_slice());
                cs += b;
                h += b * (tpl[v] - cd).transpose();
            }
            cs /= nv as f64;
            let align = rigid_from_moments(&cs, &cd, &h);
            let g = world[t].compose(&align);
            let r = g.rotation.matrix();
            for (o, s) in out[t * nv..(t + 1) * nv]
                .iter_mut()
                .zip(sum.chunks_exact(3))
            {
                *o = r * Vector3::new(s[0], s[1], s[2]) + g.translation;
            }
        }
        Ok(())
    }

    // NOTE(next): issue 6's 1 s budget needs this fused per vertex block: per-frame transforms
    // first (band rows of the part GEMMs, and the template moments in coefficient space, which
    // are linear in the basis coefficients), then GEMM + transform + average per block of
    // vertex rows while it is in L2, instead of materialising D × T per part (33 MB per
    // variation). See /work/notes/h17-results.md.

    /// [`Decoder::decode_average_into`] for many variations in parallel (rayon, one variation
    /// per task, buffers reused within a thread); `consume(k, frames)` receives variation `k`'s
    /// bodies, frame-major (`T · V` vertices), from whichever thread decoded it.
    pub fn decode_average_many<F>(
        &self,
        variations: &[Vec<DMatrix<f64>>],
        start: &RigidMotion,
        consume: F,
    ) -> Result<()>
    where
        F: Fn(usize, &[Vector3<f64>]) + Sync,
    {
        use rayon::prelude::*;
        let nv = self.model.template.len();
        variations.par_iter().enumerate().try_for_each_init(
            || (DecodeScratch::default(), Vec::new()),
            |(scratch, out), (k, latents)| {
                let t = latents.first().map_or(0, |l| l.nrows());
                out.resize(t * nv, Vector3::zeros());
                self.decode_average_into(latents, start, scratch, out)?;
                consume(k, out);
                Ok(())
            },
        )
    }
}

/// World poses `P_t` of [`place`] (module doc there) for `n` frames.
pub fn world_poses(
    n: usize,
    displacements: &[[f64; 6]],
    gravity: &[[f64; 4]],
    up: &Vector3<f64>,
    start: &RigidMotion,
) -> Vec<RigidMotion> {
    let mut poses = Vec::with_capacity(n);
    let mut cur = *start;
    for t in 0..n {
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
    poses
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
    let poses = world_poses(body.len(), displacements, gravity, up, start);
    body.iter()
        .zip(&poses)
        .map(|(f, p)| p.apply_all(f))
        .collect()
}
