//! The distal (bend) map of the limb studies (docs/studies/06-limb-orientation.md): each limb's
//! distal half
//! (the vertices farther from its joint than the proximal half) has a rotation relative to the
//! proximal half's; an affine map of that relative log-rotation, source to target, is fitted on
//! the training pairs like the proximal map (ridge 0.1 toward the identity), and at prediction
//! the distal half is turned about the elbow (the proximal vertices farthest from the joint, the
//! last fifth) by the geodesic weight w toward the map's bend, ramped in smoothly over the
//! vertices between 40 % and 60 % of the limb's distance ranks.

use capture::part_pca::PcaModel;
use mesh_core::rigid::{so3_exp, so3_log};
use nalgebra::{DMatrix, Rotation3, Vector3};
use transfer::gpr_model::TrainingSet;
use transfer::limb_orientation::{limbs, orientation, reference, Limb, LimbMap};

#[allow(dead_code)]
fn points(flat: &[f64]) -> Vec<Vector3<f64>> {
    flat.chunks_exact(3).map(|c| Vector3::new(c[0], c[1], c[2])).collect()
}

#[allow(dead_code)]
fn smoothstep(x: f64) -> f64 {
    let x = x.clamp(0.0, 1.0);
    x * x * (3.0 - 2.0 * x)
}

/// A limb's distal half, the rank of every vertex by distance from the joint in the mean shape
/// (0 nearest, 1 farthest), and its elbow vertices.
pub struct Bend {
    pub distal: Vec<usize>,
    pub rank: Vec<f64>,
    pub elbow: Vec<usize>,
}

pub fn bend(limb: &Limb, mean: &[Vector3<f64>]) -> Bend {
    let n = mean.len();
    let jc = limb.joint.iter().map(|&i| mean[i]).sum::<Vector3<f64>>() / limb.joint.len() as f64;
    let mut order: Vec<(f64, usize)> = mean.iter().enumerate().map(|(i, p)| ((p - jc).norm(), i)).collect();
    order.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    let mut rank = vec![0.0; n];
    for (r, &(_, i)) in order.iter().enumerate() {
        rank[i] = r as f64 / (n - 1).max(1) as f64;
    }
    let distal: Vec<usize> = (0..n).filter(|i| limb.proximal.binary_search(i).is_err()).collect();
    let mut prox: Vec<(f64, usize)> = limb.proximal.iter().map(|&i| (rank[i], i)).collect();
    prox.sort_by(|a, b| b.0.total_cmp(&a.0));
    let elbow = prox.iter().take((prox.len() / 5).max(1)).map(|x| x.1).collect();
    Bend { distal, rank, elbow }
}

/// The distal half's rotation relative to the proximal half's.
#[allow(dead_code)]
fn relative(mean: &[Vector3<f64>], frame: &[Vector3<f64>], limb: &Limb, b: &Bend) -> Rotation3<f64> {
    orientation(mean, frame, &limb.proximal).inverse() * orientation(mean, frame, &b.distal)
}

/// Per limb of the target, the bend map fitted on the training rows.
#[allow(dead_code)]
pub struct BendMaps {
    pairs: Vec<(Limb, Limb, LimbMap)>,
}

#[allow(dead_code)]
fn bends(pca: &PcaModel, limb: &Limb, coeffs: &DMatrix<f64>) -> Vec<Vector3<f64>> {
    let mean = reference(pca, limb.part);
    let b = bend(limb, &mean);
    let decoded = pca.parts[limb.part].pca.decode(coeffs).unwrap();
    (0..decoded.nrows())
        .map(|r| {
            let row: Vec<f64> = decoded.row(r).iter().copied().collect();
            so3_log(&relative(&mean, &points(&row), limb, &b))
        })
        .collect()
}

#[allow(dead_code)]
impl BendMaps {
    pub fn fit(spca: &PcaModel, tpca: &PcaModel, rows: &TrainingSet) -> anyhow::Result<BendMaps> {
        let (ls, lt) = (limbs(spca)?, limbs(tpca)?);
        let pairs = ls
            .into_iter()
            .zip(lt)
            .map(|(sl, tl)| {
                let map = LimbMap::fit(&bends(spca, &sl, &rows.x_parts[sl.part]), &bends(tpca, &tl, &rows.y_parts[tl.part]), 0.1)?;
                Ok((sl, tl, map))
            })
            .collect::<anyhow::Result<_>>()?;
        Ok(BendMaps { pairs })
    }

    /// Turns the distal halves of `decoded[part][frame]`, predicted from `xs`, by weight `w`.
    pub fn turn(&self, spca: &PcaModel, tpca: &PcaModel, xs: &[DMatrix<f64>], decoded: &mut [Vec<Vec<Vector3<f64>>>], w: f64) {
        for (sl, tl, map) in &self.pairs {
            let k = tl.part;
            let tmean = reference(tpca, k);
            let b = bend(tl, &tmean);
            let src = bends(spca, sl, &xs[k]);
            for (frame, x) in decoded[k].iter_mut().zip(&src) {
                let prox = orientation(&tmean, frame, &tl.proximal);
                let now = relative(&tmean, frame, tl, &b);
                let want = now * so3_exp(&(w * so3_log(&(now.inverse() * so3_exp(&map.apply(x))))));
                // World turn of the distal half, ramped in across the elbow.
                let turn = so3_log(&(prox * want * now.inverse() * prox.inverse()));
                let pivot = b.elbow.iter().map(|&i| frame[i]).sum::<Vector3<f64>>() / b.elbow.len() as f64;
                for (i, p) in frame.iter_mut().enumerate() {
                    let a = smoothstep((b.rank[i] - 0.4) / 0.2);
                    if a > 0.0 {
                        *p = pivot + so3_exp(&(turn * a)) * (*p - pivot);
                    }
                }
            }
        }
    }
}
