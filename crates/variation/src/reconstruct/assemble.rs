//! Parts merged into one body, template-aligned on the root part's core: children aligned to
//! their parents on the overlap bands, then a weighted mean of shared vertices ([`Assembly::Average`],
//! [`Assembly::Feather`]) or per-frame Poisson stitching ([`Assembly::Stitch`], with stitchers
//! lent from the decoder's pool).

use std::sync::Mutex;

use surface::poisson::Factorisation;
use surface::stitch::Stitcher;
use capture::align::fit_on;
use mesh_core::rigid::procrustes;
use mesh_core::{Error, Result};
use nalgebra::Vector3;
use rayon::prelude::*;

use super::{Assembly, DecodedParts, Decoder};

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

impl Decoder<'_> {
    /// Per part and vertex of the part, its weight in the merged vertex under `how` (an
    /// averaging assembly; `Stitch` gets the uniform weights).
    pub(super) fn merge_weights(&self, how: Assembly) -> &[Vec<f64>] {
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
                    .map(|p| surface::stitch::LayoutPart {
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
}
