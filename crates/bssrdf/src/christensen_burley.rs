//! Christensen–Burley normalized diffusion (Christensen & Burley, *Approximate Reflectance
//! Profiles for Efficient Subsurface Scattering*, Pixar Technical Memo #15-04, 2015; the
//! two-exponential shape is Burley's, *Extending the Disney BRDF to a BSDF with Integrated
//! Subsurface Scattering*, SIGGRAPH 2015 Physically Based Shading course).
//!
//! ## The profile
//!
//! A sum of two exponentials over r (memo Eq. 2-3):
//!
//! R(r) = A (e^{−r/d} + e^{−r/(3d)}) / (8π d r),  d = ℓ / s(A),
//!
//! with A the surface albedo (total diffuse reflectance) and ℓ a length scale. Because
//! ∫₀^∞ 2πr e^{−r/c}/r dr = 2πc, the plane integral is A (2πd + 6πd)/(8πd) = A exactly, and
//! the normalised radial density and its CDF (memo Eq. 11) are
//!
//! p(r) = 2πr R(r)/A = (e^{−r/d} + e^{−r/(3d)}) / (4d),
//! F(r) = 1 − ¼ e^{−r/d} − ¾ e^{−r/(3d)}.
//!
//! ## Exact sampling
//!
//! With x = e^{−r/(3d)} ∈ (0, 1], 1 − F = ¼x³ + ¾x, so F(r) = u is the depressed cubic
//! x³ + 3x − 4v = 0 with v = 1 − u. Its discriminant is positive and its one real root is
//! (Cardano, in hyperbolic form) x = 2 sinh(asinh(2v)/3); r = −3d ln x. That form loses the
//! relative accuracy of r as u → 0 (x → 1), so for u ≤ ½ the small unknown y = 1 − x is
//! solved instead: y (6 − 3y + y²)/4 = u, starting from the closed form and polished with
//! Newton steps (the left side is increasing and concave on [0, 1], so Newton from either
//! side converges), and r = −3d ln(1 − y) via `ln_1p`. The round trip F(F⁻¹(u)) is exact to
//! 10⁻¹⁴ relative in u (u ≤ ½) and in 1 − u (u > ½) from u = 10⁻¹² to 1 − 10⁻¹² (tested),
//! and u = 1 is clamped to the largest f64 below 1 (r ≈ 110 d). The closed-form
//! inverse was first published by Christensen on the memo's web page (update of September
//! 2018) and by Golubev (*Sampling Burley's Normalized Diffusion Profiles*, 2019).
//!
//! ## The scaling factor s(A)
//!
//! The memo fits s to brute-force Monte Carlo reference profiles (mean free path 1, g = 0)
//! for three configurations; all three are available as [`BurleyFit`]:
//! - [`BurleyFit::SearchlightMfp`] (the default; memo Eq. 5): perpendicular (searchlight)
//!   illumination, ℓ the volume mean free path: s = 1.85 − A + 7 |A − 0.8|³.
//! - [`BurleyFit::DiffuseTransmissionMfp`] (memo Eq. 6): ideal diffuse surface
//!   transmission, ℓ the volume mean free path: s = 1.9 − A + 3.5 (A − 0.8)².
//! - [`BurleyFit::SearchlightDmfp`] (memo Eq. 8): searchlight illumination, ℓ the diffuse
//!   mean free path ℓ_d = 1/σ_tr: s = 3.5 + 100 (A − 0.33)⁴.
//!
//! Which s goes with which length: the SIGGRAPH 2015 talk that introduced the model
//! (Christensen, *An Approximate Reflectance Profile for Efficient Subsurface Scattering*)
//! fits s = 1.85 − A + 7 |A − 0.8|³ to references with *mean free path* 1; appleseed's
//! `normalized_diffusion_s_mfp`/`_s_dmfp` (citing the memo's Eq. 5 and 8) and Unreal's
//! `GetDiffuseMeanFreePathFromMeanFreePath` (ℓ_d = ℓ · s_dmfp(A) / s_mfp(A)) pair them the
//! same way; Cycles' `bssrdf_burley_fitting` cites Eq. 6 for the diffuse-transmission fit. It
//! is also the physically consistent pairing: the two searchlight fits should describe
//! similar profiles of one medium, and with this module's A (g = 0, η = 1) ℓ_d/s_dmfp is
//! 0.87, 0.84, 0.73, 0.61, 0.53 times ℓ/s_mfp at A = 0.2, 0.5, 0.7, 0.8, 0.9 (the classical
//! ℓ_d = 1/σ_tr leaves out single scattering, which A includes), whereas pairing
//! 3.5 + 100 (A − 0.33)⁴ with the volume mean free path would give 0.22, 0.13, 0.07 times it
//! at A = 0.7, 0.8, 0.9: profiles 5-15 times too narrow (checked in the tests).
//!
//! ## From a [`Medium`] to (A, ℓ)
//!
//! The model takes a physical medium like the others, so A and ℓ are derived per channel:
//! - **A** is the total diffuse reflectance of photon beam diffusion (the crate's most
//!   accurate model against the Monte Carlo reference, and like this model one that includes
//!   single scattering) for the *similar isotropic medium* — σ_a, σ'_s = σ_s(1 − g), g = 0 —
//!   at the medium's η: the effective albedo of the shared [`PbdTable`] of (g = 0, η) at the
//!   reduced albedo α'. For g = 0 (every preset) this is exactly
//!   [`crate::PhotonBeamDiffusion`]'s total; for g ≠ 0 the similarity relation avoids that
//!   table's truncation at ≈ 204 mean free paths (only ≈ 20 reduced ones for g = 0.9), and it
//!   matches the fits, which were made at g = 0. A is in [0, 1] and non-decreasing in the
//!   albedo, so [`crate::from_reflectance`] inverts it.
//! - **ℓ** is the reduced mean free path 1/σ'_t for the mfp fits (equal to the volume mean
//!   free path 1/σ_t of the fits at g = 0; for g ≠ 0 the similarity relation again), and the
//!   classical diffuse mean free path ℓ_d = 1/σ_tr = 1/√(3σ_a σ'_t) for the dmfp fit, capped
//!   at 10⁹ ℓ because σ_tr → 0 at albedo 1.
//!
//! The fits were made without a refractive boundary; at other η only A changes and the
//! profile *shape* does not. Against this crate's Monte Carlo reference (red channel, 50 000
//! photons, relative L2 error of the energy per bin) that is accurate at η = 1 — skin1 11 %,
//! marble 18 % (photon beam diffusion: 14 %, 14 %) — but at the presets' η = 1.3 internal
//! reflection widens the true profile and this one is too narrow: skin1 36 %, marble 50 %
//! (the best single rescaling of d would be ×1.5 and ×1.8). A fit of s to (A, η) would
//! remove that; `cargo xtask compare` reports the errors.
//!
//! ## r = 0
//!
//! R has an integrable 1/r singularity at the origin. [`Bssrdf::rd`] evaluates it at
//! max(r, 10⁻¹⁰ d): finite, continuous and still non-increasing in r, and the mass it drops
//! inside that radius is A·10⁻¹⁰/4. The density [`Bssrdf::pdf_sr`] is finite at 0 (1/(2d))
//! and needs no clamp.

