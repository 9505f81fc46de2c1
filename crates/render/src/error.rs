//! The crate's error type.

use sss_bssrdf::BssrdfError;
use sss_scene::{SceneError, SceneErrorKind};
use std::fmt;

/// Everything the command-line tool and the library around it report.
///
/// Messages are single lines meant for a person (`error: ` is prepended by the binary).
#[derive(Debug)]
pub enum Error {
    /// Invalid user input that was not caught by argument parsing (exit code 2).
    Input(String),
    /// An invalid medium or model parameter (exit code 2).
    Bssrdf(BssrdfError),
    /// An I/O failure, with what was being done (exit code 1).
    Io {
        /// What was being read or written.
        what: String,
        /// The underlying error.
        source: std::io::Error,
    },
    /// A scene file is invalid, names a missing mesh, or cannot be read (exit code 2, or 1
    /// for a read failure).
    Scene(SceneError),
    /// A model produced a value that is not a finite number (exit code 1): a bug in the model,
    /// reported instead of printed.
    NonFinite(String),
    /// The method cannot render this scene as asked (exit code 2), e.g. a method that sums
    /// R_d·E·A over clusters on a material with the directional dipole. `compare` skips such
    /// method–scene pairs and lists them.
    Unsupported(String),
}

impl Error {
    /// The process exit code for this error: 2 for bad input, 1 for failures while running.
    pub fn exit_code(&self) -> u8 {
        match self {
            Error::Input(_) | Error::Bssrdf(_) | Error::Unsupported(_) => 2,
            Error::Scene(e) if e.kind == SceneErrorKind::Io => 1,
            Error::Scene(_) => 2,
            Error::Io { .. } | Error::NonFinite(_) => 1,
        }
    }
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::Input(msg) | Error::NonFinite(msg) | Error::Unsupported(msg) => f.write_str(msg),
            Error::Bssrdf(e) => write!(f, "{e}"),
            Error::Scene(e) => write!(f, "{e}"),
            Error::Io { what, source } => write!(f, "{what}: {source}"),
        }
    }
}

impl std::error::Error for Error {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            Error::Bssrdf(e) => Some(e),
            Error::Scene(e) => Some(e),
            Error::Io { source, .. } => Some(source),
            _ => None,
        }
    }
}

impl From<BssrdfError> for Error {
    fn from(e: BssrdfError) -> Self {
        match e {
            BssrdfError::NonFinite(msg) => Error::NonFinite(msg),
            e => Error::Bssrdf(e),
        }
    }
}

impl From<SceneError> for Error {
    fn from(e: SceneError) -> Self {
        Error::Scene(e)
    }
}
