//! A geometric prior for the affine mean of a part's regression: the linear map between two
//! subjects' part coefficients that their shapes alone predict, before any training pose.
//!
//! Two subjects' corresponding parts deform alike: a limb rotated about its joint by `R` moves
//! its vertices by `(R - I)(v - j)`, and on the other subject, whose part is (to first order) the
//! first one scaled by `s`, turned by `Q` and re-meshed, the same rotation moves the vertex that
//! corresponds to `v` by `s Q (R - I)(v - j)`. Displacements from the mean shape thus map
//! linearly, `Δv_B ≈ s Q P Δv_A` with `P` the vertex correspondence, and so do PCA coefficients:
//!
//! `y ≈ s C_B (I ⊗ Q) P C_Aᵀ x + C_B (s (I ⊗ Q) P (μ_A - c_A) + c_B - μ_B)`
//!
//! (`C` the PCA rows, `μ` the means, `c` the mean shapes' centroids). Shrinking the fitted map
//! toward this one rather than toward zero (`gp::affine_mean`) keeps the prediction sensible
//! along the input directions the training poses barely span, which is where unseen motions go.
//!
//! The correspondence `P` and the rotation `Q` come from the two parts' mean shapes by iterative
//! closest points: centroids matched, A scaled by `s` (the templates' height ratio), then nearest
//! neighbours and a Procrustes rotation alternated a few times (from the identity rotation: the two subjects'
//! templates face the same way, as `align` expresses every frame in its template's frame).

use gp::pca::Pca;
use mesh_core::point_tree::PointTree;
use mesh_core::rigid::procrustes;
use nalgebra::{DMatrix, Matrix3, Vector3};
use rayon::prelude::*;

/// ICP iterations of the part correspondence.
const ICP_ITERATIONS: usize = 10;

fn points(flat: &nalgebra::DVector<f64>) -> Vec<Vector3<f64>> {
    (0..flat.len() / 3)
        .map(|i| Vector3::new(flat[3 * i], flat[3 * i + 1], flat[3 * i + 2]))
        .collect()
}

fn centroid(p: &[Vector3<f64>]) -> Vector3<f64> {
    p.iter().sum::<Vector3<f64>>() / p.len().max(1) as f64
}

fn rms_radius(p: &[Vector3<f64>], c: &Vector3<f64>) -> f64 {
    (p.iter().map(|v| (v - c).norm_squared()).sum::<f64>() / p.len().max(1) as f64).sqrt()
}

/// Index of the nearest point of `cloud` to each of `queries` (the lowest of equally near ones).
fn nearest(queries: &[Vector3<f64>], cloud: &[Vector3<f64>]) -> Vec<usize> {
    let tree = PointTree::new(cloud);
    queries.par_iter().map(|q| tree.nearest(q).unwrap_or(0)).collect()
}

/// The similarity and correspondence that carry part A's mean shape onto part B's:
/// for each B vertex its A vertex, the scale `s` and rotation `Q` with
/// `v_B - c_B ≈ s Q (v_A - c_A)`.
pub struct PartCorrespondence {
    pub to_source: Vec<usize>,
    pub scale: f64,
    pub rotation: Matrix3<f64>,
    pub source_centroid: Vector3<f64>,
    pub target_centroid: Vector3<f64>,
    /// RMS distance of B's vertices to their carried A vertices, over B's RMS radius.
    pub residual: f64,
}

/// ICP between the two mean shapes (see the module documentation), at the scale `body_scale`
/// (`None`: the ratio of the two shapes' RMS radii).
pub fn correspond(source_mean: &[Vector3<f64>], target_mean: &[Vector3<f64>], body_scale: Option<f64>) -> PartCorrespondence {
    let (ca, cb) = (centroid(source_mean), centroid(target_mean));
    let (ra, rb) = (rms_radius(source_mean, &ca), rms_radius(target_mean, &cb));
    let scale = body_scale.unwrap_or(if ra > 0.0 { rb / ra } else { 1.0 });
    // Source points in the target's frame: s Q (v_A - c_A) + c_B.
    let mut rotation = Matrix3::identity();
    let mut to_source = Vec::new();
    for _ in 0..ICP_ITERATIONS {
        let moved: Vec<Vector3<f64>> = source_mean
            .iter()
            .map(|v| rotation * (v - ca) * scale + cb)
            .collect();
        to_source = nearest(target_mean, &moved);
        let src: Vec<Vector3<f64>> = to_source.iter().map(|&i| (source_mean[i] - ca) * scale).collect();
        let dst: Vec<Vector3<f64>> = target_mean.iter().map(|v| v - cb).collect();
        let fit = procrustes(&src, &dst, None);
        rotation = *fit.rotation.matrix();
    }
    let residual = (to_source
        .iter()
        .zip(target_mean)
        .map(|(&a, b)| (rotation * (source_mean[a] - ca) * scale + cb - b).norm_squared())
        .sum::<f64>()
        / target_mean.len().max(1) as f64)
        .sqrt()
        / rb.max(f64::MIN_POSITIVE);
    PartCorrespondence {
        to_source,
        scale,
        rotation,
        source_centroid: ca,
        target_centroid: cb,
        residual,
    }
}

