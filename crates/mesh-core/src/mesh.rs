//! Triangle mesh with f64 positions, and its per-face / per-vertex geometry:
//! vector areas, normals, the per-face edge frames used for deformation
//! gradients, the bounding box, and validation of untrusted meshes.

use nalgebra::{Matrix3, Vector3};
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

/// A triangle mesh: vertex positions (f64, metres unless a subject says
/// otherwise) and triangles as indices into `vertices`, counter-clockwise
/// seen from outside.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct TriMesh {
    pub vertices: Vec<Vector3<f64>>,
    pub faces: Vec<[u32; 3]>,
}

/// Vector area of the triangle (a, b, c): `0.5 * (b - a) x (c - a)`. Its
/// length is the triangle's area, its direction the (counter-clockwise) normal.
pub fn triangle_vector_area(a: &Vector3<f64>, b: &Vector3<f64>, c: &Vector3<f64>) -> Vector3<f64> {
    0.5 * (b - a).cross(&(c - a))
}

/// Edge frame of the triangle (a, b, c): the 3x3 matrix with columns
/// `[e1, e2, n]`, where `e1 = b - a`, `e2 = c - a` and `n = e1 x e2 / |e1 x e2|`
/// (unit normal; zero for a degenerate triangle).
///
/// The deformation gradient of a triangle from rest frame `F0` to deformed
/// frame `F1` is `T = F1 F0^{-1}` (Sumner & Popovic 2004, the "[20]" cited by
/// the transfer paper); solve `T F0 = F1` with a factorisation of `F0` rather
/// than forming the inverse. Note: Sumner & Popovic scale the normal by
/// `1/sqrt(|e1 x e2|)`; this frame uses the unit normal.
pub fn triangle_frame(a: &Vector3<f64>, b: &Vector3<f64>, c: &Vector3<f64>) -> Matrix3<f64> {
    let e1 = b - a;
    let e2 = c - a;
    let n = e1.cross(&e2);
    let len = n.norm();
    let n = if len > 0.0 { n / len } else { Vector3::zeros() };
    Matrix3::from_columns(&[e1, e2, n])
}

impl TriMesh {
    pub fn new(vertices: Vec<Vector3<f64>>, faces: Vec<[u32; 3]>) -> Self {
        TriMesh { vertices, faces }
    }
    pub fn n_vertices(&self) -> usize {
        self.vertices.len()
    }
    pub fn n_faces(&self) -> usize {
        self.faces.len()
    }

    /// The three corner positions of face `f`. Panics if `f` or its indices are
    /// out of range (call [`TriMesh::validate`] on untrusted meshes first).
    pub fn face_corners(&self, f: usize) -> [&Vector3<f64>; 3] {
        let [a, b, c] = self.faces[f];
        [
            &self.vertices[a as usize],
            &self.vertices[b as usize],
            &self.vertices[c as usize],
        ]
    }

    /// Per-face vector areas `0.5 (b - a) x (c - a)` (see [`triangle_vector_area`]).
    pub fn face_vector_areas(&self) -> Vec<Vector3<f64>> {
        (0..self.faces.len())
            .map(|f| {
                let [a, b, c] = self.face_corners(f);
                triangle_vector_area(a, b, c)
            })
            .collect()
    }

    /// Per-face areas (length of the vector areas).
    pub fn face_areas(&self) -> Vec<f64> {
        self.face_vector_areas().iter().map(|v| v.norm()).collect()
    }

    /// Total surface area.
    pub fn area(&self) -> f64 {
        self.face_areas().iter().sum()
    }

    /// Per-face unit normals (counter-clockwise orientation); the zero vector
    /// for a degenerate face.
    pub fn face_normals(&self) -> Vec<Vector3<f64>> {
        self.face_vector_areas()
            .iter()
            .map(|v| unit_or_zero(v))
            .collect()
    }

    /// Area-weighted vertex normals: the normalised sum of the vector areas of
    /// the faces around each vertex. Zero for isolated vertices.
    pub fn vertex_normals(&self) -> Vec<Vector3<f64>> {
        let mut acc = vec![Vector3::zeros(); self.vertices.len()];
        for (face, va) in self.faces.iter().zip(self.face_vector_areas()) {
            for &v in face {
                acc[v as usize] += va;
            }
        }
        acc.iter().map(unit_or_zero).collect()
    }

    /// Per-face edge frames `[e1, e2, n]` (see [`triangle_frame`]).
    pub fn face_frames(&self) -> Vec<Matrix3<f64>> {
        (0..self.faces.len())
            .map(|f| {
                let [a, b, c] = self.face_corners(f);
                triangle_frame(a, b, c)
            })
            .collect()
    }

