//! The training meshes nearest a predicted mesh (transfer paper §6.1, step 1): the `m` meshes of
//! least root-mean-square vertex distance `d_k = sqrt(mean_v |P_v - N_k,v|²)`, nearest first,
//! ties to the lower index ([`brute_force`] is the definition).
//!
//! [`MeshSearch`] finds the same meshes for many predictions at once. With every mesh a vector
//! of `D = 3|V|` coordinates, centred on the training meshes' mean `μ` (`p = P - μ`,
//! `t_k = N_k - μ`), the squared distances of a block of predictions to a block of training
//! meshes are `|p|² + |t_k|² - 2 pᵀt_k`: one matrix product per block pair. In floating point
//! each such value `s̃_k` is within `δ_k = 4 (D + 16) ε (|p|² + |t_k|²)` of the true `|P - N_k|²`
//! (the rounding of the centring, `γ_D` for each of the three sums; ε the machine epsilon), so
//! with `τ` the `m`-th smallest upper bound `s̃_k + δ_k`, every mesh of the `m` nearest has
//! `s̃_k - δ_k ≤ τ`. Those candidates, widened by the relative error `4 (D + 16) ε` of the exact
//! distance itself, then take the exact distance of [`brute_force`] and the same sort: the
//! chosen meshes and their distances are [`brute_force`]'s, bit for bit.

use faer::{Accum, Mat, Par};
use nalgebra::Vector3;
use rayon::prelude::*;

/// Predictions per matrix product (and per parallel task).
const PREDICTION_BLOCK: usize = 32;
/// Training meshes per matrix product.
const TRAINING_BLOCK: usize = 128;

/// Root-mean-square vertex distance.
pub fn vertex_distance(a: &[Vector3<f64>], b: &[Vector3<f64>]) -> f64 {
    (a.iter()
        .zip(b)
        .map(|(p, q)| (p - q).norm_squared())
        .sum::<f64>()
        / a.len().max(1) as f64)
        .sqrt()
}

/// The `m` (at least 1) training meshes nearest `prediction` by [`vertex_distance`]:
/// (index, distance), nearest first, equal distances by index.
pub fn brute_force(
    training: &[Vec<Vector3<f64>>],
    prediction: &[Vector3<f64>],
    m: usize,
) -> Vec<(usize, f64)> {
    let candidates: Vec<usize> = (0..training.len()).collect();
    exact(training, prediction, &candidates, m)
}

/// The `m` nearest of `candidates` by [`vertex_distance`].
fn exact(
    training: &[Vec<Vector3<f64>>],
    prediction: &[Vector3<f64>],
    candidates: &[usize],
    m: usize,
) -> Vec<(usize, f64)> {
    let mut d: Vec<(usize, f64)> = candidates
        .iter()
        .map(|&k| (k, vertex_distance(prediction, &training[k])))
        .collect();
    d.sort_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)));
    d.truncate(m.max(1));
    d
}

/// The training meshes' mean and centred squared norms, for [`MeshSearch::nearest`].
pub struct MeshSearch {
    /// `μ`, `D` coordinates.
    mean: Vec<f64>,
    /// `|t_k|²` of every centred training mesh, as the products see it.
    norms: Vec<f64>,
}

/// Writes `x - μ` into `out` and returns its squared norm.
fn centre(x: &[Vector3<f64>], mean: &[f64], out: &mut [f64]) -> f64 {
    let mut s = 0.0;
    for ((o, &c), &mu) in out
        .iter_mut()
        .zip(x.iter().flat_map(|v| v.iter()))
        .zip(mean)
    {
        *o = c - mu;
        s += *o * *o;
    }
    s
}

impl MeshSearch {
    /// `training`: meshes of one vertex count.
    pub fn new(training: &[Vec<Vector3<f64>>]) -> Self {
        let d = 3 * training.first().map_or(0, Vec::len);
        let mut mean = vec![0.0; d];
        for t in training {
            mean.iter_mut()
                .zip(t.iter().flat_map(|v| v.iter()))
                .for_each(|(m, &c)| *m += c);
        }
        let k = training.len().max(1) as f64;
        mean.iter_mut().for_each(|m| *m /= k);
        let mut column = vec![0.0; d];
        let norms = training
            .iter()
            .map(|t| centre(t, &mean, &mut column))
            .collect();
        MeshSearch { mean, norms }
    }

    /// [`brute_force`] for every prediction: `training` is the set the search was built on.
    pub fn nearest(
        &self,
        training: &[Vec<Vector3<f64>>],
        predictions: &[Vec<Vector3<f64>>],
        m: usize,
    ) -> Vec<Vec<(usize, f64)>> {
        let m = m.max(1);
        if training.len() <= m || self.norms.len() != training.len() {
            return predictions
                .par_iter()
                .map(|p| brute_force(training, p, m))
                .collect();
        }
        predictions
            .par_chunks(PREDICTION_BLOCK)
            .flat_map_iter(|block| self.block(training, block, m))
            .collect()
    }

