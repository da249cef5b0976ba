//! Pose reconstruction of sampled latent trajectories (3DV §6, eqs. 11-13) and assembly of the
//! body: every part's pose from its GP (mean, 3DV eq. 12, or a draw from eq. 11), the parts merged
//! into one template mesh, the result rigidly aligned to the template on the root part's core
//! (`group::root_core`, the normalisation `group::build` applied to the training frames), then
//! placed in the world by integrating the predicted displacements of the root point
//! (`group::root_displacements`) from the source sequence's starting pose.
//!
//! Merging: [`Assembly::Stitch`] is the paper's (child aligned to parent on the overlap band,
//! optimal boundary loop, Poisson merge: `surface::stitch::Stitcher`, one sparse factorisation
//! per frame). [`Assembly::Feather`] (the default) and [`Assembly::Average`] align each child
//! to its parent on the band the same way, then take a weighted mean of the vertices shared by
//! several parts: weights ramping smoothly across the band (`surface::feather`), or uniform
//! (as `capture::assemble`, which leaves a step where the band meets a single part). Both are
//! about 100 times cheaper per frame than stitching and fuse with the bulk decoder
//! ([`FusedDecoder`]).

use gpdm::predict::Predictor;
use std::sync::Mutex;

use surface::poisson::Factorisation;
use surface::stitch::Stitcher;
use capture::align::fit_on;
use mesh_core::rigid::{procrustes, rigid_from_moments, RigidMotion};
use mesh_core::{Error, Result};
use nalgebra::{DMatrix, Vector3, Vector6};
use rand::Rng;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::group::{root_core, PartDef};
use crate::part_data::{extra_scale, split_torso, unflatten, TORSO_EXTRA};
use crate::train::VariationModel;

/// How parts are merged into one mesh.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum Assembly {
    /// Optimal-boundary Poisson stitching per frame (3DV §6, CVPR §6.2).
    Stitch,
    /// Children aligned on their bands, then every shared vertex the mean of its parts.
    Average,
    /// As `Average`, with each band's weights ramping smoothly from the parent to the child
    /// ([`surface::feather`]). The default: the seams of `Stitch` at a quarter of its decoding
    /// time (docs/DEVIATIONS.md).
    #[default]
    Feather,
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
    /// Template vertices the assembled body is aligned to the template on (`group::root_core`;
    /// empty: every vertex), and per template vertex whether it is one of them.
    core: Vec<u32>,
    in_core: Vec<bool>,
    /// The template's root point, whose motion the displacements are (`Group::root_point`).
    root: Vector3<f64>,
    /// Per part and vertex of the part: its weight in the merged vertex, for `Average` (1 /
    /// coverage) and for `Feather` ([`surface::feather::band_weights`]).
    uniform: Vec<Vec<f64>>,
    feathered: Vec<Vec<f64>>,
    /// Stitchers (each with its symbolic factorisation) lent to the threads that stitch
    /// frames, and returned after.
    stitchers: Mutex<Vec<Stitcher>>,
}

/// A stitcher borrowed from [`Decoder`]'s pool; goes back to it when dropped.
struct Lease<'d> {
    pool: &'d Mutex<Vec<Stitcher>>,
    stitcher: Option<Stitcher>,
}