    /// Axis-aligned bounding box `(min, max)`; `None` for a mesh without vertices.
    pub fn bounding_box(&self) -> Option<(Vector3<f64>, Vector3<f64>)> {
        let first = *self.vertices.first()?;
        Some(
            self.vertices
                .iter()
                .fold((first, first), |(lo, hi), v| (lo.inf(v), hi.sup(v))),
        )
    }

    /// Checks a mesh from untrusted input: every coordinate finite, every face
    /// index in range, no face repeating an index. The error is one line naming
    /// the first offending vertex or face (callers add the file name).
    pub fn validate(&self) -> Result<()> {
        for (i, v) in self.vertices.iter().enumerate() {
            if let Some(c) = v.iter().find(|c| !c.is_finite()) {
                return Err(Error::invalid(format!(
                    "vertex {i} has a non-finite coordinate ({c})"
                )));
            }
        }
        let n = self.vertices.len();
        for (f, face) in self.faces.iter().enumerate() {
            if let Some(&i) = face.iter().find(|&&i| i as usize >= n) {
                return Err(Error::invalid(format!(
                    "face {f} uses vertex {i}, but the mesh has only {n} vertices"
                )));
            }
            if face[0] == face[1] || face[1] == face[2] || face[0] == face[2] {
                return Err(Error::invalid(format!(
                    "face {f} repeats a vertex index ({} {} {})",
                    face[0], face[1], face[2]
                )));
            }
        }
        Ok(())
    }
}

fn unit_or_zero(v: &Vector3<f64>) -> Vector3<f64> {
    let n = v.norm();
    if n > 0.0 {
        v / n
    } else {
        Vector3::zeros()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tet() -> TriMesh {
        // Unit right-angled tetrahedron, outward-facing counter-clockwise faces.
        TriMesh::new(
            vec![
                Vector3::new(0.0, 0.0, 0.0),
                Vector3::new(1.0, 0.0, 0.0),
                Vector3::new(0.0, 1.0, 0.0),
                Vector3::new(0.0, 0.0, 1.0),
            ],
            vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
        )
    }

    #[test]
    fn closed_surface_vector_areas_sum_to_zero_and_areas_are_analytic() {
        let m = tet();
        let sum: Vector3<f64> = m.face_vector_areas().iter().sum();
        assert!(sum.norm() < 1e-15);
        let a = m.face_areas();
        assert!((a[0] - 0.5).abs() < 1e-15);
        assert!((a[3] - 3f64.sqrt() / 2.0).abs() < 1e-15);
        // Outward orientation: bottom face normal points to -z.
        assert!((m.face_normals()[0] - Vector3::new(0.0, 0.0, -1.0)).norm() < 1e-15);
    }

    #[test]
    fn vertex_normal_at_corner_is_symmetric() {
        let n = tet().vertex_normals();
        // Vertex 0: faces with normals -x, -y, -z, equal areas.
        let e = -Vector3::new(1.0, 1.0, 1.0) / 3f64.sqrt();
        assert!((n[0] - e).norm() < 1e-15);
    }

    #[test]
    fn frame_maps_reference_triangle() {
        let m = tet();
        let f = triangle_frame(&m.vertices[0], &m.vertices[1], &m.vertices[3]);
        let expect = Matrix3::new(1.0, 0.0, 0.0, 0.0, 0.0, -1.0, 0.0, 1.0, 0.0);
        assert!((f - expect).norm() < 1e-15);
        // A rotated triangle has the rotated frame.
        let r = nalgebra::Rotation3::from_euler_angles(0.3, -0.2, 1.1).into_inner();
        let (a, b, c) = (r * m.vertices[0], r * m.vertices[1], r * m.vertices[3]);
        assert!((triangle_frame(&a, &b, &c) - r * expect).norm() < 1e-14);
    }

    #[test]
    fn bounding_box_and_validate() {
        let mut m = tet();
        let (lo, hi) = m.bounding_box().unwrap();
        assert_eq!(lo, Vector3::zeros());
        assert_eq!(hi, Vector3::new(1.0, 1.0, 1.0));
        assert!(m.validate().is_ok());
        m.vertices[2].y = f64::NAN;
        assert!(m.validate().unwrap_err().to_string().contains("vertex 2"));
        let mut m = tet();
        m.faces[1] = [0, 1, 4];
        assert!(m.validate().unwrap_err().to_string().contains("face 1"));
        let mut m = tet();
        m.faces[2] = [0, 3, 0];
        assert!(m.validate().unwrap_err().to_string().contains("repeats"));
        assert!(TriMesh::default().bounding_box().is_none());
    }
}
