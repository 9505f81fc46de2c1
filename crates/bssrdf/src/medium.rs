//! A homogeneous scattering medium behind a smooth dielectric boundary.

use crate::{BssrdfError, Rgb};

/// A homogeneous medium: per-channel (RGB) absorption and scattering coefficients in 1/mm, a
/// Henyey-Greenstein anisotropy `g` and the relative index of refraction `eta` (inside over
/// outside) of its smooth boundary.
///
/// Construct it with [`Medium::new`], [`Medium::from_extinction_albedo`],
/// [`Medium::preset`] or [`crate::from_reflectance`]; each validates its input. The derived
/// quantities follow Jensen et al. 2001 §2.4 (reduced coefficients σ'_s = σ_s(1-g),
/// σ'_t = σ_a + σ'_s, reduced albedo α' = σ'_s/σ'_t, effective transport coefficient
/// σ_tr = √(3σ_a σ'_t)).
#[derive(Clone, Debug, PartialEq)]
pub struct Medium {
    sigma_a: Rgb,
    sigma_s: Rgb,
    g: f64,
    eta: f64,
}

fn check_coefficient(name: &str, ch: usize, v: f64) -> Result<(), BssrdfError> {
    if !v.is_finite() || v < 0.0 {
        return Err(BssrdfError::InvalidCoefficient {
            what: format!("{name}[{ch}]"),
            value: v,
        });
    }
    Ok(())
}

fn check_g_eta(g: f64, eta: f64) -> Result<(), BssrdfError> {
    if !g.is_finite() || g.abs() >= 1.0 {
        return Err(BssrdfError::InvalidG(g));
    }
    if !eta.is_finite() || eta <= 0.0 {
        return Err(BssrdfError::InvalidEta(eta));
    }
    Ok(())
}

impl Medium {
    /// A medium from absorption and scattering coefficients (1/mm), anisotropy and relative
    /// index of refraction. Errors on negative, NaN or infinite coefficients, on a channel
    /// with σ_a = σ_s = 0, on `eta <= 0` and on `|g| >= 1`.
    pub fn new(sigma_a: Rgb, sigma_s: Rgb, g: f64, eta: f64) -> Result<Self, BssrdfError> {
        for ch in 0..3 {
            check_coefficient("sigma_a", ch, sigma_a[ch])?;
            check_coefficient("sigma_s", ch, sigma_s[ch])?;
            if sigma_a[ch] + sigma_s[ch] <= 0.0 {
                return Err(BssrdfError::NoExtinction { channel: ch });
            }
            if !(sigma_a[ch] + sigma_s[ch]).is_finite() {
                return Err(BssrdfError::InvalidCoefficient {
                    what: format!("sigma_t[{ch}]"),
                    value: sigma_a[ch] + sigma_s[ch],
                });
            }
        }
        check_g_eta(g, eta)?;
        Ok(Medium {
            sigma_a,
            sigma_s,
            g,
            eta,
        })
    }

    /// A medium from extinction σ_t (1/mm) and single-scattering albedo σ_s/σ_t per channel.
    pub fn from_extinction_albedo(
        sigma_t: Rgb,
        albedo: Rgb,
        g: f64,
        eta: f64,
    ) -> Result<Self, BssrdfError> {
        let mut sigma_a = [0.0; 3];
        let mut sigma_s = [0.0; 3];
        for ch in 0..3 {
            check_coefficient("sigma_t", ch, sigma_t[ch])?;
            let a = albedo[ch];
            if !(0.0..=1.0).contains(&a) {
                return Err(BssrdfError::InvalidAlbedo {
                    channel: ch,
                    value: a,
                });
            }
            sigma_s[ch] = a * sigma_t[ch];
            sigma_a[ch] = (1.0 - a) * sigma_t[ch];
        }
        Medium::new(sigma_a, sigma_s, g, eta)
    }