impl Drop for Lease<'_> {
    fn drop(&mut self) {
        if let Some(s) = self.stitcher.take() {
            self.pool.lock().unwrap_or_else(|e| e.into_inner()).push(s);
        }
    }
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
        let uniform = parts
            .iter()
            .map(|p| p.vertices.iter().map(|&v| 1.0 / coverage[v as usize] as f64).collect())
            .collect();
        let layout: Vec<surface::stitch::Part> = parts
            .iter()
            .map(|p| surface::stitch::Part { vertices: p.vertices.clone(), parent: p.parent })
            .collect();
        let feathered = surface::feather::band_weights(&model.template, &model.faces, &layout);
        let defs: Vec<PartDef> = parts.iter().map(|&p| p.clone()).collect();
        let core = root_core(&defs, n);
        let mut in_core = vec![core.is_empty(); n];
        core.iter().for_each(|&v| in_core[v as usize] = true);
        Ok(Decoder {
            model,
            predictors,
            torso_extra: None,
            bands,
            coverage,
            root: capture::align::root_point(&model.template, &core),
            core,
            in_core,
            uniform,
            feathered,
            stitchers: Mutex::new(Vec::new()),
        })
    }

    /// Part poses for the latent trajectories `latents[k]` (T × d each): the mean (3DV eq. 12) or,
    /// with `rng`, a draw from 3DV eq. 11.
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

    /// Per part and vertex of the part, its weight in the merged vertex under `how` (an
    /// averaging assembly; `Stitch` gets the uniform weights).
    fn merge_weights(&self, how: Assembly) -> &[Vec<f64>] {
        match how {
            Assembly::Feather => &self.feathered,
            Assembly::Average | Assembly::Stitch => &self.uniform,
        }
    }

    /// Aligns children to parents on the bands and merges shared vertices by the weights of
    /// `how` (one frame).
    pub fn assemble_weighted(&self, parts: &[&[Vector3<f64>]], how: Assembly) -> Vec<Vector3<f64>> {
        let weights = self.merge_weights(how);
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
            for ((x, &v), &w) in pts.iter().zip(&p.part.vertices).zip(&weights[k]) {
                sum[v as usize] += w * x;
            }
            placed.push(pts);
        }
        sum
    }

    /// Merged body frames (template-aligned) of decoded parts. Stitching factorises each
    /// frame's Poisson system supernodally ([`Decoder::assemble_with`]).
    pub fn assemble(
        &self,
        decoded: &DecodedParts,
        how: Assembly,
    ) -> Result<Vec<Vec<Vector3<f64>>>> {
        self.assemble_with(decoded, how, Factorisation::Supernodal)
    }

    /// [`Decoder::assemble`] with a chosen factorisation of the stitch systems (the results
    /// agree to rounding).
    pub fn assemble_with(
        &self,
        decoded: &DecodedParts,
        how: Assembly,
        factorisation: Factorisation,
    ) -> Result<Vec<Vec<Vector3<f64>>>> {
        let n_frames = decoded.displacements.len();
        if how != Assembly::Stitch || self.model.parts.len() < 2 {
            // A single part needs no merging.
            return Ok((0..n_frames)
                .map(|t| {
                    let parts: Vec<&[Vector3<f64>]> =
                        decoded.parts.iter().map(|p| p[t].as_slice()).collect();
                    let body = self.assemble_weighted(&parts, how);
                    fit_on(&body, &self.model.template, &self.core).apply_all(&body)
                })
                .collect());
        }
        // Frames are stitched independently (each refactorises its own system), in parallel,
        // with stitchers lent from the pool.
        (0..n_frames)
            .into_par_iter()
            .map_init(
                || self.lend_stitcher(factorisation),
                |lease, t| {
                    let s = match lease {
                        Ok(l) => l.stitcher.as_mut().expect("held until dropped"),
                        Err(e) => return Err(Error::invalid(e.to_string())),
                    };
                    let parts: Vec<Vec<Vector3<f64>>> =
                        decoded.parts.iter().map(|p| p[t].clone()).collect();
                    let body = s.stitch(&parts)?.vertices;
                    Ok(fit_on(&body, &self.model.template, &self.core).apply_all(&body))
                },
            )
            .collect()
    }

    /// A stitcher of this model's parts with `factorisation`, from the pool or new.
    fn lend_stitcher(&self, factorisation: Factorisation) -> Result<Lease<'_>> {
        let pooled = {
            let mut pool = self.stitchers.lock().unwrap_or_else(|e| e.into_inner());
            let i = pool.iter().position(|s| s.factorisation() == factorisation);
            i.map(|i| pool.swap_remove(i))
        };
        let stitcher = match pooled {
            Some(s) => s,
            None => {
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
                Stitcher::new(layout).with_factorisation(factorisation)
            }
        };
        Ok(Lease {
            pool: &self.stitchers,
            stitcher: Some(stitcher),
        })
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
            &self.root,
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
    /// The fast path of [`Decoder::decode`] with [`Assembly::Average`] and mean poses (3DV eq. 12),
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
        let t_len = variation_frames(latents, k_parts)?;
        let nv = self.model.template.len();
        if out.len() != t_len * nv {
            return Err(Error::invalid(format!(
                "output of {} vertices for {t_len} frames of {nv}",
                out.len()
            )));
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
        let world = world_poses(t_len, &disp, &grav, &self.model.up, start, &self.root);
        let tpl = &self.model.template;
        let (cd, n_core) = self.core_centroid();
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
            // Average, and the moments of the template alignment on the core (procrustes to
            // the template: H = Σ b_v (τ_v − τ̄)ᵀ over the core since Σ (τ_v − τ̄) = 0 there).
            let mut cs = Vector3::zeros();
            let mut h = nalgebra::Matrix3::zeros();
            for (v, (s, &cov)) in sum.chunks_exact_mut(3).zip(&self.coverage).enumerate() {
                let inv = 1.0 / cov as f64;
                let b = Vector3::new(s[0] * inv, s[1] * inv, s[2] * inv);
                s.copy_from_slice(b.as_slice());
                if self.in_core[v] {
                    cs += b;
                    h += b * (tpl[v] - cd).transpose();
                }
            }
            cs /= n_core as f64;
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

    /// Centroid of the template's core vertices (the root point) and their count.
    fn core_centroid(&self) -> (Vector3<f64>, usize) {
        (self.root, self.in_core.iter().filter(|&&c| c).count().max(1))
    }

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

/// Vertices per block of the fused decoding: the block's basis rows (3·128 × (R+1)) and its
/// poses for 100 frames (3·128 × 100) take about 0.65 MB together, within one core's L2
/// (2 MB here; 96-192 measured within noise of each other on the demo body, 256 and 512
/// 5-15 % slower).
pub const FUSED_BLOCK_VERTICES: usize = 128;

/// One part's 3DV eq. 12 as an affine map of coefficients: the poses of latent points `x_*` are
/// `[B | ȳ] · [c(x_*); 1]` (`Predictor::pose_coefficients` and `Predictor::pose_basis`: exact,
/// `c = k_Y(X, x_*)` and `B = (K_Y⁻¹ Y)ᵀ`; kernel basis of rank R, `c = Q_Rᵀ k_Y(X, x_*)` and
/// `B = (K_Y⁻¹ Y)ᵀ Q_R`). The fused decoder multiplies `[B | ȳ]` one block of vertex rows at a time.
struct PartMap {
    /// `[B | ȳ]`, D × (R+1), column-major (the torso without its displacement rows).
    basis: faer::Mat<f64>,
}

/// `out = a · b`, sequential.
fn gemm(out: faer::MatMut<'_, f64>, a: faer::MatRef<'_, f64>, b: faer::MatRef<'_, f64>) {
    faer::linalg::matmul::matmul(out, faer::Accum::Replace, a, b, 1.0, faer::Par::Seq);
}

/// The rows of `[B | ȳ]` of the given part vertices (3 per vertex).
fn vertex_rows(basis: &faer::Mat<f64>, verts: impl Iterator<Item = usize>) -> faer::Mat<f64> {
    let idx: Vec<usize> = verts.flat_map(|i| [3 * i, 3 * i + 1, 3 * i + 2]).collect();
    faer::Mat::from_fn(idx.len(), basis.ncols(), |r, c| basis[(idx[r], c)])
}

/// Fused, vertex-blocked form of [`Decoder::decode_average_into`] (same result up to
/// rounding; the `D × T` part poses never exist). Everything the per-vertex pass needs is
/// first computed per frame from the coefficients `[c(x_t); 1]` alone:
/// - the child-to-parent band alignments (Procrustes on the band rows only: `3·|band|` rows of
///   `[B | ȳ]` per child and parent);
/// - the body's alignment to the template on the core, from moments that are linear in the
///   coefficients: with `b_v = Σ_{k∋v} w_v (R_k p_{k,v} + t_k)` (`w_v` the merge weight, 0 off
///   the core) and `e_v = τ_v − τ̄` (`τ̄` the core's centroid),
///   `Σ_v b_v = Σ_k R_k S_k c + t_k Σ w` and `H = Σ_v b_v e_vᵀ = Σ_k R_k M_k c + t_k (Σ w e)ᵀ`,
///   where `S_k = Σ_v w_v [B | ȳ]_v` (3 rows) and `M_k = Σ_v w_v e_v[b] [B | ȳ]_{v,a}` (9 rows)
///   are precomputed;
/// - the composed world ∘ template-alignment ∘ band transform `F_{k,t}` of every part.
///
/// Then, per block of [`FUSED_BLOCK_VERTICES`] part vertices, one GEMM of the block's basis
/// rows with all frames' coefficients (in L2), and `w_v F_{k,t}(p)` written (first part of a
/// vertex) or added (later parts) straight into the output. Each part's vertex rows are
/// stored reordered: vertices in no other part first (written without weight or branch), and
/// within a block all x rows, then all y, then all z, so that the transform loop runs over
/// contiguous arrays.
pub struct FusedDecoder<'d, 'a> {
    dec: &'d Decoder<'a>,
    maps: Vec<PartMap>,
    /// Per child part: band rows of `[B | ȳ]` of the child, and of its parent.
    band_child: Vec<faer::Mat<f64>>,
    band_parent: Vec<faer::Mat<f64>>,
    /// Per part: the 12 moment rows (`S_k`, then `M_k` row-major), `Σ w` and `Σ w e`.
    moments: Vec<faer::Mat<f64>>,
    wsum: Vec<f64>,
    esum: Vec<Vector3<f64>>,
    /// Per part, in the reordered vertex order (type doc): template vertex, averaging weight,
    /// whether this part writes it first, and the count of vertices in this part only.
    verts: Vec<Vec<u32>>,
    weight: Vec<Vec<f64>>,
    first: Vec<Vec<bool>>,
    singles: Vec<usize>,
    /// Per part: the reordered vertex rows of `[B | ȳ]`, blocked (type doc).
    vbasis: Vec<faer::Mat<f64>>,
    /// Per part: reordered position → local vertex index.
    order: Vec<Vec<usize>>,
    /// Centroid of the template's core and its vertex count.
    cd: Vector3<f64>,
    n_core: usize,
    block: usize,
}

/// Per-thread buffer of [`FusedDecoder::decode_average_into`].
#[derive(Default)]
pub struct FusedScratch {
    block: Vec<f64>,
}

impl<'a> Decoder<'a> {
    /// The fused bulk decoder of this decoder's predictors (exact, or kernel bases from
    /// [`Decoder::with_pose_basis`]), merging parts by `how` (`Average` or `Feather`).
    pub fn fused(&self, how: Assembly) -> Result<FusedDecoder<'_, 'a>> {
        if how == Assembly::Stitch {
            return Err(Error::invalid("the fused decoder merges parts by a weighted average, not by stitching"));
        }
        let part_weights = self.merge_weights(how);
        let model = self.model;
        let nv = model.template.len();
        let maps: Vec<PartMap> = model
            .parts
            .par_iter()
            .zip(&self.predictors)
            .enumerate()
            .map(|(k, (p, pr))| {
                let basis = pr.pose_basis();
                let rows = if k == 0 && self.torso_extra.is_some() {
                    p.gpdm.y.ncols() - TORSO_EXTRA
                } else {
                    basis.nrows()
                };
                PartMap {
                    basis: basis.as_ref().subrows(0, rows).to_owned(),
                }
            })
            .collect();
        for (m, p) in maps.iter().zip(&model.parts) {
            if m.basis.nrows() < 3 * p.part.vertices.len() {
                return Err(Error::invalid(format!(
                    "part '{}': {} pose values for {} vertices",
                    p.part.name,
                    m.basis.nrows(),
                    p.part.vertices.len()
                )));
            }
        }
        let tpl = &model.template;
        let (cd, n_core) = self.core_centroid();
        let mut seen = vec![false; nv];
        let (mut weight, mut first, mut order) = (Vec::new(), Vec::new(), Vec::new());
        let (mut vlist, mut singles) = (Vec::new(), Vec::new());
        let (mut moments, mut wsum, mut esum) = (Vec::new(), Vec::new(), Vec::new());
        let (mut band_child, mut band_parent) = (Vec::new(), Vec::new());
        // The band-moment sums of every part (module doc), in parallel.
        let sums: Vec<(faer::Mat<f64>, f64, Vector3<f64>)> = model
            .parts
            .par_iter()
            .zip(&maps)
            .zip(part_weights)
            .map(|((p, m), pw)| {
                let b = &m.basis;
                let mut mom = faer::Mat::<f64>::zeros(12, b.ncols());
                let (mut ws, mut es) = (0.0, Vector3::zeros());
                for (i, &v) in p.part.vertices.iter().enumerate() {
                    if !self.in_core[v as usize] {
                        continue;
                    }
                    let wi = pw[i];
                    let e = tpl[v as usize] - cd;
                    ws += wi;
                    es += wi * e;
                    for c in 0..b.ncols() {
                        for a in 0..3 {
                            let x = wi * b[(3 * i + a, c)];
                            mom[(a, c)] += x;
                            for (bb, eb) in e.iter().enumerate() {
                                mom[(3 + 3 * a + bb, c)] += x * eb;
                            }
                        }
                    }
                }
                (mom, ws, es)
            })
            .collect();
        for (mom, ws, es) in sums {
            moments.push(mom);
            wsum.push(ws);
            esum.push(es);
        }
        for (k, p) in model.parts.iter().enumerate() {
            let verts = &p.part.vertices;
            let w = &part_weights[k];
            first.push(
                verts
                    .iter()
                    .map(|&v| !std::mem::replace(&mut seen[v as usize], true))
                    .collect::<Vec<bool>>(),
            );
            let b = &maps[k].basis;
            // Vertices in this part only first (stable), then the shared ones.
            let single = |i: usize| self.coverage[verts[i] as usize] == 1;
            let mut o: Vec<usize> = (0..verts.len()).filter(|&i| single(i)).collect();
            singles.push(o.len());
            o.extend((0..verts.len()).filter(|&i| !single(i)));
            let fk = first.last_mut().expect("pushed above");
            *fk = o.iter().map(|&i| fk[i]).collect();
            weight.push(o.iter().map(|&i| w[i]).collect());
            vlist.push(o.iter().map(|&i| verts[i]).collect());
            order.push(o);
            if k == 0 {
                band_child.push(faer::Mat::zeros(0, b.ncols()));
                band_parent.push(faer::Mat::zeros(0, b.ncols()));
            } else {
                let q = p.part.parent.expect("checked in new");
                band_child.push(vertex_rows(b, self.bands[k].iter().map(|&(i, _)| i)));
                band_parent.push(vertex_rows(
                    &maps[q].basis,
                    self.bands[k].iter().map(|&(_, j)| j),
                ));
            }
        }
        Ok(FusedDecoder {
            dec: self,
            maps,
            band_child,
            band_parent,
            moments,
            wsum,
            esum,
            verts: vlist,
            weight,
            first,
            singles,
            vbasis: Vec::new(),
            order,
            cd,
            n_core,
            block: 0,
        }
        .with_block_vertices(FUSED_BLOCK_VERTICES))
    }
}

impl FusedDecoder<'_, '_> {
    /// Sets the number of vertices per block (at least 1; the default suits a 2 MB L2).
    pub fn with_block_vertices(mut self, n: usize) -> Self {
        self.block = n.max(1);
        self.vbasis = self
            .maps
            .par_iter()
            .zip(&self.order)
            .map(|(m, o)| {
                let b = &m.basis;
                let mut rows = Vec::with_capacity(3 * o.len());
                for blk in o.chunks(self.block) {
                    for a in 0..3 {
                        rows.extend(blk.iter().map(|&i| 3 * i + a));
                    }
                }
                faer::Mat::from_fn(rows.len(), b.ncols(), |r, c| b[(rows[r], c)])
            })
            .collect();
        self
    }

    /// [`Decoder::decode_average_into`], fused (type doc): frame `t`'s body into
    /// `out[t·V..(t+1)·V]`.
    pub fn decode_average_into(
        &self,
        latents: &[DMatrix<f64>],
        start: &RigidMotion,
        scratch: &mut FusedScratch,
        out: &mut [Vector3<f64>],
    ) -> Result<()> {
        self.decode_batch(&[latents], start, scratch, &mut [out])
    }

    /// Several variations at once, all of the same length: their coefficients side by side,
    /// so that each block's basis rows are read once for the whole batch (one GEMM of
    /// `batch · T` columns). `outs[b]` receives variation `b` as in
    /// [`FusedDecoder::decode_average_into`].
    pub fn decode_batch(
        &self,
        variations: &[&[DMatrix<f64>]],
        start: &RigidMotion,
        scratch: &mut FusedScratch,
        outs: &mut [&mut [Vector3<f64>]],
    ) -> Result<()> {
        let k_parts = self.maps.len();
        let nv = self.dec.model.template.len();
        let t_len = variations
            .first()
            .and_then(|v| v.first())
            .map_or(0, |l| l.nrows());
        if variations.len() != outs.len()
            || outs.iter().any(|o| o.len() != t_len * nv)
            || variations
                .iter()
                .any(|v| v.iter().any(|l| l.nrows() != t_len))
        {
            return Err(Error::invalid(
                "latent trajectories of different lengths or output of the wrong size",
            ));
        }
        let mut coef: Vec<faer::Mat<f64>> = self
            .maps
            .iter()
            .map(|m| faer::Mat::zeros(m.basis.ncols(), variations.len() * t_len))
            .collect();
        let mut frames: Vec<Vec<RigidMotion>> = vec![Vec::new(); k_parts];
        for (b, latents) in variations.iter().enumerate() {
            let (c, f) = self.frame_transforms(latents, start)?;
            for k in 0..k_parts {
                coef[k]
                    .as_mut()
                    .subcols_mut(b * t_len, t_len)
                    .copy_from(c[k].as_ref());
                frames[k].extend_from_slice(&f[k]);
            }
        }
        self.write_bodies(&coef, &frames, t_len, scratch, outs);
        Ok(())
    }

    /// Per part, the coefficients `[c(x_t); 1]` ((R+1) × T) and the composed transforms
    /// `F_{k,t}` of one variation (type doc).
    fn frame_transforms(
        &self,
        latents: &[DMatrix<f64>],
        start: &RigidMotion,
    ) -> Result<(Vec<faer::Mat<f64>>, Vec<Vec<RigidMotion>>)> {
        let dec = self.dec;
        let k_parts = self.maps.len();
        let t_len = variation_frames(latents, k_parts)?;
        let coef = dec
            .predictors
            .iter()
            .zip(latents)
            .enumerate()
            .map(|(k, (pr, x))| {
                pr.pose_coefficients(x)
                    .map_err(|e| Error::invalid(format!("part {k}: {e}")))
            })
            .collect::<Result<Vec<_>>>()?;
        // Displacement and gravity values (unscaled), TORSO_EXTRA × T.
        let mut tail = faer::Mat::<f64>::zeros(TORSO_EXTRA, t_len);
        match &dec.torso_extra {
            Some(pr) => {
                let mut buf = vec![0.0; TORSO_EXTRA * t_len];
                pr.pose_mean_cols(&latents[0], &mut buf)
                    .map_err(|e| Error::invalid(format!("part 0: {e}")))?;
                tail = faer::Mat::from_fn(TORSO_EXTRA, t_len, |i, t| buf[t * TORSO_EXTRA + i]);
            }
            None => {
                let b = &self.maps[0].basis;
                if b.nrows() < TORSO_EXTRA {
                    return Err(Error::invalid("torso has no displacement columns"));
                }
                let rows = b.as_ref().subrows(b.nrows() - TORSO_EXTRA, TORSO_EXTRA);
                gemm(tail.as_mut(), rows, coef[0].as_ref());
            }
        }
        let extra = |t: usize, k: usize| tail[(k, t)] / extra_scale(k, dec.model.scale);
        let disp: Vec<[f64; 6]> = (0..t_len)
            .map(|t| std::array::from_fn(|k| extra(t, k)))
            .collect();
        let grav: Vec<[f64; 4]> = (0..t_len)
            .map(|t| std::array::from_fn(|k| extra(t, 6 + k)))
            .collect();
        let world = world_poses(t_len, &disp, &grav, &dec.model.up, start, &dec.root);
        // Band rows and moments of every frame.
        let small = |m: &faer::Mat<f64>, c: &faer::Mat<f64>| {
            let mut o = faer::Mat::<f64>::zeros(m.nrows(), c.ncols());
            gemm(o.as_mut(), m.as_ref(), c.as_ref());
            o
        };
        let parent = |k: usize| dec.model.parts[k].part.parent.expect("checked in new");
        let bc: Vec<faer::Mat<f64>> = (0..k_parts)
            .map(|k| small(&self.band_child[k], &coef[k]))
            .collect();
        let bp: Vec<faer::Mat<f64>> = (0..k_parts)
            .map(|k| {
                let q = if k == 0 { 0 } else { parent(k) };
                small(&self.band_parent[k], &coef[q])
            })
            .collect();
        let mom: Vec<faer::Mat<f64>> = (0..k_parts)
            .map(|k| small(&self.moments[k], &coef[k]))
            .collect();
        // F_{k,t} = world_t ∘ align_t ∘ band_{k,t}, stored [k][t].
        let mut frames: Vec<Vec<RigidMotion>> = vec![Vec::with_capacity(t_len); k_parts];
        let mut placed: Vec<RigidMotion> = Vec::with_capacity(k_parts);
        let (mut src, mut dst) = (Vec::new(), Vec::new());
        let vtx = |m: &faer::Mat<f64>, i: usize, t: usize| {
            Vector3::new(m[(3 * i, t)], m[(3 * i + 1, t)], m[(3 * i + 2, t)])
        };
        for t in 0..t_len {
            placed.clear();
            placed.push(RigidMotion::identity());
            for k in 1..k_parts {
                let q = parent(k);
                src.clear();
                dst.clear();
                for i in 0..self.band_child[k].nrows() / 3 {
                    src.push(vtx(&bc[k], i, t));
                    dst.push(placed[q].apply(&vtx(&bp[k], i, t)));
                }
                placed.push(procrustes(&src, &dst, None));
            }
            let mut cs = Vector3::zeros();
            let mut h = nalgebra::Matrix3::zeros();
            for (k, pk) in placed.iter().enumerate() {
                let m = &mom[k];
                let s = Vector3::new(m[(0, t)], m[(1, t)], m[(2, t)]);
                let mk = nalgebra::Matrix3::from_fn(|a, b| m[(3 + 3 * a + b, t)]);
                cs += pk.rotation * s + pk.translation * self.wsum[k];
                h += pk.rotation.matrix() * mk + pk.translation * self.esum[k].transpose();
            }
            cs /= self.n_core as f64;
            let g = world[t].compose(&rigid_from_moments(&cs, &self.cd, &h));
            for (f, pk) in frames.iter_mut().zip(&placed) {
                f.push(g.compose(pk));
            }
        }
        Ok((coef, frames))
    }

    /// The per-block pass (type doc): `coef[k]` and `frames[k]` hold the columns of every
    /// variation of `outs`, `t_len` each.
    fn write_bodies(
        &self,
        coef: &[faer::Mat<f64>],
        frames: &[Vec<RigidMotion>],
        t_len: usize,
        scratch: &mut FusedScratch,
        outs: &mut [&mut [Vector3<f64>]],
    ) {
        let nv = self.dec.model.template.len();
        let cols = t_len * outs.len();
        for k in 0..self.maps.len() {
            let verts = &self.verts[k];
            let basis = self.vbasis[k].as_ref();
            for i0 in (0..verts.len()).step_by(self.block) {
                let n = self.block.min(verts.len() - i0);
                scratch.block.resize(3 * n * cols, 0.0);
                let blk =
                    faer::MatMut::from_column_major_slice_mut(&mut scratch.block, 3 * n, cols);
                gemm(blk, basis.subrows(3 * i0, 3 * n), coef[k].as_ref());
                let (vs, ws, fs) = (
                    &verts[i0..i0 + n],
                    &self.weight[k][i0..i0 + n],
                    &self.first[k][i0..i0 + n],
                );
                let ns = self.singles[k].saturating_sub(i0).min(n);
                for (j, col) in scratch.block.chunks_exact(3 * n).enumerate() {
                    let f = &frames[k][j];
                    let r = f.rotation.matrix();
                    let t = j % t_len;
                    let o = &mut outs[j / t_len][t * nv..(t + 1) * nv];
                    let (xs, rest) = col.split_at(n);
                    let (ys, zs) = rest.split_at(n);
                    place_singles(o, &vs[..ns], [&xs[..ns], &ys[..ns], &zs[..ns]], f);
                    for i in ns..n {
                        let p = Vector3::new(xs[i], ys[i], zs[i]);
                        let y = ws[i] * (r * p + f.translation);
                        if fs[i] {
                            o[vs[i] as usize] = y;
                        } else {
                            o[vs[i] as usize] += y;
                        }
                    }
                }
            }
        }
    }

    /// [`Decoder::decode_average_many`] through the fused path: rayon tasks of `batch`
    /// consecutive variations ([`FusedDecoder::decode_batch`]; variations of different
    /// lengths go one by one), buffers reused within a thread. The batches do not depend on
    /// the thread count, so neither do the results. `consume(k, frames)` receives variation
    /// `k`'s bodies, frame-major. On the demo body `batch = 1` was fastest (2 and 4: 0-15 %
    /// slower; the output writes, not the basis reads, are the memory traffic that counts).
    pub fn decode_average_many<F>(
        &self,
        variations: &[Vec<DMatrix<f64>>],
        start: &RigidMotion,
        batch: usize,
        consume: F,
    ) -> Result<()>
    where
        F: Fn(usize, &[Vector3<f64>]) + Sync,
    {
        use rayon::prelude::*;
        let nv = self.dec.model.template.len();
        let len = |v: &Vec<DMatrix<f64>>| v.first().map_or(0, |l| l.nrows());
        // Buffers go back to a shared pool when rayon drops a job's state, so that the
        // 32 MB outputs are allocated (and page-faulted) about once per thread, not per job.
        let pool = std::sync::Mutex::new(Vec::new());
        variations
            .par_chunks(batch.max(1))
            .enumerate()
            .try_for_each_init(
                || Pooled::take(&pool),
                |state, (c, chunk)| {
                    let (scratch, bufs) = state.get();
                    let t = len(&chunk[0]);
                    let groups: Vec<&[Vec<DMatrix<f64>>]> = if chunk.iter().all(|v| len(v) == t) {
                        vec![chunk]
                    } else {
                        chunk.chunks(1).collect()
                    };
                    let mut k0 = c * batch.max(1);
                    for g in groups {
                        let t = len(&g[0]);
                        bufs.resize_with(g.len(), Vec::new);
                        let mut outs: Vec<&mut [Vector3<f64>]> = bufs
                            .iter_mut()
                            .map(|b| {
                                b.resize(t * nv, Vector3::zeros());
                                &mut b[..]
                            })
                            .collect();
                        let lat: Vec<&[DMatrix<f64>]> = g.iter().map(|v| &v[..]).collect();
                        self.decode_batch(&lat, start, scratch, &mut outs)?;
                        for (i, o) in outs.iter().enumerate() {
                            consume(k0 + i, o);
                        }
                        k0 += g.len();
                    }
                    Ok(())
                },
            )
    }
}

/// Per-thread buffers of [`FusedDecoder::decode_average_many`].
type Buffers = (FusedScratch, Vec<Vec<Vector3<f64>>>);

/// Buffers borrowed from a pool and returned to it on drop.
struct Pooled<'p> {
    pool: &'p std::sync::Mutex<Vec<Buffers>>,
    item: Option<Buffers>,
}

