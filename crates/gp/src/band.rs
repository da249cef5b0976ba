//! Symmetric positive-definite banded solves: a Cholesky factorisation `A = L Lᵀ` of a matrix
//! whose entries vanish beyond `w` diagonals of the main one, in `O(n w²)` time and `O(n w)`
//! memory (a dense factorisation is `O(n³)` and `O(n²)`), with the jitter retry of
//! [`crate::linalg::Cholesky`]. The normal equations of a least-squares problem over a
//! sequence whose terms couple only nearby frames (smoothness by second differences, say) are
//! such matrices, whatever the sequence's length.

use nalgebra::DMatrix;

use crate::linalg::JITTER_LADDER;
use crate::{GpError, Result};

/// A symmetric `n x n` matrix with `width` diagonals below the main one: its lower band, row
/// by row (entry `(i, i - k)` at `i (width + 1) + k`).
#[derive(Clone, Debug, PartialEq)]
pub struct SymmetricBand {
    n: usize,
    width: usize,
    lower: Vec<f64>,
}

impl SymmetricBand {
    /// The zero matrix.
    pub fn zeros(n: usize, width: usize) -> Self {
        SymmetricBand { n, width, lower: vec![0.0; n * (width + 1)] }
    }

    pub fn dim(&self) -> usize {
        self.n
    }

    /// Adds `v` to entries `(i, j)` and `(j, i)` (once when `i == j`). Panics outside the band:
    /// the caller's indices come from its own stencil.
    pub fn add(&mut self, i: usize, j: usize, v: f64) {
        let (i, j) = (i.max(j), i.min(j));
        assert!(i < self.n && i - j <= self.width, "entry ({i}, {j}) outside a band of width {} and size {}", self.width, self.n);
        self.lower[i * (self.width + 1) + (i - j)] += v;
    }

    /// Entry `(i, j)` (0 outside the band).
    pub fn get(&self, i: usize, j: usize) -> f64 {
        let (i, j) = (i.max(j), i.min(j));
        if i >= self.n || i - j > self.width {
            return 0.0;
        }
        self.lower[i * (self.width + 1) + (i - j)]
    }

    /// The dense matrix (for tests and small checks).
    pub fn to_dense(&self) -> DMatrix<f64> {
        DMatrix::from_fn(self.n, self.n, |i, j| self.get(i, j))
    }

    /// `L` of `A + jitter I = L Lᵀ` in this layout; None when a pivot is not positive.
    fn factor(&self, jitter: f64) -> Option<SymmetricBand> {
        let (n, w) = (self.n, self.width);
        let mut l = SymmetricBand::zeros(n, w);
        let at = |i: usize, k: usize| i * (w + 1) + k;
        for i in 0..n {
            for j in i.saturating_sub(w)..=i {
                // (A - Σ_k L_ik L_jk)_ij over the columns k both rows have.
                let mut s = self.lower[at(i, i - j)] + if i == j { jitter } else { 0.0 };
                for k in i.saturating_sub(w)..j {
                    s -= l.lower[at(i, i - k)] * l.lower[at(j, j - k)];
                }
                l.lower[at(i, i - j)] = if i == j {
                    if !(s > 0.0) || !s.is_finite() {
                        return None;
                    }
                    s.sqrt()
                } else {
                    s / l.lower[at(j, 0)]
                };
            }
        }
        Some(l)
    }
}

/// The Cholesky factorisation of a [`SymmetricBand`] (module doc).
pub struct BandCholesky {
    l: SymmetricBand,
    /// Absolute jitter that was added to the diagonal (0 when none was needed).
    pub jitter: f64,
}

impl BandCholesky {
    /// Factorises `a`. If the plain factorisation fails, retries with `jitter = c * mean(diag a)`
    /// for `c` in 1e-10..1e-3, pushing one line per retry into `notes` (`what` names the matrix),
    /// as [`crate::linalg::Cholesky::new`] does.
    pub fn new(a: &SymmetricBand, what: &str, notes: &mut Vec<String>) -> Result<Self> {
        if let Some(l) = a.factor(0.0) {
            return Ok(BandCholesky { l, jitter: 0.0 });
        }
        let n = a.n;
        let mean_diag = (0..n).map(|i| a.get(i, i).abs()).sum::<f64>() / n.max(1) as f64;
        let scale = if mean_diag > 0.0 && mean_diag.is_finite() { mean_diag } else { 1.0 };
        let mut last = 0.0;
        for c in JITTER_LADDER {
            last = c * scale;
            if let Some(l) = a.factor(last) {
                notes.push(format!("{what}: not positive definite, added jitter {last:.3e} to the diagonal"));
                return Ok(BandCholesky { l, jitter: last });
            }
        }
        Err(GpError::NotPositiveDefinite { what: what.to_string(), jitter: last })
    }

