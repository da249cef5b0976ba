//! Per-face gradients and deformation gradients.
//!
//! **Gradient operator G.** On face `f` with corners `x_0, x_1, x_2`, unit normal `n̂` and area
//! `A_f`, the hat function of corner `i` has the constant gradient
//! `g_i = n̂ × e_i / (2 A_f)`, where `e_i` is the edge opposite `i` in counter-clockwise order
//! (`e_0 = x_2 - x_1`, ...). A per-vertex field `X` (`|V|` x 3) has on face `f` the gradient
//! `J_f = Σ_i X_i g_iᵀ` (3 x 3: row = coordinate, column = spatial direction). `J_f` maps a
//! tangent vector of the reference face to the corresponding vector of `X` and the normal to 0:
//! this is the "2D frame" variant (no 4th vertex) used for all Poisson right-hand sides.
//! Divergence of a per-face field: `div(J)_i = Σ_f A_f J_f g_i`, i.e. `Gᵀ A J`, and
//! `Gᵀ A G` is the cotangent Laplacian of [`crate::laplacian`].
//!
//! **Deformation gradient** of a triangle (Sumner & Popović 2004): with edges `e_1, e_2` and
//! the 4th vertex direction `v_4 = (e_1 × e_2) / sqrt(|e_1 × e_2|)`, `V = [e_1 e_2 v_4]`,
//! `D = V' V⁻¹` (computed by an LU solve of `Vᵀ Dᵀ = V'ᵀ`, no explicit inverse). It is full
//! rank, so its polar decomposition gives a well-defined per-face rotation.

use faer::sparse::{SparseColMat, Triplet};
use nalgebra::{Matrix3, Vector3};

/// The per-face gradient operator G on a reference geometry, with face areas A.
#[derive(Clone, Debug)]
pub struct GradientOperator {
    n_vertices: usize,
    faces: Vec<[u32; 3]>,
    grads: Vec<[Vector3<f64>; 3]>,
    areas: Vec<f64>,
}

/// Hat-function gradients and area of one triangle; zero gradients and area for a degenerate one.
pub fn hat_gradients(t: &[Vector3<f64>; 3]) -> ([Vector3<f64>; 3], f64) {
    let n = (t[1] - t[0]).cross(&(t[2] - t[0]));
    let twice_area = n.norm();
    if !(twice_area > 1e-300) || !twice_area.is_finite() {
        return ([Vector3::zeros(); 3], 0.0);
    }
    let nh = n / twice_area;
    let e = [t[2] - t[1], t[0] - t[2], t[1] - t[0]];
    (e.map(|ei| nh.cross(&ei) / twice_area), 0.5 * twice_area)
}

impl GradientOperator {
    /// G on the geometry `vertices`. Panics on out-of-range face indices
    /// (check with [`crate::check_faces`]).
    pub fn new(vertices: &[Vector3<f64>], faces: &[[u32; 3]]) -> Self {
        Self::from_triangles(vertices.len(), faces, |f| {
            faces[f].map(|i| vertices[i as usize])
        })
    }

    /// G where face `f` takes its reference triangle from `triangle(f)`: each face may come
    /// from a different source geometry (used by stitching).
    pub fn from_triangles(
        n_vertices: usize,
        faces: &[[u32; 3]],
        triangle: impl Fn(usize) -> [Vector3<f64>; 3],
    ) -> Self {
        let (grads, areas) = (0..faces.len())
            .map(|f| hat_gradients(&triangle(f)))
            .unzip();
        GradientOperator {
            n_vertices,
            faces: faces.to_vec(),
            grads,
            areas,
        }
    }

    /// The bytes the operator holds (faces, hat gradients, areas).
    pub fn bytes(&self) -> usize {
        self.faces.len() * (12 + 72 + 8)
    }

    pub fn n_vertices(&self) -> usize {
        self.n_vertices
    }
    pub fn faces(&self) -> &[[u32; 3]] {
        &self.faces
    }
    /// Face areas A_f of the reference geometry (0 for degenerate faces).
    pub fn areas(&self) -> &[f64] {
        &self.areas
    }
    /// Hat-function gradients of face `f`.
    pub fn face_gradients(&self, f: usize) -> &[Vector3<f64>; 3] {
        &self.grads[f]
    }

