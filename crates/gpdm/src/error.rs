//! Errors of the GPDM library: shape mismatches, bad input, factorisation failures.

/// Everything that can go wrong in this crate; messages are one line.
#[derive(Debug, thiserror::Error)]
pub enum GpdmError {
    /// A kernel matrix stayed non-positive-definite after all jitter retries (or another
    /// failure of the shared linear algebra).
    #[error(transparent)]
    Linalg(#[from] gp::GpError),
    /// Inconsistent shapes or invalid parameters supplied by the caller.
    #[error("invalid input: {0}")]
    Invalid(String),
}

/// Crate result type.
pub type Result<T> = std::result::Result<T, GpdmError>;

pub(crate) fn invalid<T>(msg: impl Into<String>) -> Result<T> {
    Err(GpdmError::Invalid(msg.into()))
}
