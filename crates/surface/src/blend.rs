//! Non-linear interpolation of two poses of one subject (the `blend` stage; the variation
//! paper's mesh interpolation, its refs [16], [38], [39]).
//!
//! For each face, the deformation gradient from the rest mesh to pose `k` (Sumner frame) is
//! polar-decomposed, `D_f^k = R_f^k S_f^k`. At weight `w`:
//! `R_f(w) = R_f^0 exp(w log(R_f^0ᵀ R_f^1))` (quaternion power along the shorter arc) and
//! `S_f(w) = (1-w) S_f^0 + w S_f^1`; the target gradients `J_f = R_f(w) S_f(w) ∇rest` go into a
//! Poisson solve on the rest mesh (one factorisation for all weights and frames); each connected
//! part of the mesh (a character's eyes, teeth or clothing are often their own) is anchored at
//! its first vertex and translated so that its centroid is `(1-w) c^0 + w c^1`, the blend of its
//! centroids in the two poses. `w = 0` and `w = 1` reproduce the poses up to round-off.

use crate::deformation_gradient::{triangle_deformation, GradientOperator};
use crate::poisson::PoissonSolver;
use crate::polar::{polar, triangle_rotation};
use crate::{check_faces, check_vertices, Error, Result};
use mesh_core::topology::Topology;
use nalgebra::{Matrix3, Rotation3, UnitQuaternion, Vector3};

/// A pose split into per-face rotations and stretches relative to the rest mesh.
#[derive(Clone, Debug)]
pub struct PoseGradients {
    pub rotations: Vec<UnitQuaternion<f64>>,
    pub stretches: Vec<Matrix3<f64>>,
    /// Centroid of each connected part of the mesh in this pose, in [`Blender`]'s order.
    pub centroids: Vec<Vector3<f64>>,
}

/// Rest mesh, its gradient operator and factorised Laplacian.
pub struct Blender {
    rest: Vec<Vector3<f64>>,
    faces: Vec<[u32; 3]>,
    op: GradientOperator,
    rest_gradient: Vec<Matrix3<f64>>,
    /// The mesh's connected parts (through edges; a vertex in no face is its own), each sorted,
    /// ordered by their first vertex, which anchors the part in the Poisson solve.
    parts: Vec<Vec<u32>>,
    solver: PoissonSolver,
}

/// Mean of the vertices `part` of `pose`.
fn part_centroid(pose: &[Vector3<f64>], part: &[u32]) -> Vector3<f64> {
    part.iter().map(|&v| pose[v as usize]).sum::<Vector3<f64>>() / part.len() as f64
}

/// Linear vertex blending, the baseline: `(1-w) a + w b`.
pub fn linear_blend(a: &[Vector3<f64>], b: &[Vector3<f64>], w: f64) -> Vec<Vector3<f64>> {
    a.iter()
        .zip(b)
        .map(|(p, q)| p * (1.0 - w) + q * w)
        .collect()
}

impl Blender {
    pub fn new(rest: Vec<Vector3<f64>>, faces: Vec<[u32; 3]>) -> Result<Self> {
        if rest.is_empty() {
            return Err(Error::invalid("blend: empty rest mesh"));
        }
        check_vertices(&rest, rest.len(), "blend: rest mesh")?;
        check_faces(rest.len(), &faces, "blend: rest mesh")?;
        let op = GradientOperator::new(&rest, &faces);
        let parts = Topology::new(rest.len(), &faces).connected_components();
        let anchors: Vec<usize> = parts.iter().map(|p| p[0] as usize).collect();
        let solver = PoissonSolver::new(&op.stiffness(), &anchors)?;
        let rest_gradient = op.gradient(&rest);
        Ok(Blender {
            rest,
            faces,
            op,
            rest_gradient,
            parts,
            solver,
        })
    }

