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
//!
//! Files: [`decoder`] (the per-part predictors and full decoding), [`assemble`] (parts merged
//! into one body), [`average`] (the exact bulk decoder), [`fused`] and [`fused_plan`] (the
//! vertex-blocked bulk decoder and its precomputed plan), [`pool`] (per-thread buffers lent by
//! a pool), [`simd`] (the placement of one-part vertices); the world placement is
//! `capture::root_placement`'s, with the decoded gravity values.

use mesh_core::{Error, Result};
use nalgebra::{DMatrix, Vector3};
use serde::{Deserialize, Serialize};

mod assemble;
mod average;
mod decoder;
mod fused;
mod fused_plan;
mod pool;
mod simd;

pub use average::DecodeScratch;
pub use decoder::Decoder;
pub use fused::{FusedDecoder, FusedScratch};
pub use fused_plan::FUSED_BLOCK_VERTICES;

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
