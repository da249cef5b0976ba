//! Where the transferred poses start and which displacements move them: the per-frame rigid
//! displacements are integrated from a start pose by [`capture::root_placement`] (CVPR §4,
//! "Rigid Transformation": `P_i = P_{i-1} ∘ (dT_i, dR_i)`).
//!
//! Everything is integrated as *root poses* `Q_i = P_i ∘ T(c)`: the pose of the
//! subject's root point `c` (the centroid of the template's alignment anchor,
//! `align --frame`), so that a displacement's translation is the root's own
//! motion and does not depend on where the template happens to stand (a turn
//! about the body is not a swing about the template's origin). The start is the
//! source's first root pose with its position scaled about the world origin by
//! the height ratio `s = h_t / h_s` (heights: the templates' extents along +y;
//! the floor is `y = 0`): the target performs the motion in the same capture
//! volume, at its own size. `P_i = Q_i ∘ T(-c_t)` places the target's frames.
//!
//! Three choices of per-frame displacement, all reported by `transfer-eval`:
//! - `scaled-source` (the default): the source's own root displacement with its
//!   translation scaled by `s`; rotation unchanged;
//! - `regressed` (the paper): the displacement GP's prediction;
//! - `blended`: per frame `D = (1 - w) D_regressed + w D_scaled`, on the
//!   6-vectors, with `w = σ²_*(x) / k(x, x)` the displacement GP's latent
//!   predictive variance (CVPR eq. 12) relative to its prior variance: `w ≈ 0`
//!   where the source displacement is like the training data, `w -> 1` where
//!   the GP extrapolates (its mean falls back to the prior mean, 0, which
//!   integrates to a standing body, while the scaled source keeps moving).

use mesh_core::rigid::RigidMotion;
use nalgebra::Vector3;

pub use capture::choices::Placement;
use capture::part_pca::PcaModel;

/// Extent along +y of a subject's template, from the union of the PCA parts'
/// reference vertices (each part's reference is the template part).
pub fn template_height(pca: &PcaModel) -> f64 {
    let ys = pca
        .parts
        .iter()
        .flat_map(|p| p.reference.iter().map(|v| v.y));
    let (lo, hi) = ys.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), y| {
        (lo.min(y), hi.max(y))
    });
    if hi > lo {
        hi - lo
    } else {
        0.0
    }
}

/// The template's root point (see [`capture::align::root_point`]).
pub fn root_point(pca: &PcaModel) -> Vector3<f64> {
    capture::align::root_point(&pca.template_vertices(), &pca.anchor)
}

/// The target's first root pose: the source's first root pose `source_root_start` with
/// its position scaled by `ratio` about the world origin, same orientation.
pub fn scaled_start(source_root_start: &RigidMotion, ratio: f64) -> RigidMotion {
    RigidMotion::new(
        source_root_start.rotation,
        source_root_start.translation * ratio,
    )
}

/// The source displacements with translation scaled by `ratio`.
pub fn scaled_source(source_disp: &[[f64; 6]], ratio: f64) -> Vec<[f64; 6]> {
    source_disp
        .iter()
        .map(|d| [d[0] * ratio, d[1] * ratio, d[2] * ratio, d[3], d[4], d[5]])
        .collect()
}

/// `(1 - w_i) a_i + w_i b_i` per frame.
pub fn blend(regressed: &[[f64; 6]], scaled: &[[f64; 6]], weights: &[f64]) -> Vec<[f64; 6]> {
    regressed
        .iter()
        .zip(scaled)
        .zip(weights)
        .map(|((a, b), &w)| std::array::from_fn(|c| (1.0 - w) * a[c] + w * b[c]))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scaling_and_blending() {
        let d = [[0.1, 0.2, 0.3, 0.01, 0.02, 0.03]];
        assert_eq!(
            scaled_source(&d, 2.0),
            vec![[0.2, 0.4, 0.6, 0.01, 0.02, 0.03]]
        );
        let (a, b) = ([[1.0; 6]], [[3.0; 6]]);
        assert_eq!(blend(&a, &b, &[0.0]), a.to_vec());
        assert_eq!(blend(&a, &b, &[1.0]), b.to_vec());
        assert_eq!(blend(&a, &b, &[0.25]), vec![[1.5; 6]]);
    }
}