    /// A measured material of Jensen et al. 2001 (Table 2) by name, case-insensitive
    /// (see [`crate::presets::PRESETS`]). The table gives reduced scattering coefficients, so
    /// the medium has g = 0 and σ_s = σ'_s; eta is 1.3 as in the paper.
    pub fn preset(name: &str) -> Result<Self, BssrdfError> {
        let p = crate::presets::find(name)?;
        Medium::new(
            p.sigma_a,
            p.sigma_s_reduced,
            0.0,
            crate::presets::PRESET_ETA,
        )
    }

    /// The same medium with another relative index of refraction.
    pub fn with_eta(&self, eta: f64) -> Result<Self, BssrdfError> {
        Medium::new(self.sigma_a, self.sigma_s, self.g, eta)
    }

    /// The same medium with another anisotropy.
    pub fn with_g(&self, g: f64) -> Result<Self, BssrdfError> {
        Medium::new(self.sigma_a, self.sigma_s, g, self.eta)
    }

    /// Absorption coefficients σ_a (1/mm).
    pub fn sigma_a(&self) -> Rgb {
        self.sigma_a
    }
    /// Scattering coefficients σ_s (1/mm).
    pub fn sigma_s(&self) -> Rgb {
        self.sigma_s
    }
    /// Henyey-Greenstein anisotropy g.
    pub fn g(&self) -> f64 {
        self.g
    }
    /// Relative index of refraction η = n_inside / n_outside.
    pub fn eta(&self) -> f64 {
        self.eta
    }
    /// The bit patterns of σ_a, σ_s, g and η: equal exactly when the media are, for keying
    /// caches of per-medium work.
    pub fn bits(&self) -> [u64; 8] {
        let (a, s) = (self.sigma_a, self.sigma_s);
        [
            a[0].to_bits(),
            a[1].to_bits(),
            a[2].to_bits(),
            s[0].to_bits(),
            s[1].to_bits(),
            s[2].to_bits(),
            self.g.to_bits(),
            self.eta.to_bits(),
        ]
    }

    /// Extinction σ_t = σ_a + σ_s of channel `ch` (1/mm).
    pub fn sigma_t(&self, ch: usize) -> f64 {
        self.sigma_a[ch] + self.sigma_s[ch]
    }
    /// Single-scattering albedo σ_s/σ_t of channel `ch`.
    pub fn albedo(&self, ch: usize) -> f64 {
        self.sigma_s[ch] / self.sigma_t(ch)
    }
    /// Reduced scattering σ'_s = σ_s (1 - g) (1/mm).
    pub fn sigma_s_reduced(&self, ch: usize) -> f64 {
        self.sigma_s[ch] * (1.0 - self.g)
    }
    /// Reduced extinction σ'_t = σ_a + σ'_s (1/mm); > 0 for every valid medium.
    pub fn sigma_t_reduced(&self, ch: usize) -> f64 {
        self.sigma_a[ch] + self.sigma_s_reduced(ch)
    }
    /// Reduced albedo α' = σ'_s / σ'_t.
    pub fn reduced_albedo(&self, ch: usize) -> f64 {
        (self.sigma_s_reduced(ch) / self.sigma_t_reduced(ch)).clamp(0.0, 1.0)
    }
    /// Classical effective transport coefficient σ_tr = √(3 σ_a σ'_t) (1/mm), Jensen et al. 2001.
    pub fn sigma_tr(&self, ch: usize) -> f64 {
        (3.0 * self.sigma_a[ch] * self.sigma_t_reduced(ch))
            .max(0.0)
            .sqrt()
    }
    /// Mean free path 1/σ_t (mm).
    pub fn mean_free_path(&self, ch: usize) -> f64 {
        1.0 / self.sigma_t(ch)
    }
    /// Reduced (transport) mean free path ℓ = 1/σ'_t (mm): the length scale of every
    /// diffusion profile.
    pub fn reduced_mean_free_path(&self, ch: usize) -> f64 {
        1.0 / self.sigma_t_reduced(ch)
    }
}

/// Where a medium comes from, as a command or a binding names it: a measured preset by name
/// or explicit coefficients; [`MediumSpec::medium`] validates it into a [`Medium`].
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