use crate::photon_beam_diffusion::PbdTable;
use crate::{Bssrdf, Medium, ModelKind};
use std::f64::consts::PI;

/// Radii below `R0_FRACTION · d` are evaluated at that radius (see the module docs).
pub const R0_FRACTION: f64 = 1e-10;

/// Largest u accepted by the sampler: the largest f64 below 1 (r ≈ 110 d there).
const U_MAX: f64 = 1.0 - f64::EPSILON / 2.0;

/// Which fit of the scaling factor s(A) of Christensen & Burley 2015 the model uses, and with
/// it which length scale ℓ (see the module docs).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum BurleyFit {
    /// Searchlight (perpendicular) illumination, ℓ = mean free path: memo Eq. 5.
    #[default]
    SearchlightMfp,
    /// Ideal diffuse surface transmission, ℓ = mean free path: memo Eq. 6.
    DiffuseTransmissionMfp,
    /// Searchlight illumination, ℓ = diffuse mean free path 1/σ_tr: memo Eq. 8.
    SearchlightDmfp,
}

impl BurleyFit {
    /// Every fit.
    pub const ALL: [BurleyFit; 3] = [
        BurleyFit::SearchlightMfp,
        BurleyFit::DiffuseTransmissionMfp,
        BurleyFit::SearchlightDmfp,
    ];

