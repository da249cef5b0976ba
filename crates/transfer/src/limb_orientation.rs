//! Limb orientation: how each limb is turned relative to the body it hangs from, mapped from
//! the source on its own and fused with the orientation the pose GP predicts (a departure from
//! CVPR §5: docs/DEVIATIONS.md; measured in docs/studies/06-limb-orientation.md).
//!
//! The pose GPs map a part's PCA coefficients, which are linear in vertex positions: a limb
//! turned further than any training pose is extrapolated along straight lines, and its
//! orientation relative to the torso is where most of the error of unseen motions lies. A
//! rotation is better extrapolated in its own coordinates. So per limb (every part but the
//! root, the first part of the PCA models):
//! * its **orientation** in a frame is the Procrustes rotation of the limb's *proximal half*
//!   (the half of its vertices nearest the band it shares with the parts placed before it,
//!   `capture::assemble::plan`, i.e. its joint) from the PCA mean shape onto the frame;
//! * it is measured in the limb's [`LimbFrame`]: the root part's frame (every part's PCA
//!   frame), or the frame of its **attachment**, the root part's vertices nearest its joint
//!   (an arm's shoulder girdle), whose own orientation is measured likewise. An arm hangs from
//!   the shoulder girdle, which turns against the rest of the torso as the spine bends and the
//!   shoulders shrug; in the attachment's frame the arm's turn is the shoulder joint's alone;
//! * an affine map of log-rotations, `log R_t = [log R_s, 1] W` (`3 -> 3`), is fitted on the
//!   training pairs by ridge least squares shrunk toward the identity map
//!   (`W = (X₁ᵀX₁ + λI) \ (X₁ᵀY + λ W₀)`, `W₀ = [I; 0]`, `λ` = [`RIDGE`] × the mean diagonal);
//! * at prediction the map's orientation is `A_t · exp(map(log(A_s⁻¹ R_s)))`, `A` the
//!   attachment's orientation (the identity in the root frame; the target's is the one its
//!   predicted root part has), and the limb is turned about its joint from the GP's orientation
//!   `R_gp` to `R_gp · exp(w · log(R_gpᵀ R_map))`: the geodesic point `w` ([`WEIGHT`]) of the way
//!   to the map's orientation. `w = 0` is the paper's model (nothing is turned).
//!
//! Orientations on both sides are measured on PCA-decoded coefficients, at training and at
//! prediction alike.

use capture::assemble::plan;
use capture::part_pca::{PartPca, PcaModel};
use mesh_core::rigid::{procrustes, so3_exp, so3_log};
use mesh_core::{Error, Result};
use nalgebra::{DMatrix, Matrix4, Matrix4x3, Rotation3, Vector3, Vector4};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// Default of `gpr-train --orientation-weight`: how far each limb is turned from the GP's
/// orientation toward the map's (docs/studies/06-limb-orientation.md).
pub const WEIGHT: f64 = 0.5;

/// Ridge of the maps, relative to the mean diagonal of the normal equations.
pub const RIDGE: f64 = 0.1;

/// The share of a limb's vertices, nearest its joint, that its orientation is measured on.
pub const PROXIMAL_SHARE: f64 = 0.5;

/// The share of the root part's vertices, nearest a limb's joint, that make its attachment.
pub const ATTACHMENT_SHARE: f64 = 0.2;

/// The frame a limb's orientation is measured and mapped in (module documentation).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum LimbFrame {
    /// The root part's frame.
    Root,
    /// The frame of the `share` of the root part's vertices nearest the limb's joint.
    Attachment { share: f64 },
}

/// A limb of a PCA model: its part index, the part-local vertices of its joint band and of
/// its proximal half.
#[derive(Clone, Debug, PartialEq)]
pub struct Limb {
    pub part: usize,
    pub joint: Vec<usize>,
    pub proximal: Vec<usize>,
}

/// Points of a flattened `(x1, y1, z1, x2, ...)` row.
fn points(flat: &[f64]) -> Vec<Vector3<f64>> {
    flat.chunks_exact(3).map(|c| Vector3::new(c[0], c[1], c[2])).collect()
}