impl MediumSpec {
    /// The validated medium, with `eta` if given (default [`crate::presets::PRESET_ETA`]).
    pub fn medium(&self, eta: Option<f64>) -> Result<Medium, BssrdfError> {
        let eta = eta.unwrap_or(crate::presets::PRESET_ETA);
        match self {
            MediumSpec::Preset(name) => Medium::preset(name)?.with_eta(eta),
            MediumSpec::Coefficients {
                sigma_a,
                sigma_s,
                g,
            } => Medium::new(*sigma_a, *sigma_s, *g, eta),
        }
    }

    /// A short description of the medium built from it (plot titles): the preset's name or
    /// the coefficients, and η.
    pub fn label(&self, medium: &Medium) -> String {
        match self {
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
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rejects_bad_coefficients() {
        let ok = [1.0; 3];
        assert!(matches!(
            Medium::new([-1.0, 1.0, 1.0], ok, 0.0, 1.3),
            Err(BssrdfError::InvalidCoefficient { .. })
        ));
        assert!(Medium::new(ok, [1.0, f64::NAN, 1.0], 0.0, 1.3).is_err());
        assert!(Medium::new(ok, [1.0, f64::INFINITY, 1.0], 0.0, 1.3).is_err());
        assert!(matches!(
            Medium::new([0.0; 3], [0.0, 1.0, 1.0], 0.0, 1.3),
            Err(BssrdfError::NoExtinction { channel: 0 })
        ));
        assert!(matches!(
            Medium::new(ok, ok, 1.0, 1.3),
            Err(BssrdfError::InvalidG(_))
        ));
        assert!(matches!(
            Medium::new(ok, ok, -1.0, 1.3),
            Err(BssrdfError::InvalidG(_))
        ));
        assert!(matches!(
            Medium::new(ok, ok, 0.0, 0.0),
            Err(BssrdfError::InvalidEta(_))
        ));
        assert!(Medium::new(ok, ok, 0.0, f64::NAN).is_err());
        assert!(Medium::from_extinction_albedo(ok, [1.1, 0.5, 0.5], 0.0, 1.3).is_err());
    }

    #[test]
    fn derived_quantities() {
        let m = Medium::new([0.1, 0.2, 0.3], [1.0, 2.0, 3.0], 0.5, 1.3).unwrap();
        assert!((m.sigma_s_reduced(1) - 1.0).abs() < 1e-15);
        assert!((m.sigma_t_reduced(1) - 1.2).abs() < 1e-15);
        assert!((m.reduced_albedo(1) - 1.0 / 1.2).abs() < 1e-15);
        assert!((m.sigma_tr(1) - (3.0f64 * 0.2 * 1.2).sqrt()).abs() < 1e-15);
        let e = Medium::from_extinction_albedo([2.0; 3], [0.25; 3], 0.0, 1.0).unwrap();
        assert_eq!(e.sigma_a(), [1.5; 3]);
        assert_eq!(e.sigma_s(), [0.5; 3]);
    }

    /// A spec builds its medium (η defaulting to the presets' 1.3) and names it for a title.
    #[test]
    fn specs_build_and_name_their_media() {
        let preset = MediumSpec::Preset("skin1".into());
        let m = preset.medium(None).unwrap();
        assert_eq!(m, Medium::preset("skin1").unwrap());
        assert_eq!(preset.label(&m), "skin1, eta 1.3");
        let m2 = preset.medium(Some(1.4)).unwrap();
        assert_eq!(m2.eta(), 1.4);
        let coeffs = MediumSpec::Coefficients {
            sigma_a: [0.5, 0.25, 1.0],
            sigma_s: [2.0, 2.0, 2.0],
            g: 0.5,
        };
        let m3 = coeffs.medium(Some(1.2)).unwrap();
        assert_eq!(
            m3,
            Medium::new([0.5, 0.25, 1.0], [2.0, 2.0, 2.0], 0.5, 1.2).unwrap()
        );
        assert_eq!(
            coeffs.label(&m3),
            "sigma_a [0.5, 0.25, 1.0], sigma_s [2.0, 2.0, 2.0], g 0.5, eta 1.2"
        );
        assert!(MediumSpec::Preset("nope".into()).medium(None).is_err());
        assert!(preset.medium(Some(-1.0)).is_err());
    }
}
