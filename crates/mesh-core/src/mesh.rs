//! Triangle mesh with f64 positions.

use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

/// A triangle mesh: vertex positions (f64, metres unless a subject says
/// otherwise) and triangles as indices into `vertices`, counter-clockwise
/// seen from outside.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct TriMesh {
    pub vertices: Vec<Vector3<f64>>,
    pub faces: Vec<[u32; 3]>,
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
}