    /// Gradient of face `f` of a field given by its three corner values.
    pub fn face_gradient(&self, f: usize, corners: &[Vector3<f64>; 3]) -> Matrix3<f64> {
        let g = &self.grads[f];
        corners[0] * g[0].transpose()
            + corners[1] * g[1].transpose()
            + corners[2] * g[2].transpose()
    }

    /// Per-face gradients `J_f = Σ_i X_i g_iᵀ` of a per-vertex field.
    pub fn gradient(&self, x: &[Vector3<f64>]) -> Vec<Matrix3<f64>> {
        (0..self.faces.len())
            .map(|f| self.face_gradient(f, &self.faces[f].map(|i| x[i as usize])))
            .collect()
    }

    /// Divergence `Gᵀ A J`: `b_i = Σ_f A_f J_f g_i` (one 3-vector per vertex).
    pub fn divergence(&self, field: &[Matrix3<f64>]) -> Vec<Vector3<f64>> {
        let mut b = vec![Vector3::zeros(); self.n_vertices];
        for (f, face) in self.faces.iter().enumerate() {
            let a = self.areas[f];
            for k in 0..3 {
                b[face[k] as usize] += a * (field[f] * self.grads[f][k]);
            }
        }
        b
    }

    /// `Gᵀ A G`: the cotangent Laplacian of the reference geometry (PSD convention),
    /// every diagonal entry present in the sparsity pattern.
    pub fn stiffness(&self) -> SparseColMat<usize, f64> {
        let mut e = Vec::with_capacity(self.faces.len() * 9);
        for (f, face) in self.faces.iter().enumerate() {
            let (g, a) = (&self.grads[f], self.areas[f]);
            for i in 0..3 {
                for j in 0..3 {
                    e.push((face[i] as usize, face[j] as usize, a * g[i].dot(&g[j])));
                }
            }
        }
        crate::laplacian::assemble(self.n_vertices, e)
    }

    /// G as a sparse `3|F| x |V|` matrix: row `3f + d` holds the `d`-th component of the
    /// hat gradients of face `f`.
    pub fn matrix(&self) -> SparseColMat<usize, f64> {
        let mut t = Vec::with_capacity(self.faces.len() * 9);
        for (f, face) in self.faces.iter().enumerate() {
            for k in 0..3 {
                for d in 0..3 {
                    t.push(Triplet::new(
                        3 * f + d,
                        face[k] as usize,
                        self.grads[f][k][d],
                    ));
                }
            }
        }
        SparseColMat::try_new_from_triplets(3 * self.faces.len(), self.n_vertices, &t)
            .expect("indices checked by the caller")
    }
}

/// The sparsity pattern of `Gᵀ A G` for one face list, with the 9 value slots of every face,
/// so the matrix is refilled for a new geometry without sorting triplets again (stitching
/// assembles a new mixed-geometry Laplacian every frame).
#[derive(Clone)]
pub struct StiffnessPattern {
    matrix: SparseColMat<usize, f64>,
    slots: Vec<[usize; 9]>,
}

impl StiffnessPattern {
    /// Panics on out-of-range face indices (check with [`crate::check_faces`]).
    pub fn new(n_vertices: usize, faces: &[[u32; 3]]) -> Self {
        let e = faces
            .iter()
            .flat_map(|f| (0..9).map(move |k| (f[k / 3] as usize, f[k % 3] as usize, 0.0)))
            .collect();
        let matrix = crate::laplacian::assemble(n_vertices, e);
        let (cp, ri) = (matrix.symbolic().col_ptr(), matrix.symbolic().row_idx());
        let slot = |i: usize, j: usize| {
            cp[j]
                + ri[cp[j]..cp[j + 1]]
                    .iter()
                    .position(|&r| r == i)
                    .expect("in pattern")
        };
        let slots = faces
            .iter()
            .map(|f| std::array::from_fn(|k| slot(f[k / 3] as usize, f[k % 3] as usize)))
            .collect();
        StiffnessPattern { matrix, slots }
    }

