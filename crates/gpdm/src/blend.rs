//! Parametrised variation (paper §7): latent-level blending of sampled trajectory variants.
//!
//! The model is trained with the original sequences and pre-blended ones `Y_w`, `w ∈ W`;
//! `X_{w=0} := X_1`, `X_{w=1} := X_2`. For a requested `w*` the bounding `w1 ≤ w* ≤ w2` are
//! found and two random variants are blended:
//! `X̃_{w*} = (w* − w2)/(w1 − w2) · X̃_{w1} + (w* − w1)/(w2 − w1) · X̃_{w2}`.
//! Trajectories must be time-aligned (same T × d).

use crate::error::{invalid, Result};
use nalgebra::DMatrix;
use rand::RngExt;

/// Sampled variants of the latent trajectories at the available blend weights.
#[derive(Clone, Debug, PartialEq)]
pub struct BlendSet {
    weights: Vec<f64>,
    variants: Vec<Vec<DMatrix<f64>>>,
}

impl BlendSet {
    /// `entries`: (w, variants of X_w). Weights must include 0 and 1, lie in [0, 1], be
    /// distinct; every set non-empty; all trajectories of one shape.
    pub fn new(mut entries: Vec<(f64, Vec<DMatrix<f64>>)>) -> Result<Self> {
        entries.sort_by(|a, b| a.0.total_cmp(&b.0));
        if entries.iter().any(|(w, _)| !(0.0..=1.0).contains(w)) {
            return invalid("blend weights must lie in [0, 1]");
        }
        if entries.first().map(|e| e.0) != Some(0.0) || entries.last().map(|e| e.0) != Some(1.0) {
            return invalid("blend weights must include the endpoints 0 and 1");
        }
        if entries.windows(2).any(|p| p[0].0 == p[1].0) {
            return invalid("blend weights must be distinct");
        }
        let shape = match entries[0].1.first() {
            Some(t) => t.shape(),
            None => return invalid("every blend weight needs at least one trajectory"),
        };
        for (w, v) in &entries {
            if v.is_empty() {
                return invalid(format!("no trajectory for blend weight {w}"));
            }
            if v.iter().any(|t| t.shape() != shape) {
                return invalid(format!(
                    "trajectories for weight {w} are not time-aligned with shape {shape:?}"
                ));
            }
        }
        let (weights, variants) = entries.into_iter().unzip();
        Ok(BlendSet { weights, variants })
    }

    /// Sorted available weights.
    pub fn weights(&self) -> &[f64] {
        &self.weights
    }

    /// Indices `(i1, i2)` of the bounding weights `w_{i1} ≤ w* ≤ w_{i2}` (equal when `w*` is
    /// one of the weights).
    pub fn bounding(&self, w: f64) -> Result<(usize, usize)> {
        if !(0.0..=1.0).contains(&w) {
            return invalid(format!("blend weight {w} outside [0, 1]"));
        }
        if let Some(i) = self.weights.iter().position(|&v| v == w) {
            return Ok((i, i));
        }
        let i2 = self
            .weights
            .iter()
            .position(|&v| v > w)
            .expect("1 is present");
        Ok((i2 - 1, i2))
    }

    /// One variation of `X_{w*}`: random variants of the bounding trajectories blended in
    /// proportion (§7); at an available weight, a random variant of that trajectory.
    pub fn sample<R: rand::Rng + ?Sized>(&self, w: f64, rng: &mut R) -> Result<DMatrix<f64>> {
        let (i1, i2) = self.bounding(w)?;
        let a = &self.variants[i1][rng.random_range(0..self.variants[i1].len())];
        if i1 == i2 {
            return Ok(a.clone());
        }
        let b = &self.variants[i2][rng.random_range(0..self.variants[i2].len())];
        Ok(blend_pair(a, self.weights[i1], b, self.weights[i2], w))
    }
}

/// `(w − w2)/(w1 − w2) · a + (w − w1)/(w2 − w1) · b` (§7), for `w1 ≠ w2`.
pub fn blend_pair(a: &DMatrix<f64>, w1: f64, b: &DMatrix<f64>, w2: f64, w: f64) -> DMatrix<f64> {
    let ca = (w - w2) / (w1 - w2);
    let cb = (w - w1) / (w2 - w1);
    a * ca + b * cb
}