impl<'p> Pooled<'p> {
    fn take(pool: &'p std::sync::Mutex<Vec<Buffers>>) -> Self {
        let item = pool.lock().ok().and_then(|mut p| p.pop());
        Pooled {
            pool,
            item: Some(item.unwrap_or_default()),
        }
    }

    fn get(&mut self) -> (&mut FusedScratch, &mut Vec<Vec<Vector3<f64>>>) {
        let (s, b) = self.item.get_or_insert_with(Default::default);
        (s, b)
    }
}

impl Drop for Pooled<'_> {
    fn drop(&mut self) {
        if let (Some(item), Ok(mut p)) = (self.item.take(), self.pool.lock()) {
            p.push(item);
        }
    }
}

/// `o[v_i] = F(x_i, y_i, z_i)` for the vertices of a block that are in one part only; with
/// AVX2 when the CPU has it (the same arithmetic, no FMA contraction: identical results).
fn place_singles(o: &mut [Vector3<f64>], vs: &[u32], p: [&[f64]; 3], f: &RigidMotion) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU supports AVX2 (checked just above).
        unsafe { place_singles_avx2(o, vs, p, f) };
        return;
    }
    place_singles_soa(o, vs, p, f)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn place_singles_avx2(o: &mut [Vector3<f64>], vs: &[u32], p: [&[f64]; 3], f: &RigidMotion) {
    place_singles_soa(o, vs, p, f)
}

