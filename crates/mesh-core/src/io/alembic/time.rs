//! Time samplings: the time of a sample, the sample nearest a time, and a sampling's frame rate.

/// Time per cycle of acyclic time samplings (`f64::MAX / 32` in Alembic).
pub(super) const ACYCLIC_TIME_PER_CYCLE: f64 = f64::MAX / 32.0;

/// A time sampling: time per cycle and the times of one cycle.
#[derive(Clone, Debug)]
pub(super) struct TimeSampling {
    pub(super) time_per_cycle: f64,
    pub(super) times: Vec<f64>,
}

/// Where a sample lies in time: sample `i` of a sampling.
pub(super) fn sample_time(ts: &TimeSampling, i: u32) -> f64 {
    let n = ts.times.len().max(1);
    if ts.time_per_cycle >= ACYCLIC_TIME_PER_CYCLE {
        return ts.times.get(i as usize).or(ts.times.last()).copied().unwrap_or(0.0);
    }
    let (cycle, k) = (i as usize / n, i as usize % n);
    ts.times.get(k).copied().unwrap_or(0.0) + cycle as f64 * ts.time_per_cycle
}

/// The sample (of `samples`) of a sampling nearest to time `t`.
pub(super) fn sample_near(ts: &TimeSampling, samples: u32, t: f64) -> u32 {
    // Times increase with the index: the first sample at or after t, or the one before it.
    let (mut lo, mut hi) = (0u32, samples.saturating_sub(1));
    while lo < hi {
        let mid = lo + (hi - lo) / 2;
        if sample_time(ts, mid) < t {
            lo = mid + 1;
        } else {
            hi = mid;
        }
    }
    if lo > 0 && (t - sample_time(ts, lo - 1)).abs() <= (sample_time(ts, lo) - t).abs() {
        lo - 1
    } else {
        lo
    }
}

/// The frames per second of a time sampling: uniform (one time per cycle), or acyclic with
/// evenly spaced times.
pub(super) fn sampling_fps(ts: &TimeSampling, what: &str) -> std::result::Result<f64, String> {
    let fps = if ts.time_per_cycle >= ACYCLIC_TIME_PER_CYCLE {
        let steps: Vec<f64> = ts.times.windows(2).map(|w| w[1] - w[0]).collect();
        let Some(&dt) = steps.first() else {
            return Err(format!("{what}'s acyclic time sampling has a single time: no frame rate"));
        };
        if steps.iter().any(|s| (s - dt).abs() > 1e-9 * dt.abs()) {
            return Err(format!("{what}'s time sampling is acyclic with uneven steps: no frame rate"));
        }
        1.0 / dt
    } else if ts.times.len() == 1 {
        1.0 / ts.time_per_cycle
    } else {
        return Err(format!(
            "{what}'s time sampling is cyclic ({} samples per cycle), not uniform: no frame rate",
            ts.times.len()
        ));
    };
    // 1 / (1/24) may come back as 24.000000000000004: snap to a thousandth when that close.
    let snapped = (fps * 1000.0).round() / 1000.0;
    let fps = if (fps - snapped).abs() <= 1e-9 * fps.abs() { snapped } else { fps };
    crate::frame_rate::check_fps(fps).map_err(|e| format!("{what}'s time sampling: {e}"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_rates_of_time_samplings() {
        let ts = |time_per_cycle, times: &[f64]| TimeSampling { time_per_cycle, times: times.to_vec() };
        assert_eq!(sampling_fps(&ts(1.0 / 24.0, &[0.0]), "P"), Ok(24.0));
        assert_eq!(sampling_fps(&ts(1.0 / 25.0, &[1.0 / 25.0]), "P"), Ok(25.0));
        assert!((sampling_fps(&ts(1001.0 / 30000.0, &[0.0]), "P").unwrap() - 30000.0 / 1001.0).abs() < 1e-9);
        assert_eq!(sampling_fps(&ts(ACYCLIC_TIME_PER_CYCLE, &[0.0, 0.02, 0.04]), "P"), Ok(50.0));
        assert!(sampling_fps(&ts(ACYCLIC_TIME_PER_CYCLE, &[0.0, 0.02, 0.05]), "P").unwrap_err().contains("uneven"));
        assert!(sampling_fps(&ts(1.0, &[0.0, 0.5]), "P").unwrap_err().contains("cyclic"));
        assert!(sampling_fps(&ts(1e-300, &[0.0]), "P").unwrap_err().contains("outside 1 to 10000 fps"));
        assert!(sampling_fps(&ts(0.0, &[0.0]), "P").is_err());
        assert!(sampling_fps(&ts(-0.04, &[0.0]), "P").is_err());
        // Sample times, and the sample of an animated Xform nearest a frame's time.
        let uniform = ts(0.04, &[0.04]);
        assert!((sample_time(&uniform, 2) - 0.12).abs() < 1e-15);
        assert_eq!([0.08, 0.081, 10.0, -5.0].map(|t| sample_near(&uniform, 3, t)), [1, 1, 2, 0]);
        let acyclic = ts(ACYCLIC_TIME_PER_CYCLE, &[0.0, 0.5, 2.0]);
        assert_eq!([0.2, 0.3, 1.9, 9.0].map(|t| sample_near(&acyclic, 3, t)), [0, 1, 2, 2]);
        assert_eq!(sample_near(&uniform, 0, 1.0), 0);
    }
}
