//! The frame rate a mesh sequence folder plays at: an explicit `--fps`, else the folder's own
//! rate file ([`mesh_core::sequence::RATE_FILE`], written by `gpr-predict` and `hmc-sample`), else
//! the `subject.json` of the capture set the folder belongs to (`set/A/walk`, `set/A/test/walk`),
//! else [`FALLBACK_FPS`] with the reason stated.

use std::fmt;
use std::path::{Path, PathBuf};

use mesh_core::capture_set::SubjectSpec;
use mesh_core::Result;

/// The rate assumed when nothing records one.
pub const FALLBACK_FPS: f64 = 30.0;

/// Where a sequence's frame rate came from.
#[derive(Clone, Debug, PartialEq)]
pub enum RateSource {
    /// `--fps` on the command line.
    Given,
    /// The folder's rate file.
    RateFile(PathBuf),
    /// The capture's `subject.json`.
    Subject(PathBuf),
    /// Nothing recorded: [`FALLBACK_FPS`].
    Fallback,
}

impl fmt::Display for RateSource {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            RateSource::Given => f.write_str("--fps"),
            RateSource::RateFile(p) | RateSource::Subject(p) => write!(f, "{}", p.display()),
            RateSource::Fallback => f.write_str("no rate recorded"),
        }
    }
}

/// The frame rate of the sequence folder `dir` and where it came from (module doc).
pub fn sequence_fps(dir: &Path, given: Option<f64>) -> Result<(f64, RateSource)> {
    if let Some(fps) = given {
        mesh_core::frame_rate::check_fps(fps).map_err(|e| mesh_core::Error::invalid(format!("--fps: {e}")))?;
        return Ok((fps, RateSource::Given));
    }
    if let Some(fps) = mesh_core::sequence::read_rate(dir)? {
        return Ok((fps, RateSource::RateFile(dir.join(mesh_core::sequence::RATE_FILE))));
    }
    if let Some((path, spec)) = sequence_subject(dir)? {
        return Ok((spec.fps, RateSource::Subject(path)));
    }
    Ok((FALLBACK_FPS, RateSource::Fallback))
}

/// The `subject.json` of the capture set the sequence folder `dir` belongs to, if any: a motion
/// folder sits in its subject's folder, a test motion one deeper.
pub fn sequence_subject(dir: &Path) -> Result<Option<(PathBuf, SubjectSpec)>> {
    for subject_dir in dir.ancestors().skip(1).take(2) {
        let path = subject_dir.join("subject.json");
        if path.is_file() {
            let spec = SubjectSpec::load(&path)?;
            return Ok(Some((path, spec)));
        }
    }
    Ok(None)
}
