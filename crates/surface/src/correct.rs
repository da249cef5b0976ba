//! Body part correction (transfer paper §6.1, figure 4).
//!
//! For a predicted part mesh `P` (same topology as the training part meshes):
//! 1. the `M` nearest training meshes `N_k` by vertex distance
//!    `d_k = sqrt(mean_v |P_v - N_k,v|²)` (no alignment: parts are already rigidly aligned);
//! 2. weights decreasing with distance: `w_k = (1/d_k) / Σ_j (1/d_j)`; an exact match
//!    (`d_k ≤ 1e-12 · size of P`) gets weight 1 and the others 0;
//! 3. per face, the deformation gradient `D_f` from `N_k`'s triangle to `P`'s (Sumner frame)
//!    and its polar decomposition `D_f = R_f S_f` ([`crate::polar::triangle_rotation`], closed
//!    form, equal to the SVD route); the non-isometric `S_f` is dropped;
//! 4. `N_k` deformed by the rotations only: target gradients `J_f = R_f ∇N_k` (gradients on
//!    `N_k`'s own geometry), Poisson solve with `N_k`'s cotangent Laplacian and one Dirichlet
//!    vertex per connected piece of the part (its first vertex; a part modelled as several
//!    pieces, a game character's pads or hair, has several), then each piece translated so its
//!    centroid is the same piece's centroid in `P`;
//! 5. result `Σ_k w_k X_k`.
//!
//! Each training mesh's operator and numeric factorisation are built on first use and cached,
//! all on one symbolic analysis of the part's topology, so a sequence of predictions only pays
//! for the polar decompositions and the solves. The cache is unbounded by default;
//! [`Corrector::set_cache_limit`] bounds its bytes, the least recently used factorisations
//! then being rebuilt when needed again (the same bits: [`crate::bounded_cache`]).
//! [`Corrector::nearest_all`] finds step 1's meshes for many predictions at once
//! ([`crate::nearest::MeshSearch`]).

use crate::bounded_cache::BoundedCache;
use crate::deformation_gradient::GradientOperator;
use crate::nearest::MeshSearch;
use crate::poisson::{Factorisation, PoissonSolver, SymbolicPoisson};
use crate::polar::triangle_rotation;
use crate::{centroid, check_faces, check_vertices, Error, Result};
use nalgebra::{Matrix3, Vector3};
use rayon::prelude::*;
use std::sync::{Arc, OnceLock};

/// Default number of nearest training meshes (the paper's M = 3).
pub const DEFAULT_NEIGHBOURS: usize = 3;

struct Prepared {
    op: GradientOperator,
    solver: PoissonSolver,
    /// ∇N_k on its own geometry (tangent projectors).
    own_gradient: Vec<Matrix3<f64>>,
}

impl Prepared {
    fn bytes(&self) -> usize {
        self.op.bytes() + self.solver.bytes() + self.own_gradient.len() * 72
    }
}

/// The training part meshes of one body part, ready to correct predictions of that part.
pub struct Corrector {
    faces: Vec<[u32; 3]>,
    /// The part's connected pieces (through edges; an isolated vertex is a piece), each the
    /// sorted list of its vertices.
    pieces: Vec<Vec<u32>>,
    training: Vec<Vec<Vector3<f64>>>,
    search: MeshSearch,
    /// The symbolic factorisation of the part's Poisson system (its pattern is the faces'),
    /// made on the first training mesh prepared and shared by all.
    symbolic: OnceLock<std::result::Result<SymbolicPoisson, String>>,
    prepared: BoundedCache<Prepared>,
}

/// Weights `w_k ∝ 1/d_k`, normalised; an exact match (`d ≤ tol`) takes all the weight.
pub fn distance_weights(distances: &[f64], tol: f64) -> Vec<f64> {
    if let Some(k) = distances.iter().position(|&d| d <= tol) {
        return (0..distances.len())
            .map(|j| if j == k { 1.0 } else { 0.0 })
            .collect();
    }
    let inv: Vec<f64> = distances.iter().map(|d| 1.0 / d).collect();
    let s: f64 = inv.iter().sum();
    inv.iter().map(|w| w / s).collect()
}

pub use crate::nearest::vertex_distance;

impl Corrector {
    /// Checks the training meshes against `faces` (equal vertex counts, finite, valid indices).
    pub fn new(faces: Vec<[u32; 3]>, training: Vec<Vec<Vector3<f64>>>) -> Result<Self> {
        let n = training
            .first()
            .ok_or_else(|| Error::invalid("correct: no training meshes"))?
            .len();
        check_faces(n, &faces, "correct: part faces")?;
        for (k, t) in training.iter().enumerate() {
            check_vertices(t, n, &format!("correct: training mesh {k}"))?;
        }
        let prepared = BoundedCache::new(usize::MAX);
        let pieces = mesh_core::topology::Topology::new(n, &faces).connected_components();
        Ok(Corrector {
            faces,
            pieces,
            search: MeshSearch::new(&training),
            training,
            symbolic: OnceLock::new(),
            prepared,
        })
    }

    pub fn n_vertices(&self) -> usize {
        self.training[0].len()
    }
    /// Bounds the bytes of the cached training mesh operators and factorisations (module
    /// docs). Results do not depend on it.
    pub fn set_cache_limit(&mut self, bytes: usize) {
        self.prepared.set_limit(bytes);
    }
    /// How many training meshes have been prepared (factorised) so far, rebuilds included.
    pub fn factorisations(&self) -> usize {
        self.prepared.builds()
    }
    /// The bytes of the training meshes held (each `Vec` of vertices).
    pub fn training_bytes(&self) -> usize {
        self.training.iter().map(|t| t.len() * 24).sum()
    }
    pub fn faces(&self) -> &[[u32; 3]] {
        &self.faces
    }
    /// Training mesh `i` (an index [`Corrector::nearest`] returns).
    pub fn training_mesh(&self, i: usize) -> &[Vector3<f64>] {
        &self.training[i]
    }

