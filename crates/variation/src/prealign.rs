//! Temporal pre-alignment of the motions of one movement group (paper §5 "Multiple sequences"
//! and §8): dynamic time warping of each motion to a reference motion, guided by feet-contact
//! annotations.
//!
//! Frames are compared after rigid alignment to the template (`capture::align`), so the cost
//! sees pose only: `C_ij = mean_v ‖s_i(v) − r_j(v)‖ + λ · #feet whose contact differs`, with the
//! vertices subsampled to at most `max_vertices` and `λ` by default the median pose cost (a
//! contact disagreement costs as much as a typical pose difference, so contact changes snap
//! together). The least-cost monotonic path is `gp::dtw::dtw_path` (corners fixed, at most 3
//! consecutive horizontal or vertical steps). Each reference frame `j` then takes the median
//! motion frame paired with it, and the warped motion's world poses are `P_{map(j)}`, its
//! displacements recomputed from them (so the body still travels the captured path).

use gp::dtw::{dtw_path, DtwOptions, Endpoints};
use mesh_core::{Error, Result};
use nalgebra::{DMatrix, Vector3};
use rayon::prelude::*;
use capture::align::AlignedMotion;

use crate::contacts::{mismatch, Contacts};

/// Settings of [`warp`].
#[derive(Clone, Debug, PartialEq)]
pub struct PrealignOptions {
    /// Cost of one foot's contact disagreement; `None`: the median pose cost.
    pub contact_weight: Option<f64>,
    /// Vertices used for the pose cost (evenly subsampled).
    pub max_vertices: usize,
    /// Maximum consecutive horizontal or vertical DTW steps.
    pub max_run: usize,
}

impl Default for PrealignOptions {
    fn default() -> Self {
        PrealignOptions {
            contact_weight: None,
            max_vertices: 600,
            max_run: 3,
        }
    }
}

/// A time warp of a motion onto a reference.
#[derive(Clone, Debug, PartialEq)]
pub struct Warp {
    /// DTW path `(motion frame, reference frame)`.
    pub path: Vec<(usize, usize)>,
    /// For each reference frame, the motion frame that replaces it.
    pub map: Vec<usize>,
    /// The contact weight λ used.
    pub contact_weight: f64,
    /// Mean cost `C_ij` (contact term included) along the path.
    pub mean_cost: f64,
}

/// Reference frames whose distance sums [`pose_cost`] accumulates side by side: each sum keeps
/// its own accumulator, added in vertex order as one sum alone (same bits), and the independent
/// chains of additions (and the square roots, one vector instruction per batch) overlap.
const COST_BATCH: usize = 4;

/// `C_ij`: mean distance between subsampled vertices of motion frame `i` and reference frame `j`.
pub fn pose_cost(
    frames: &[Vec<Vector3<f64>>],
    reference: &[Vec<Vector3<f64>>],
    max_vertices: usize,
) -> DMatrix<f64> {
    let n = reference.first().map_or(0, |f| f.len());
    let step = n.div_ceil(max_vertices.max(1)).max(1);
    let idx: Vec<usize> = (0..n).step_by(step).collect();
    let k = idx.len();
    let m = reference.len();
    // The subsampled reference vertices, COST_BATCH frames interleaved per vertex and
    // coordinate: `packed[b·k + i][c][l]` is coordinate c of vertex idx[i] of frame
    // b·COST_BATCH + l (lanes past the last frame repeat it: computed, not used).
    let batches = m.div_ceil(COST_BATCH);
    let mut packed = vec![[[0.0f64; COST_BATCH]; 3]; batches * k];
    for b in 0..batches {
        for l in 0..COST_BATCH {
            let frame = &reference[(b * COST_BATCH + l).min(m - 1)];
            for (i, &v) in idx.iter().enumerate() {
                for c in 0..3 {
                    packed[b * k + i][c][l] = frame[v][c];
                }
            }
        }
    }
    let rows: Vec<Vec<f64>> = frames
        .par_iter()
        .map(|a| {
            let points: Vec<Vector3<f64>> = idx.iter().map(|&v| a[v]).collect();
            let mut row = Vec::with_capacity(m);
            for b in 0..batches {
                let mut acc = [-0.0f64; COST_BATCH];
                for (p, r) in points.iter().zip(&packed[b * k..(b + 1) * k]) {
                    for l in 0..COST_BATCH {
                        let (dx, dy, dz) = (p.x - r[0][l], p.y - r[1][l], p.z - r[2][l]);
                        // As `Vector3::norm`: sqrt((x² + y²) + z²).
                        acc[l] += (dx * dx + dy * dy + dz * dz).sqrt();
                    }
                }
                let lanes = COST_BATCH.min(m - b * COST_BATCH);
                row.extend(acc[..lanes].iter().map(|s| s / k.max(1) as f64));
            }
            row
        })
        .collect();
    DMatrix::from_fn(frames.len(), m, |i, j| rows[i][j])
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(|a, b| a.total_cmp(b));
    if v.is_empty() {
        0.0
    } else {
        v[v.len() / 2]
    }
}

