//! Cotangent Laplacian and lumped (barycentric) mass.
//!
//! Convention: `L` is the positive semi-definite "stiffness" form,
//! `L_ij = -(cot α_ij + cot β_ij) / 2` for an edge `ij` with opposite angles `α, β`,
//! `L_ii = -Σ_j L_ij`. Then `xᵀ L x = Σ_f A_f |∇x|²` (Dirichlet energy) and `L = Gᵀ A G`
//! with the gradient operator of [`crate::deformation_gradient`]. Linear functions on a flat
//! mesh are in the kernel at interior vertices (linear precision).

use faer::sparse::{SparseColMat, Triplet};
use nalgebra::Vector3;

/// Assembles a symmetric n x n matrix from (row, col, value) entries (duplicates summed).
/// Every diagonal entry is present in the pattern, even if zero.
pub(crate) fn assemble(n: usize, entries: Vec<(usize, usize, f64)>) -> SparseColMat<usize, f64> {
    let mut t: Vec<Triplet<usize, usize, f64>> = entries
        .into_iter()
        .map(|(r, c, v)| Triplet::new(r, c, v))
        .collect();
    t.extend((0..n).map(|i| Triplet::new(i, i, 0.0)));
    SparseColMat::try_new_from_triplets(n, n, &t).expect("indices checked by the caller")
}

/// Cotangent of the angle at `k` in triangle (i, j, k).
fn cot_at(pk: &Vector3<f64>, pi: &Vector3<f64>, pj: &Vector3<f64>) -> f64 {
    let (a, b) = (pi - pk, pj - pk);
    let s = a.cross(&b).norm();
    if s <= f64::MIN_POSITIVE {
        0.0
    } else {
        a.dot(&b) / s
    }
}

/// The cotangent Laplacian (PSD convention, see module doc). Degenerate faces contribute nothing.
/// Panics if a face index is out of range (check with [`crate::check_faces`]).
pub fn cotangent_laplacian(
    vertices: &[Vector3<f64>],
    faces: &[[u32; 3]],
) -> SparseColMat<usize, f64> {
    let mut e = Vec::with_capacity(faces.len() * 12);
    for f in faces {
        for k in 0..3 {
            let (i, j, o) = (
                f[k] as usize,
                f[(k + 1) % 3] as usize,
                f[(k + 2) % 3] as usize,
            );
            let w = 0.5 * cot_at(&vertices[o], &vertices[i], &vertices[j]);
            e.push((i, j, -w));
            e.push((j, i, -w));
            e.push((i, i, w));
            e.push((j, j, w));
        }
    }
    assemble(vertices.len(), e)
}

/// Lumped barycentric mass: a third of the area of each incident face.
pub fn lumped_mass(vertices: &[Vector3<f64>], faces: &[[u32; 3]]) -> Vec<f64> {
    let mut m = vec![0.0; vertices.len()];
    for f in faces {
        let [a, b, c] = f.map(|i| vertices[i as usize]);
        let area = 0.5 * (b - a).cross(&(c - a)).norm();
        for &i in f {
            m[i as usize] += area / 3.0;
        }
    }
    m
}
