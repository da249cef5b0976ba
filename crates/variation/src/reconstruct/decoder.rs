//! The decoder: every part's factorised predictor (exact, or through a kernel basis), the
//! averaging plan of the merge (bands, coverage, weights, the template's core), and the full
//! decoding of latent trajectories: part poses (3DV eqs. 11-12), assembly, world placement.

use gpdm::predict::Predictor;
use std::sync::Mutex;

use surface::stitch::Stitcher;
use mesh_core::rigid::RigidMotion;
use mesh_core::{Error, Result};
use nalgebra::{DMatrix, Vector3};
use rand::Rng;

use capture::root_placement::{place, world_poses_from, Gravity};
use super::{Assembly, DecodedParts};
use crate::group::{root_core, PartDef};
use crate::part_data::{split_torso, unflatten, TORSO_EXTRA};
use crate::train::VariationModel;

/// Factorised predictors of every part, plus the averaging plan.
pub struct Decoder<'a> {
    pub model: &'a VariationModel,
    pub predictors: Vec<Predictor>,
    /// Exact predictor of the torso's extra columns when `predictors` use a basis.
    pub(super) torso_extra: Option<Predictor>,
    /// Per child part: (its local index, parent's local index) of every band vertex.
    pub(super) bands: Vec<Vec<(usize, usize)>>,
    pub(super) coverage: Vec<u32>,
    /// Template vertices the assembled body is aligned to the template on (`group::root_core`;
    /// empty: every vertex), and per template vertex whether it is one of them.
    pub(super) core: Vec<u32>,
    pub(super) in_core: Vec<bool>,
    /// The template's root point, whose motion the displacements are (`Group::root_point`).
    pub(super) root: Vector3<f64>,
    /// Per part and vertex of the part: its weight in the merged vertex, for `Average` (1 /
    /// coverage) and for `Feather` ([`surface::feather::band_weights`]).
    pub(super) uniform: Vec<Vec<f64>>,
    pub(super) feathered: Vec<Vec<f64>>,
    /// Stitchers (each with its symbolic factorisation) lent to the threads that stitch
    /// frames, and returned after.
    pub(super) stitchers: Mutex<Vec<Stitcher>>,
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
        let layout: Vec<surface::stitch::LayoutPart> = parts
            .iter()
            .map(|p| surface::stitch::LayoutPart { vertices: p.vertices.clone(), parent: p.parent })
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
        let gravity = Gravity { targets: &decoded.gravity, up: &self.model.up };
        let poses = world_poses_from(start, &self.root, &decoded.displacements, body.len(), Some(&gravity));
        Ok(place(&poses, &body))
    }
}

/// The columns `from..from + n` of a GPDM's poses (same latents and hyperparameters).
fn columns(g: &gpdm::Gpdm, from: usize, n: usize) -> gpdm::Gpdm {
    let mut c = g.clone();
    c.y = g.y.columns(from, n).into_owned();
    c.y_mean = g.y_mean.rows(from, n).into_owned();
    c
}
