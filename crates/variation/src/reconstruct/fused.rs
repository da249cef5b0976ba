//! The fused, vertex-blocked bulk decoder: per frame the band, template and world transforms
//! from the pose coefficients alone, then per block of vertices one GEMM and the placed,
//! weighted vertices written straight into the output.

use mesh_core::rigid::{procrustes, rigid_from_moments, RigidMotion};
use mesh_core::{Error, Result};
use nalgebra::{DMatrix, Vector3};

use super::fused_plan::PartMap;
use super::pool::Pooled;
use super::simd::place_singles;
use capture::root_placement::{world_poses_from, Gravity};
use super::{variation_frames, Decoder};
use crate::part_data::{extra_scale, TORSO_EXTRA};

/// `out = a · b`, sequential.
fn gemm(out: faer::MatMut<'_, f64>, a: faer::MatRef<'_, f64>, b: faer::MatRef<'_, f64>) {
    faer::linalg::matmul::matmul(out, faer::Accum::Replace, a, b, 1.0, faer::Par::Seq);
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
/// Then, per block of [`FUSED_BLOCK_VERTICES`](super::FUSED_BLOCK_VERTICES) part vertices, one GEMM of the block's basis
/// rows with all frames' coefficients (in L2), and `w_v F_{k,t}(p)` written (first part of a
/// vertex) or added (later parts) straight into the output. Each part's vertex rows are
/// stored reordered: vertices in no other part first (written without weight or branch), and
/// within a block all x rows, then all y, then all z, so that the transform loop runs over
/// contiguous arrays.
pub struct FusedDecoder<'d, 'a> {
    pub(super) dec: &'d Decoder<'a>,
    pub(super) maps: Vec<PartMap>,
    /// Per child part: band rows of `[B | ȳ]` of the child, and of its parent.
    pub(super) band_child: Vec<faer::Mat<f64>>,
    pub(super) band_parent: Vec<faer::Mat<f64>>,
    /// Per part: the 12 moment rows (`S_k`, then `M_k` row-major), `Σ w` and `Σ w e`.
    pub(super) moments: Vec<faer::Mat<f64>>,
    pub(super) wsum: Vec<f64>,
    pub(super) esum: Vec<Vector3<f64>>,
    /// Per part, in the reordered vertex order (type doc): template vertex, averaging weight,
    /// whether this part writes it first, and the count of vertices in this part only.
    pub(super) verts: Vec<Vec<u32>>,
    pub(super) weight: Vec<Vec<f64>>,
    pub(super) first: Vec<Vec<bool>>,
    pub(super) singles: Vec<usize>,
    /// Per part: the reordered vertex rows of `[B | ȳ]`, blocked (type doc).
    pub(super) vbasis: Vec<faer::Mat<f64>>,
    /// Per part: reordered position → local vertex index.
    pub(super) order: Vec<Vec<usize>>,
    /// Centroid of the template's core and its vertex count.
    pub(super) cd: Vector3<f64>,
    pub(super) n_core: usize,
    pub(super) block: usize,
}

/// Per-thread buffer of [`FusedDecoder::decode_average_into`].
#[derive(Default)]
pub struct FusedScratch {
    block: Vec<f64>,
}

impl FusedDecoder<'_, '_> {
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
        let gravity = Gravity { targets: &grav, up: &dec.model.up };
        let world = world_poses_from(start, &dec.root, &disp, t_len, Some(&gravity));
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