    /// Solves `A X = B` for every column of `B` (`n` rows) by the two banded triangular solves.
    pub fn solve(&self, b: &DMatrix<f64>) -> DMatrix<f64> {
        let (l, n, w) = (&self.l, self.l.n, self.l.width);
        let at = |i: usize, k: usize| l.lower[i * (w + 1) + k];
        let mut x = b.clone();
        for mut col in x.column_iter_mut() {
            for i in 0..n {
                let mut s = col[i];
                for k in i.saturating_sub(w)..i {
                    s -= at(i, i - k) * col[k];
                }
                col[i] = s / at(i, 0);
            }
            for i in (0..n).rev() {
                let mut s = col[i];
                for k in i + 1..(i + w + 1).min(n) {
                    s -= at(k, k - i) * col[k];
                }
                col[i] = s / at(i, 0);
            }
        }
        x
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::linalg::Cholesky;

    /// A diagonally dominant matrix of bandwidth `w` with scattered entries in [-1, 1].
    fn scattered_band(n: usize, w: usize) -> SymmetricBand {
        let mut a = SymmetricBand::zeros(n, w);
        for i in 0..n {
            a.add(i, i, 2.0 * w as f64 + 1.0);
            for j in i.saturating_sub(w)..i {
                a.add(i, j, ((i * 31 + j * 17) % 13) as f64 / 6.0 - 1.0);
            }
        }
        a
    }

    #[test]
    fn solves_as_the_dense_cholesky_does() {
        for (n, w) in [(1, 0), (1, 2), (7, 1), (40, 2), (200, 5)] {
            let a = scattered_band(n, w);
            let b = DMatrix::from_fn(n, 3, |i, j| ((i * 7 + j * 3) % 11) as f64 - 5.0);
            let x = BandCholesky::new(&a, "test", &mut Vec::new()).unwrap().solve(&b);
            let want = Cholesky::new(&a.to_dense(), "test", &mut Vec::new()).unwrap().solve(&b);
            assert!((&x - &want).amax() < 1e-12 * want.amax().max(1.0), "n {n} w {w}");
            // And the residual of the system itself.
            assert!((a.to_dense() * &x - &b).amax() < 1e-10, "n {n} w {w}");
        }
    }

    #[test]
    fn a_singular_matrix_gets_jitter_and_a_note_and_an_indefinite_one_an_error() {
        // The second-difference operator alone has the constant and the linear sequences in its
        // null space.
        let n = 30;
        let mut a = SymmetricBand::zeros(n, 2);
        let stencil = [1.0, -2.0, 1.0];
        for t in 1..n - 1 {
            for (u, wu) in stencil.iter().enumerate() {
                for (v, wv) in stencil.iter().enumerate().take(u + 1) {
                    let (i, j) = (t + u - 1, t + v - 1);
                    a.add(i, j, wu * wv);
                }
            }
        }
        let mut notes = Vec::new();
        let c = BandCholesky::new(&a, "second differences", &mut notes).unwrap();
        assert!(c.jitter > 0.0 && notes.len() == 1 && notes[0].contains("second differences"), "{notes:?}");
        let mut minus = SymmetricBand::zeros(3, 1);
        minus.add(0, 0, -1.0);
        minus.add(1, 1, -1.0);
        minus.add(2, 2, -1.0);
        assert!(BandCholesky::new(&minus, "negative", &mut Vec::new()).is_err());
    }

    #[test]
    fn entries_are_symmetric_and_zero_outside_the_band() {
        let mut a = SymmetricBand::zeros(4, 1);
        a.add(1, 0, 2.0);
        a.add(0, 1, 1.0);
        assert_eq!((a.get(0, 1), a.get(1, 0), a.get(3, 0), a.dim()), (3.0, 3.0, 0.0, 4));
    }
}
