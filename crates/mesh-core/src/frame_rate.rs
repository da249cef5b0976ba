//! The frame rates surfcap accepts: 1 to 10,000 frames per second, wherever a rate is read
//! (`subject.json`, a folder's `rate.json`, `--fps`, an aligned motion's record) or written.
//!
//! Outside that range a rate is a typo or a corrupt file, not a capture: 1e-300 fps makes the
//! key times of a glTF animation overflow to infinity (an invalid `.glb`), 1e300 fps puts every
//! frame at time 0. Real captures run at 24-240 fps, high-speed cameras at a few thousand.

/// The slowest accepted rate, frames per second.
pub const MIN_FPS: f64 = 1.0;
/// The fastest accepted rate, frames per second.
pub const MAX_FPS: f64 = 10_000.0;

/// `fps` itself when it lies in [`MIN_FPS`, `MAX_FPS`], else the problem as one line
/// (`frame rate 1e-300 fps is outside 1 to 10000 fps`); NaN and infinities are outside too.
pub fn check_fps(fps: f64) -> Result<f64, String> {
    if (MIN_FPS..=MAX_FPS).contains(&fps) {
        Ok(fps)
    } else {
        Err(format!("frame rate {} fps is outside {MIN_FPS} to {MAX_FPS} fps", short(fps)))
    }
}

/// `fps` as written in a message: plain for ordinary magnitudes, `1e-300` for the others (Rust's
/// plain form of 1e-300 has 300 zeros).
fn short(fps: f64) -> String {
    if fps == 0.0 || !fps.is_finite() || (1e-3..1e7).contains(&fps.abs()) {
        format!("{fps}")
    } else {
        format!("{fps:e}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rates_of_real_cameras_pass_and_absurd_ones_are_refused() {
        for fps in [1.0, 23.976, 25.0, 50.0, 240.0, 10_000.0] {
            assert_eq!(check_fps(fps), Ok(fps));
        }
        for fps in [1e-300, 0.5, 0.0, -25.0, 10_000.5, 1e300, f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            let err = check_fps(fps).unwrap_err();
            assert!(err.contains("outside 1 to 10000 fps"), "{fps}: {err}");
        }
        assert_eq!(check_fps(1e-300).unwrap_err(), "frame rate 1e-300 fps is outside 1 to 10000 fps");
        assert_eq!(check_fps(1e300).unwrap_err(), "frame rate 1e300 fps is outside 1 to 10000 fps");
        assert_eq!(check_fps(0.5).unwrap_err(), "frame rate 0.5 fps is outside 1 to 10000 fps");
    }
}
