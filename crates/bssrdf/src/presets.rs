//! Measured materials of Jensen, Marschner, Levoy and Hanrahan, *A Practical Model for
//! Subsurface Light Transport*, SIGGRAPH 2001, Table 2 (also in pbrt-v3/v4's
//! `GetMediumScatteringProperties`).
//!
//! The table lists reduced scattering σ'_s and absorption σ_a in 1/mm for red, green and blue,
//! measured with η = 1.3, and the total diffuse reflectance R_d the authors computed from them.

use crate::{BssrdfError, Rgb};

/// Relative index of refraction of the measurements (Jensen et al. 2001, Table 2 caption).
pub const PRESET_ETA: f64 = 1.3;

/// One row of the measured table.
#[derive(Clone, Copy, Debug)]
pub struct Preset {
    /// Name as printed in the paper.
    pub name: &'static str,
    /// Reduced scattering coefficient σ'_s (1/mm).
    pub sigma_s_reduced: Rgb,
    /// Absorption coefficient σ_a (1/mm).
    pub sigma_a: Rgb,
    /// Total diffuse reflectance R_d as published in the table.
    pub published_rd: Rgb,
}

const fn p(name: &'static str, s: Rgb, a: Rgb, rd: Rgb) -> Preset {
    Preset {
        name,
        sigma_s_reduced: s,
        sigma_a: a,
        published_rd: rd,
    }
}

/// Every measured material of Jensen et al. 2001, Table 2.
pub const PRESETS: [Preset; 12] = [
    p(
        "apple",
        [2.29, 2.39, 1.97],
        [0.0030, 0.0034, 0.046],
        [0.85, 0.84, 0.53],
    ),
    p(
        "chicken1",
        [0.15, 0.21, 0.38],
        [0.015, 0.077, 0.19],
        [0.31, 0.15, 0.10],
    ),
    p(
        "chicken2",
        [0.19, 0.25, 0.32],
        [0.018, 0.088, 0.20],
        [0.32, 0.16, 0.10],
    ),
    p(
        "cream",
        [7.38, 5.47, 3.15],
        [0.0002, 0.0028, 0.0163],
        [0.98, 0.90, 0.73],
    ),
    p(
        "ketchup",
        [0.18, 0.07, 0.03],
        [0.061, 0.97, 1.45],
        [0.16, 0.01, 0.00],
    ),
    p(
        "marble",
        [2.19, 2.62, 3.00],
        [0.0021, 0.0041, 0.0071],
        [0.83, 0.79, 0.75],
    ),
    p(
        "potato",
        [0.68, 0.70, 0.55],
        [0.0024, 0.0090, 0.12],
        [0.77, 0.62, 0.21],
    ),
    p(
        "skimmilk",
        [0.70, 1.22, 1.90],
        [0.0014, 0.0025, 0.0142],
        [0.81, 0.81, 0.69],
    ),
    p(
        "skin1",
        [0.74, 0.88, 1.01],
        [0.032, 0.17, 0.48],
        [0.44, 0.22, 0.13],
    ),
    p(
        "skin2",
        [1.09, 1.59, 1.79],
        [0.013, 0.070, 0.145],
        [0.63, 0.44, 0.34],
    ),
    p(
        "spectralon",
        [11.6, 20.4, 14.9],
        [0.00, 0.00, 0.00],
        [1.00, 1.00, 1.00],
    ),
    p(
        "wholemilk",
        [2.55, 3.21, 3.77],
        [0.0011, 0.0024, 0.014],
        [0.91, 0.88, 0.76],
    ),
];

/// Looks a preset up by name, ignoring case, spaces, `-` and `_` (`Skim Milk` = `skimmilk`).
pub fn find(name: &str) -> Result<&'static Preset, BssrdfError> {
    let key: String = name
        .chars()
        .filter(|c| !matches!(c, ' ' | '-' | '_'))
        .flat_map(char::to_lowercase)
        .collect();
    PRESETS
        .iter()
        .find(|p| p.name == key)
        .ok_or_else(|| BssrdfError::UnknownPreset(name.to_string()))
}
