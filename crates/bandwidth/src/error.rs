//! The crate's error type.

use std::fmt;

/// Everything that can go wrong in this crate: bad arguments are reported, never panicked on.
#[derive(Clone, Debug, PartialEq)]
pub enum BandwidthError {
    /// An argument outside its documented domain, with an explanation.
    InvalidArgument(String),
    /// A profile returned NaN or ±∞ at a sample point.
    NonFiniteProfile {
        /// x coordinate of the sample (mm).
        x_mm: f64,
        /// y coordinate of the sample (mm).
        y_mm: f64,
    },
    /// A mesh that cannot be processed (index out of range, non-finite position).
    InvalidMesh(String),
}

impl fmt::Display for BandwidthError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            BandwidthError::InvalidArgument(msg) => f.write_str(msg),
            BandwidthError::NonFiniteProfile { x_mm, y_mm } => write!(
                f,
                "the profile is not finite at ({x_mm} mm, {y_mm} mm): profiles must return finite values"
            ),
            BandwidthError::InvalidMesh(msg) => write!(f, "invalid mesh: {msg}"),
        }
    }
}

impl std::error::Error for BandwidthError {}
