//! Fresnel terms for a smooth dielectric boundary.
//!
//! Convention: `eta` is always the ratio n_t / n_i of the refractive index on the side the light
//! goes *into* over the side it comes *from*. For a medium of relative index η (inside over
//! outside), light arriving from outside sees `eta = η`; light inside the medium hitting the
//! boundary from below sees `eta = 1/η`. Every function accepts any finite `eta > 0`, including
//! `eta < 1` (total internal reflection beyond the critical angle) and `eta = 1` (no boundary).
//!
//! The reflectance is the unpolarised Fresnel equation for dielectrics (Born & Wolf,
//! *Principles of Optics*, §1.5; pbrt 3rd ed. Eq. 8.2-8.3). The moments are computed by
//! Gauss-Legendre quadrature of the exact reflectance, split at the critical angle, instead of
//! the polynomial fits of d'Eon & Irving 2011 used by pbrt, so they are accurate to ~1e-14 for
//! every `eta`.

use crate::quadrature::integrate;

/// Unpolarised Fresnel reflectance of a smooth dielectric interface.
///
/// `cos_i` is the cosine of the angle between the incident direction and the normal (its
/// absolute value is used); `eta = n_t / n_i`. Returns 1 under total internal reflection.
pub fn fr_dielectric(cos_i: f64, eta: f64) -> f64 {
    let cos_i = cos_i.abs().min(1.0);
    if !(eta > 0.0) || !eta.is_finite() || eta == 1.0 {
        return 0.0;
    }
    let sin2_t = (1.0 - cos_i * cos_i).max(0.0) / (eta * eta);
    if sin2_t >= 1.0 {
        return 1.0;
    }
    let cos_t = (1.0 - sin2_t).max(0.0).sqrt();
    // Both denominators are > 0 here: cos_t > 0 because sin2_t < 1.
    let r_parl = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let r_perp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    (0.5 * (r_parl * r_parl + r_perp * r_perp)).clamp(0.0, 1.0)
}

/// Fresnel transmittance `1 - fr_dielectric(cos_i, eta)`.
pub fn ft_dielectric(cos_i: f64, eta: f64) -> f64 {
    1.0 - fr_dielectric(cos_i, eta)
}

/// k-th Fresnel moment ∫₀¹ F_r(μ; eta) μ^k dμ by piecewise Gauss-Legendre quadrature.
fn fresnel_moment(k: i32, eta: f64) -> f64 {
    let f = |mu: f64| fr_dielectric(mu, eta) * mu.powi(k);
    // For eta < 1 the reflectance is 1 below the critical cosine and has a kink there.
    let mu_c = if eta < 1.0 {
        (1.0 - eta * eta).max(0.0).sqrt()
    } else {
        0.0
    };
    // Substitute μ = μ_c + (1 − μ_c) t²: the reflectance has a square-root singularity in
    // μ − μ_c at the critical angle (cos θ_t ∝ √(μ − μ_c)), which becomes smooth in t.
    let mut total = 0.0;
    if mu_c > 0.0 {
        // F_r = 1 exactly on [0, mu_c].
        total += mu_c.powi(k + 1) / f64::from(k + 1);
    }
    let span = 1.0 - mu_c;
    let h = |t: f64| f(mu_c + span * t * t) * 2.0 * span * t;
    let panels = 8;
    for p in 0..panels {
        let a = p as f64 / panels as f64;
        let b = (p + 1) as f64 / panels as f64;
        total += integrate(&h, a, b, 24);
    }
    total
}

/// First Fresnel moment ∫₀¹ F_r(μ; eta) μ dμ (called C₁ by d'Eon & Irving, "2C₁" is the
/// hemispherical diffuse reflectance).
pub fn fresnel_moment1(eta: f64) -> f64 {
    fresnel_moment(1, eta)
}

/// Second Fresnel moment ∫₀¹ F_r(μ; eta) μ² dμ (called C₂; "3C₂" enters the extrapolation
/// distance of the better dipole).
pub fn fresnel_moment2(eta: f64) -> f64 {
    fresnel_moment(2, eta)
}

/// Diffuse Fresnel reflectance F_dr = 2 ∫₀¹ F_r(μ) μ dμ: the fraction of uniformly diffuse
/// (Lambertian) light that the boundary reflects. For light inside a medium of index η pass
/// `eta = 1/η` (Jensen et al. 2001 use this internal value in the dipole boundary condition).
pub fn diffuse_fresnel_reflectance(eta: f64) -> f64 {
    2.0 * fresnel_moment1(eta)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normal_incidence_matches_closed_form() {
        for eta in [0.5f64, 0.75, 1.0, 1.33, 1.5, 2.5] {
            let expected = ((eta - 1.0) / (eta + 1.0)).powi(2);
            assert!(
                (fr_dielectric(1.0, eta) - expected).abs() < 1e-14,
                "eta {eta}"
            );
        }
    }

    #[test]
    fn total_internal_reflection_beyond_critical_angle() {
        let eta: f64 = 1.0 / 1.5;
        let cos_c = (1.0 - eta * eta).sqrt();
        assert_eq!(fr_dielectric(cos_c * 0.999, eta), 1.0);
        assert!(fr_dielectric(cos_c * 1.001, eta) < 1.0);
        assert_eq!(
            fr_dielectric(0.0, 1.5),
            1.0,
            "grazing incidence reflects everything"
        );
    }

    #[test]
    fn moments_of_index_matched_boundary_vanish() {
        assert_eq!(fresnel_moment1(1.0), 0.0);
        assert_eq!(fresnel_moment2(1.0), 0.0);
    }

    #[test]
    fn diffuse_reflectance_obeys_the_inside_outside_relation() {
        // For a diffuse field, energy balance across the interface gives
        // 1 - F_dr(1/eta) = (1 - F_dr(eta)) / eta^2 (e.g. Walsh, or d'Eon & Irving 2011 Eq. 8).
        for eta in [1.0001, 1.1, 1.3, 1.33, 1.5, 2.0, 2.5] {
            let inside = diffuse_fresnel_reflectance(1.0 / eta);
            let outside = diffuse_fresnel_reflectance(eta);
            let lhs = 1.0 - inside;
            let rhs = (1.0 - outside) / (eta * eta);
            assert!((lhs - rhs).abs() < 1e-9, "eta {eta}: {lhs} vs {rhs}");
        }
    }

    #[test]
    fn internal_diffuse_reflectance_matches_egan_hilgeman_fit() {
        // Jensen et al. 2001 Eq. 7 quote the fit F_dr = -1.440/η² + 0.710/η + 0.668 + 0.0636η,
        // accurate to about 1% for 1 < η < 2.
        for eta in [1.2, 1.3, 1.4, 1.5] {
            let fit = -1.440 / (eta * eta) + 0.710 / eta + 0.668 + 0.0636 * eta;
            let ours = diffuse_fresnel_reflectance(1.0 / eta);
            assert!((ours - fit).abs() < 0.01, "eta {eta}: {ours} vs fit {fit}");
        }
    }
}
