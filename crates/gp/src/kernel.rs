//! Covariance functions `k(x, x')` of the GP (CVPR eq. 9), with analytic gradients with respect
//! to the **log** hyperparameters (the optimiser works in log space so `l, σf > 0`).
//!
//! # Neural-network kernel (CVPR eq. 10), convention pinned here
//! ```text
//! k_nn(x, x') = σf² asin( a xᵀx' / sqrt((1 + a xᵀx)(1 + a x'ᵀx')) ),   a = 1 / (2 l²)
//! ```
//! exactly as eq. 10 is printed: **no `2/π` factor and no bias term**. Rasmussen & Williams
//! (eq. 4.29) augment the input with a constant, `x̃ = (1, x)`; that variant is available with
//! `bias: true` (off by default) and amounts to `xᵀx' -> 1 + xᵀx'`.
//!
//! Mapping to GPy's `MLP` kernel,
//! `σ²_GPy (2/π) asin((w xᵀx' + b) / sqrt((w xᵀx + b + 1)(w x'ᵀx' + b + 1)))`:
//! `w = 1/(2l²)`, `b = 0` (or `b = 1/(2l²)` with `bias: true`), `σ²_GPy = σf² π/2`.
//! The "+1" in GPy's denominator is the paper's "1 +": they agree with `b = 0`.
//!
//! The arcsine argument satisfies `|u| < 1` strictly (Cauchy-Schwarz plus the "1 +" terms),
//! so the kernel and its gradient stay finite.
//!
//! # Other kernels (for the paper's comparison, section 7)
//! - squared exponential: `σf² exp(-|x - x'|² / (2 l²))`;
//! - linear: `σf² xᵀx'`.

use nalgebra::{DMatrix, DVector};
use serde::{Deserialize, Serialize};

/// A covariance function and its hyperparameters.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum Kernel {
    /// Eq. 10 (see the module doc for the convention and `bias`).
    NeuralNetwork { l: f64, sigma_f: f64, bias: bool },
    /// `σf² exp(-|x - x'|² / (2 l²))`.
    SquaredExponential { l: f64, sigma_f: f64 },
    /// `σf² xᵀx'`.
    Linear { sigma_f: f64 },
}

/// Per-row quantities that make an entry cheap: `p = xᵀx` (plus 1 with bias), and for the
/// NN kernel `d = 1/sqrt(1 + a p)` and `g = a p / (1 + a p)`, so that
/// `u = a s d_i d_j` and `∂u/∂log l = u (-2 + g_i + g_j)`.
struct Rows {
    p: Vec<f64>,
    d: Vec<f64>,
    g: Vec<f64>,
}

impl Kernel {
    fn rows(&self, x: &DMatrix<f64>) -> Rows {
        let mut p: Vec<f64> = x.row_iter().map(|r| r.norm_squared()).collect();
        let (mut d, mut g) = (Vec::new(), Vec::new());
        if let Kernel::NeuralNetwork { l, bias, .. } = *self {
            if bias {
                p.iter_mut().for_each(|v| *v += 1.0);
            }
            let a = 0.5 / (l * l);
            d = p.iter().map(|v| 1.0 / (1.0 + a * v).sqrt()).collect();
            g = p.iter().map(|v| a * v / (1.0 + a * v)).collect();
        }
        Rows { p, d, g }
    }

    /// Value of entry `(i, j)` and its derivative with respect to `log l` (0 where the kernel
    /// has no length scale), from `s = x_iᵀx'_j` and the per-row data.
    #[inline(always)]
    fn entry(&self, s: f64, ri: &Rows, i: usize, rj: &Rows, j: usize, grad: bool) -> (f64, f64) {
        match *self {
            Kernel::NeuralNetwork { l, sigma_f, bias } => {
                let s = if bias { s + 1.0 } else { s };
                let a = 0.5 / (l * l);
                let u = (a * s * ri.d[i] * rj.d[j]).clamp(-1.0, 1.0);
                let sf2 = sigma_f * sigma_f;
                let k = sf2 * u.asin();
                let dk = if grad {
                    sf2 * u / (1.0 - u * u).sqrt() * (-2.0 + ri.g[i] + rj.g[j])
                } else {
                    0.0
                };
                (k, dk)
            }
            Kernel::SquaredExponential { l, sigma_f } => {
                let r2 = (ri.p[i] + rj.p[j] - 2.0 * s).max(0.0);
                let il2 = 1.0 / (l * l);
                let k = sigma_f * sigma_f * (-0.5 * r2 * il2).exp();
                (k, k * r2 * il2)
            }
            Kernel::Linear { sigma_f } => (sigma_f * sigma_f * s, 0.0),
        }
    }

