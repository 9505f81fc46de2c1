//! The crate's error type.

use std::fmt;

/// Everything that can go wrong in this crate. Bad input is reported, never a panic.
#[derive(Clone, Debug, PartialEq)]
pub enum SeparableError {
    /// An argument outside its documented range (the message says which and why).
    InvalidArgument(String),
    /// A buffer of [`crate::ScreenInput`] (or another image) has the wrong length.
    BufferSize {
        /// Which buffer.
        what: &'static str,
        /// The length it should have (width × height).
        expected: usize,
        /// The length it has.
        got: usize,
    },
    /// A kernel has (close to) zero energy in a channel, so it cannot be renormalised.
    ZeroEnergy {
        /// The channel.
        channel: usize,
    },
    /// The singular value decomposition failed (non-finite input, or no convergence).
    Svd(String),
    /// A kernel file ([`crate::kernel_json`]) that cannot be read or written: the message
    /// names the field and what is wrong with it.
    KernelFile(String),
}

impl fmt::Display for SeparableError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SeparableError::InvalidArgument(m) => write!(f, "invalid argument: {m}"),
            SeparableError::BufferSize {
                what,
                expected,
                got,
            } => write!(f, "buffer `{what}` has {got} elements, expected {expected}"),
            SeparableError::ZeroEnergy { channel } => write!(
                f,
                "kernel has no energy in channel {channel}, cannot renormalise it"
            ),
            SeparableError::Svd(m) => write!(f, "singular value decomposition failed: {m}"),
            SeparableError::KernelFile(m) => write!(f, "kernel file: {m}"),
        }
    }
}

impl std::error::Error for SeparableError {}

/// `Err(InvalidArgument(msg))` unless `ok`.
pub(crate) fn ensure(ok: bool, msg: impl FnOnce() -> String) -> Result<(), SeparableError> {
    if ok {
        Ok(())
    } else {
        Err(SeparableError::InvalidArgument(msg()))
    }
}
