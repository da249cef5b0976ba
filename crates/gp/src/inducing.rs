//! Inducing inputs of the sparse GP ([`crate::sparse_gpr`]): greedy variance selection.
//!
//! The rule, deterministic and seed-free: a pivoted Cholesky factorisation of the prior
//! covariance `K_ff` over the candidate inputs, which at every step picks the candidate whose
//! prior variance is least explained by the inputs already picked,
//! ```text
//! d_i = k(x_i, x_i) - Q_ii,   Q = K_fu K_uu⁻¹ K_uf,   next = argmax_i d_i   (lowest index on ties)
//! ```
//! (Fine & Scheinberg 2001; the diagonal `d` is exactly `diag(K_ff - Q_ff)`, the trace term
//! of Titsias' bound, so each pick greedily lowers it.) It stops early when the largest
//! residual variance falls below `1e-10` of the largest prior variance: the remaining inputs
//! are then explained to numerical precision and adding them would only make `K_uu`
//! singular. The candidates are `min(F, 16 M)` evenly spaced training rows (all rows when
//! `F <= 16 M`): dense correspondences of captured motions are near-duplicates frame to frame,
//! and this keeps the selection `O(16 M³)` instead of `O(F M²)`.

use crate::kernel::Kernel;
use nalgebra::{DMatrix, DVector};

/// Candidate inputs per inducing input (see the module documentation).
pub const CANDIDATES_PER_INDUCING: usize = 16;

/// Residual-variance floor, relative to the largest prior variance, below which selection stops.
const RELATIVE_FLOOR: f64 = 1e-10;

/// Indices (rows of `x`, in the order picked) of at most `m` inducing inputs chosen by greedy
/// variance selection under `kernel`.
pub fn greedy_variance(kernel: &Kernel, x: &DMatrix<f64>, m: usize) -> Vec<usize> {
    let n = x.nrows();
    let nc = n.min(CANDIDATES_PER_INDUCING.saturating_mul(m)).max(m.min(n));
    if nc == 0 {
        return Vec::new();
    }
    let cand: Vec<usize> = (0..nc).map(|i| i * n / nc).collect();
    let xc = x.select_rows(cand.iter());
    let mut d: DVector<f64> = kernel.diag(&xc);
    let floor = RELATIVE_FLOOR * d.max().max(0.0);
    let m = m.min(nc);
    // Columns of the partial Cholesky factor of K_ff over the candidates.
    let mut l = DMatrix::<f64>::zeros(nc, m);
    let mut picked = Vec::with_capacity(m);
    for j in 0..m {
        let (p, dp) = d
            .iter()
            .enumerate()
            .fold((0, f64::NEG_INFINITY), |best, (i, &v)| if v > best.1 { (i, v) } else { best });
        if !(dp > floor) {
            break;
        }
        picked.push(p);
        let kp = kernel.cross(&xc, &xc.rows(p, 1).into_owned());
        let mut col = kp.column(0).into_owned();
        if j > 0 {
            let lp = l.view((p, 0), (1, j)).transpose();
            col -= l.columns(0, j) * lp;
        }
        col /= dp.sqrt();
        for i in 0..nc {
            d[i] -= col[i] * col[i];
        }
        d[p] = f64::NEG_INFINITY; // never picked twice
        l.set_column(j, &col);
    }
    picked.into_iter().map(|p| cand[p]).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Duplicated inputs are never both picked (the second has zero residual variance), and
    /// selection stops once every distinct input is in.
    #[test]
    fn duplicates_are_skipped_and_selection_stops_when_explained() {
        let base = DMatrix::from_fn(6, 2, |r, c| ((r * 2 + c) as f64 * 0.7).sin() * 2.0);
        let x = DMatrix::from_fn(12, 2, |r, c| base[(r % 6, c)]);
        let k = Kernel::SquaredExponential { l: 0.5, sigma_f: 1.0 };
        let picked = greedy_variance(&k, &x, 12);
        let mut distinct: Vec<usize> = picked.iter().map(|i| i % 6).collect();
        distinct.sort();
        distinct.dedup();
        assert_eq!(distinct.len(), picked.len(), "{picked:?}");
        assert_eq!(picked.len(), 6, "{picked:?}");
    }

    /// The first pick maximises the prior variance (NN kernel: the largest input norm).
    #[test]
    fn first_pick_has_the_largest_prior_variance() {
        let x = DMatrix::from_row_slice(4, 1, &[0.1, -3.0, 2.0, 0.5]);
        let k = Kernel::neural_network(1.0, 1.0);
        assert_eq!(greedy_variance(&k, &x, 2)[0], 1);
    }
}