    /// Lower triangle (diagonal included) of the Gram matrix and, if `grad`, of `∂K/∂log l`;
    /// the strict upper triangle is left unspecified. Column-wise so writes are contiguous.
    pub(crate) fn gram_lower(
        &self,
        x: &DMatrix<f64>,
        grad: bool,
    ) -> (DMatrix<f64>, Option<DMatrix<f64>>) {
        let n = x.nrows();
        let mut k = x * x.transpose();
        let r = self.rows(x);
        let want = grad && self.param_names().len() == 2;
        let mut dl = if want {
            Some(DMatrix::zeros(n, n))
        } else {
            None
        };
        for j in 0..n {
            let kcol = &mut k.as_mut_slice()[j * n..(j + 1) * n];
            match dl.as_mut() {
                Some(dl) => {
                    let dcol = &mut dl.as_mut_slice()[j * n..(j + 1) * n];
                    for i in j..n {
                        let (v, d) = self.entry(kcol[i], &r, i, &r, j, true);
                        kcol[i] = v;
                        dcol[i] = d;
                    }
                }
                None => {
                    for i in j..n {
                        kcol[i] = self.entry(kcol[i], &r, i, &r, j, false).0;
                    }
                }
            }
        }
        (k, dl)
    }
}

impl Kernel {
    /// Lower triangle of `∂K/∂log l` alone (`None` for kernels without a length scale), for
    /// a gradient requested after the value: avoids recomputing `K`'s arcsines/exponentials
    /// where only the derivative is needed (NN: `σf² u / sqrt(1 - u²) (-2 + g_i + g_j)`).
    pub(crate) fn dgram_dlog_l_lower(&self, x: &DMatrix<f64>) -> Option<DMatrix<f64>> {
        if self.param_names().len() != 2 {
            return None;
        }
        let n = x.nrows();
        let mut dl = x * x.transpose();
        let r = self.rows(x);
        for j in 0..n {
            let col = &mut dl.as_mut_slice()[j * n..(j + 1) * n];
            match *self {
                Kernel::NeuralNetwork { l, sigma_f, bias } => {
                    let a = 0.5 / (l * l);
                    let sf2 = sigma_f * sigma_f;
                    let (dj, gj) = (r.d[j], r.g[j]);
                    for i in j..n {
                        let s = if bias { col[i] + 1.0 } else { col[i] };
                        let u = (a * s * r.d[i] * dj).clamp(-1.0, 1.0);
                        col[i] = sf2 * u / (1.0 - u * u).sqrt() * (-2.0 + r.g[i] + gj);
                    }
                }
                _ => {
                    for i in j..n {
                        col[i] = self.entry(col[i], &r, i, &r, j, true).1;
                    }
                }
            }
        }
        Some(dl)
    }
}

