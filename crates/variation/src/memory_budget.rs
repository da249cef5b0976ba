//! What a query of `hmc-sample` will hold in memory, checked before any of it is allocated: a
//! length or count the machine cannot hold is refused with one line naming the flags, instead
//! of an allocation failure or an abort part way through.

use mesh_core::{Error, Result};

/// Bytes of one vertex of a decoded frame (three f64).
const VERTEX_BYTES: u128 = 24;

/// Estimated peak bytes of synthesising `n` variations of `frames` frames of a body of
/// `vertices` vertices: every variation of one sequence is kept decoded for its statistics,
/// plus the source and one decoding buffer per thread.
pub fn bytes_needed(n: usize, frames: usize, vertices: usize, threads: usize) -> u128 {
    (n as u128 + 1 + threads as u128) * frames as u128 * vertices as u128 * VERTEX_BYTES
}

/// Total physical memory (bytes) from `/proc/meminfo`, None where it cannot be read.
pub fn physical_memory() -> Option<u128> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemTotal:"))?;
    let kb: u128 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

/// `n` bytes in GB (10⁹), one decimal.
fn gb(n: u128) -> String {
    format!("{:.1} GB", n as f64 / 1e9)
}

/// Refuses a query of `needed` bytes above `available` (physical memory), naming the flags
/// `-n N` and `--frame-count F` that set its size.
pub fn check(n: usize, frames: usize, needed: u128, available: Option<u128>) -> Result<()> {
    match available {
        Some(avail) if needed > avail => Err(Error::invalid(format!(
            "-n {n} --frame-count {frames}: the variations would need about {} of memory, more than \
             this machine's {} (ask for fewer or shorter variations)",
            gb(needed),
            gb(avail)
        ))),
        _ => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ten_million_frames_of_a_body_are_refused_and_a_capture_length_is_not() {
        let needed = bytes_needed(5, 10_000_000, 13_380, 2);
        // 8 frames' worth of 10⁷ × 13,380 vertices × 24 bytes: 2.6 × 10¹³ bytes.
        assert_eq!(needed, 8 * 10_000_000 * 13_380 * 24);
        let err = check(5, 10_000_000, needed, Some(64 << 30)).unwrap_err().to_string();
        assert!(err.contains("--frame-count 10000000") && err.contains("GB"), "{err}");
        assert!(check(5, 300, bytes_needed(5, 300, 13_380, 2), Some(8 << 30)).is_ok());
    }

    #[test]
    fn this_machine_reports_some_memory() {
        assert!(physical_memory().is_some_and(|m| m > 1 << 20));
    }
}
