//! What the two baselines share about a pair (gather cluster, light cluster) of the product
//! graph of Multidimensional Lightcuts (Walter et al. 2006): the light transport H(y, x) of
//! one (VPL, gather point) pair, its upper bound over two clusters, and the Max-Extent choice of
//! the cluster to refine.
//!
//! H(y, x) = cos⁺θ_i · cos⁺θ_y · min(1/d², G_max) · V(x, y) · F_t(cos θ_i) (Nabata & Iwasaki
//! Eq. 3 with MDLC's clamped geometric term), exactly as the many-light estimator evaluates it
//! (`estimator.rs`: the same grazing cut-off [`GRAZING_COS`] and the same clamp), so the
//! baselines and `manylight` estimate the same pixel value.
//!
//! Its bound over a gather cluster (box, normal cone) and a light cluster (box, cone) is
//! H^u = cos_i^u · cos_y^u · min(1/d_min², G_max) · F_t(cos_i^u) with the bounds of
//! [`crate::bounds`] (MDLC's cosine bound, the box-to-box distance, V ≤ 1); R_d needs no bound
//! here because it is folded exactly into each gather point's strength
//! ([`crate::gather_tree`]).

use glam::DVec3;

use crate::bounds;
use crate::estimator::{GRAZING_COS, Visibility};
use crate::gather_tree::{GatherNode, GatherPoint};
use crate::profile::Transmittance;
use crate::vpl::{LightNode, Vpl};

/// H(y, x) for a VPL and a gather point, and whether G was clamped. 0 when the point's
/// shading normal faces away (or sees the light edge-on: cos θ_i ≤ [`GRAZING_COS`]), the light
/// is not above the triangle's own plane (its geometric normal, as the estimator and the
/// renderer's shadow rays), the VPL emits away from it, they coincide, or the visibility test
/// fails (only called when H would be > 0).
pub(crate) fn transfer(
    vpl: &Vpl,
    x: &GatherPoint,
    ft: &Transmittance,
    g_max: f64,
    visibility: &dyn Visibility,
) -> (f64, bool) {
    let to_light = vpl.position - x.position;
    let d2 = to_light.length_squared();
    let d = d2.sqrt();
    if d.is_nan() || d <= 0.0 {
        return (0.0, false);
    }
    let dir = to_light / d;
    let cos_i = x.normal.dot(dir);
    let cos_y = vpl.emission_cos(-dir);
    let above = x.geometric == DVec3::ZERO || x.geometric.dot(dir) > GRAZING_COS;
    if !(cos_i > GRAZING_COS && cos_y > 0.0 && above) {
        return (0.0, false);
    }
    let clamped = d2 < 1.0 / g_max;
    let h = cos_i * cos_y * bounds::inv_sq_clamped(d2, g_max) * ft.eval(cos_i);
    if !(h > 0.0 && h.is_finite() && visibility.visible(x.position, vpl.position)) {
        return (0.0, clamped);
    }
    (h, clamped)
}

/// H^u over a gather cluster and a light cluster (see the module doc): an upper bound of
/// [`transfer`] for every gather point below `g` and every VPL below `l`; 0 when every pair
/// faces away.
pub(crate) fn transfer_upper(g: &GatherNode, l: &LightNode, ft: &Transmittance, g_max: f64) -> f64 {
    let cos_i_u = bounds::cos_i_upper(g.cone.as_ref(), &g.bbox, &l.bbox);
    if cos_i_u <= 0.0 {
        return 0.0;
    }
    let cos_y_u = bounds::cos_y_upper(l.cone.as_ref(), &l.bbox, &g.bbox);
    cos_i_u * cos_y_u * bounds::g_upper(&l.bbox, &g.bbox, g_max) * bounds::ft_upper(ft, cos_i_u)
}

/// Which side of a pair to refine.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Side {
    Gather,
    Light,
}

