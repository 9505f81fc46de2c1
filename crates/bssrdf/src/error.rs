//! The crate's error type.

use std::fmt;

/// Everything that can go wrong when building a medium or a model.
///
/// Every constructor in this crate validates its input and returns one of these instead of
/// panicking, so that a renderer can report a bad scene file with a clear message.
#[derive(Clone, Debug, PartialEq)]
pub enum BssrdfError {
    /// A coefficient was negative, NaN or infinite. `what` names it (`sigma_a[1]`, ...).
    InvalidCoefficient {
        /// Which coefficient, e.g. `sigma_s[2]`.
        what: String,
        /// The offending value.
        value: f64,
    },
    /// A channel has neither absorption nor scattering, so nothing is defined there.
    NoExtinction {
        /// The channel index (0 = red, 1 = green, 2 = blue).
        channel: usize,
    },
    /// The relative index of refraction was not a finite number > 0.
    InvalidEta(f64),
    /// The Henyey-Greenstein anisotropy was not a finite number with |g| < 1.
    InvalidG(f64),
    /// An albedo outside [0, 1] (or NaN).
    InvalidAlbedo {
        /// The channel index.
        channel: usize,
        /// The offending value.
        value: f64,
    },
    /// A preset name not in the measured table.
    UnknownPreset(String),
    /// A model name that is not one of the models; the message lists [`crate::ModelKind::ALL`].
    UnknownModel(String),
    /// A requested diffuse reflectance the chosen model cannot produce for any albedo.
    UnreachableReflectance {
        /// The model that was inverted.
        model: &'static str,
        /// The channel index.
        channel: usize,
        /// The requested reflectance.
        requested: f64,
        /// The largest reflectance the model reaches (at albedo 1).
        max: f64,
    },
    /// Any other invalid argument, with an explanation.
    InvalidArgument(String),
    /// A computation gave a NaN or an infinity where a number was due (a bug, reported
    /// instead of printed); the message says what.
    NonFinite(String),
}

impl fmt::Display for BssrdfError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            BssrdfError::InvalidCoefficient { what, value } => write!(
                f,
                "{what} = {value}: coefficients must be finite and non-negative (1/mm)"
            ),
            BssrdfError::NoExtinction { channel } => write!(
                f,
                "channel {channel} has sigma_a = sigma_s = 0: the medium must absorb or scatter"
            ),
            BssrdfError::InvalidEta(e) => {
                write!(
                    f,
                    "eta = {e}: the relative index of refraction must be finite and > 0"
                )
            }
            BssrdfError::InvalidG(g) => {
                write!(
                    f,
                    "g = {g}: the phase anisotropy must be finite with |g| < 1"
                )
            }
            BssrdfError::InvalidAlbedo { channel, value } => {
                write!(f, "albedo[{channel}] = {value}: albedo must lie in [0, 1]")
            }
            BssrdfError::UnknownPreset(name) => write!(
                f,
                "unknown preset '{name}' (run `sss presets` for the list)"
            ),
            BssrdfError::UnknownModel(name) => {
                let names: Vec<&str> = crate::ModelKind::ALL.iter().map(|k| k.name()).collect();
                let (last, rest) = names.split_last().expect("at least one model");
                write!(
                    f,
                    "unknown model '{name}' (expected {} or {last})",
                    rest.join(", ")
                )
            }
            BssrdfError::UnreachableReflectance {
                model,
                channel,
                requested,
                max,
            } => write!(
                f,
                "diffuse reflectance {requested} in channel {channel} is out of reach of the {model} model for any albedo (it reaches at most {max:.6})"
            ),
            BssrdfError::InvalidArgument(msg) | BssrdfError::NonFinite(msg) => f.write_str(msg),
        }
    }
}

impl std::error::Error for BssrdfError {}
