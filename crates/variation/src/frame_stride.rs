//! Training at a reduced frame rate, sampling at the capture's (a deviation from the paper,
//! which fits every frame; `docs/DEVIATIONS.md`, "Frame stride").
//!
//! The GPDM's cost grows as N³ in training frames (3DV eqs. 3 and 5 factor N × N kernels every
//! objective evaluation), and a 50 fps capture doubles N against a 25 fps one without adding
//! poses the dynamics need. With a stride `s`, training keeps frames `0, s, 2s, …` of every
//! time-aligned sequence ([`kept_frames`]), so the first-order dynamics of 3DV eq. 2 learn the step
//! over `s` capture frames; the torso's per-frame displacement columns keep their meaning (metres
//! and radians *per capture frame*) by averaging the `s` displacements of each step
//! ([`strided_displacements`]). Sampled and learned trajectories are brought back to the
//! capture's rate by Catmull-Rom interpolation in the latent space ([`upsample`]) before decoding
//! (3DV eq. 12 is smooth in `x`), so every output keeps the capture's frame count and rate.

use nalgebra::DMatrix;

/// The stride that brings `fps` to about `fit_rate` frames per second (at least 1), lowered,
/// when `min_frames` is given, until `frames` capture frames keep at least `min_frames` (or the
/// stride is 1), then raised, when `max_frames` is given, until they keep at most `max_frames`.
pub fn stride_for(
    fps: f64,
    fit_rate: Option<f64>,
    frames: usize,
    min_frames: Option<usize>,
    max_frames: Option<usize>,
) -> usize {
    let mut s = match fit_rate {
        Some(r) if r > 0.0 && fps > r => (fps / r).round().max(1.0) as usize,
        _ => 1,
    };
    if let Some(m) = min_frames {
        while s > 1 && kept_count(frames, s) < m {
            s -= 1;
        }
    }
    if let Some(m) = max_frames.filter(|&m| m >= 2) {
        while kept_count(frames, s) > m {
            s += 1;
        }
    }
    s
}

/// Number of frames a sequence of `frames` keeps at stride `s`: `⌊(frames − 1)/s⌋ + 1`.
pub fn kept_count(frames: usize, s: usize) -> usize {
    if frames == 0 {
        0
    } else {
        (frames - 1) / s.max(1) + 1
    }
}

/// Indices of the kept frames `0, s, 2s, …` (the last at most `frames − 1`).
pub fn kept_frames(frames: usize, s: usize) -> Vec<usize> {
    (0..kept_count(frames, s)).map(|i| i * s.max(1)).collect()
}

/// Rows `0, s, 2s, …` of `m`.
pub fn strided_rows(m: &DMatrix<f64>, s: usize) -> DMatrix<f64> {
    let kept = kept_frames(m.nrows(), s);
    DMatrix::from_fn(kept.len(), m.ncols(), |i, c| m[(kept[i], c)])
}

/// Per-frame displacements at the kept frames: kept frame `i > 0` takes the mean of capture
/// frames `(i−1)s+1 ..= is` (so the value stays a per-capture-frame rate), kept frame 0 takes
/// kept frame 1's (as [`crate::part_data::model_displacements`] does at stride 1).
pub fn strided_displacements(disp: &[[f64; 6]], s: usize) -> Vec<[f64; 6]> {
    let s = s.max(1);
    let kept = kept_frames(disp.len(), s);
    let mut out: Vec<[f64; 6]> = kept
        .iter()
        .map(|&f| {
            if f == 0 {
                return disp[0];
            }
            let mut m = [0.0; 6];
            for d in &disp[f + 1 - s..=f] {
                for k in 0..6 {
                    m[k] += d[k] / s as f64;
                }
            }
            m
        })
        .collect();
    if out.len() > 1 {
        out[0] = out[1];
    }
    out
}

/// The strided length that covers `frames` capture frames: `⌈(frames − 1)/s⌉ + 1` points, so
/// that [`upsample`] never extrapolates.
pub fn covering_count(frames: usize, s: usize) -> usize {
    if frames == 0 {
        0
    } else {
        (frames - 1).div_ceil(s.max(1)) + 1
    }
}