    /// Per-face polar decomposition of the deformation from the rest mesh to `pose`: the
    /// rotation in closed form ([`triangle_rotation`], the exact polar rotation of Sumner's
    /// gradient `D`), the stretch `S = Rᵀ D` symmetrised against round-off; the SVD
    /// ([`polar`]) only where the closed form has no triangle frame.
    pub fn decompose(&self, pose: &[Vector3<f64>]) -> Result<PoseGradients> {
        check_vertices(pose, self.rest.len(), "blend: pose")?;
        let (rotations, stretches) = self
            .faces
            .iter()
            .map(|f| {
                let rest = f.map(|i| self.rest[i as usize]);
                let posed = f.map(|i| pose[i as usize]);
                let d = triangle_deformation(&rest, &posed).unwrap_or_else(Matrix3::identity);
                let (r, s) = match triangle_rotation(&rest, &posed) {
                    Some(r) => {
                        let s = r.transpose() * d;
                        (r, (s + s.transpose()) * 0.5)
                    }
                    None => polar(&d),
                };
                (
                    UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(r)),
                    s,
                )
            })
            .unzip();
        Ok(PoseGradients {
            rotations,
            stretches,
            centroids: self.parts.iter().map(|p| part_centroid(pose, p)).collect(),
        })
    }

    /// Interpolates two decomposed poses at weight `w` and reconstructs the mesh.
    pub fn interpolate(
        &self,
        a: &PoseGradients,
        b: &PoseGradients,
        w: f64,
    ) -> Result<Vec<Vector3<f64>>> {
        let (nf, np) = (self.faces.len(), self.parts.len());
        for g in [a, b] {
            if g.rotations.len() != nf || g.stretches.len() != nf || g.centroids.len() != np {
                return Err(Error::invalid(format!(
                    "blend: a pose of {} faces and {} parts, the rest mesh has {nf} and {np}",
                    g.rotations.len(),
                    g.centroids.len()
                )));
            }
        }
        let field: Vec<Matrix3<f64>> = (0..self.faces.len())
            .map(|f| {
                let (q0, mut q1) = (a.rotations[f], b.rotations[f]);
                if q0.coords.dot(&q1.coords) < 0.0 {
                    q1 = UnitQuaternion::new_unchecked(-q1.into_inner());
                }
                let q = q0 * (q0.inverse() * q1).powf(w);
                let s = a.stretches[f] * (1.0 - w) + b.stretches[f] * w;
                q.to_rotation_matrix().into_inner() * s * self.rest_gradient[f]
            })
            .collect();
        let anchors: Vec<Vector3<f64>> = self.parts.iter().map(|p| self.rest[p[0] as usize]).collect();
        let mut x = self.solver.solve(&self.op.divergence(&field), &anchors)?;
        for (k, part) in self.parts.iter().enumerate() {
            let shift = a.centroids[k] * (1.0 - w) + b.centroids[k] * w - part_centroid(&x, part);
            part.iter().for_each(|&v| x[v as usize] += shift);
        }
        Ok(x)
    }

    /// Blends two poses at weight `w` (0 gives `a`, 1 gives `b`).
    pub fn blend(
        &self,
        a: &[Vector3<f64>],
        b: &[Vector3<f64>],
        w: f64,
    ) -> Result<Vec<Vector3<f64>>> {
        self.interpolate(&self.decompose(a)?, &self.decompose(b)?, w)
    }

    /// Blends two time-aligned sequences frame by frame.
    pub fn blend_sequences(
        &self,
        a: &[Vec<Vector3<f64>>],
        b: &[Vec<Vector3<f64>>],
        w: f64,
    ) -> Result<Vec<Vec<Vector3<f64>>>> {
        if a.len() != b.len() {
            return Err(Error::invalid(format!(
                "blend: sequences have {} and {} frames",
                a.len(),
                b.len()
            )));
        }
        a.iter().zip(b).map(|(p, q)| self.blend(p, q, w)).collect()
    }
}