fn mean_shape(part: &PartPca) -> Vec<Vector3<f64>> {
    points(part.pca.mean.as_slice())
}

/// The limbs of `pca`: every part after the root, with the band it shares with the parts
/// placed before it (its joint) and the [`PROXIMAL_SHARE`] of its vertices nearest the
/// joint's centroid in the mean shape (ties by vertex order).
pub fn limbs(pca: &PcaModel) -> Result<Vec<Limb>> {
    let plan = plan(pca)?;
    Ok(plan
        .steps
        .iter()
        .skip(1)
        .map(|step| {
            let mean = mean_shape(&pca.parts[step.part]);
            let joint = step.anchor_local.clone();
            let pivot = centroid(joint.iter().map(|&i| &mean[i]));
            let mut by_distance: Vec<(f64, usize)> =
                mean.iter().enumerate().map(|(i, p)| ((p - pivot).norm(), i)).collect();
            by_distance.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            let keep = ((mean.len() as f64) * PROXIMAL_SHARE).ceil().max(3.0) as usize;
            let mut proximal: Vec<usize> = by_distance.iter().take(keep).map(|&(_, i)| i).collect();
            proximal.sort_unstable();
            Limb { part: step.part, joint, proximal }
        })
        .collect())
}

fn centroid<'a>(points: impl Iterator<Item = &'a Vector3<f64>>) -> Vector3<f64> {
    let (sum, n) = points.fold((Vector3::zeros(), 0usize), |(s, n), p| (s + p, n + 1));
    sum / n.max(1) as f64
}

/// The rotation of `subset` of `reference` onto the same vertices of `frame` (Procrustes).
pub fn orientation(reference: &[Vector3<f64>], frame: &[Vector3<f64>], subset: &[usize]) -> Rotation3<f64> {
    let a: Vec<Vector3<f64>> = subset.iter().map(|&i| reference[i]).collect();
    let b: Vec<Vector3<f64>> = subset.iter().map(|&i| frame[i]).collect();
    procrustes(&a, &b, None).rotation
}

/// One limb's map of log-rotations, `log R_t = W[0..3]ᵀ log R_s + W[3]`, both measured in
/// `frame`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LimbMap {
    /// Rows: the coefficients of the source log-rotation's x, y, z, then the constant.
    pub w: [[f64; 3]; 4],
    pub frame: LimbFrame,
}

impl LimbMap {
    /// Ridge least squares of `target` on `[source, 1]`, shrunk toward the identity map
    /// (see the module documentation), `ridge` relative to the mean diagonal.
    pub fn fit(source: &[Vector3<f64>], target: &[Vector3<f64>], ridge: f64) -> Result<LimbMap> {
        if source.is_empty() || source.len() != target.len() {
            return Err(Error::invalid(format!(
                "limb orientation: {} source and {} target rotations",
                source.len(),
                target.len()
            )));
        }
        let mut xtx = Matrix4::<f64>::zeros();
        let mut xty = Matrix4x3::<f64>::zeros();
        for (x, y) in source.iter().zip(target) {
            let x1 = Vector4::new(x.x, x.y, x.z, 1.0);
            xtx += x1 * x1.transpose();
            xty += x1 * y.transpose();
        }
        let lambda = ridge * xtx.trace() / 4.0;
        let mut identity = Matrix4x3::<f64>::zeros();
        for i in 0..3 {
            identity[(i, i)] = 1.0;
        }
        let lhs = xtx + Matrix4::identity() * lambda;
        let rhs = xty + identity * lambda;
        let w = lhs
            .cholesky()
            .ok_or_else(|| Error::invalid("limb orientation: the normal equations are not positive definite"))?
            .solve(&rhs);
        Ok(LimbMap { w: std::array::from_fn(|r| std::array::from_fn(|c| w[(r, c)])), frame: LimbFrame::Root })
    }

    /// Consistency of a map read from a file.
    pub fn validate(&self) -> std::result::Result<(), String> {
        if self.w.iter().flatten().any(|x| !x.is_finite()) {
            return Err("a limb orientation map holds a non-finite number".into());
        }
        if let LimbFrame::Attachment { share } = self.frame {
            if !(share > 0.0 && share <= 1.0) {
                return Err(format!("limb attachment share {share} is not in (0, 1]"));
            }
        }
        Ok(())
    }

