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
    /// `Σ_ij W_ij ∂K(xs, x)_ij/∂log l` for `W` shaped as [`Kernel::cross`] (`N x F`): the
    /// contraction the sparse GP's gradient needs, without forming `∂K_uf` (one `N x F`
    /// block less) and without the kernel's arcsines (NN: only `u / sqrt(1 - u²)`). 0 for
    /// kernels without a length scale.
    pub(crate) fn cross_dlog_l_contract(&self, xs: &DMatrix<f64>, x: &DMatrix<f64>, w: &DMatrix<f64>) -> f64 {
        assert_eq!((w.nrows(), w.ncols()), (xs.nrows(), x.nrows()), "cross_dlog_l_contract: W's shape");
        if self.param_names().len() != 2 {
            return 0.0;
        }
        let s = xs * x.transpose();
        let (rs, rt) = (self.rows(xs), self.rows(x));
        let n = s.nrows().max(1);
        let mut total = 0.0;
        for (j, (scol, wcol)) in s.as_slice().chunks_exact(n).zip(w.as_slice().chunks_exact(n)).enumerate() {
            total += match *self {
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
        total
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
