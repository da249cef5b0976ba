//! PCA initialisation of the latent coordinates: the paper's starting point for X, before the
//! MAP fit of [`crate::optim`].

use crate::error::{invalid, Result};
use crate::linalg::{mul_abt, view};
use nalgebra::DMatrix;

/// PCA initialisation: the top `d` principal-component scores of the centred `y` (N × D),
/// computed from the N × N matrix `Y Yᵀ` (never D × D), then scaled by one common factor so
/// that the latent coordinates have unit mean variance (the paper's unit hyperparameters and
/// the unit first-point prior then start at a sensible length scale; relative scales kept).
pub fn pca_init(y: &DMatrix<f64>, d: usize) -> Result<DMatrix<f64>> {
    let n = y.nrows();
    if d == 0 || d > n {
        return invalid(format!(
            "cannot take {d} principal components of {n} frames"
        ));
    }
    let s = crate::linalg::to_na(mul_abt(view(y), view(y)).as_ref());
    let eig = nalgebra::SymmetricEigen::new(s);
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| eig.eigenvalues[b].total_cmp(&eig.eigenvalues[a]));
    let mut x = DMatrix::zeros(n, d);
    for (c, &k) in order.iter().take(d).enumerate() {
        let lam = eig.eigenvalues[k].max(0.0);
        let u = eig.eigenvectors.column(k);
        // Deterministic sign: largest-magnitude entry positive.
        let imax = u.iamax();
        let sign = if u[imax] < 0.0 { -1.0 } else { 1.0 };
        for i in 0..n {
            x[(i, c)] = sign * u[i] * lam.sqrt();
        }
    }
    let var = x.iter().map(|v| v * v).sum::<f64>() / (n * d) as f64;
    if var > 0.0 {
        x /= var.sqrt();
    }
    Ok(x)
}