    /// The mapped log-rotation of `x`.
    pub fn apply(&self, x: &Vector3<f64>) -> Vector3<f64> {
        let w = &self.w;
        Vector3::from_fn(|c, _| x.x * w[0][c] + x.y * w[1][c] + x.z * w[2][c] + w[3][c])
    }
}

/// The limb maps of a model and how far they turn the GP's limbs (kept in the `gpr-model`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LimbOrientation {
    /// The geodesic share `w` of the turn toward the map's orientation, in `(0, 1]`.
    pub weight: f64,
    /// One per part of the PCA models, `None` for the root.
    pub maps: Vec<Option<LimbMap>>,
}

impl LimbOrientation {
    /// Consistency of a model read from a file with `n_parts` parts.
    pub fn validate(&self, n_parts: usize) -> std::result::Result<(), String> {
        if !(self.weight > 0.0 && self.weight <= 1.0) {
            return Err(format!("limb orientation weight {} is not in (0, 1]", self.weight));
        }
        if self.maps.len() != n_parts {
            return Err(format!("{} limb orientation maps for {n_parts} parts", self.maps.len()));
        }
        self.maps.iter().flatten().try_for_each(LimbMap::validate)
    }
}

/// The orientations of the vertices `subset` of `part` in the decoded coefficient rows `coeffs`.
pub fn orientations(part: &PartPca, subset: &[usize], coeffs: &DMatrix<f64>) -> Result<Vec<Rotation3<f64>>> {
    let mean = mean_shape(part);
    let mut out = Vec::with_capacity(coeffs.nrows());
    // Decoded a block of rows at a time: a training set's rows decoded whole would be the
    // part's vertices for every pair (GBs at 10^5 pairs).
    for block in gp::linalg::blocks(coeffs.nrows()) {
        let rows = part
            .pca
            .decode(&coeffs.rows(block.start, block.len()).into_owned())
            .map_err(|e| Error::invalid(format!("part '{}': {e}", part.name)))?;
        out.par_extend((0..rows.nrows()).into_par_iter().map(|r| {
            let row: Vec<f64> = rows.row(r).iter().copied().collect();
            orientation(&mean, &points(&row), subset)
        }));
    }
    Ok(out)
}

/// The root part's vertices (local indices) that make `limb`'s attachment: the `share` of them
/// nearest the centroid of the limb's joint band, both in their mean shapes (ties by index).
pub fn attachment(pca: &PcaModel, root: usize, limb: &Limb, share: f64) -> Vec<usize> {
    let limb_mean = mean_shape(&pca.parts[limb.part]);
    let joint = centroid(limb.joint.iter().map(|&i| &limb_mean[i]));
    let root_mean = mean_shape(&pca.parts[root]);
    let mut by_distance: Vec<(f64, usize)> = root_mean.iter().enumerate().map(|(i, p)| ((p - joint).norm(), i)).collect();
    by_distance.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    let keep = ((root_mean.len() as f64) * share).ceil().max(3.0) as usize;
    let mut near: Vec<usize> = by_distance.iter().take(keep).map(|&(_, i)| i).collect();
    near.sort_unstable();
    near
}

/// The log-orientations of `limb` of `pca` in the coefficient rows `coeffs` (one matrix per
/// part), measured in `frame`.
fn log_orientations(pca: &PcaModel, limb: &Limb, frame: LimbFrame, coeffs: &[DMatrix<f64>]) -> Result<Vec<Vector3<f64>>> {
    let turns = orientations(&pca.parts[limb.part], &limb.proximal, &coeffs[limb.part])?;
    Ok(match frame {
        LimbFrame::Root => turns.iter().map(so3_log).collect(),
        LimbFrame::Attachment { share } => {
            let root = plan(pca)?.steps[0].part;
            let frames = orientations(&pca.parts[root], &attachment(pca, root, limb, share), &coeffs[root])?;
            frames.iter().zip(&turns).map(|(a, r)| so3_log(&(a.inverse() * r))).collect()
        }
    })
}

