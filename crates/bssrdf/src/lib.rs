//! # sss-bssrdf: BSSRDF models for subsurface scattering
//!
//! Use this crate when you need the *physics* of translucent materials (skin, marble, milk,
//! wax) and nothing else: a validated [`Medium`], exact [`fresnel`] terms, five diffusion
//! models and a tabulated Monte Carlo profile ([`mc_table`]) behind one [`Bssrdf`] trait,
//! importance sampling of their radial profiles, and a Monte Carlo photon random walk
//! ([`monte_carlo`]) on the flat half-space under a normal beam, the reference the models'
//! profiles are measured against (real transport there; on curved objects the renderer's
//! `volpath` is the reference). It depends on no renderer; everything is `f64`, and every constructor
//! validates its input and returns a [`BssrdfError`] instead of panicking.
//!
//! ```
//! use sss_bssrdf::{make_model, Bssrdf, Medium, ModelKind};
//!
//! let skin = Medium::preset("skin1")?;                       // Jensen et al. 2001, Table 2
//! let model = make_model(ModelKind::BetterDipole, &skin);
//! let rd_red = model.rd(0, 0.5);                             // Rd(0.5 mm), 1/mm²
//! let total = model.total_diffuse_reflectance(0);            // ∫ 2πr Rd(r) dr
//! let r = model.sample_sr(0, 0.3);                           // r ∝ 2πr Rd(r)
//! let pdf = model.pdf_sr(0, r);                              // its density per mm
//! let cull = model.radius_for_energy(0, 0.99);               // radius holding 99 %
//! assert!(rd_red > 0.0 && total < 1.0 && pdf > 0.0 && cull > r.min(cull) - 1.0);
//! # Ok::<(), sss_bssrdf::BssrdfError>(())
//! ```
//!
//! ## Conventions
//! - Lengths in mm, coefficients in 1/mm, RGB channels indexed 0, 1, 2.
//! - `rd(ch, r)` is the radial profile R_d(r) in 1/mm² per unit power *entering* the medium
//!   (the entry Fresnel factor is not included, as in Jensen et al. 2001), at normal incidence;
//!   ∫₀^∞ 2πr R_d(r) dr is the total diffuse reflectance.
//! - The full BSSRDF of the separable models is, as in pbrt (3rd ed. §11.4 and §15.4),
//!   S = F_t(η, ω_o) · R_d(‖x_o − x_i‖) · F_t(η, ω_i) / (c π), c = 1 − 2 C₁(η).
//! - Fresnel `eta` arguments are n_t / n_i; see [`fresnel`].
//! - [`angular`] gives the half-space's directional albedo A(θ) from the same walk at
//!   oblique incidence ([`DirectionalAlbedo`]); with it the angular factors become
//!   F_t(η, 1) A(θ_i)/A(0°) and A(θ_o)/(πĀ), which a renderer may use instead (the scene
//!   format's `angular = "albedo"`).
//! - [`sphere_profile`] reshapes a radial model to a ball of radius R: the same walk in a ball
//!   ([`monte_carlo::simulate_sphere`], tallied by chord distance, which a sphere's hat-box
//!   area πr² turns into a radial profile on [0, 2R]) minus the walk in the half-space, added
//!   to the model's profile ([`SphereProfile`]; the scene format's `sphere_radius`); a
//!   [`BallFamily`] holds such walks at radii 2^(k/2) mm and reads a pair of points' own ball
//!   between them, for a renderer that gives each point its own radius (`sphere_radius =
//!   "local"`).
//! - [`entry_drift`] gives where obliquely entering light leaves: the first azimuthal harmonic
//!   k(r, θ_i) of the same walk's exit density about the light's direction along the surface
//!   ([`EntryDrift`]), for a renderer to multiply S by 1 + k(r, θ_i) cos φ_i + k(r, θ_o)
//!   cos φ_o (the exit's term by reciprocity; the scene format's `drift`).
//!
//! ## Papers implemented
//! - Jensen, Marschner, Levoy, Hanrahan. *A Practical Model for Subsurface Light Transport.*
//!   SIGGRAPH 2001 — the standard dipole ([`StandardDipole`]) and the measured presets.
//! - d'Eon. *A Better Dipole.* 2012 — [`BetterDipole`].
//! - Frisvad, Hachisuka, Kjeldsen. *Directional Dipole Model for Subsurface Scattering.*
//!   ACM TOG 34(1), 2014 — [`DirectionalDipole`].
//! - Habel, Christensen, Jarosz. *Photon Beam Diffusion: A Hybrid Monte Carlo Method for
//!   Subsurface Scattering.* EGSR 2013, tabulated as in Pharr, Jakob, Humphreys, *Physically
//!   Based Rendering* 3rd ed. §11.4.2, §15.4-15.5 — [`PhotonBeamDiffusion`].
//! - Christensen, Burley. *Approximate Reflectance Profiles for Efficient Subsurface
//!   Scattering.* Pixar Technical Memo #15-04, 2015 — normalized diffusion
//!   ([`ChristensenBurley`]).
//! - Wang, Jacques, Zheng. *MCML — Monte Carlo modeling of light transport in multi-layered
//!   tissues.* 1995 — the photon random walk in [`monte_carlo`], tabulated over albedo by the
//!   condensed walk of Graaff et al., *Condensed Monte Carlo simulations for the description
//!   of light transport*, Appl. Opt. 32(4), 1993 ([`monte_carlo::condensed`]) as the
//!   `mc-table` model ([`McTableModel`]).
//! - Chandrasekhar. *Radiative Transfer.* 1960, §V — the H function and the plane albedo
//!   1 − H(μ₀)√(1 − ω) of an isotropic, index-matched half-space, the closed form
//!   [`angular`]'s walk is tested against.
//! - Archimedes' hat-box theorem: the area of a sphere's cap within chord distance r of its
//!   pole is πr², whatever the radius ([`sphere_profile`]).

