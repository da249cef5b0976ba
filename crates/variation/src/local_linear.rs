//! Gaussian-weighted local linear fits along time: at every frame, the value of the line that
//! fits the frames around it, each weighted by a Gaussian of its distance in frames. In the
//! interior it smooths like a Gaussian average; at the ends of a sequence, where a renormalised
//! Gaussian average leans toward the frames on one side (a steady drift lags, a first frame jumps
//! toward the next ones), the fitted line follows the trend.

/// Gaussian-weighted local linear fit of `e` at every frame (width `sigma` frames; `sigma <= 0`
/// returns `e`): at frame `t`, the value at `t` of the line minimising
/// `Σ_s exp(−(s − t)² / 2σ²) (e_s − a − b (s − t))²`.
pub fn fit(e: &[f64], sigma: f64) -> Vec<f64> {
    if !(sigma > 0.0) || e.len() < 3 {
        return e.to_vec();
    }
    let reach = (4.0 * sigma).ceil() as isize;
    (0..e.len() as isize)
        .map(|t| {
            let (mut s0, mut s1, mut s2, mut y0, mut y1) = (0.0, 0.0, 0.0, 0.0, 0.0);
            for s in (t - reach).max(0)..=(t + reach).min(e.len() as isize - 1) {
                let x = (s - t) as f64;
                let w = (-0.5 * x * x / (sigma * sigma)).exp();
                let y = e[s as usize];
                s0 += w;
                s1 += w * x;
                s2 += w * x * x;
                y0 += w * y;
                y1 += w * x * y;
            }
            let det = s0 * s2 - s1 * s1;
            if det.abs() <= 1e-12 * s0 * s2.max(1.0) {
                y0 / s0
            } else {
                (s2 * y0 - s1 * y1) / det
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

}
