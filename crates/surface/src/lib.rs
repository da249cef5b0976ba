//! surface: shape pose reconstruction (transfer paper §6) and non-linear pose blending.
//!
//! Gradient-domain geometry on triangle meshes that share one topology:
//!
//! * [`laplacian`]: cotangent Laplacian and lumped mass.
//! * [`deformation_gradient`]: per-face hat-function gradients (operator G), per-face
//!   deformation gradients (Sumner's 4th-vertex frame), divergence `Gᵀ A J`.
//! * [`poisson`]: `L x = div J` with Dirichlet vertices, one sparse Cholesky factorisation
//!   reused for the 3 coordinates and across frames.
//! * [`polar`]: 3x3 polar decomposition `A = R S`, `det R = +1`.
//! * [`correct`]: body part correction (§6.1); [`nearest`]: its nearest training meshes;
//!   [`bounded_cache`]: its factorisations kept up to a number of bytes.
//! * [`optimal_boundary`]: cheapest closed loop in an overlap band (§6.2, Huang et al. 2007).
//! * [`stitch`]: Poisson merging of the parts along the optimal loops (§6.2).
//! * [`feather`]: part weights ramping smoothly across the overlap bands, for merging by a
//!   weighted average instead.
//! * [`blend`]: non-linear interpolation of two poses (rotation by log/exp, stretch linearly).
//! * [`frames`], [`segmentation`]: file plumbing for the `correct`, `stitch` and `blend` binaries.

pub mod blend;
pub mod bounded_cache;
pub mod correct;
pub mod deformation_gradient;
pub mod feather;
pub mod frames;
pub mod laplacian;
pub mod nearest;
pub mod optimal_boundary;
pub mod poisson;
pub mod polar;
pub mod segmentation;
pub mod stage;
pub mod stitch;
mod topo;

pub use mesh_core::{Error, Result};

use nalgebra::Vector3;

/// Checks that every face index is `< n_vertices`; `what` names the mesh in the error.
pub fn check_faces(n_vertices: usize, faces: &[[u32; 3]], what: &str) -> Result<()> {
    for (f, face) in faces.iter().enumerate() {
        for &v in face {
            if v as usize >= n_vertices {
                return Err(Error::invalid(format!(
                    "{what}: face {f} uses vertex {v} but there are only {n_vertices} vertices"
                )));
            }
        }
        if face[0] == face[1] || face[1] == face[2] || face[0] == face[2] {
            return Err(Error::invalid(format!(
                "{what}: face {f} repeats a vertex: {face:?}"
            )));
        }
    }
    Ok(())
}

/// Checks that a vertex array has the expected length and only finite coordinates.
pub fn check_vertices(v: &[Vector3<f64>], n: usize, what: &str) -> Result<()> {
    if v.len() != n {
        return Err(Error::invalid(format!(
            "{what}: {} vertices, expected {n}",
            v.len()
        )));
    }
    if let Some(i) = v.iter().position(|p| !p.iter().all(|c| c.is_finite())) {
        return Err(Error::invalid(format!("{what}: vertex {i} is not finite")));
    }
    Ok(())
}

/// Mean of a set of points (zero for an empty set).
pub fn centroid(v: &[Vector3<f64>]) -> Vector3<f64> {
    if v.is_empty() {
        return Vector3::zeros();
    }
    v.iter().sum::<Vector3<f64>>() / v.len() as f64
}