/// A trajectory sampled every `s` capture frames (row `i` at capture frame `i·s`), interpolated
/// to `frames` capture frames by uniform Catmull-Rom splines (through every point, continuous
/// velocity; end tangents by one-sided differences). Frames past the last point hold it. At
/// `s = 1` the rows are returned unchanged (cut or held to `frames`).
pub fn upsample(x: &DMatrix<f64>, s: usize, frames: usize) -> DMatrix<f64> {
    let (n, d) = x.shape();
    let s = s.max(1);
    if n == 0 {
        return DMatrix::zeros(frames, d);
    }
    let row = |i: isize| {
        let i = i.clamp(0, n as isize - 1) as usize;
        x.row(i)
    };
    DMatrix::from_fn(frames, d, |t, c| {
        let (i, r) = (t / s, t % s);
        if r == 0 || i + 1 >= n {
            return row(i as isize)[c];
        }
        let u = r as f64 / s as f64;
        let i = i as isize;
        let (p0, p1, p2, p3) = (row(i - 1)[c], row(i)[c], row(i + 1)[c], row(i + 2)[c]);
        // Tangents (p_{i+1} − p_{i−1})/2; at the ends the clamped rows make them one-sided.
        let m1 = if i == 0 { p2 - p1 } else { 0.5 * (p2 - p0) };
        let m2 = if i + 2 >= n as isize {
            p2 - p1
        } else {
            0.5 * (p3 - p1)
        };
        let (u2, u3) = (u * u, u * u * u);
        (2.0 * u3 - 3.0 * u2 + 1.0) * p1
            + (u3 - 2.0 * u2 + u) * m1
            + (-2.0 * u3 + 3.0 * u2) * p2
            + (u3 - u2) * m2
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn strides_reach_the_fit_rate_and_the_frame_cap() {
        assert_eq!(stride_for(50.0, Some(25.0), 600, None, None), 2);
        assert_eq!(stride_for(25.0, Some(25.0), 600, None, None), 1);
        assert_eq!(stride_for(20.0, Some(25.0), 600, None, None), 1);
        assert_eq!(stride_for(100.0, None, 600, None, None), 1);
        // 600 frames at stride 2 keep 300; a cap of 200 needs stride 3.
        assert_eq!(stride_for(50.0, Some(25.0), 600, None, Some(200)), 3);
        assert!(kept_count(600, 3) <= 200 && kept_count(600, 2) > 200);
    }

    #[test]
    fn short_clips_keep_the_minimum_of_frames() {
        // B's 104-frame jump at 50 fps would keep 52 frames at stride 2: below 100, every frame.
        assert_eq!(stride_for(50.0, Some(25.0), 104, Some(100), Some(240)), 1);
        // 120 fps: stride 5 keeps 60 of 300 frames, 4 keeps 75, 3 keeps 100: stride 3.
        assert_eq!(stride_for(120.0, Some(25.0), 300, Some(100), Some(240)), 3);
        assert!(kept_count(300, 3) >= 100 && kept_count(300, 4) < 100);
        // Long enough at the fit rate: unchanged; the cap still wins over the minimum.
        assert_eq!(stride_for(50.0, Some(25.0), 444, Some(100), Some(240)), 2);
        assert_eq!(stride_for(50.0, Some(25.0), 600, Some(100), Some(200)), 3);
        // A clip shorter than the minimum keeps every frame.
        assert_eq!(stride_for(50.0, Some(25.0), 60, Some(100), Some(240)), 1);
    }

    #[test]
    fn kept_frames_and_covering_count() {
        assert_eq!(kept_frames(7, 2), vec![0, 2, 4, 6]);
        assert_eq!(kept_frames(8, 2), vec![0, 2, 4, 6]);
        assert_eq!(covering_count(8, 2), 5); // 0, 2, 4, 6, 8 ≥ 7
        assert_eq!(covering_count(7, 2), 4);
        assert_eq!(kept_frames(5, 1), vec![0, 1, 2, 3, 4]);
    }

    #[test]
    fn upsampling_a_cubic_sampled_trajectory_is_exact_inside_and_keeps_the_points() {
        // Catmull-Rom reproduces polynomials up to degree 2 exactly away from the ends
        // (its tangents are exact central differences of a quadratic).
        let f = |t: f64| 0.3 + 0.02 * t - 0.001 * t * t;
        let s = 3;
        let x = DMatrix::from_fn(10, 1, |i, _| f((i * s) as f64));
        let up = upsample(&x, s, 28);
        for t in 0..28 {
            let e = (up[(t, 0)] - f(t as f64)).abs();
            if t % s == 0 {
                assert!(e < 1e-15, "frame {t}: the sampled point is kept");
            } else if t >= s && t < 27 - s {
                assert!(e < 1e-12, "frame {t}: error {e}");
            }
        }
        assert_eq!(upsample(&x, 1, 10), x);
    }

    #[test]
    fn strided_displacements_keep_the_per_frame_rate() {
        // Constant velocity 0.01 m per frame along x: every stride keeps 0.01.
        let disp: Vec<[f64; 6]> = (0..9).map(|_| [0.01, 0.0, 0.0, 0.0, 0.002, 0.0]).collect();
        for s in 1..4 {
            for d in strided_displacements(&disp, s) {
                assert!((d[0] - 0.01).abs() < 1e-15 && (d[4] - 0.002).abs() < 1e-15);
            }
        }
        // A ramp: the mean of frames 1..=2 and 3..=4.
        let ramp: Vec<[f64; 6]> = (0..5)
            .map(|t| [t as f64, 0.0, 0.0, 0.0, 0.0, 0.0])
            .collect();
        let st = strided_displacements(&ramp, 2);
        assert_eq!(
            st.iter().map(|d| d[0]).collect::<Vec<_>>(),
            vec![1.5, 1.5, 3.5]
        );
    }
}