/// The frame of each part's map in `pca` (by part index): the attachment's
/// ([`ATTACHMENT_SHARE`]) for the limbs named in `attached`, the root's for the others. A name
/// that is not a limb of `pca` is an error, unless `pca` has no limbs (a whole-body model).
pub fn frames(pca: &PcaModel, attached: &[String]) -> Result<Vec<LimbFrame>> {
    let limbs = limbs(pca)?;
    let is_limb = |name: &str| limbs.iter().any(|l| pca.parts[l.part].name == name);
    if !limbs.is_empty() {
        if let Some(bad) = attached.iter().find(|n| !is_limb(n)) {
            let names: Vec<&str> = limbs.iter().map(|l| pca.parts[l.part].name.as_str()).collect();
            return Err(Error::invalid(format!("attached limb '{bad}' is not a limb of the PCA models (limbs: {})", names.join(", "))));
        }
    }
    Ok(pca
        .parts
        .iter()
        .map(|p| if attached.contains(&p.name) && is_limb(&p.name) { LimbFrame::Attachment { share: ATTACHMENT_SHARE } } else { LimbFrame::Root })
        .collect())
}

/// The limb of part `k` in both models, or `None` when `k` is the root.
fn limb_pair<'a>(source: &'a [Limb], target: &'a [Limb], k: usize) -> Option<(&'a Limb, &'a Limb)> {
    Some((source.iter().find(|l| l.part == k)?, target.iter().find(|l| l.part == k)?))
}

/// The map of part `k`, measured in `frame`, from the training rows `x` (source coefficients)
/// and `y` (target coefficients), one matrix per part; `None` for the root. The models' parts
/// correspond by index.
pub fn fit_part(source: &PcaModel, target: &PcaModel, k: usize, frame: LimbFrame, x: &[DMatrix<f64>], y: &[DMatrix<f64>]) -> Result<Option<LimbMap>> {
    let (ls, lt) = (limbs(source)?, limbs(target)?);
    let Some((s, t)) = limb_pair(&ls, &lt, k) else {
        return Ok(None);
    };
    let xs = log_orientations(source, s, frame, x)?;
    let ys = log_orientations(target, t, frame, y)?;
    Ok(Some(LimbMap { frame, ..LimbMap::fit(&xs, &ys, RIDGE)? }))
}

/// The limb log-orientations of every frame of a list of training pairs, measured once, so that
/// the maps of many subsets of their rows (cross-validation folds) are fitted without decoding
/// a frame again. Fitting from them gives the map [`fit_part`] fits on the same rows.
pub struct PairLogs {
    /// Per part (`None`: the root): its frame and, per pair, the source and the target frames'
    /// log-orientations.
    parts: Vec<Option<(LimbFrame, Vec<[Vec<Vector3<f64>>; 2]>)>>,
}

impl PairLogs {
    /// The log-orientations of each pair's frames, `pairs` giving each pair's source and target
    /// coefficients (one matrix per part), each part measured in `frames[k]`.
    pub fn new(source: &PcaModel, target: &PcaModel, frames: &[LimbFrame], pairs: &[(&[DMatrix<f64>], &[DMatrix<f64>])]) -> Result<PairLogs> {
        let (ls, lt) = (limbs(source)?, limbs(target)?);
        let parts = (0..frames.len())
            .map(|k| {
                let Some((s, t)) = limb_pair(&ls, &lt, k) else { return Ok(None) };
                let per_pair = pairs
                    .iter()
                    .map(|(x, y)| Ok([log_orientations(source, s, frames[k], x)?, log_orientations(target, t, frames[k], y)?]))
                    .collect::<Result<_>>()?;
                Ok(Some((frames[k], per_pair)))
            })
            .collect::<Result<_>>()?;
        Ok(PairLogs { parts })
    }