impl Kernel {
    /// [`Kernel::cross`] with the NN kernel's arcsine by [`asin_cephes`] (within 1 ulp of
    /// the C library's, measured over `[-1, 1]`; about 4x faster here): the sparse GP's
    /// `K_uf`, `F x M` arcsines per evaluation (with glibc's they took a quarter of its time).
    /// Written into `out` (reallocated only when its shape differs), a block of
    /// [`crate::linalg::blocks`] at a time, so that a training loop reuses one `N x F` buffer and no
    /// transposed copy of `x` is made.
    pub(crate) fn cross_fast_into(&self, xs: &DMatrix<f64>, x: &DMatrix<f64>, out: &mut DMatrix<f64>) {
        let Kernel::NeuralNetwork { l, sigma_f, bias } = *self else {
            *out = self.cross(xs, x);
            return;
        };
        if out.shape() != (xs.nrows(), x.nrows()) {
            *out = DMatrix::zeros(xs.nrows(), x.nrows());
        }
        let n = out.nrows();
        if n == 0 {
            return;
        }
        let (rs, rt) = (self.rows(xs), self.rows(x));
        let (a, sf2) = (0.5 / (l * l), sigma_f * sigma_f);
        for cols in crate::linalg::blocks(x.nrows()) {
            out.columns_mut(cols.start, cols.len()).gemm(1.0, xs, &x.rows(cols.start, cols.len()).transpose(), 0.0);
            let block = &mut out.as_mut_slice()[cols.start * n..cols.end * n];
            for (j, col) in block.chunks_exact_mut(n).enumerate() {
                let adj = a * rt.d[cols.start + j];
                for (i, v) in col.iter_mut().enumerate() {
                    let s = if bias { *v + 1.0 } else { *v };
                    *v = sf2 * asin_cephes((adj * s * rs.d[i]).clamp(-1.0, 1.0));
                }
            }
        }
    }

    /// Adds `Σ_ij W_ij ∂K(xs, x)_ij/∂log l` over the columns `cols` of the cross-covariance
    /// (the rows `cols` of `x`) to `total`, column by column in order, with `W` the `N x |cols|`
    /// block of weights: the contraction the sparse GP's gradient needs, a block at a time,
    /// without forming `∂K_uf` and without the kernel's arcsines (NN: only `u / sqrt(1 - u²)`).
    /// Adds nothing for kernels without a length scale.
    pub(crate) fn cross_dlog_l_contract(
        &self,
        xs: &DMatrix<f64>,
        x: &DMatrix<f64>,
        cols: std::ops::Range<usize>,
        w: &DMatrix<f64>,
        total: &mut f64,
    ) {
        assert_eq!((w.nrows(), w.ncols()), (xs.nrows(), cols.len()), "cross_dlog_l_contract: W's shape");
        if self.param_names().len() != 2 {
            return;
        }
        let xb = x.rows(cols.start, cols.len()).into_owned();
        let s = xs * xb.transpose();
        let (rs, rt) = (self.rows(xs), self.rows(&xb));
        let n = s.nrows().max(1);
        for (j, (scol, wcol)) in s.as_slice().chunks_exact(n).zip(w.as_slice().chunks_exact(n)).enumerate() {
            *total += match *self {
                Kernel::NeuralNetwork { l, sigma_f, bias } => {
                    let a = 0.5 / (l * l);
                    let (dj, gj) = (rt.d[j], rt.g[j]);
                    let mut acc = 0.0;
                    for i in 0..scol.len() {
                        let sv = if bias { scol[i] + 1.0 } else { scol[i] };
                        let u = (a * sv * rs.d[i] * dj).clamp(-1.0, 1.0);
                        acc += wcol[i] * u / (1.0 - u * u).sqrt() * (-2.0 + rs.g[i] + gj);
                    }
                    sigma_f * sigma_f * acc
                }
                _ => (0..scol.len()).map(|i| wcol[i] * self.entry(scol[i], &rs, i, &rt, j, true).1).sum(),
            };
        }
    }

    /// Prior variances `k(x_i, x_i)` and their derivatives `∂/∂log l` (zeros for kernels
    /// without a length scale).
    pub(crate) fn diag_with_dlog_l(&self, xs: &DMatrix<f64>) -> (DVector<f64>, DVector<f64>) {
        let r = self.rows(xs);
        let bias = matches!(self, Kernel::NeuralNetwork { bias: true, .. });
        let n = xs.nrows();
        let (mut k, mut d) = (DVector::zeros(n), DVector::zeros(n));
        for i in 0..n {
            let s = if bias { r.p[i] - 1.0 } else { r.p[i] };
            let (v, dv) = self.entry(s, &r, i, &r, i, true);
            k[i] = v;
            d[i] = if self.param_names().len() == 2 { dv } else { 0.0 };
        }
        (k, d)
    }
}