#[inline(always)]
fn place_singles_soa(o: &mut [Vector3<f64>], vs: &[u32], p: [&[f64]; 3], f: &RigidMotion) {
    let r = f.rotation.matrix();
    let t = f.translation;
    let [xs, ys, zs] = p;
    let n = vs.len().min(xs.len()).min(ys.len()).min(zs.len());
    for i in 0..n {
        let (x, y, z) = (xs[i], ys[i], zs[i]);
        o[vs[i] as usize] = Vector3::new(
            r[(0, 0)] * x + r[(0, 1)] * y + r[(0, 2)] * z + t[0],
            r[(1, 0)] * x + r[(1, 1)] * y + r[(1, 2)] * z + t[1],
            r[(2, 0)] * x + r[(2, 1)] * y + r[(2, 2)] * z + t[2],
        );
    }
}

/// The columns `from..from + n` of a GPDM's poses (same latents and hyperparameters).
/// Frames of one variation given as one latent trajectory per part: checks there are `parts`
/// of them, all of one length.
fn variation_frames(latents: &[DMatrix<f64>], parts: usize) -> Result<usize> {
    if latents.len() != parts || parts == 0 {
        return Err(Error::invalid(format!(
            "{} latent trajectories for {parts} parts",
            latents.len()
        )));
    }
    let t_len = latents[0].nrows();
    if latents.iter().any(|l| l.nrows() != t_len) {
        return Err(Error::invalid("latent trajectories of different lengths"));
    }
    Ok(t_len)
}

