//! Synthetic training pairs shaped like the transfer problem (shared by the benchmark and the
//! `gpr_compare` study binary): 5 body parts with 20 PCA coefficients in and out, plus the 6-D
//! rigid displacement, for `n` dense pose pairs. Poses follow a few periodic "motions"; the
//! target is a smooth non-linear function of the source plus small noise.
#![allow(dead_code)]
use nalgebra::DMatrix;

struct Rng(u64);
impl Rng {
    fn normal(&mut self) -> f64 {
        let mut u = || {
            self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut z = self.0;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
        };
        let (a, b) = (u().max(1e-300), u());
        (-2.0 * a.ln()).sqrt() * (2.0 * std::f64::consts::PI * b).cos()
    }
    fn matrix(&mut self, r: usize, c: usize, s: f64) -> DMatrix<f64> {
        DMatrix::from_fn(r, c, |_, _| s * self.normal())
    }
}

/// `(X, Y)` per part (5 x `n x 20`) then the displacement (`n x 6`), source -> target.
pub fn pairs(n: usize, seed: u64) -> Vec<(DMatrix<f64>, DMatrix<f64>)> {
    let mut rng = Rng(seed);
    // Latent motion state: 5 motions, each a loop with its own speed.
    let latent = DMatrix::from_fn(n, 6, |f, k| {
        let motion = (f * 5) / n;
        let t = f as f64 * (0.15 + 0.05 * motion as f64);
        let h = (k / 2 + 1) as f64;
        let amp = 1.0 + 0.3 * motion as f64;
        if k % 2 == 0 {
            amp * (h * t).sin() / h
        } else {
            amp * (h * t).cos() / h
        }
    });
    let mut out = Vec::new();
    for (din, dout) in [(20, 20), (20, 20), (20, 20), (20, 20), (20, 20), (6, 6)] {
        let scale_in = DMatrix::from_fn(1, din, |_, k| 3.0 / (1.0 + k as f64));
        let mix = rng.matrix(6, din, 1.0);
        let mut x = &latent * &mix;
        for (k, mut c) in x.column_iter_mut().enumerate() {
            c *= scale_in[k] / 2.0;
        }
        x += rng.matrix(n, din, 0.02);
        let w1 = rng.matrix(din, dout, 0.4);
        let w2 = rng.matrix(din, dout, 0.2);
        let mut y = (&x * &w1).map(|v| 2.0 * (0.5 * v).tanh()) + (&x * &w2).map(|v| v * v * 0.1);
        y += rng.matrix(n, dout, 0.05);
        out.push((x, y));
    }
    out
}

/// Both directions: source -> target problems followed by target -> source.
pub fn both_directions(n: usize, seed: u64) -> Vec<(DMatrix<f64>, DMatrix<f64>)> {
    let fwd = pairs(n, seed);
    let back: Vec<_> = fwd.iter().map(|(x, y)| (y.clone(), x.clone())).collect();
    fwd.into_iter().chain(back).collect()
}
