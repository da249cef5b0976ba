//! Per-part pose vectors (paper §4, "Body parts"): each aligned frame's part vertices, rigidly
//! aligned (Procrustes) to the template part so that the model sees only the part's own
//! deformation (as `capture::part_pca` does), stacked `(x_1, y_1, z_1, x_2, ...)`. The torso
//! (root part) vector is appended with the frame's 6 rigid-displacement values.
//!
//! **Displacement scale.** The 6 values `(t, h)` (metres, radians per frame) are multiplied by
//! `s_t` (translation) and `s_h` (rotation), chosen so that each triple carries the same total
//! variance over the training frames as all torso vertex coordinates together:
//! `s_t² Σ_k var(t_k) = Σ_c var(y_c)` (likewise `s_h`). Unscaled, 6 of ~10⁴ columns would be
//! invisible in `tr(K_Y⁻¹ Y Yᵀ)` and the latent space would ignore timing and travel; with
//! this scale displacement and deformation weigh equally in the torso's likelihood (3DV eq. 3).
//! Scales fall back to 1 when a triple has no variance. The first frame's displacement
//! (identity by construction) is replaced by the second's so it is not an outlier.
//!
//! **Gravity values (deviation from the paper).** Integrating sampled displacements is a random
//! walk: sampled variations drifted upwards and tilted within a second. The torso vector
//! therefore also carries 4 absolute values per frame: the height of the frame's root point
//! (`up · Q_i(0)`, the root pose of `crate::group::root_displacements`; scaled like
//! translations) and the world up axis in body coordinates
//! (`R_iᵀ up`, scaled like rotations). `capture::root_placement::Gravity` keeps the integrated
//! heading and horizontal travel but takes height and tilt from these.

use mesh_core::rigid::procrustes;
use nalgebra::{DMatrix, Vector3};
use serde::{Deserialize, Serialize};
use capture::align::AlignedMotion;

use crate::group::PartDef;

/// Multipliers of the torso vector's displacement columns (module doc).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct DisplacementScale {
    pub translation: f64,
    pub rotation: f64,
}

/// The template positions of a part's vertices.
pub fn reference(template: &[Vector3<f64>], part: &PartDef) -> Vec<Vector3<f64>> {
    part.vertices
        .iter()
        .map(|&v| template[v as usize])
        .collect()
}

/// One frame's part vertices, rigidly aligned to `reference`.
pub fn aligned_part(
    frame: &[Vector3<f64>],
    part: &PartDef,
    reference: &[Vector3<f64>],
) -> Vec<Vector3<f64>> {
    let pts: Vec<Vector3<f64>> = part.vertices.iter().map(|&v| frame[v as usize]).collect();
    procrustes(&pts, reference, None).apply_all(&pts)
}

/// `T × 3n` matrix of a motion's aligned part vertices.
pub fn part_rows(
    motion: &AlignedMotion,
    part: &PartDef,
    reference: &[Vector3<f64>],
) -> DMatrix<f64> {
    let d = 3 * part.vertices.len();
    let mut m = DMatrix::zeros(motion.n_frames(), d);
    for (t, f) in motion.frames.iter().enumerate() {
        for (i, p) in aligned_part(f, part, reference).iter().enumerate() {
            for c in 0..3 {
                m[(t, 3 * i + c)] = p[c];
            }
        }
    }
    m
}

/// The displacements used for modelling: frame 0 takes frame 1's value (module doc).
pub fn model_displacements(motion: &AlignedMotion) -> Vec<[f64; 6]> {
    let mut d = motion.displacements.clone();
    if d.len() > 1 {
        d[0] = d[1];
    }
    d
}

fn total_variance(cols: impl Iterator<Item = Vec<f64>>) -> f64 {
    cols.map(|c| {
        let n = c.len().max(1) as f64;
        let m = c.iter().sum::<f64>() / n;
        c.iter().map(|v| (v - m) * (v - m)).sum::<f64>() / n
    })
    .sum()
}

/// Scales from the torso rows (all training sequences) and their displacements.
pub fn displacement_scale(torso: &[DMatrix<f64>], disp: &[Vec<[f64; 6]>]) -> DisplacementScale {
    let d = torso.first().map_or(0, |m| m.ncols());
    let v_y = total_variance((0..d).map(|c| {
        torso
            .iter()
            .flat_map(|m| m.column(c).iter().copied().collect::<Vec<_>>())
            .collect()
    }));
    let col = |k: usize| {
        disp.iter()
            .flat_map(|s| s.iter().map(move |r| r[k]))
            .collect::<Vec<f64>>()
    };
    let v_t = total_variance((0..3).map(col));
    let v_h = total_variance((3..6).map(col));
    let s = |v: f64| {
        if v > 1e-18 && v_y > 0.0 {
            (v_y / v).sqrt()
        } else {
            1.0
        }
    };
    DisplacementScale {
        translation: s(v_t),
        rotation: s(v_h),
    }
}

/// Columns appended to the torso vector: 6 displacement values, height, body-frame up axis.
pub const TORSO_EXTRA: usize = 10;

/// Per frame `[height, (R_iᵀ up)_x, _y, _z]` of a motion's root poses (module doc; `root` the
/// template's root point).
pub fn gravity(motion: &AlignedMotion, up: &Vector3<f64>, root: &Vector3<f64>) -> Vec<[f64; 4]> {
    motion
        .poses
        .iter()
        .map(|p| {
            let u = p.rotation.inverse() * up;
            [p.apply(root).dot(up), u.x, u.y, u.z]
        })
        .collect()
}

/// Multiplier of torso extra column `k` (0-2 and 6: translation scale, else rotation scale).
pub fn extra_scale(k: usize, scale: DisplacementScale) -> f64 {
    if matches!(k, 0..=2 | 6) {
        scale.translation
    } else {
        scale.rotation
    }
}

/// Appends the scaled displacement and gravity columns to torso rows.
pub fn with_displacement(
    rows: &DMatrix<f64>,
    disp: &[[f64; 6]],
    grav: &[[f64; 4]],
    scale: DisplacementScale,
) -> DMatrix<f64> {
    let d = rows.ncols();
    let mut m = rows.clone().resize_horizontally(d + TORSO_EXTRA, 0.0);
    for (t, (r, g)) in disp.iter().zip(grav).enumerate() {
        for k in 0..TORSO_EXTRA {
            let v = if k < 6 { r[k] } else { g[k - 6] };
            m[(t, d + k)] = v * extra_scale(k, scale);
        }
    }
    m
}

/// Splits a torso pose row back into vertices, the unscaled displacement and gravity values.
pub fn split_torso(
    row: &[f64],
    scale: DisplacementScale,
) -> (Vec<Vector3<f64>>, [f64; 6], [f64; 4]) {
    let d = row.len() - TORSO_EXTRA;
    let verts = unflatten(&row[..d]);
    let disp = std::array::from_fn(|k| row[d + k] / extra_scale(k, scale));
    let grav = std::array::from_fn(|k| row[d + 6 + k] / extra_scale(6 + k, scale));
    (verts, disp, grav)
}

/// `(x_1, y_1, z_1, ...)` to points.
pub fn unflatten(row: &[f64]) -> Vec<Vector3<f64>> {
    row.chunks_exact(3)
        .map(|c| Vector3::new(c[0], c[1], c[2]))
        .collect()
}
