//! Upper bounds of R_d, G and F_t over a triplet of clusters, the error bound e_j, and the two
//! cluster selections (BSSRDF-aware, Nabata & Iwasaki Eq. 10–13, and Max-Extent).
//!
//! # Derivations (the paper's Appendix A is missing from its text; wave2 F2.0 reconstructs it)
//!
//! One sample of triplet j is `f = A_j W_j I_j · ρ · G · V · F_t`, with `ρ = Σ_c w_c I_c(y)
//! R_d,c(r) / Σ_c w_c I_c(y)` (the luminance-weighted profile of the sampled VPL's colour),
//! `G = cos⁺θ_i · cos⁺θ_y · min(1/d², G_max)` and `0 ≤ V ≤ 1`. Then:
//!
//! * **R_d^u** = max_c R_d,c(r_min): ρ is a weighted mean of the channels, each channel is
//!   non-increasing in r (checked by [`RadialProfile::new`]), and r ≥ r_min, the minimum
//!   distance between the IC and SC boxes.
//! * **G^u** = cos_i^u · cos_y^u · min(1/d_min², G_max): d ≥ d_min (LC box to IC box), and the
//!   cosines are bounded by the clusters' normal cones ([`crate::cone::cos_upper`], MDLC's
//!   cosine bound; 1 for a cluster of point lights). The clamp G_max is the same constant as in
//!   the estimator (VPLs on or next to the surface make 1/d_min² unbounded; MDLC clamps d² at
//!   (0.05 × scene half-diagonal)², wave2 F2.3). The paper's bound has no cosines; without
//!   them every triangle facing away from the light (a slab's underside, a sphere's night
//!   side) keeps a bound as large as a lit one, and the refinement splits it although every
//!   sample is 0.
//! * **F_t^u** = F_t(cos_i^u) (F_t is non-decreasing in cos θ, checked by
//!   [`Transmittance::new`]; F_t(1), the normal-incidence value, without a cone).
//! * **e_j** = A_j W_j I_j R_d^u G^u F_t^u / (2√n_j): every sample lies in [0, M_j] with
//!   M_j = A_j W_j I_j R_d^u G^u F_t^u, so by Popoviciu's inequality (Popoviciu 1935: a
//!   variable confined to [a, b] has variance ≤ (b − a)²/4) its standard deviation is ≤ M_j/2
//!   and that of the n_j-sample mean is ≤ M_j/(2√n_j).
//!
//! Distances between clusters use boxes for the bounds (exact minimum box-to-box distance) and
//! bounding spheres for the selection (Eq. 11–13, as the paper), every distance clamped at ≥ 0.

use crate::aabb::{Aabb, Sphere};
use crate::cone::{NormalCone, cos_upper};
use crate::estimator::GRAZING_COS;
use crate::profile::{RadialProfile, Transmittance};

/// The clamped inverse square distance min(1/d², G_max) = 1/max(d², 1/G_max), used by the
/// estimator and by [`g_upper`] alike. Finite for d = 0.
#[inline]
pub fn inv_sq_clamped(d2: f64, g_max: f64) -> f64 {
    1.0 / d2.max(1.0 / g_max)
}

/// R_d^u: max_c R_d,c(r_min) with r_min the minimum distance between the irradiance-cluster box
/// `ic` and the shading-cluster box `sc`.
pub fn rd_upper(profile: &RadialProfile, ic: &Aabb, sc: &Aabb) -> f64 {
    profile.max_channel(ic.min_distance_sq(sc).sqrt())
}

/// G^u: min(1/d_min², G_max) with d_min the minimum distance between the light-cluster box `lc`
/// and the irradiance-cluster box `ic`.
pub fn g_upper(lc: &Aabb, ic: &Aabb, g_max: f64) -> f64 {
    inv_sq_clamped(lc.min_distance_sq(ic), g_max)
}

/// cos_i^u: the largest cosine between a normal of the irradiance cluster (box `ic`, normals
/// in `ic_cone`) and the direction from its points to the light cluster's box `lc`; 0 when it
/// is at most [`GRAZING_COS`] (the estimator counts such lights as none), 1 without a cone.
pub fn cos_i_upper(ic_cone: Option<&NormalCone>, ic: &Aabb, lc: &Aabb) -> f64 {
    let c = ic_cone.map_or(1.0, |k| cos_upper(k, ic, lc));
    if c <= GRAZING_COS { 0.0 } else { c }
}

/// cos_y^u: the largest emission cosine of an oriented light cluster (normals in `lc_cone`)
/// towards the irradiance cluster's box; 1 for a cluster holding a point light (`None`).
pub fn cos_y_upper(lc_cone: Option<&NormalCone>, lc: &Aabb, ic: &Aabb) -> f64 {
    lc_cone.map_or(1.0, |k| cos_upper(k, lc, ic))
}

/// F_t^u: F_t at the largest cosine `cos_i_u` (the normal-incidence value when that is 1).
pub fn ft_upper(ft: &Transmittance, cos_i_u: f64) -> f64 {
    ft.eval(cos_i_u).min(ft.max())
}

