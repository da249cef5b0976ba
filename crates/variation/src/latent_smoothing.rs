//! Temporal smoothing of sampled latent trajectories (a post-process; σ = [`DEFAULT_SIGMA`]
//! frames by default).
//!
//! The sampled trajectories follow the learned first-order dynamics with their one-step noise,
//! so consecutive latent points jitter; decoded, the legs shake frame to frame, swing feet
//! skim the floor, and a jump of the limbs between two frames turns the whole body's best rigid
//! fit faster than any capture turns (docs/studies/15-latent-smoothing.md and
//! docs/studies/25-spins-and-tears.md). This filter convolves every latent
//! coordinate of every part with a Gaussian of `sigma` frames (truncated at 3σ, weights
//! renormalised at the ends of the sequence) and keeps the first point exactly, as the sampler
//! does (the paper's fixed `x1`).

use nalgebra::DMatrix;

/// `hmc-sample`'s σ (frames): two frames remove the frame-to-frame jumps (one leaves some)
/// and keep the variations as far from their source as unsmoothed
/// (docs/studies/15-latent-smoothing.md).
pub const DEFAULT_SIGMA: f64 = 2.0;

/// Smooths each trajectory (T × d, one row per frame) in place; `sigma <= 0` leaves it alone.
pub fn smooth_trajectory(x: &mut DMatrix<f64>, sigma: f64) {
    let t = x.nrows();
    if !(sigma > 0.0) || t < 3 {
        return;
    }
    let radius = (3.0 * sigma).ceil() as usize;
    let weights: Vec<f64> = (0..=radius)
        .map(|k| (-0.5 * (k as f64 / sigma).powi(2)).exp())
        .collect();
    let source = x.clone();
    for i in 1..t {
        let (lo, hi) = (i.saturating_sub(radius), (i + radius).min(t - 1));
        let mut total = 0.0;
        let mut acc = vec![0.0; x.ncols()];
        for k in lo..=hi {
            let w = weights[k.abs_diff(i)];
            total += w;
            for (a, v) in acc.iter_mut().zip(source.row(k).iter()) {
                *a += w * v;
            }
        }
        for (c, a) in acc.into_iter().enumerate() {
            x[(i, c)] = a / total;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keeps_lines_and_the_first_point_and_damps_jitter() {
        // A straight line through time is reproduced away from the ends (symmetric weights).
        let mut line = DMatrix::from_fn(40, 2, |i, c| 0.1 * i as f64 + c as f64);
        let orig = line.clone();
        smooth_trajectory(&mut line, 1.5);
        assert_eq!(line.row(0), orig.row(0));
        for i in 5..35 {
            for c in 0..2 {
                assert!((line[(i, c)] - orig[(i, c)]).abs() < 1e-12);
            }
        }
        // Alternating jitter of amplitude 1 is damped to the Gaussian's response at the
        // Nyquist frequency, about exp(−π²σ²/2) = 1.5e-5 for σ = 1.5.
        let mut zig = DMatrix::from_fn(40, 1, |i, _| if i % 2 == 0 { 1.0 } else { -1.0 });
        smooth_trajectory(&mut zig, 1.5);
        for i in 5..35 {
            assert!(zig[(i, 0)].abs() < 0.01, "frame {i}: {}", zig[(i, 0)]);
        }
        // sigma 0: unchanged.
        let mut same = orig.clone();
        smooth_trajectory(&mut same, 0.0);
        assert_eq!(same, orig);
    }
}