#![forbid(unsafe_code)]

pub mod angular;
pub mod better_dipole;
mod binned;
pub mod catmull_rom;
pub mod christensen_burley;
pub mod directional_dipole;
pub mod entry_drift;
mod error;
pub mod fresnel;
mod inversion;
pub mod mc_table;
mod medium;
pub mod monte_carlo;
pub mod photon_beam_diffusion;
pub mod presets;
pub mod profile_rows;
pub mod profile_table;
pub mod quadrature;
pub mod radial;
pub mod sphere_profile;
pub mod spline_row;
pub mod standard_dipole;

use std::fmt;
use std::str::FromStr;

pub use angular::DirectionalAlbedo;
pub use better_dipole::BetterDipole;
pub use christensen_burley::{BurleyFit, ChristensenBurley};
pub use directional_dipole::DirectionalDipole;
pub use entry_drift::{DriftAt, EntryDrift};
pub use error::BssrdfError;
pub use glam::DVec3;
pub use inversion::from_reflectance;
pub use mc_table::McTableModel;
pub use medium::{Medium, MediumSpec};
pub use photon_beam_diffusion::PhotonBeamDiffusion;
pub use sphere_profile::family::BallFamily;
pub use sphere_profile::{SphereDelta, SphereProfile};
pub use standard_dipole::StandardDipole;

/// Three linear colour channels (red, green, blue): `sss-util`'s, the one colour type of the
/// toolkit.
pub use sss_util::Rgb;

/// A point on the boundary of a translucent object with its unit normal, pointing out of the
/// medium.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfacePoint {
    /// Position (mm, or scene units converted to mm by the caller).
    pub p: DVec3,
    /// Unit outward normal.
    pub n: DVec3,
}

/// A BSSRDF model of one medium.
///
/// Every method takes a channel `ch` in 0..3 and returns finite, non-negative values for every
/// valid [`Medium`] (including albedo 0 and 1, r = 0, grazing angles, η < 1 and η = 1).
pub trait Bssrdf: Send + Sync {
    /// Which model this is.
    fn kind(&self) -> ModelKind;

    /// The medium the model was built for.
    fn medium(&self) -> &Medium;

    /// Radial profile R_d(r) in 1/mm² (per unit power entering the medium, normal incidence).
    fn rd(&self, ch: usize, r: f64) -> f64;

    /// Total diffuse reflectance ∫₀^∞ 2πr R_d(r) dr of channel `ch` (closed form where one
    /// exists, quadrature otherwise); in [0, 1].
    fn total_diffuse_reflectance(&self, ch: usize) -> f64;

    /// Samples a radius with density proportional to 2πr R_d(r), from a uniform `u` in [0, 1).
    fn sample_sr(&self, ch: usize, u: f64) -> f64;