    /// The map of part `k` fitted on the rows `origin` (`[pair, source frame, target frame]`),
    /// `pair_of` turning a row's pair index into an index of the pairs given to [`PairLogs::new`].
    pub fn fit(&self, k: usize, origin: &[[usize; 3]], pair_of: &dyn Fn(usize) -> usize) -> Result<Option<LimbMap>> {
        let Some((frame, per_pair)) = &self.parts[k] else { return Ok(None) };
        let lookup = |side: usize, p: usize, f: usize| {
            per_pair.get(pair_of(p)).and_then(|logs| logs[side].get(f)).copied().ok_or_else(|| Error::invalid(format!("limb orientation: no frame {f} in training pair {p}")))
        };
        let xs = origin.iter().map(|&[p, i, _]| lookup(0, p, i)).collect::<Result<Vec<_>>>()?;
        let ys = origin.iter().map(|&[p, _, j]| lookup(1, p, j)).collect::<Result<Vec<_>>>()?;
        Ok(Some(LimbMap { frame: *frame, ..LimbMap::fit(&xs, &ys, RIDGE)? }))
    }
}

/// Turns every limb of the decoded target parts (`decoded[part][frame]`, predicted from the
/// source coefficients `source_coeffs`) about its joint, as the module documentation says.
pub fn apply(
    model: &LimbOrientation,
    source: &PcaModel,
    target: &PcaModel,
    source_coeffs: &[DMatrix<f64>],
    decoded: &mut [Vec<Vec<Vector3<f64>>>],
) -> Result<()> {
    if model.maps.len() != target.parts.len() || decoded.len() != target.parts.len() || source_coeffs.len() != source.parts.len() {
        return Err(Error::invalid(format!(
            "limb orientation of {} parts for PCA models of {} and {} parts",
            model.maps.len(),
            source.parts.len(),
            target.parts.len()
        )));
    }
    let (ls, lt) = (limbs(source)?, limbs(target)?);
    let root = plan(target)?.steps[0].part;
    for (k, map) in model.maps.iter().enumerate() {
        let (Some(map), Some((s, t))) = (map, limb_pair(&ls, &lt, k)) else {
            continue;
        };
        let sources = log_orientations(source, s, map.frame, source_coeffs)?;
        if sources.len() != decoded[k].len() || decoded[root].len() != decoded[k].len() {
            return Err(Error::invalid(format!(
                "part '{}': {} source frames for {} predicted",
                target.parts[k].name,
                sources.len(),
                decoded[k].len()
            )));
        }
        // The target's attachment as its predicted root part has it (the root is never turned).
        let attached: Vec<Rotation3<f64>> = match map.frame {
            LimbFrame::Root => vec![Rotation3::identity(); sources.len()],
            LimbFrame::Attachment { share } => {
                let (root_mean, near) = (mean_shape(&target.parts[root]), attachment(target, root, t, share));
                decoded[root].par_iter().map(|f| orientation(&root_mean, f, &near)).collect()
            }
        };
        let mean = mean_shape(&target.parts[k]);
        decoded[k].par_iter_mut().zip(&sources).zip(&attached).for_each(|((frame, x), a)| {
            let now = orientation(&mean, frame, &t.proximal);
            let mapped = a * so3_exp(&map.apply(x));
            let want = now * so3_exp(&(model.weight * so3_log(&(now.inverse() * mapped))));
            turn_to(frame, t, &now, &want);
        });
    }
    Ok(())
}

/// Turns the limb `frame` of `limb` about its joint (the centroid of its joint band) from its
/// orientation `now` ([`orientation`] against the part's PCA mean shape) to `want`.
pub fn turn_to(frame: &mut [Vector3<f64>], limb: &Limb, now: &Rotation3<f64>, want: &Rotation3<f64>) {
    let turn = want * now.inverse();
    let pivot = centroid(limb.joint.iter().map(|&i| &frame[i]));
    for p in frame.iter_mut() {
        *p = pivot + turn * (*p - pivot);
    }
}