    /// The `m` nearest training meshes to `prediction`: (index, distance), nearest first.
    pub fn nearest(&self, prediction: &[Vector3<f64>], m: usize) -> Vec<(usize, f64)> {
        crate::nearest::brute_force(&self.training, prediction, m)
    }

    /// [`Corrector::nearest`] of every prediction, by blocked matrix products (the same meshes
    /// and distances, [`crate::nearest`]).
    pub fn nearest_all(
        &self,
        predictions: &[Vec<Vector3<f64>>],
        m: usize,
    ) -> Vec<Vec<(usize, f64)>> {
        self.search.nearest(&self.training, predictions, m)
    }

    /// The part's symbolic analysis, made from `laplacian` (any training mesh's: they share
    /// the pattern) on first use.
    fn symbolic(&self, laplacian: &faer::sparse::SparseColMat<usize, f64>) -> Result<&SymbolicPoisson> {
        self.symbolic
            .get_or_init(|| {
                SymbolicPoisson::new(laplacian, Factorisation::Auto).map_err(|e| e.to_string())
            })
            .as_ref()
            .map_err(|e| Error::invalid(format!("correct: {e}")))
    }

    fn prepared(&self, k: usize) -> Result<Arc<Prepared>> {
        self.prepared
            .get_or_build(
                k,
                || {
                    let n = &self.training[k];
                    let op = GradientOperator::new(n, &self.faces);
                    let laplacian = op.stiffness();
                    let solver: PoissonSolver = self
                        .symbolic(&laplacian)
                        .and_then(|s| s.factorise(&laplacian, &self.piece_roots()))
                        .map_err(|e| e.to_string())?;
                    let own_gradient = op.gradient(n);
                    Ok(Prepared {
                        op,
                        solver,
                        own_gradient,
                    })
                },
                Prepared::bytes,
            )
            .map_err(|e| Error::invalid(format!("correct: training mesh {k}: {e}")))
    }

    /// Training mesh `k` deformed by the per-face rotations of its polar decompositions towards
    /// `prediction` (steps 3-4), centred on the prediction's centroid.
    pub fn rotate_towards(
        &self,
        k: usize,
        prediction: &[Vector3<f64>],
    ) -> Result<Vec<Vector3<f64>>> {
        let p = self.prepared(k)?;
        let nk = &self.training[k];
        let field: Vec<Matrix3<f64>> = self
            .faces
            .par_iter()
            .zip(p.own_gradient.par_iter())
            .map(|(f, g)| {
                let rest = f.map(|i| nk[i as usize]);
                let def = f.map(|i| prediction[i as usize]);
                let r = triangle_rotation(&rest, &def).unwrap_or_else(Matrix3::identity);
                r * g
            })
            .collect();
        let roots: Vec<Vector3<f64>> = self.piece_roots().iter().map(|&r| nk[r]).collect();
        let mut x = p.solver.solve(&p.op.divergence(&field), &roots)?;
        for piece in &self.pieces {
            let of = |m: &[Vector3<f64>]| piece.iter().map(|&v| m[v as usize]).collect::<Vec<_>>();
            let shift = centroid(&of(prediction)) - centroid(&of(&x));
            piece.iter().for_each(|&v| x[v as usize] += shift);
        }
        Ok(x)
    }

    /// The Dirichlet vertex of each piece: its first.
    fn piece_roots(&self) -> Vec<usize> {
        self.pieces.iter().map(|p| p[0] as usize).collect()
    }

    /// Corrects one predicted part mesh with the `m` nearest training meshes.
    pub fn correct(&self, prediction: &[Vector3<f64>], m: usize) -> Result<Vec<Vector3<f64>>> {
        check_vertices(prediction, self.n_vertices(), "correct: prediction")?;
        self.correct_with(prediction, &self.nearest(prediction, m))
    }

    /// [`Corrector::correct`] with its nearest training meshes given (from
    /// [`Corrector::nearest_all`]).
    pub fn correct_with(
        &self,
        prediction: &[Vector3<f64>],
        near: &[(usize, f64)],
    ) -> Result<Vec<Vector3<f64>>> {
        check_vertices(prediction, self.n_vertices(), "correct: prediction")?;
        if let Some(&(k, _)) = near.iter().find(|x| x.0 >= self.training.len()) {
            return Err(Error::invalid(format!(
                "correct: training mesh {k} asked for, there are {}",
                self.training.len()
            )));
        }
        let size = prediction
            .iter()
            .map(|v| v.norm())
            .fold(0.0, f64::max)
            .max(f64::MIN_POSITIVE);
        let w = distance_weights(&near.iter().map(|x| x.1).collect::<Vec<_>>(), 1e-12 * size);
        let used: Vec<(usize, f64)> = near
            .iter()
            .zip(w)
            .filter(|x| x.1 > 0.0)
            .map(|(n, w)| (n.0, w))
            .collect();
        let shapes: Vec<Vec<Vector3<f64>>> = used
            .par_iter()
            .map(|&(k, _)| self.rotate_towards(k, prediction))
            .collect::<Result<_>>()?;
        let mut out = vec![Vector3::zeros(); prediction.len()];
        for (x, (_, wk)) in shapes.iter().zip(&used) {
            out.iter_mut().zip(x).for_each(|(o, v)| *o += *wk * v);
        }
        Ok(out)
    }
}
