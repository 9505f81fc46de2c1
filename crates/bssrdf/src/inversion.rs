//! The (diffuse reflectance colour, mean free path) parameterisation: find the albedo whose
//! total diffuse reflectance, under a chosen model, equals the requested colour.
//!
//! This is the artist-facing parameterisation of pbrt's `kdsubsurface` (which inverts the
//! tabulated ρ_eff with `InvertCatmullRom`) and of appleseed and Cycles. We invert any of the
//! five models with bisection on the single-scattering albedo ρ ∈ [0, 1]: every model's total
//! reflectance is non-decreasing in ρ, bisection needs nothing else, and 200 halvings reach
//! the resolution of f64, so the round trip reflectance → medium → reflectance is exact to the
//! model's own evaluation.

use crate::{BssrdfError, Medium, ModelKind, Rgb, make_model};

/// Total diffuse reflectance of `kind` for a medium with extinction `sigma_t`, albedo `rho`.
fn total_for(
    kind: ModelKind,
    sigma_t: f64,
    rho: f64,
    g: f64,
    eta: f64,
) -> Result<f64, BssrdfError> {
    let m = Medium::from_extinction_albedo([sigma_t; 3], [rho; 3], g, eta)?;
    Ok(make_model(kind, &m).total_diffuse_reflectance(0))
}

/// A medium whose total diffuse reflectance under `model` is `reflectance` per channel, with
/// mean free path 1/σ_t = `mfp` (mm), anisotropy `g` and relative index `eta`:
/// σ_s = ρ/mfp, σ_a = (1 − ρ)/mfp with ρ found by bisection.
///
/// Errors: reflectance outside [0, 1] or NaN, mfp not finite and > 0, invalid g or η, and
/// [`BssrdfError::UnreachableReflectance`] when the model cannot produce the requested value
/// for any albedo (e.g. the directional dipole, whose total does not tend to 0 as α' → 0).
pub fn from_reflectance(
    model: ModelKind,
    reflectance: Rgb,
    mfp: Rgb,
    g: f64,
    eta: f64,
) -> Result<Medium, BssrdfError> {
    let mut albedo = [0.0; 3];
    let mut sigma_t = [0.0; 3];
    for ch in 0..3 {
        let target = reflectance[ch];
        if !(0.0..=1.0).contains(&target) {
            return Err(BssrdfError::InvalidArgument(format!(
                "reflectance[{ch}] = {target}: a diffuse reflectance must lie in [0, 1]"
            )));
        }
        let l = mfp[ch];
        if !(l > 0.0) || !l.is_finite() {
            return Err(BssrdfError::InvalidArgument(format!(
                "mfp[{ch}] = {l}: the mean free path must be finite and > 0 (mm)"
            )));
        }
        sigma_t[ch] = 1.0 / l;
        if !sigma_t[ch].is_finite() {
            return Err(BssrdfError::InvalidArgument(format!(
                "mfp[{ch}] = {l}: too small, 1/mfp overflows"
            )));
        }
        let f = |rho: f64| total_for(model, sigma_t[ch], rho, g, eta);
        let (r_lo, r_hi) = (f(0.0)?, f(1.0)?);
        if target > r_hi || target < r_lo {
            return Err(BssrdfError::UnreachableReflectance {
                model: model.name(),
                channel: ch,
                requested: target,
                max: r_hi,
            });
        }
        // Bisection, keeping the reflectance at both ends of the bracket.
        let (mut lo, mut hi) = (0.0f64, 1.0f64);
        let (mut f_lo, mut f_hi) = (r_lo, r_hi);
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if mid <= lo || mid >= hi || hi - lo < 1e-16 {
                break;
            }
            let f_mid = f(mid)?;
            if f_mid < target {
                (lo, f_lo) = (mid, f_mid);
            } else {
                (hi, f_hi) = (mid, f_mid);
            }
        }
        // Return the end whose reflectance is closer to the target; a model whose total jumps
        // (the directional dipole between α' = 0 and α' > 0) has gaps no albedo reaches.
        let (e_lo, e_hi) = ((f_lo - target).abs(), (f_hi - target).abs());
        albedo[ch] = if e_lo <= e_hi { lo } else { hi };
        if e_lo.min(e_hi) > 1e-9 {
            return Err(BssrdfError::UnreachableReflectance {
                model: model.name(),
                channel: ch,
                requested: target,
                max: r_hi,
            });
        }
    }
    Medium::from_extinction_albedo(sigma_t, albedo, g, eta)
}
