//! The plan of the fused decoder ([`FusedDecoder`]): every part's `[B | ȳ]`, its band rows,
//! its moment rows against the template's core, and its vertex rows reordered and blocked.

use mesh_core::{Error, Result};
use nalgebra::Vector3;
use rayon::prelude::*;

use super::fused::FusedDecoder;
use super::{Assembly, Decoder};
use crate::part_data::TORSO_EXTRA;

/// Vertices per block of the fused decoding: the block's basis rows (3·128 × (R+1)) and its
/// poses for 100 frames (3·128 × 100) take about 0.65 MB together, within one core's L2
/// (2 MB here; 96-192 measured within noise of each other on the demo body, 256 and 512
/// 5-15 % slower).
pub const FUSED_BLOCK_VERTICES: usize = 128;

/// One part's 3DV eq. 12 as an affine map of coefficients: the poses of latent points `x_*` are
/// `[B | ȳ] · [c(x_*); 1]` (`Predictor::pose_coefficients` and `Predictor::pose_basis`: exact,
/// `c = k_Y(X, x_*)` and `B = (K_Y⁻¹ Y)ᵀ`; kernel basis of rank R, `c = Q_Rᵀ k_Y(X, x_*)` and
/// `B = (K_Y⁻¹ Y)ᵀ Q_R`). The fused decoder multiplies `[B | ȳ]` one block of vertex rows at a time.
pub(super) struct PartMap {
    /// `[B | ȳ]`, D × (R+1), column-major (the torso without its displacement rows).
    pub(super) basis: faer::Mat<f64>,
}

/// The rows of `[B | ȳ]` of the given part vertices (3 per vertex).
fn vertex_rows(basis: &faer::Mat<f64>, verts: impl Iterator<Item = usize>) -> faer::Mat<f64> {
    let idx: Vec<usize> = verts.flat_map(|i| [3 * i, 3 * i + 1, 3 * i + 2]).collect();
    faer::Mat::from_fn(idx.len(), basis.ncols(), |r, c| basis[(idx[r], c)])
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

}