/// `asin(x)` for `|x| <= 1` by Cephes' rational approximations (S. L. Moshier, `asin.c`):
/// `x + x³ P(x²)/Q(x²)` for `|x| <= 0.625`, `π/2 - 2 asin(sqrt((1 - |x|)/2))` in the form
/// `π/4 - (sqrt(2z) - (sqrt(2z) z R(z)/S(z) - ε)) + π/4`, `z = 1 - |x|`, above. Straight-line
/// code with one division, no table lookups or multi-precision fallback.
#[inline(always)]
pub(crate) fn asin_cephes(x: f64) -> f64 {
    const P: [f64; 6] = [
        4.253011369004428248960e-3,
        -6.019598008014123785661e-1,
        5.444622390564711410273e0,
        -1.626247967210700244449e1,
        1.956261983317594739197e1,
        -8.198089802484824371615e0,
    ];
    const Q: [f64; 5] = [
        -1.474091372988853791896e1,
        7.049610280856842141659e1,
        -1.471791292232726029859e2,
        1.395105614657485689735e2,
        -4.918853881490881290097e1,
    ];
    const R: [f64; 5] = [
        2.967721961301243206100e-3,
        -5.634242780008963776856e-1,
        6.968710824104713396794e0,
        -2.556901049652824852289e1,
        2.853665548261061424989e1,
    ];
    const S: [f64; 4] = [
        -2.194779531642920639778e1,
        1.470656354026814941758e2,
        -3.838770957603691357202e2,
        3.424398657913078477438e2,
    ];
    const PIO4: f64 = 7.853981633974483096160e-1;
    const MOREBITS: f64 = 6.123233995736765886130e-17;
    let poly = |z: f64, c: &[f64]| c.iter().skip(1).fold(c[0], |r, &v| r * z + v);
    let poly1 = |z: f64, c: &[f64]| c.iter().skip(1).fold(z + c[0], |r, &v| r * z + v);
    let a = x.abs();
    let r = if a > 0.625 {
        let z = 1.0 - a;
        let p = z * poly(z, &R) / poly1(z, &S);
        let w = (z + z).sqrt();
        ((PIO4 - w) - (w * p - MOREBITS)) + PIO4
    } else if a < 1e-8 {
        a
    } else {
        let z = a * a;
        a * (z * poly(z, &P) / poly1(z, &Q)) + a
    };
    r.copysign(x)
}

fn mirror_lower(m: &mut DMatrix<f64>) {
    let n = m.nrows();
    for j in 0..n {
        for i in j + 1..n {
            m[(j, i)] = m[(i, j)];
        }
    }
}

impl Kernel {
    /// Eq. 10 with the paper's convention (no bias).
    pub fn neural_network(l: f64, sigma_f: f64) -> Self {
        Kernel::NeuralNetwork {
            l,
            sigma_f,
            bias: false,
        }
    }