/// Contact-guided DTW of `frames` (with `contacts`) onto `reference` (with `ref_contacts`).
/// Both frame lists must be rigidly aligned to the same template; contacts may be absent
/// (plain pose DTW).
pub fn warp(
    frames: &[Vec<Vector3<f64>>],
    contacts: Option<&Contacts>,
    reference: &[Vec<Vector3<f64>>],
    ref_contacts: Option<&Contacts>,
    opts: &PrealignOptions,
) -> Result<Warp> {
    if frames.is_empty() || reference.is_empty() {
        return Err(Error::invalid("prealign: empty motion or reference"));
    }
    if frames[0].len() != reference[0].len() {
        return Err(Error::invalid(format!(
            "prealign: motion has {} vertices, reference {}",
            frames[0].len(),
            reference[0].len()
        )));
    }
    let (fs, ft) = (frames.len(), reference.len());
    let r = opts.max_run.max(1);
    if fs > (r + 1) * ft || ft > (r + 1) * fs {
        return Err(Error::invalid(format!(
            "prealign: {fs} frames cannot be warped onto {ft} with at most {r} repeated steps (ratio above {})",
            r + 1
        )));
    }
    let mut cost = pose_cost(frames, reference, opts.max_vertices);
    let lambda = opts
        .contact_weight
        .unwrap_or_else(|| median(&mut cost.as_slice().to_vec()));
    if let (Some(a), Some(b)) = (contacts, ref_contacts) {
        for i in 0..fs {
            for j in 0..ft {
                cost[(i, j)] += lambda * mismatch(a[i], b[j]) as f64;
            }
        }
    }
    let path = dtw_path(
        &cost,
        &[],
        &DtwOptions {
            max_run: r,
            endpoints: Endpoints::Corners,
        },
    )
    .map_err(|e| Error::invalid(format!("prealign: {e}")))?;
    let map = reference_map(&path, ft);
    let mean_cost = path.iter().map(|&(i, j)| cost[(i, j)]).sum::<f64>() / path.len() as f64;
    Ok(Warp {
        path,
        map,
        contact_weight: lambda,
        mean_cost,
    })
}

/// For each reference frame `j < n_ref`, the median motion frame paired with it on `path`.
pub fn reference_map(path: &[(usize, usize)], n_ref: usize) -> Vec<usize> {
    let mut paired: Vec<Vec<usize>> = vec![Vec::new(); n_ref];
    for &(i, j) in path {
        if j < n_ref {
            paired[j].push(i);
        }
    }
    let mut last = 0;
    paired
        .iter()
        .map(|v| {
            if let Some(&m) = v.get(v.len() / 2) {
                last = m;
            }
            last
        })
        .collect()
}

/// The motion re-timed by `map`: frames and world poses `map[j]`, displacements of the template
/// point `root` recomputed (`group::root_displacements`).
pub fn apply(motion: &AlignedMotion, map: &[usize], root: &Vector3<f64>) -> AlignedMotion {
    let frames = map.iter().map(|&i| motion.frames[i].clone()).collect();
    let poses: Vec<_> = map.iter().map(|&i| motion.poses[i]).collect();
    let displacements = crate::group::root_displacements(&poses, root);
    AlignedMotion {
        faces: motion.faces.clone(),
        frames,
        poses,
        displacements,
        anchor: motion.anchor.clone(),
        capture: motion.capture.clone(),
    }
}

/// The contacts re-timed by `map`.
pub fn apply_contacts(contacts: &Contacts, map: &[usize]) -> Contacts {
    map.iter().map(|&i| contacts[i]).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};

    /// The batched sums against the plain mean of `Vector3::norm` over the same vertices, to
    /// the bit: reference lengths that are and are not a multiple of the batch, with and
    /// without subsampling.
    #[test]
    fn pose_cost_equals_the_plain_mean_distance_bit_for_bit() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let mut frames = |count: usize| -> Vec<Vec<Vector3<f64>>> {
            (0..count)
                .map(|_| {
                    (0..37)
                        .map(|_| Vector3::new(rng.random::<f64>(), rng.random::<f64>() - 0.5, 2.0 * rng.random::<f64>()))
                        .collect()
                })
                .collect()
        };
        let a = frames(6);
        for m in [1, 4, 7, 9] {
            let reference = frames(m);
            for max_vertices in [400, 10] {
                let cost = pose_cost(&a, &reference, max_vertices);
                let step = 37usize.div_ceil(max_vertices);
                let idx: Vec<usize> = (0..37).step_by(step).collect();
                for (i, f) in a.iter().enumerate() {
                    for (j, r) in reference.iter().enumerate() {
                        let plain = idx.iter().map(|&v| (f[v] - r[v]).norm()).sum::<f64>() / idx.len() as f64;
                        assert_eq!(cost[(i, j)].to_bits(), plain.to_bits(), "m {m}, max {max_vertices}, ({i}, {j})");
                    }
                }
            }
        }
    }
}