    /// Fills the pattern with `op`'s `Gᵀ A G` (same faces as at construction). Every value is
    /// rewritten, so the caller may modify the returned matrix's values in place (e.g.
    /// [`crate::poisson::PoissonSolver::refactor_in_place`]).
    pub fn fill(&mut self, op: &GradientOperator) -> &mut SparseColMat<usize, f64> {
        assert_eq!(
            op.faces.len(),
            self.slots.len(),
            "stiffness pattern built for other faces"
        );
        let vals = self.matrix.val_mut();
        vals.iter_mut().for_each(|v| *v = 0.0);
        for (f, sl) in self.slots.iter().enumerate() {
            let (g, a) = (&op.grads[f], op.areas[f]);
            for k in 0..9 {
                vals[sl[k]] += a * g[k / 3].dot(&g[k % 3]);
            }
        }
        &mut self.matrix
    }
}

impl StiffnessPattern {
    /// Stitching's system in one pass over the faces: fills the pattern with the
    /// mixed-geometry `Gᵀ A G` where face `f` takes its reference triangle `t = triangle(f)`
    /// (the values of [`StiffnessPattern::fill`] on [`GradientOperator::from_triangles`], bit
    /// for bit) and writes into `rhs` the divergence `Gᵀ A J` of the field of each face's own
    /// gradient, `J_f = Σ_j t_j g_jᵀ`. Then `A_f J_f g_i = Σ_j A_f (g_i·g_j) t_j`: the face's
    /// stiffness entries applied to its corners, so no per-face matrix is formed (the same sum
    /// as [`GradientOperator::divergence`] in another order: equal to rounding).
    pub fn fill_with_own_field(
        &mut self,
        triangle: impl Fn(usize) -> [Vector3<f64>; 3],
        rhs: &mut Vec<Vector3<f64>>,
    ) -> &mut SparseColMat<usize, f64> {
        let n = self.matrix.nrows();
        rhs.clear();
        rhs.resize(n, Vector3::zeros());
        let (symbolic, vals) = self.matrix.parts_mut();
        let rows = symbolic.row_idx();
        vals.iter_mut().for_each(|v| *v = 0.0);
        for (f, sl) in self.slots.iter().enumerate() {
            let t = triangle(f);
            let (g, a) = hat_gradients(&t);
            for i in 0..3 {
                let mut b = Vector3::zeros();
                for j in 0..3 {
                    let k = 3 * i + j;
                    let l = a * g[i].dot(&g[j]);
                    vals[sl[k]] += l;
                    b += l * t[j];
                }
                // Slot k = 3i + j lies in column j's vertex and row i's: the row is face corner i.
                rhs[rows[sl[3 * i]]] += b;
            }
        }
        &mut self.matrix
    }
}

/// Sumner's frame `[e_1 e_2 v_4]` of a triangle.
fn frame(t: &[Vector3<f64>; 3]) -> Matrix3<f64> {
    let (e1, e2) = (t[1] - t[0], t[2] - t[0]);
    let n = e1.cross(&e2);
    let v4 = n / n.norm().sqrt();
    Matrix3::from_columns(&[e1, e2, v4])
}

/// Deformation gradient `D = V' V⁻¹` mapping the `rest` triangle onto `deformed`
/// (4th-vertex frame, module doc). `None` for a degenerate triangle.
pub fn triangle_deformation(
    rest: &[Vector3<f64>; 3],
    deformed: &[Vector3<f64>; 3],
) -> Option<Matrix3<f64>> {
    let (v, vd) = (frame(rest), frame(deformed));
    if !v.iter().chain(vd.iter()).all(|x| x.is_finite()) {
        return None;
    }
    let dt = v.transpose().lu().solve(&vd.transpose())?;
    let d = dt.transpose();
    d.iter().all(|x| x.is_finite()).then_some(d)
}

/// Deformation gradients of every face from `rest` to `deformed`; identity for degenerate faces.
pub fn face_deformations(
    rest: &[Vector3<f64>],
    deformed: &[Vector3<f64>],
    faces: &[[u32; 3]],
) -> Vec<Matrix3<f64>> {
    faces
        .iter()
        .map(|f| {
            let r = f.map(|i| rest[i as usize]);
            let d = f.map(|i| deformed[i as usize]);
            triangle_deformation(&r, &d).unwrap_or_else(Matrix3::identity)
        })
        .collect()
}