/// The prior of the affine mean `m(x) = Wᵀ [x; 1]` of one part: `W0` of shape `(d + 1) x p`
/// (`d`, `p`: source and target coefficient counts), as in the module documentation.
pub fn affine_prior(source: &Pca, target: &Pca, body_scale: Option<f64>) -> DMatrix<f64> {
    let (mu_a, mu_b) = (points(&source.mean), points(&target.mean));
    let c = correspond(&mu_a, &mu_b, body_scale);
    let angle = ((c.rotation.trace() - 1.0) / 2.0).clamp(-1.0, 1.0).acos().to_degrees();
    mesh_core::info!(
        "geometric prior: scale {:.3}, turn {angle:.1} deg, ICP residual {:.3} of the part's radius",
        c.scale,
        c.residual
    );
    let (d, p) = (source.components.nrows(), target.components.nrows());
    // M = (I ⊗ s Q) P C_Aᵀ: 3 n_B x d, and the offset vector s (I ⊗ Q) P (μ_A - c_A) + c_B - μ_B.
    let n_b = mu_b.len();
    let sq = c.rotation * c.scale;
    let mut m = DMatrix::zeros(3 * n_b, d);
    let mut offset = nalgebra::DVector::zeros(3 * n_b);
    for (b, &a) in c.to_source.iter().enumerate() {
        for k in 0..d {
            let col = Vector3::new(
                source.components[(k, 3 * a)],
                source.components[(k, 3 * a + 1)],
                source.components[(k, 3 * a + 2)],
            );
            let moved = sq * col;
            for r in 0..3 {
                m[(3 * b + r, k)] = moved[r];
            }
        }
        let o = sq * (mu_a[a] - c.source_centroid) + c.target_centroid - mu_b[b];
        for r in 0..3 {
            offset[3 * b + r] = o[r];
        }
    }
    let lin = &target.components * m; // p x d
    let off = &target.components * offset; // p
    let mut w0 = DMatrix::zeros(d + 1, p);
    for j in 0..p {
        for k in 0..d {
            w0[(k, j)] = lin[(j, k)];
        }
        w0[(d, j)] = off[j];
    }
    w0
}

/// The prior of every part of two subjects' PCA models (parts paired by position, as the
/// regressions are), every part scaled by the templates' height ratio (the scale of the default
/// placement): a part's own extent depends on where its curves cut it, its motions do not.
pub fn part_priors(
    source: &capture::part_pca::PcaModel,
    target: &capture::part_pca::PcaModel,
) -> Vec<DMatrix<f64>> {
    let hs = crate::placement::template_height(source);
    let body_scale = (hs > 0.0).then(|| crate::placement::template_height(target) / hs);
    source
        .parts
        .iter()
        .zip(&target.parts)
        .map(|(a, b)| affine_prior(&a.pca, &b.pca, body_scale))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use gp::pca::Components;
    use nalgebra::Rotation3;

    /// A bent "limb" (points along a curve) rotated about its root by many angles; subject B
    /// is subject A scaled by 1.3, turned 10° and re-sampled in a shuffled vertex order. The prior
    /// fitted on B's and A's PCA means must map A's coefficients of a pose to B's coefficients of
    /// the same pose with a small error, also for poses outside the angles the PCAs were fitted on.
    #[test]
    fn maps_a_scaled_turned_reordered_limb_exactly_enough() {
        let limb: Vec<Vector3<f64>> = (0..60)
            .map(|i| {
                let t = i as f64 / 59.0;
                Vector3::new(0.05 * (7.0 * t).sin(), -t, 0.03 * (11.0 * t).cos() + 0.02 * t)
            })
            .collect();
        let turn = Rotation3::from_axis_angle(&Vector3::z_axis(), 10f64.to_radians());
        let order: Vec<usize> = (0..60).map(|i| (i * 37) % 60).collect();
        let pose = |shape: &[Vector3<f64>], a: f64, b: f64| -> Vec<Vector3<f64>> {
            let r = Rotation3::from_euler_angles(a, 0.3 * b, b);
            shape.iter().map(|v| r * v).collect()
        };
        let flat = |p: &[Vector3<f64>]| -> Vec<f64> { p.iter().flat_map(|v| [v.x, v.y, v.z]).collect() };
        let angles: Vec<(f64, f64)> = (0..40).map(|i| (0.02 * i as f64, 0.015 * (i % 7) as f64)).collect();
        let rows = |shape: &[Vector3<f64>], turned: bool| {
            let data: Vec<f64> = angles
                .iter()
                .flat_map(|&(a, b)| {
                    let p = pose(shape, a, b);
                    flat(&if turned { p.iter().map(|v| turn * v).collect::<Vec<_>>() } else { p })
                })
                .collect();
            DMatrix::from_row_slice(angles.len(), 3 * shape.len(), &data)
        };
        // B's poses: the same rotations applied in B's own (turned) frame.
        let b_rest: Vec<Vector3<f64>> = order.iter().map(|&i| limb[i] * 1.3).collect();
        let (ya, yb) = (rows(&limb, false), rows(&b_rest, true));
        let pa = Pca::fit(&ya, Components::Count(6)).unwrap();
        let pb = Pca::fit(&yb, Components::Count(6)).unwrap();
        let w0 = affine_prior(&pa, &pb, None);
        let (d, p) = (pa.components.nrows(), pb.components.nrows());
        assert_eq!(w0.shape(), (d + 1, p));
        // A pose beyond the fitted angles.
        let (a, b) = (0.9, 0.1);
        let xa = pa.encode(&DMatrix::from_row_slice(1, 180, &flat(&pose(&limb, a, b)))).unwrap();
        let tb: Vec<Vector3<f64>> = pose(&b_rest, a, b).iter().map(|v| turn * v).collect();
        let truth = pb.encode(&DMatrix::from_row_slice(1, 180, &flat(&tb))).unwrap();
        let x1 = DMatrix::from_fn(1, d + 1, |_, c| if c < d { xa[(0, c)] } else { 1.0 });
        let pred = &x1 * &w0;
        let err = (&pred - &truth).norm();
        let zero = truth.norm();
        assert!(err < 0.05 * zero, "prior error {err} against a zero map's {zero}");
    }
}