    /// One block of predictions against every training mesh.
    fn block(
        &self,
        training: &[Vec<Vector3<f64>>],
        predictions: &[Vec<Vector3<f64>>],
        m: usize,
    ) -> Vec<Vec<(usize, f64)>> {
        let (d, k, b) = (self.mean.len(), training.len(), predictions.len());
        let mut p = Mat::<f64>::zeros(d, b);
        let mut p_norm = vec![0.0; b];
        for (j, x) in predictions.iter().enumerate() {
            if x.len() * 3 != d {
                p_norm[j] = f64::NAN;
                continue;
            }
            p_norm[j] = centre(x, &self.mean, p.col_as_slice_mut(j));
        }
        // approx[j k + i]: the squared distance of prediction j to training mesh i.
        let mut approx = vec![0.0; b * k];
        let tb = TRAINING_BLOCK.min(k);
        let mut t = Mat::<f64>::zeros(d, tb);
        let mut g = Mat::<f64>::zeros(tb, b);
        for start in (0..k).step_by(tb) {
            let len = tb.min(k - start);
            for c in 0..len {
                centre(&training[start + c], &self.mean, t.col_as_slice_mut(c));
            }
            faer::linalg::matmul::matmul(
                g.as_mut().subrows_mut(0, len),
                Accum::Replace,
                t.as_ref().subcols(0, len).transpose(),
                p.as_ref(),
                1.0,
                Par::Seq,
            );
            for j in 0..b {
                for c in 0..len {
                    approx[j * k + start + c] =
                        p_norm[j] + self.norms[start + c] - 2.0 * g[(c, j)];
                }
            }
        }
        let slack = 4.0 * (d as f64 + 16.0) * f64::EPSILON;
        predictions
            .iter()
            .enumerate()
            .map(|(j, x)| {
                let row = &approx[j * k..(j + 1) * k];
                if !p_norm[j].is_finite() || row.iter().any(|a| !a.is_finite()) {
                    return brute_force(training, x, m);
                }
                let bound = |i: usize| slack * (p_norm[j] + self.norms[i]);
                let mut upper: Vec<f64> = row.iter().enumerate().map(|(i, a)| a + bound(i)).collect();
                let tau = *upper.select_nth_unstable_by(m - 1, f64::total_cmp).1;
                let cutoff = tau + slack * tau.abs();
                let candidates: Vec<usize> = (0..k).filter(|&i| row[i] - bound(i) <= cutoff).collect();
                exact(training, x, &candidates, m)
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lcg(state: &mut u64) -> f64 {
        *state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (*state >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Random meshes near a common shape, with exact duplicates and copies moved by a few
    /// units in the last place: the blocked search chooses [`brute_force`]'s meshes and
    /// distances, bit for bit, for every `m`.
    #[test]
    fn the_blocked_search_picks_the_brute_force_meshes_including_near_ties() {
        let mut s = 7u64;
        let n = 200;
        let base: Vec<Vector3<f64>> = (0..n)
            .map(|_| Vector3::new(lcg(&mut s), 5.0 + lcg(&mut s), lcg(&mut s)))
            .collect();
        let jitter = |s: &mut u64, x: &[Vector3<f64>], a: f64| -> Vec<Vector3<f64>> {
            x.iter()
                .map(|v| v + a * Vector3::new(lcg(s) - 0.5, lcg(s) - 0.5, lcg(s) - 0.5))
                .collect()
        };
        let mut training: Vec<Vec<Vector3<f64>>> = (0..300).map(|_| jitter(&mut s, &base, 0.1)).collect();
        for i in 0..40 {
            // An exact duplicate, and a copy of one vertex moved by one ulp.
            training.push(training[3 * i].clone());
            let mut near = training[3 * i + 1].clone();
            near[i].x = f64::from_bits(near[i].x.to_bits() + 1 + (i as u64 % 3));
            training.push(near);
        }
        let mut predictions: Vec<Vec<Vector3<f64>>> = (0..70).map(|_| jitter(&mut s, &base, 0.1)).collect();
        predictions.extend((0..20).map(|i| training[5 * i].clone()));
        // Equidistant from two training meshes: their midpoint.
        predictions.extend((0..10).map(|i| {
            training[i].iter().zip(&training[i + 1]).map(|(a, b)| 0.5 * (a + b)).collect()
        }));
        let search = MeshSearch::new(&training);
        for m in [1, 3, 7] {
            let fast = search.nearest(&training, &predictions, m);
            for (j, p) in predictions.iter().enumerate() {
                let want = brute_force(&training, p, m);
                assert_eq!(fast[j].len(), m);
                assert!(
                    fast[j].iter().zip(&want).all(|(a, b)| a.0 == b.0 && a.1.to_bits() == b.1.to_bits()),
                    "m = {m}, prediction {j}: {:?} against {want:?}",
                    fast[j]
                );
            }
        }
    }

    /// Fewer training meshes than asked for: all of them, nearest first.
    #[test]
    fn with_fewer_meshes_than_m_every_mesh_is_returned() {
        let training = vec![
            vec![Vector3::new(2.0, 0.0, 0.0)],
            vec![Vector3::new(1.0, 0.0, 0.0)],
        ];
        let got = MeshSearch::new(&training).nearest(&training, &[vec![Vector3::zeros()]], 3);
        assert_eq!(got, vec![vec![(1, 1.0), (0, 2.0)]]);
    }
}