    /// Short name used in reports and file names: `nn`, `se`, `linear`.
    pub fn name(&self) -> &'static str {
        match self {
            Kernel::NeuralNetwork { .. } => "nn",
            Kernel::SquaredExponential { .. } => "se",
            Kernel::Linear { .. } => "linear",
        }
    }

    /// Names of the log hyperparameters, in the order of [`Kernel::log_params`].
    pub fn param_names(&self) -> &'static [&'static str] {
        match self {
            Kernel::Linear { .. } => &["log_sigma_f"],
            _ => &["log_l", "log_sigma_f"],
        }
    }

    /// Log hyperparameters `(log l, log σf)` (linear: `(log σf)`).
    pub fn log_params(&self) -> Vec<f64> {
        match *self {
            Kernel::NeuralNetwork { l, sigma_f, .. }
            | Kernel::SquaredExponential { l, sigma_f } => {
                vec![l.ln(), sigma_f.ln()]
            }
            Kernel::Linear { sigma_f } => vec![sigma_f.ln()],
        }
    }

    /// The same kernel with hyperparameters set from log values (`p.len()` must be
    /// `param_names().len()`).
    pub fn with_log_params(&self, p: &[f64]) -> Self {
        assert_eq!(
            p.len(),
            self.param_names().len(),
            "kernel log-parameter count"
        );
        match *self {
            Kernel::NeuralNetwork { bias, .. } => Kernel::NeuralNetwork {
                l: p[0].exp(),
                sigma_f: p[1].exp(),
                bias,
            },
            Kernel::SquaredExponential { .. } => Kernel::SquaredExponential {
                l: p[0].exp(),
                sigma_f: p[1].exp(),
            },
            Kernel::Linear { .. } => Kernel::Linear {
                sigma_f: p[0].exp(),
            },
        }
    }

    /// `k(x, x')` for two vectors of equal length.
    pub fn eval(&self, x: &[f64], y: &[f64]) -> f64 {
        let a = DMatrix::from_row_slice(1, x.len(), x);
        let b = DMatrix::from_row_slice(1, y.len(), y);
        self.cross(&a, &b)[(0, 0)]
    }

    /// Gram matrix `K` of CVPR eq. 9 over the rows of `x` (`F x F`).
    pub fn gram(&self, x: &DMatrix<f64>) -> DMatrix<f64> {
        let mut k = self.gram_lower(x, false).0;
        mirror_lower(&mut k);
        k
    }

    /// Cross covariance `K_*` of CVPR eq. 9: row `i` holds `k(xs_i, x_j)` for all rows `x_j`
    /// (`N x F`), for many test inputs at once.
    pub fn cross(&self, xs: &DMatrix<f64>, x: &DMatrix<f64>) -> DMatrix<f64> {
        let mut k = xs * x.transpose();
        let (rs, rt) = (self.rows(xs), self.rows(x));
        let n = k.nrows();
        for (j, col) in k.as_mut_slice().chunks_exact_mut(n.max(1)).enumerate() {
            for (i, v) in col.iter_mut().enumerate() {
                *v = self.entry(*v, &rs, i, &rt, j, false).0;
            }
        }
        k
    }

    /// Prior variances `K_** = k(x_i, x_i)` for every row of `xs`.
    pub fn diag(&self, xs: &DMatrix<f64>) -> DVector<f64> {
        let r = self.rows(xs);
        let bias = matches!(self, Kernel::NeuralNetwork { bias: true, .. });
        // r.p already includes the bias term; entry() adds it to s again, so pass s = xᵀx.
        DVector::from_iterator(
            xs.nrows(),
            (0..xs.nrows()).map(|i| {
                let s = if bias { r.p[i] - 1.0 } else { r.p[i] };
                self.entry(s, &r, i, &r, i, false).0
            }),
        )
    }

    /// Gram matrix and its derivatives `∂K/∂(log θ)` for each log hyperparameter (same order
    /// as [`Kernel::log_params`]). Uses `∂K/∂log σf = 2K`.
    pub fn gram_with_grads(&self, x: &DMatrix<f64>) -> (DMatrix<f64>, Vec<DMatrix<f64>>) {
        let (mut k, dl) = self.gram_lower(x, true);
        mirror_lower(&mut k);
        let ds = &k * 2.0;
        match dl {
            Some(mut dl) => {
                mirror_lower(&mut dl);
                (k, vec![dl, ds])
            }
            None => (k, vec![ds]),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Within 1 ulp (relative) of the C library's arcsine over `[-1, 1]`: a uniform grid, the
    /// approach to ±1 and tiny arguments.
    #[test]
    fn asin_cephes_matches_the_library() {
        let grid = (0..=200_000).map(|i| -1.0 + i as f64 * 1e-5);
        let near_one = (0..320).flat_map(|k| {
            let e = 10f64.powf(-(k as f64) / 20.0);
            [1.0 - e, -(1.0 - e), e * 1e-3, -e * 1e-3]
        });
        let mut worst: f64 = 0.0;
        for x in grid.chain(near_one).chain([1.0, -1.0, 0.0, 0.625, -0.625, 0.6250000000000001]) {
            let (got, want) = (asin_cephes(x), x.asin());
            let ulps = (got - want).abs() / (want.abs().max(f64::MIN_POSITIVE) * f64::EPSILON);
            worst = worst.max(ulps);
        }
        assert!(worst <= 1.0 + 1e-9, "worst error {worst} ulp");
    }

    /// Inputs spanning several column blocks: `F x D` and `M x D`.
    fn blocked_inputs() -> (DMatrix<f64>, DMatrix<f64>) {
        let xs = DMatrix::from_fn(9, 7, |i, j| ((i * 5 + j * 3) % 11) as f64 * 0.3 - 1.4);
        let x = DMatrix::from_fn(5000, 7, |i, j| ((i * 7 + j * 13) % 29) as f64 * 0.1 - 1.5);
        (xs, x)
    }

    /// Blocked `K_uf` is the whole-matrix computation to the bit: one product `xs xᵀ`, then
    /// the arcsines.
    #[test]
    fn blocked_cross_equals_the_whole_product() {
        let (xs, x) = blocked_inputs();
        assert!(crate::linalg::blocks(x.nrows()).count() > 1);
        for k in [Kernel::neural_network(0.4, 1.3), Kernel::NeuralNetwork { l: 2.0, sigma_f: 0.7, bias: true }] {
            let Kernel::NeuralNetwork { l, sigma_f, bias } = k else { unreachable!() };
            let (rs, rt) = (k.rows(&xs), k.rows(&x));
            let whole = &xs * x.transpose();
            let want = DMatrix::from_fn(xs.nrows(), x.nrows(), |i, j| {
                let s = if bias { whole[(i, j)] + 1.0 } else { whole[(i, j)] };
                sigma_f * sigma_f * asin_cephes((0.5 / (l * l) * rt.d[j] * s * rs.d[i]).clamp(-1.0, 1.0))
            });
            let mut got = DMatrix::from_element(3, 3, f64::NAN);
            k.cross_fast_into(&xs, &x, &mut got);
            assert!(got.iter().zip(want.iter()).all(|(a, b)| a.to_bits() == b.to_bits()), "{k:?}");
        }
    }

    /// The contraction block by block equals one pass over all columns to the bit, and the
    /// finite-difference derivative of `Σ W K` in `log l`.
    #[test]
    fn blocked_contraction_equals_one_pass_and_differences() {
        let (xs, x) = blocked_inputs();
        let w = DMatrix::from_fn(xs.nrows(), x.nrows(), |i, j| ((i * 3 + j) % 17) as f64 / 17.0 - 0.4);
        for k in [Kernel::neural_network(0.8, 1.3), Kernel::SquaredExponential { l: 1.5, sigma_f: 0.9 }] {
            let mut blocked = 0.0;
            for cols in crate::linalg::blocks(x.nrows()) {
                let wb = w.columns(cols.start, cols.len()).into_owned();
                k.cross_dlog_l_contract(&xs, &x, cols, &wb, &mut blocked);
            }
            let mut one_pass = 0.0;
            k.cross_dlog_l_contract(&xs, &x, 0..x.nrows(), &w, &mut one_pass);
            assert_eq!(blocked.to_bits(), one_pass.to_bits(), "{k:?}");
            let h = 1e-6;
            let mut theta = k.log_params();
            theta[0] += h;
            let up = w.dot(&k.with_log_params(&theta).cross(&xs, &x));
            theta[0] -= 2.0 * h;
            let down = w.dot(&k.with_log_params(&theta).cross(&xs, &x));
            let fd = (up - down) / (2.0 * h);
            assert!((blocked - fd).abs() <= 1e-6 * fd.abs().max(1.0), "{k:?}: {blocked} vs {fd}");
        }
    }

    #[test]
    fn fast_cross_equals_cross() {
        let xs = DMatrix::from_fn(7, 4, |i, j| ((i * 5 + j * 3) % 11) as f64 * 0.3 - 1.4);
        let x = DMatrix::from_fn(9, 4, |i, j| ((i * 7 + j) % 13) as f64 * 0.25 - 1.5);
        for k in [Kernel::neural_network(0.4, 1.3), Kernel::NeuralNetwork { l: 2.0, sigma_f: 0.7, bias: true }, Kernel::Linear { sigma_f: 2.0 }] {
            let (mut a, b) = (DMatrix::zeros(0, 0), k.cross(&xs, &x));
            k.cross_fast_into(&xs, &x, &mut a);
            assert!((&a - &b).amax() <= 4.0 * f64::EPSILON * b.amax(), "{k:?}");
        }
    }
}