/// The mean shape of part `k` of `pca`, the reference of its orientations.
pub fn reference(pca: &PcaModel, k: usize) -> Vec<Vector3<f64>> {
    mean_shape(&pca.parts[k])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_fixtures::bending_capsule;
    use capture::align::AlignedMotion;
    use capture::part_pca::{fit as pca_fit, PartAlignment};
    use gp::pca::Components;
    use rand::{RngExt, SeedableRng};

    /// The capsule of [`bending_capsule`], whose limb turns about the z axis by a different
    /// angle in each frame, and its PCA.
    fn turning_limb() -> (PcaModel, AlignedMotion) {
        let (mesh, seg, motion) = bending_capsule();
        let (pca, _) = pca_fit(&mesh.vertices, &seg, &[&motion], Components::Count(20), PartAlignment::Body).unwrap();
        (pca, motion)
    }

    /// Distance of two rotations (Frobenius norm of the difference: precise near zero).
    fn apart(a: &Rotation3<f64>, b: &Rotation3<f64>) -> f64 {
        (a.matrix() - b.matrix()).norm()
    }

    /// The turn of a rigidly turned point set is its orientation, whatever the subset.
    #[test]
    fn orientation_of_a_turned_set_is_the_turn() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let reference: Vec<Vector3<f64>> =
            (0..40).map(|_| Vector3::new(rng.random::<f64>(), rng.random::<f64>(), rng.random::<f64>())).collect();
        let turn = so3_exp(&Vector3::new(0.3, -0.7, 0.4));
        let moved: Vec<Vector3<f64>> = reference.iter().map(|p| turn * p + Vector3::new(1.0, 2.0, 3.0)).collect();
        for subset in [(0..40).collect::<Vec<_>>(), vec![1, 5, 9, 30]] {
            let r = orientation(&reference, &moved, &subset);
            assert!(apart(&r, &turn) < 1e-9);
        }
    }

    /// Exact affine data give back the map; an overwhelming ridge gives the identity map.
    #[test]
    fn map_fit_recovers_a_known_map_and_shrinks_toward_the_identity() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let m = nalgebra::Matrix3::new(0.9, 0.1, 0.0, -0.2, 1.3, 0.05, 0.0, 0.3, 0.7);
        let b = Vector3::new(0.05, -0.1, 0.2);
        let xs: Vec<Vector3<f64>> = (0..60).map(|_| Vector3::from_fn(|_, _| rng.random::<f64>() * 2.0 - 1.0)).collect();
        let ys: Vec<Vector3<f64>> = xs.iter().map(|x| m * x + b).collect();
        let exact = LimbMap::fit(&xs, &ys, 1e-12).unwrap();
        for x in &xs {
            assert!((exact.apply(x) - (m * x + b)).norm() < 1e-8);
        }
        let shrunk = LimbMap::fit(&xs, &ys, 1e9).unwrap();
        for x in &xs {
            assert!((shrunk.apply(x) - x).norm() < 1e-6);
        }
        assert!(LimbMap::fit(&xs, &ys[1..], 0.1).is_err());
    }

    /// The limb is the part after the root; its joint is its band with the torso and its
    /// proximal half the half of its vertices nearest that band.
    #[test]
    fn limbs_are_the_parts_after_the_root_with_joint_and_proximal_half() {
        let (pca, _) = turning_limb();
        let limbs = limbs(&pca).unwrap();
        assert_eq!(limbs.len(), 1);
        let limb = &limbs[0];
        assert_eq!(limb.part, 1);
        let torso: std::collections::HashSet<u32> = pca.parts[0].vertices.iter().copied().collect();
        let shared: Vec<usize> = (0..pca.parts[1].vertices.len()).filter(|&i| torso.contains(&pca.parts[1].vertices[i])).collect();
        assert_eq!(limb.joint, shared);
        let n = pca.parts[1].vertices.len();
        assert_eq!(limb.proximal.len(), n.div_ceil(2));
        let mean = mean_shape(&pca.parts[1]);
        let pivot = centroid(limb.joint.iter().map(|&i| &mean[i]));
        let far = (0..n).filter(|i| !limb.proximal.contains(i)).map(|i| (mean[i] - pivot).norm()).fold(f64::INFINITY, f64::min);
        assert!(limb.proximal.iter().all(|&i| (mean[i] - pivot).norm() <= far));
    }

    /// In its attachment's frame a limb is carried with the root region it hangs from: with the
    /// identity map at weight 1, a target whose root part is the source's turned by `q` gets each
    /// limb turned to `A_t A_s⁻¹ R_s = q R_s` (`A` the attachment's orientations, `R_s` the
    /// source limb's), whatever the limb was; the root part is not moved.
    #[test]
    fn attachment_frame_carries_the_limb_with_its_attachment() {
        let (pca, motion) = turning_limb();
        let xs = pca.encode(&motion).unwrap();
        let source = pca.decode(&xs).unwrap();
        let limb = limbs(&pca).unwrap().remove(0);
        let near = attachment(&pca, 0, &limb, ATTACHMENT_SHARE);
        assert_eq!(near.len(), (pca.parts[0].vertices.len() as f64 * ATTACHMENT_SHARE).ceil() as usize);
        let (mean, root_mean) = (mean_shape(&pca.parts[1]), mean_shape(&pca.parts[0]));
        let q = so3_exp(&Vector3::new(0.1, -0.2, 0.3));
        let frame = LimbFrame::Attachment { share: ATTACHMENT_SHARE };
        let identity = LimbMap { w: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [0.0; 3]], frame };
        let model = LimbOrientation { weight: 1.0, maps: vec![None, Some(identity)] };
        let mut decoded = source.clone();
        for f in decoded[0].iter_mut() {
            f.iter_mut().for_each(|p| *p = q * *p + Vector3::new(0.3, -1.0, 2.0));
        }
        decoded[1].iter_mut().for_each(|f| *f = mean.clone());
        let root_before = decoded[0].clone();
        apply(&model, &pca, &pca, &xs, &mut decoded).unwrap();
        assert_eq!(decoded[0], root_before);
        for (f, frame) in decoded[1].iter().enumerate() {
            let (a_s, a_t) = (orientation(&root_mean, &source[0][f], &near), orientation(&root_mean, &decoded[0][f], &near));
            assert!(apart(&a_t, &(q * a_s)) < 1e-9);
            let want = q * orientation(&mean, &source[1][f], &limb.proximal);
            let got = orientation(&mean, frame, &limb.proximal);
            assert!(apart(&got, &want) < 1e-9, "frame {f}: {}", apart(&got, &want));
        }
        // In the root frame the same map ignores the root's turn: the limb gets R_s.
        let root_model = LimbOrientation { weight: 1.0, maps: vec![None, Some(LimbMap { frame: LimbFrame::Root, ..model.maps[1].clone().unwrap() })] };
        decoded[1].iter_mut().for_each(|f| *f = mean.clone());
        apply(&root_model, &pca, &pca, &xs, &mut decoded).unwrap();
        for (f, frame) in decoded[1].iter().enumerate() {
            assert!(apart(&orientation(&mean, frame, &limb.proximal), &orientation(&mean, &source[1][f], &limb.proximal)) < 1e-9);
        }
        // A share outside (0, 1] is refused.
        let bad = LimbMap { frame: LimbFrame::Attachment { share: 0.0 }, ..model.maps[1].clone().unwrap() };
        assert!(LimbOrientation { weight: 1.0, maps: vec![None, Some(bad)] }.validate(2).is_err());
    }

    /// The maps fitted from the pairs' log-orientations are the maps `fit_part` fits on the same
    /// rows' coefficients, for rows drawn from two pairs in any order (a pair's frames repeated,
    /// skipped, matched out of order), in the root's and the attachment's frame; a row naming a
    /// frame a pair does not have is an error.
    #[test]
    fn maps_from_the_pairs_log_orientations_are_the_maps_of_the_rows() {
        let (pca, motion) = turning_limb();
        let xs = pca.encode(&motion).unwrap();
        let f = xs[0].nrows();
        let reversed: Vec<DMatrix<f64>> = xs.iter().map(|m| DMatrix::from_fn(f, m.ncols(), |r, c| m[(f - 1 - r, c)])).collect();
        let pairs: [(&[DMatrix<f64>], &[DMatrix<f64>]); 2] = [(&xs, &reversed), (&reversed, &xs)];
        let origin: Vec<[usize; 3]> = vec![[1, 0, 2], [0, 3, 3], [0, 3, 4], [1, 7, 0], [0, 1, 6], [1, 2, 2], [0, 6, 1]];
        let rows = |side: usize| -> Vec<DMatrix<f64>> {
            (0..xs.len())
                .map(|k| DMatrix::from_fn(origin.len(), xs[k].ncols(), |r, c| {
                    let [p, i, j] = origin[r];
                    let m = if side == 0 { pairs[p].0 } else { pairs[p].1 };
                    m[k][(if side == 0 { i } else { j }, c)]
                }))
                .collect()
        };
        let (x, y) = (rows(0), rows(1));
        for attached in [vec![], vec!["limb".to_string()]] {
            let frames = frames(&pca, &attached).unwrap();
            let logs = PairLogs::new(&pca, &pca, &frames, &pairs).unwrap();
            for k in 0..2 {
                let want = fit_part(&pca, &pca, k, frames[k], &x, &y).unwrap();
                assert_eq!(logs.fit(k, &origin, &|p| p).unwrap(), want, "part {k}, {attached:?}");
            }
            assert!(logs.fit(1, &origin, &|p| 1 - p).unwrap() != fit_part(&pca, &pca, 1, frames[1], &x, &y).unwrap(), "the pairs as named");
            assert!(logs.fit(1, &[[0, f, 0]], &|p| p).unwrap_err().to_string().contains("no frame 8 in training pair 0"));
        }
    }

    /// Named limbs get the attachment's frame, the others the root's; a name that is not a limb
    /// (the root, a typo) is refused.
    #[test]
    fn frames_follow_the_named_limbs() {
        let (pca, _) = turning_limb();
        let attached = LimbFrame::Attachment { share: ATTACHMENT_SHARE };
        assert_eq!(frames(&pca, &[]).unwrap(), vec![LimbFrame::Root, LimbFrame::Root]);
        assert_eq!(frames(&pca, &["limb".to_string()]).unwrap(), vec![LimbFrame::Root, attached]);
        for bad in ["torso", "arm_l"] {
            let e = frames(&pca, &[bad.to_string()]).unwrap_err().to_string();
            assert!(e.contains(&format!("'{bad}' is not a limb")) && e.contains("limbs: limb"), "{e}");
        }
    }

    /// A prediction that never turns the limb (its mean shape in every frame), with the
    /// identity map: weight 1 turns each frame's limb to the source's orientation, weight 0.5
    /// half way (the geodesic midpoint), and the joint stays where it was.
    #[test]
    fn apply_turns_limbs_about_the_joint_toward_the_mapped_orientation() {
        let (pca, motion) = turning_limb();
        let xs = pca.encode(&motion).unwrap();
        let source = pca.decode(&xs).unwrap();
        let limb = limbs(&pca).unwrap().remove(0);
        let mean = mean_shape(&pca.parts[1]);
        let identity = LimbMap { w: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [0.0; 3]], frame: LimbFrame::Root };
        for weight in [1.0, 0.5] {
            let model = LimbOrientation { weight, maps: vec![None, Some(identity.clone())] };
            let mut decoded = source.clone();
            decoded[1].iter_mut().for_each(|f| *f = mean.clone());
            apply(&model, &pca, &pca, &xs, &mut decoded).unwrap();
            assert_eq!(decoded[0], source[0], "the root is not moved");
            for (f, frame) in decoded[1].iter().enumerate() {
                let want = so3_exp(&(weight * so3_log(&orientation(&mean, &source[1][f], &limb.proximal))));
                let got = orientation(&mean, frame, &limb.proximal);
                assert!(apart(&got, &want) < 1e-9, "frame {f}, weight {weight}: {}", apart(&got, &want));
                let joint = |x: &[Vector3<f64>]| centroid(limb.joint.iter().map(|&i| &x[i]));
                assert!((joint(frame) - joint(&mean)).norm() < 1e-12);
            }
        }
        // Weight 0 is not a model: gpr-train stores none.
        assert!(LimbOrientation { weight: 0.0, maps: vec![None, None] }.validate(2).is_err());
    }
}
