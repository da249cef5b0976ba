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
use mesh_core::rigid::relative_in_body_frame;
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

/// `C_ij`: mean distance between subsampled vertices of motion frame `i` and reference frame `j`.
pub fn pose_cost(
    frames: &[Vec<Vector3<f64>>],
    reference: &[Vec<Vector3<f64>>],
    max_vertices: usize,
) -> DMatrix<f64> {
    let n = reference.first().map_or(0, |f| f.len());
    let step = n.div_ceil(max_vertices.max(1)).max(1);
    let idx: Vec<usize> = (0..n).step_by(step).collect();
    let rows: Vec<Vec<f64>> = frames
        .par_iter()
        .map(|a| {
            reference
                .iter()
                .map(|b| {
                    idx.iter().map(|&v| (a[v] - b[v]).norm()).sum::<f64>() / idx.len().max(1) as f64
                })
                .collect()
        })
        .collect();
    DMatrix::from_fn(frames.len(), reference.len(), |i, j| rows[i][j])
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

/// The motion re-timed by `map`: frames and world poses `map[j]`, displacements recomputed.
pub fn apply(motion: &AlignedMotion, map: &[usize]) -> AlignedMotion {
    let frames = map.iter().map(|&i| motion.frames[i].clone()).collect();
    let poses: Vec<_> = map.iter().map(|&i| motion.poses[i]).collect();
    let mut displacements = vec![[0.0; 6]];
    for w in poses.windows(2) {
        let d = relative_in_body_frame(&w[0], &w[1]).to_6vec();
        displacements.push([d[0], d[1], d[2], d[3], d[4], d[5]]);
    }
    displacements.truncate(poses.len());
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
