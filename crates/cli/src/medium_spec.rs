//! The medium a command names (`--preset NAME` or `--sigma-a/--sigma-s/--g`, with `--eta`),
//! as data ([`MediumSpec`]) and as a validated [`Medium`] ([`build_medium`]); shared by
//! `sss profile`, `sss kernel` and `sss filter`.

use crate::Error;
use sss_bssrdf::{Medium, Rgb, presets};

/// Where the medium comes from.
#[derive(Clone, Debug, PartialEq)]
pub enum MediumSpec {
    /// A measured material of Jensen et al. 2001 by name (g = 0, σ_s = σ'_s).
    Preset(String),
    /// Explicit coefficients (1/mm) and anisotropy.
    Coefficients {
        /// Absorption σ_a per channel.
        sigma_a: Rgb,
        /// Scattering σ_s per channel.
        sigma_s: Rgb,
        /// Henyey-Greenstein anisotropy.
        g: f64,
    },
}

/// Builds the medium of `spec`, with `eta` if given (default [`presets::PRESET_ETA`]).
pub fn build_medium(spec: &MediumSpec, eta: Option<f64>) -> Result<Medium, Error> {
    let eta = eta.unwrap_or(presets::PRESET_ETA);
    let medium = match spec {
        MediumSpec::Preset(name) => Medium::preset(name)?.with_eta(eta)?,
        MediumSpec::Coefficients {
            sigma_a,
            sigma_s,
            g,
        } => Medium::new(*sigma_a, *sigma_s, *g, eta)?,
    };
    Ok(medium)
}

/// A short description of the medium for plot titles.
pub(crate) fn medium_label(spec: &MediumSpec, medium: &Medium) -> String {
    match spec {
        MediumSpec::Preset(name) => format!("{name}, eta {}", medium.eta()),
        MediumSpec::Coefficients {
            sigma_a,
            sigma_s,
            g,
        } => format!(
            "sigma_a {:?}, sigma_s {:?}, g {g}, eta {}",
            sigma_a,
            sigma_s,
            medium.eta()
        ),
    }
}