/// Max-Extent (the cluster choice of MDLC and EELC, the baseline of the paper's Table 3): the
/// splittable cluster with the longer box diagonal, the gather cluster on a tie (as
/// [`bounds::select`] prefers the irradiance cluster). `None` when both are leaves.
pub(crate) fn refine_side(g: &GatherNode, l: &LightNode) -> Option<Side> {
    match (g.children.is_some(), l.children.is_some()) {
        (false, false) => None,
        (true, false) => Some(Side::Gather),
        (false, true) => Some(Side::Light),
        (true, true) => Some(if l.bbox.diagonal() > g.bbox.diagonal() {
            Side::Light
        } else {
            Side::Gather
        }),
    }
}

/// The RGB intensity summed over each node of a light tree (nodes' children have larger ids,
/// so one reverse pass fills them): MDLC's cluster intensity per channel.
pub(crate) fn light_rgb_sums(nodes: &[LightNode], vpls: &[Vpl]) -> Vec<[f64; 3]> {
    let mut out = vec![[0.0; 3]; nodes.len()];
    for id in (0..nodes.len()).rev() {
        out[id] = match nodes[id].children {
            None => vpls[nodes[id].vpl as usize].intensity,
            Some([a, b]) => {
                let (x, y) = (out[a as usize], out[b as usize]);
                [x[0] + y[0], x[1] + y[1], x[2] + y[2]]
            }
        };
    }
    out
}

/// `a ⊙ b` per channel.
#[inline]
pub(crate) fn mul3(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] * b[0], a[1] * b[1], a[2] * b[2]]
}

/// The settings MDLC and EELC share: ε finite and ≥ 0, G_max finite and > 0, `max_pairs` in
/// 1..=2³⁰.
pub(crate) fn validate_settings(
    epsilon: f64,
    g_max: f64,
    max_pairs: usize,
) -> Result<(), crate::Error> {
    let bad = |m: String| Err(crate::Error::InvalidInput(m));
    if !(epsilon.is_finite() && epsilon >= 0.0) {
        return bad(format!("ε = {epsilon} must be finite and ≥ 0"));
    }
    if !(g_max.is_finite() && g_max > 0.0) {
        return bad(format!("G_max = {g_max} must be finite and > 0"));
    }
    if max_pairs == 0 || max_pairs > (1 << 30) {
        return bad(format!("max_pairs = {max_pairs} must be in 1..=2^30"));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A gather point whose shading normal leans towards a light that is below its triangle's
    /// own plane gets no light from it (a shadow ray cannot leave a flat triangle on its back
    /// side); the same light a little above the plane lights it, through the shading normal's
    /// cosine.
    #[test]
    fn a_light_below_the_triangle_plane_transfers_nothing() {
        let lean = DVec3::new(0.6, 0.0, 0.8);
        let x = GatherPoint {
            position: DVec3::ZERO,
            normal: lean,
            geometric: DVec3::Z,
            strength: [1.0; 3],
        };
        let ft = Transmittance::one();
        let open = |_: DVec3, _: DVec3| true;
        let below = Vpl::point(DVec3::new(1.0, 0.0, -0.1), [1.0; 3]);
        let above = Vpl::point(DVec3::new(1.0, 0.0, 0.1), [1.0; 3]);
        // The shading normal faces both lights.
        assert!(lean.dot(below.position.normalize()) > 0.5);
        assert_eq!(transfer(&below, &x, &ft, 1e6, &open).0, 0.0);
        let (h, _) = transfer(&above, &x, &ft, 1e6, &open);
        let d = above.position;
        let want = lean.dot(d.normalize()) / d.length_squared();
        assert!((h - want).abs() < 1e-12 * want, "{h} vs {want}");
        // Without a geometric normal there is no plane test.
        let free = GatherPoint {
            geometric: DVec3::ZERO,
            ..x
        };
        assert!(transfer(&below, &free, &ft, 1e6, &open).0 > 0.0);
    }
}