    /// The scaling factor s(A) of this fit.
    pub fn scaling(self, a: f64) -> f64 {
        match self {
            BurleyFit::SearchlightMfp => s_searchlight_mfp(a),
            BurleyFit::DiffuseTransmissionMfp => s_diffuse_transmission_mfp(a),
            BurleyFit::SearchlightDmfp => s_searchlight_dmfp(a),
        }
    }
}

/// s = 1.85 − A + 7 |A − 0.8|³ (Christensen & Burley 2015, Eq. 5: searchlight configuration,
/// mean free path parameterisation). In [0.906, 4.43] for A in [0, 1].
pub fn s_searchlight_mfp(a: f64) -> f64 {
    let x = (a - 0.8).abs();
    1.85 - a + 7.0 * x * x * x
}

/// s = 1.9 − A + 3.5 (A − 0.8)² (Christensen & Burley 2015, Eq. 6: diffuse surface
/// transmission, mean free path parameterisation). In [1.02, 4.14] for A in [0, 1].
pub fn s_diffuse_transmission_mfp(a: f64) -> f64 {
    let x = a - 0.8;
    1.9 - a + 3.5 * x * x
}

/// s = 3.5 + 100 (A − 0.33)⁴ (Christensen & Burley 2015, Eq. 8: searchlight configuration,
/// diffuse mean free path parameterisation). In [3.5, 23.6] for A in [0, 1].
pub fn s_searchlight_dmfp(a: f64) -> f64 {
    let x = (a - 0.33) * (a - 0.33);
    3.5 + 100.0 * x * x
}

/// The normalised CDF F(r) = 1 − ¼ e^{−r/d} − ¾ e^{−r/(3d)} (memo Eq. 11) at `t` = r/d.
pub fn cdf(t: f64) -> f64 {
    if !(t > 0.0) {
        return 0.0;
    }
    // 1 − F = ¼x³ + ¾x with x = e^{−t/3}; written as the sum of −expm1 terms so that small t
    // keeps its relative accuracy: F = −¼ expm1(−t) − ¾ expm1(−t/3).
    (-0.25 * (-t).exp_m1() - 0.75 * (-t / 3.0).exp_m1()).clamp(0.0, 1.0)
}

/// The inverse of [`cdf`]: t = r/d with F(t) = u, for u in [0, 1) (clamped; NaN gives 0).
pub fn inverse_cdf(u: f64) -> f64 {
    if !(u > 0.0) {
        return 0.0;
    }
    let u = u.min(U_MAX);
    if u <= 0.5 {
        // Solve g(y) = y (6 − 3y + y²)/4 = u for y = 1 − x ∈ (0, 0.41].
        let v = 1.0 - u;
        let y0 = 1.0 - 2.0 * ((2.0 * v).asinh() / 3.0).sinh();
        // g(y) ≤ 3y/2, so the root is ≥ 2u/3; the closed form is accurate except for tiny u.
        let mut y = y0.max(2.0 * u / 3.0);
        for _ in 0..8 {
            let g = y * (6.0 - 3.0 * y + y * y) * 0.25 - u;
            let dg = 0.75 * (2.0 - 2.0 * y + y * y);
            let step = g / dg;
            y -= step;
            if step.abs() <= 1e-17 * y {
                break;
            }
        }
        let t = -3.0 * (-y).ln_1p();
        if t.is_finite() { t.max(0.0) } else { 0.0 }
    } else {
        // v = 1 − u is exact here (Sterbenz) and x = 2 sinh(asinh(2v)/3) keeps its relative
        // accuracy as v → 0.
        let v = 1.0 - u;
        let x = 2.0 * ((2.0 * v).asinh() / 3.0).sinh();
        if !(x > 0.0) {
            return -3.0 * (f64::MIN_POSITIVE).ln();
        }
        (-3.0 * x.ln()).max(0.0)
    }
}

/// The surface albedo A of channel `ch` of `medium` (see the module docs): the total
/// diffuse reflectance of photon beam diffusion for the similar isotropic medium
/// (σ_a, σ'_s, g = 0) at the medium's η, i.e. the effective albedo of the (g = 0, η) table
/// at the reduced albedo α'. In [0, 1].
pub fn surface_albedo(medium: &Medium, ch: usize) -> f64 {
    PbdTable::shared(0.0, medium.eta()).effective_albedo(medium.reduced_albedo(ch))
}

