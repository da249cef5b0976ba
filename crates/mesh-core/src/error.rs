//! One error type for library code. Every variant renders as a single line
//! that names the file (when there is one) and the problem, so that a stage
//! can print `stage: file: problem` and exit 1.

use std::path::{Path, PathBuf};

#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A problem with the contents of a named file (malformed, truncated, wrong kind...).
    #[error("{}: {msg}", path.display())]
    File { path: PathBuf, msg: String },
    /// An operating-system error while reading or writing a named file.
    #[error("{}: {source}", path.display())]
    Io { path: PathBuf, source: std::io::Error },
    /// Bad input that is not tied to one file (e.g. two sequences that disagree).
    #[error("{0}")]
    Invalid(String),
}

pub type Result<T> = std::result::Result<T, Error>;

impl Error {
    pub fn file(path: impl AsRef<Path>, msg: impl Into<String>) -> Self {
        Error::File { path: path.as_ref().to_path_buf(), msg: msg.into() }
    }
    pub fn io(path: impl AsRef<Path>, source: std::io::Error) -> Self {
        Error::Io { path: path.as_ref().to_path_buf(), source }
    }
    pub fn invalid(msg: impl Into<String>) -> Self {
        Error::Invalid(msg.into())
    }
}