/// M_j = A_j W_j I_j R_d^u G^u F_t^u: the largest value one sample of the triplet can take
/// (and so also an upper bound of the triplet's true value I_j).
pub fn sample_bound(a: f64, w: f64, i: f64, rd_u: f64, g_u: f64, ft_u: f64) -> f64 {
    a * w * i * rd_u * g_u * ft_u
}

/// e_j = M_j / (2√n_j) (Popoviciu; see the module doc).
pub fn error_bound(m: f64, n_j: u32) -> f64 {
    m / (2.0 * f64::from(n_j.max(1)).sqrt())
}

/// Which cluster of a triplet to refine.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ClusterKind {
    /// The light cluster C^L.
    Light,
    /// The irradiance cluster C^I.
    Irradiance,
    /// The shading cluster C^S.
    Shading,
}

/// How the cluster to refine is chosen once a triplet is picked.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub enum Selection {
    /// Nabata & Iwasaki §4.3: the cluster whose refinement can reduce the range of R_d/d² the
    /// most, i.e. the smallest lower term of Eq. 11–13.
    #[default]
    BssrdfAware,
    /// The cluster with the longest box diagonal (MDLC, EELC; the paper's Table 3 baseline).
    MaxExtent,
}

/// `R_d(r)/d²` with d² clamped as in the estimator; `r` and `d` clamped at ≥ 0.
fn rd_over_d2(profile: &RadialProfile, r: f64, d: f64, g_max: f64) -> f64 {
    let d = d.max(0.0);
    profile.max_channel(r.max(0.0)) * inv_sq_clamped(d * d, g_max)
}

/// The common upper term of Eq. 11–13, R_d(r_min)/d_min² over bounding spheres:
/// r_min = r_c − r_I − r_S, d_min = d_c − r_L − r_I (clamped at ≥ 0, d² clamped by G_max).
pub fn selection_upper(
    lc: &Sphere,
    ic: &Sphere,
    sc: &Sphere,
    profile: &RadialProfile,
    g_max: f64,
) -> f64 {
    let r_c = ic.center.distance(sc.center);
    let d_c = lc.center.distance(ic.center);
    rd_over_d2(
        profile,
        r_c - ic.radius - sc.radius,
        d_c - lc.radius - ic.radius,
        g_max,
    )
}

/// The lower terms of Eq. 11–13, `[L, I, S]`: each pins the other two clusters at their near
/// side and puts the candidate at its far side (wave2 F2.0 checks them by hand):
///
/// * L: R_d(r_c − r_I − r_S) / (d_c − r_I + r_L)²
/// * I: R_d(r_c − r_S + r_I) / (d_c − r_L + r_I)²
/// * S: R_d(r_c − r_I + r_S) / (d_c − r_L − r_I)²
///
/// Since Δ_c = upper − lower_c with one common upper term, the cluster with the smallest lower
/// term has the largest range.
pub fn selection_lower(
    lc: &Sphere,
    ic: &Sphere,
    sc: &Sphere,
    profile: &RadialProfile,
    g_max: f64,
) -> [f64; 3] {
    let r_c = ic.center.distance(sc.center);
    let d_c = lc.center.distance(ic.center);
    let (r_l, r_i, r_s) = (lc.radius, ic.radius, sc.radius);
    [
        rd_over_d2(profile, r_c - r_i - r_s, d_c - r_i + r_l, g_max),
        rd_over_d2(profile, r_c - r_s + r_i, d_c - r_l + r_i, g_max),
        rd_over_d2(profile, r_c - r_i + r_s, d_c - r_l - r_i, g_max),
    ]
}

/// Picks the cluster to refine among those marked `splittable` (`[L, I, S]`).
///
/// BSSRDF-aware: the smallest lower term of [`selection_lower`]; Max-Extent: the longest box
/// diagonal. Ties go to the irradiance cluster, then the light, then the shading cluster.
/// `None` when nothing is splittable.
pub fn select(
    selection: Selection,
    boxes: [&Aabb; 3],
    splittable: [bool; 3],
    profile: &RadialProfile,
    g_max: f64,
) -> Option<ClusterKind> {
    let kinds = [
        ClusterKind::Light,
        ClusterKind::Irradiance,
        ClusterKind::Shading,
    ];
    let score: [f64; 3] = match selection {
        Selection::BssrdfAware => {
            let [l, i, s] = boxes.map(|b| b.sphere());
            selection_lower(&l, &i, &s, profile, g_max)
        }
        // Larger diagonal first: minimise its negative.
        Selection::MaxExtent => boxes.map(|b| -b.diagonal()),
    };
    let mut best: Option<usize> = None;
    for k in [1usize, 0, 2] {
        if !splittable[k] {
            continue;
        }
        match best {
            Some(b) if score[k] >= score[b] => {}
            _ => best = Some(k),
        }
    }
    best.map(|k| kinds[k])
}