    /// Density (per mm of radius) with which [`Bssrdf::sample_sr`] returns `r`; integrates
    /// to 1 over [0, ∞). Divide by 2πr for the density per unit area of the plane.
    fn pdf_sr(&self, ch: usize, r: f64) -> f64;

    /// The radius holding `fraction` (in [0, 1)) of the channel's diffuse reflectance: beyond it
    /// the profile may be culled.
    fn radius_for_energy(&self, ch: usize, fraction: f64) -> f64;

    /// R_d(r) with its first two radial derivatives, (R_d, dR_d/dr, d²R_d/dr²) in 1/mm²,
    /// 1/mm³ and 1/mm⁴, for r ≥ 0 (negative r is read as |r|). Finite everywhere, r = 0
    /// included (where the closed forms, even in r, give dR_d/dr = 0; a tabulated spline
    /// need not be flat there); where a model clamps R_d
    /// (to 0, or to a constant near r = 0) the derivatives are those of the clamped function.
    /// The value is [`Bssrdf::rd`]'s to rounding. Used by local expansions of R_d (Taylor
    /// series of R_d(‖x − p‖) about a point: value, gradient R_d′ u, Hessian
    /// R_d″ uuᵀ + (R_d′/r)(I − uuᵀ)).
    ///
    /// The standard and better dipole and Christensen–Burley override it with closed forms
    /// (the derivatives of their formulas, see each module), photon beam diffusion and
    /// `mc-table` with the derivatives of their Catmull-Rom spline
    /// ([`spline_row::SplineRow::eval_over_x_derivatives`]). This default is only a fallback
    /// (the directional dipole's radial part): central differences of [`Bssrdf::rd`]
    /// ([`rd_derivatives_by_differences`]).
    fn rd_derivatives(&self, ch: usize, r: f64) -> (f64, f64, f64) {
        rd_derivatives_by_differences(
            |x| self.rd(ch, x),
            r,
            self.medium().reduced_mean_free_path(ch),
        )
    }

    /// R_d(r) for the three channels.
    fn rd_rgb(&self, r: f64) -> Rgb {
        [self.rd(0, r), self.rd(1, r), self.rd(2, r)]
    }

    /// Spatial term S_p(x_i, x_o) = R_d(‖x_o − x_i‖) of the separable factorisation.
    fn sp(&self, xi: &SurfacePoint, xo: &SurfacePoint) -> Rgb {
        self.rd_rgb((xo.p - xi.p).length())
    }

    /// The full BSSRDF S(x_i, ω_i; x_o, ω_o) in 1/(mm² sr). `wi` points from x_i towards the
    /// light, `wo` from x_o towards the viewer; both unit vectors. Directions below their
    /// surface give 0.
    ///
    /// The default is the separable form of pbrt (3rd ed. Eq. 11.6-11.7):
    /// S = F_t(η, cos θ_o) R_d(r) F_t(η, cos θ_i) / (c π), c = 1 − 2 C₁(η). The directional
    /// dipole overrides it with its full expression.
    fn s(&self, xi: &SurfacePoint, wi: DVec3, xo: &SurfacePoint, wo: DVec3) -> Rgb {
        separable_s(self.medium(), self.sp(xi, xo), xi.n.dot(wi), xo.n.dot(wo))
    }
}

/// S = F_t(η, cos_o) · sp · F_t(η, cos_i) / (c π) for given cosines, shared by the separable
/// models and by renderers that already hold R_d.
pub fn separable_s(medium: &Medium, sp: Rgb, cos_i: f64, cos_o: f64) -> Rgb {
    if !(cos_i > 0.0) || !(cos_o > 0.0) {
        return [0.0; 3];
    }
    let eta = medium.eta();
    let c = fresnel_normalization(eta);
    let w = fresnel::ft_dielectric(cos_i, eta) * fresnel::ft_dielectric(cos_o, eta)
        / (c * std::f64::consts::PI);
    [sp[0] * w, sp[1] * w, sp[2] * w]
}

