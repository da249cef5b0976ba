//! Synthetic "capture": four cyclic sequences (446 frames) of a smooth 3-D latent motion,
//! mapped to D dimensions by fixed pseudo-random sinusoids (amplitude 0.1, like metres),
//! plus optional uniform noise of the given amplitude.
use nalgebra::DMatrix;

pub fn synthetic(d_obs: usize, noise: f64) -> Vec<DMatrix<f64>> {
    let w: Vec<[f64; 4]> = (0..d_obs)
        .map(|j| {
            std::array::from_fn(|k| {
                (((j * 4 + k) as f64 * 12.9898).sin() * 43758.5453).fract() * 2.0
            })
        })
        .collect();
    [120usize, 110, 106, 110]
        .iter()
        .enumerate()
        .map(|(s, &len)| {
            DMatrix::from_fn(len, d_obs, |t, j| {
                let ph = 0.25 * t as f64 * (1.0 + 0.1 * s as f64) + s as f64;
                let z = [ph.cos(), ph.sin(), 0.3 * (2.0 * ph).sin()];
                0.1 * (w[j][0] * z[0] + w[j][1] * z[1] + w[j][2] * z[2] + w[j][3]).sin()
                    + noise * ((t * 7919 + j * 104729) % 1000) as f64 / 1000.0
            })
        })
        .collect()
}
