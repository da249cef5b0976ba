//! Gaussian-weighted local linear fits along time: at every frame, the value of the line that
//! fits the frames around it, each weighted by a Gaussian of its distance in frames. In the
//! interior it smooths like a Gaussian average; at the ends of a sequence, where a renormalised
//! Gaussian average leans toward the frames on one side (a steady drift lags, a first frame jumps
//! toward the next ones), the fitted line follows the trend.

/// Gaussian-weighted local linear fit of `values` at every frame (window ±3σ frames; `sigma <= 0`
/// returns `values`): at frame `t`, the value at `t` of the line minimising
/// `Σ_s exp(−(s − t)² / 2σ²) (values_s − a − b (s − t))²`. Reproduces linear profiles exactly.
pub fn fit(values: &[f64], sigma: f64) -> Vec<f64> {
    if !(sigma > 0.0) || values.len() < 3 {
        return values.to_vec();
    }
    let r = (3.0 * sigma).ceil() as isize;
    let n = values.len() as isize;
    (0..n)
        .map(|t| {
            let (mut s0, mut s1, mut s2, mut sy, mut sxy) = (0.0, 0.0, 0.0, 0.0, 0.0);
            for j in (t - r).max(0)..=(t + r).min(n - 1) {
                let x = (j - t) as f64;
                let w = (-0.5 * (x / sigma).powi(2)).exp();
                let y = values[j as usize];
                s0 += w;
                s1 += w * x;
                s2 += w * x * x;
                sy += w * y;
                sxy += w * x * y;
            }
            let det = s0 * s2 - s1 * s1;
            if det.abs() < 1e-12 * s0 * s0 {
                sy / s0
            } else {
                // Intercept of the weighted least-squares line a + b x at x = 0.
                (s2 * sy - s1 * sxy) / det
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_local_linear_fit_keeps_a_line_to_its_ends_and_removes_a_fast_sway() {
        let line: Vec<f64> = (0..30).map(|t| 0.1 * t as f64 - 1.0).collect();
        for (a, b) in fit(&line, 5.0).iter().zip(&line) {
            assert!((a - b).abs() < 1e-9, "{a} vs {b}");
        }
        let sway: Vec<f64> = (0..60).map(|t| 0.2 * (t as f64 * std::f64::consts::PI / 2.0).sin()).collect();
        let smooth = fit(&sway, 5.0);
        assert!(smooth[15..45].iter().all(|v| v.abs() < 1e-3), "{smooth:?}");
    }


    #[test]
    fn a_local_linear_fit_keeps_lines_and_damps_spikes() {
        let line: Vec<f64> = (0..20).map(|t| 0.3 - 0.01 * t as f64).collect();
        for (a, b) in fit(&line, 2.0).iter().zip(&line) {
            assert!((a - b).abs() < 1e-12);
        }
        let mut spike = vec![0.0; 21];
        spike[10] = 1.0;
        let s = fit(&spike, 2.0);
        assert!(s[10] < 0.4 && s[10] > 0.0, "{}", s[10]);
    }

}