#[derive(Clone, Copy, Debug)]
struct Channel {
    /// Surface albedo A.
    a: f64,
    /// Scaling factor s(A).
    s: f64,
    /// Length ℓ the fit is expressed in (mm).
    l: f64,
    /// Shape parameter d = ℓ/s (mm).
    d: f64,
}

impl Channel {
    fn rd(&self, r: f64) -> f64 {
        if !(self.a > 0.0) || !(r >= 0.0) {
            return 0.0;
        }
        let d = self.d;
        let t = (r / d).max(R0_FRACTION);
        if !t.is_finite() {
            return 0.0;
        }
        let e3 = (-t / 3.0).exp();
        let v = self.a / (8.0 * PI * d) / d * (e3 * e3 * e3 + e3) / t;
        if v.is_nan() {
            0.0
        } else {
            v.clamp(0.0, f64::MAX)
        }
    }

    /// (R, R′, R″) in closed form: with t = r/d, K = A/(8π d²) and
    /// f(t) = (e^{−t} + e^{−t/3})/t, R = K f(t), R′ = K f′(t)/d, R″ = K f″(t)/d², where
    /// f′ = −(e^{−t} + e^{−t/3}/3)/t − (e^{−t} + e^{−t/3})/t² and
    /// f″ = (e^{−t} + e^{−t/3}/9)/t + 2(e^{−t} + e^{−t/3}/3)/t² + 2(e^{−t} + e^{−t/3})/t³
    /// (memo Eq. 2-3 differentiated). Below t = [`R0_FRACTION`], where `rd` is held constant,
    /// both derivatives are 0.
    fn derivatives(&self, r: f64) -> (f64, f64, f64) {
        if !(self.a > 0.0) || !(r >= 0.0) {
            return (0.0, 0.0, 0.0);
        }
        let d = self.d;
        let t = r / d;
        if !t.is_finite() {
            return (0.0, 0.0, 0.0);
        }
        let v = self.rd(r);
        if t < R0_FRACTION {
            return (v, 0.0, 0.0);
        }
        let k = self.a / (8.0 * PI * d) / d;
        let e1 = (-t).exp();
        let e3 = (-t / 3.0).exp();
        let (s0, s1, s2) = (e1 + e3, e1 + e3 / 3.0, e1 + e3 / 9.0);
        let f1 = -(s1 + s0 / t) / t;
        let f2 = (s2 + (2.0 * s1 + 2.0 * s0 / t) / t) / t;
        (
            v,
            crate::finite_or_zero(k * f1 / d),
            crate::finite_or_zero(k * f2 / (d * d)),
        )
    }

    fn pdf(&self, r: f64) -> f64 {
        if !(r >= 0.0) || !r.is_finite() {
            return 0.0;
        }
        let e3 = (-r / (3.0 * self.d)).exp();
        let v = (e3 * e3 * e3 + e3) / (4.0 * self.d);
        if v.is_finite() { v } else { 0.0 }
    }

    fn sample(&self, u: f64) -> f64 {
        let r = self.d * inverse_cdf(u);
        if r.is_finite() { r } else { 0.0 }
    }
}

/// Christensen–Burley normalized diffusion for one [`Medium`] (see the module docs for the
/// profile, the fits and how (A, ℓ) follow from the medium).
///
/// - [`Bssrdf::rd`] is A (e^{−r/d} + e^{−r/(3d)})/(8π d r), evaluated at max(r, 10⁻¹⁰ d).
/// - [`Bssrdf::total_diffuse_reflectance`] is A.
/// - [`Bssrdf::sample_sr`] inverts the closed-form CDF exactly and [`Bssrdf::pdf_sr`] is its
///   density (e^{−r/d} + e^{−r/(3d)})/(4d), the same shape at every A (also A = 0).
/// - [`Bssrdf::radius_for_energy`] is the same exact inverse.
#[derive(Clone, Debug)]
pub struct ChristensenBurley {
    medium: Medium,
    fit: BurleyFit,
    ch: [Channel; 3],
}

impl ChristensenBurley {
    /// The model with the default fit, [`BurleyFit::SearchlightMfp`] (the configuration of
    /// the crate's Monte Carlo reference: a beam at normal incidence).
    pub fn new(medium: Medium) -> Self {
        Self::with_fit(medium, BurleyFit::default())
    }

