//! Capture-like noise on input sequences (truth stays clean): per frame, independent surface
//! noise `N(0, σ_s²)` on every vertex coordinate, plus a temporally coherent rigid jitter (a
//! sum of three sinusoids per axis with random frequencies 0.5-3 Hz and phases, amplitude
//! `σ_j`). Deterministic: one ChaCha stream per (seed, subject, motion) for the jitter and one
//! per frame for the surface noise, so frames can be made in parallel.

use nalgebra::Vector3;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

/// Noise levels in metres.
#[derive(Clone, Copy, Debug)]
pub struct NoiseLevel {
    pub surface: f64,
    pub jitter: f64,
}

/// A stable 64-bit stream id from a seed and labels (FNV-1a).
pub fn stream(seed: u64, labels: &[&str]) -> u64 {
    let mut h: u64 = 0xcbf29ce484222325 ^ seed.wrapping_mul(0x9e3779b97f4a7c15);
    for l in labels {
        for b in l.bytes().chain(std::iter::once(0xff)) {
            h ^= b as u64;
            h = h.wrapping_mul(0x100000001b3);
        }
    }
    h
}

/// The jitter process of one sequence.
#[derive(Clone, Debug)]
pub struct Jitter {
    terms: Vec<[f64; 3]>, // (amplitude, frequency Hz, phase) per axis-term, 3 per axis
}

impl Jitter {
    pub fn new(stream_id: u64, level: f64) -> Self {
        let mut rng = ChaCha8Rng::seed_from_u64(stream_id);
        let terms = (0..9)
            .map(|_| {
                let a = level / 3f64.sqrt() * (0.5 + rng.random::<f64>());
                let f = 0.5 + 2.5 * rng.random::<f64>();
                let p = std::f64::consts::TAU * rng.random::<f64>();
                [a, f, p]
            })
            .collect();
        Jitter { terms }
    }
    /// The rigid offset at time `t` (seconds).
    pub fn at(&self, t: f64) -> Vector3<f64> {
        let mut o = Vector3::zeros();
        for (k, [a, f, p]) in self.terms.iter().enumerate() {
            o[k / 3] += a * (std::f64::consts::TAU * f * t + p).sin();
        }
        o
    }
}

/// Adds the noise of frame `frame` (at time `t`) to `vertices`.
pub fn add_noise(
    vertices: &mut [Vector3<f64>],
    level: &NoiseLevel,
    jitter: &Jitter,
    stream_id: u64,
    frame: usize,
    t: f64,
) {
    let mut rng =
        ChaCha8Rng::seed_from_u64(stream_id ^ (frame as u64 + 1).wrapping_mul(0xd1b54a32d192ed03));
    let normal = Normal::new(0.0, level.surface.max(0.0)).expect("finite sigma");
    let off = jitter.at(t);
    for v in vertices.iter_mut() {
        *v += off
            + Vector3::new(
                normal.sample(&mut rng),
                normal.sample(&mut rng),
                normal.sample(&mut rng),
            );
    }
}
