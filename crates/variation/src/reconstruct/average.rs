//! The exact bulk decoder: mean poses (3DV eq. 12) merged by [`Assembly::Average`](super::Assembly),
//! one GEMM per part and one pass per frame, no allocation per frame.

use mesh_core::rigid::{procrustes, rigid_from_moments, RigidMotion};
use mesh_core::{Error, Result};
use nalgebra::{DMatrix, Vector3};

use capture::root_placement::{world_poses_from, Gravity};
use super::{variation_frames, Decoder};
use crate::part_data::{extra_scale, TORSO_EXTRA};

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
    /// The fast path of [`Decoder::decode`] with [`Assembly::Average`](super::Assembly::Average) and mean poses (3DV eq. 12),
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
        let gravity = Gravity { targets: &grav, up: &self.model.up };
        let world = world_poses_from(start, &self.root, &disp, t_len, Some(&gravity));
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
    pub(super) fn core_centroid(&self) -> (Vector3<f64>, usize) {
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