    /// The model with the given fit of s(A).
    pub fn with_fit(medium: Medium, fit: BurleyFit) -> Self {
        let table = PbdTable::shared(0.0, medium.eta());
        let ch = std::array::from_fn(|c| {
            let a = table.effective_albedo(medium.reduced_albedo(c));
            let mfp = medium.reduced_mean_free_path(c);
            let l = match fit {
                BurleyFit::SearchlightMfp | BurleyFit::DiffuseTransmissionMfp => mfp,
                BurleyFit::SearchlightDmfp => {
                    let sigma_tr = medium.sigma_tr(c);
                    if sigma_tr * 1e9 * mfp > 1.0 {
                        1.0 / sigma_tr
                    } else {
                        1e9 * mfp
                    }
                }
            };
            let s = fit.scaling(a);
            // s ≥ 0.9 for A in [0, 1]; keep d a finite positive length for any ℓ.
            let d = (l / s).clamp(1e-300, 1e300);
            Channel { a, s, l, d }
        });
        ChristensenBurley { medium, fit, ch }
    }

    /// The fit in use.
    pub fn fit(&self) -> BurleyFit {
        self.fit
    }

    /// The surface albedo A of channel `ch`.
    pub fn surface_albedo(&self, ch: usize) -> f64 {
        self.ch[ch].a
    }

    /// The scaling factor s(A) of channel `ch`.
    pub fn scaling(&self, ch: usize) -> f64 {
        self.ch[ch].s
    }

    /// The length ℓ (mm) the fit of channel `ch` is expressed in: the reduced mean free path,
    /// or the diffuse mean free path for [`BurleyFit::SearchlightDmfp`].
    pub fn length(&self, ch: usize) -> f64 {
        self.ch[ch].l
    }

    /// The shape parameter d = ℓ/s (mm) of channel `ch`.
    pub fn d(&self, ch: usize) -> f64 {
        self.ch[ch].d
    }
}

impl Bssrdf for ChristensenBurley {
    fn kind(&self) -> ModelKind {
        ModelKind::Burley
    }
    fn medium(&self) -> &Medium {
        &self.medium
    }
    fn rd(&self, ch: usize, r: f64) -> f64 {
        self.ch[ch].rd(r.abs())
    }
    fn rd_derivatives(&self, ch: usize, r: f64) -> (f64, f64, f64) {
        self.ch[ch].derivatives(r.abs())
    }
    fn total_diffuse_reflectance(&self, ch: usize) -> f64 {
        self.ch[ch].a
    }
    fn sample_sr(&self, ch: usize, u: f64) -> f64 {
        self.ch[ch].sample(u)
    }
    fn pdf_sr(&self, ch: usize, r: f64) -> f64 {
        self.ch[ch].pdf(r)
    }
    fn radius_for_energy(&self, ch: usize, fraction: f64) -> f64 {
        self.ch[ch].sample(fraction)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cdf_is_one_minus_the_two_exponentials() {
        // Direct evaluation of memo Eq. 11 where it has no cancellation.
        for t in [0.5f64, 1.0, 3.0, 10.0, 50.0] {
            let direct = 1.0 - 0.25 * (-t).exp() - 0.75 * (-t / 3.0).exp();
            assert!((cdf(t) - direct).abs() < 1e-15, "t {t}");
        }
        assert_eq!(cdf(0.0), 0.0);
        assert_eq!(cdf(f64::NAN), 0.0);
        // Small t: F = t/2 − t²/6 + O(t³) (series of Eq. 11).
        let t = 1e-9;
        assert!((cdf(t) - (t / 2.0 - t * t / 6.0)).abs() < 1e-23);
    }

    #[test]
    fn inverse_cdf_handles_the_ends() {
        assert_eq!(inverse_cdf(0.0), 0.0);
        assert_eq!(inverse_cdf(-1.0), 0.0);
        assert_eq!(inverse_cdf(f64::NAN), 0.0);
        let top = inverse_cdf(1.0);
        assert!(top.is_finite() && top > 100.0 && top < 120.0, "{top}");
        assert_eq!(inverse_cdf(1.0), inverse_cdf(U_MAX));
        // Small u: t ≈ 2u (F ≈ t/2).
        let t = inverse_cdf(1e-300);
        assert!((t / 2e-300 - 1.0).abs() < 1e-12, "{t}");
    }
}