fn columns(g: &gpdm::Gpdm, from: usize, n: usize) -> gpdm::Gpdm {
    let mut c = g.clone();
    c.y = g.y.columns(from, n).into_owned();
    c.y_mean = g.y_mean.rows(from, n).into_owned();
    c
}

/// World poses `P_t` of [`place`] (module doc there) for `n` frames.
pub fn world_poses(
    n: usize,
    displacements: &[[f64; 6]],
    gravity: &[[f64; 4]],
    up: &Vector3<f64>,
    start: &RigidMotion,
    root: &Vector3<f64>,
) -> Vec<RigidMotion> {
    let mut poses = Vec::with_capacity(n);
    let to_root = RigidMotion::new(nalgebra::Rotation3::identity(), *root);
    let back = to_root.inverse();
    // The root pose `Q = P ∘ T(root)` is integrated and corrected; each frame's `P = Q ∘ T(−root)`.
    let mut cur = start.compose(&to_root);
    for t in 0..n {
        if t > 0 {
            cur = cur.compose(&RigidMotion::from_6vec(&Vector6::from_row_slice(
                &displacements[t],
            )));
        }
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
        poses.push(cur.compose(&back));
    }
    poses
}

/// World frames `P_t = Q_t ∘ T(−root)` of the root poses `Q_0 = G_0(start ∘ T(root))`,
/// `Q_t = G_t(Q_{t−1} ∘ D_t)` (the first displacement is ignored), where `G_t` is the gravity
/// correction (deviation, see [`crate::part_data`]): the smallest world rotation about the root
/// point taking the pose's body-frame up axis to the decoded one, then the root point's height
/// set to the decoded height. Heading and horizontal travel stay
/// integrated. Frame 0 is corrected too: a variation starts at its source's first pose, whose
/// lean and height can be another motion's (a blend starts where its first motion does), and
/// would otherwise tilt by the difference between frames 0 and 1. With `gravity` empty, plain
/// integration.
pub fn place(
    body: &[Vec<Vector3<f64>>],
    displacements: &[[f64; 6]],
    gravity: &[[f64; 4]],
    up: &Vector3<f64>,
    start: &RigidMotion,
    root: &Vector3<f64>,
) -> Vec<Vec<Vector3<f64>>> {
    let poses = world_poses(body.len(), displacements, gravity, up, start, root);
    body.iter()
        .zip(&poses)
        .map(|(f, p)| p.apply_all(f))
        .collect()
}