/// (f(r), f′(r), f″(r)) of an even radial profile f by central differences with step
/// h = 10⁻³ max(|r|, 10⁻² ℓ) (ℓ > 0 a length scale of the profile, 1 if it is not finite and
/// positive), evaluating f at |r ± h| (so r = 0 gives f′ = 0). Truncation and rounding
/// errors are near 10⁻⁷ and 10⁻¹⁰ relative for profiles smooth on the scale of r; the fallback of
/// [`Bssrdf::rd_derivatives`]. Non-finite results are clamped ([`finite_or_zero`]).
pub fn rd_derivatives_by_differences(
    f: impl Fn(f64) -> f64,
    r: f64,
    scale: f64,
) -> (f64, f64, f64) {
    let r = r.abs();
    let scale = if scale.is_finite() && scale > 0.0 {
        scale
    } else {
        1.0
    };
    let h = 1e-3 * r.max(1e-2 * scale);
    let (f0, fp, fm) = (f(r), f(r + h), f((r - h).abs()));
    (
        finite_or_zero(f0),
        finite_or_zero((fp - fm) / (2.0 * h)),
        finite_or_zero((fp - 2.0 * f0 + fm) / (h * h)),
    )
}

/// `x` if finite, ±`f64::MAX` for ±∞, 0 for NaN.
#[inline]
pub fn finite_or_zero(x: f64) -> f64 {
    if x.is_nan() {
        0.0
    } else {
        x.clamp(-f64::MAX, f64::MAX)
    }
}

/// c = 1 − 2 C₁(η) = ∫ F_t(η, cos θ) cos θ dω / π: the normalisation that makes the
/// directional factor F_t/(cπ) integrate to one over the hemisphere. Never 0 (at least the
/// normal-incidence cone transmits for every finite η).
pub fn fresnel_normalization(eta: f64) -> f64 {
    (1.0 - 2.0 * fresnel::fresnel_moment1(eta)).max(f64::MIN_POSITIVE)
}

/// The models, by name.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ModelKind {
    /// Jensen et al. 2001.
    StandardDipole,
    /// d'Eon 2012.
    BetterDipole,
    /// Frisvad et al. 2014.
    DirectionalDipole,
    /// Habel et al. 2013, tabulated as in pbrt.
    PhotonBeamDiffusion,
    /// Christensen & Burley 2015, normalized diffusion.
    Burley,
    /// The crate's own photon random walk, tabulated ([`mc_table`]).
    McTable,
}

impl ModelKind {
    /// Every model, in the order reports list them.
    pub const ALL: [ModelKind; 6] = [
        ModelKind::StandardDipole,
        ModelKind::BetterDipole,
        ModelKind::DirectionalDipole,
        ModelKind::PhotonBeamDiffusion,
        ModelKind::Burley,
        ModelKind::McTable,
    ];

    /// The command-line name (`standard-dipole`, `better-dipole`, `directional-dipole`, `pbd`,
    /// `burley`, `mc-table`).
    pub fn name(self) -> &'static str {
        match self {
            ModelKind::StandardDipole => "standard-dipole",
            ModelKind::BetterDipole => "better-dipole",
            ModelKind::DirectionalDipole => "directional-dipole",
            ModelKind::PhotonBeamDiffusion => "pbd",
            ModelKind::Burley => "burley",
            ModelKind::McTable => "mc-table",
        }
    }
}

impl fmt::Display for ModelKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for ModelKind {
    type Err = BssrdfError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        ModelKind::ALL
            .into_iter()
            .find(|k| k.name() == s)
            .ok_or_else(|| BssrdfError::UnknownModel(s.to_string()))
    }
}

/// Builds the model `kind` for `medium`. Photon beam diffusion shares one table per (g, η)
/// across all media (built on first use, in parallel); normalized diffusion takes its surface
/// albedo from the table of (0, η) and uses the default fit [`BurleyFit::SearchlightMfp`];
/// `mc-table` shares one table per η, blended from the embedded Monte Carlo tables (η clamped
/// to [1, 1.5], g mapped to reduced coefficients: see [`mc_table`]).
pub fn make_model(kind: ModelKind, medium: &Medium) -> Box<dyn Bssrdf> {
    match kind {
        ModelKind::StandardDipole => Box::new(StandardDipole::new(medium.clone())),
        ModelKind::BetterDipole => Box::new(BetterDipole::new(medium.clone())),
        ModelKind::DirectionalDipole => Box::new(DirectionalDipole::new(medium.clone())),
        ModelKind::PhotonBeamDiffusion => Box::new(PhotonBeamDiffusion::new(medium.clone())),
        ModelKind::Burley => Box::new(ChristensenBurley::new(medium.clone())),
        ModelKind::McTable => Box::new(McTableModel::new(medium.clone())),
    }
}
