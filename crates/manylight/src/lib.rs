//! # sss-manylight
//!
//! Many-light rendering of subsurface scattering with adaptive irradiance sampling and
//! Student-t error control: Nabata & Iwasaki, "Adaptive Irradiance Sampling for Many-Light
//! Rendering of Subsurface Scattering", IEEE TVCG 2021 (after Nabata et al., "An error
//! estimation framework for many-light rendering", PG 2016, and Multidimensional Lightcuts,
//! Walter et al., SIGGRAPH 2006). The crate knows nothing of scenes: it works on plain data
//! (points, triangles, VPLs, closures), and a renderer wires it in as an integrator.
//!
//! A pixel's value (Eq. 1, with w(x_o) of Eq. 2 folded into the shading weights)
//!
//! ```text
//! I = Σ_{x_o ∈ S} w(x_o) ∫_A R_d(‖x_i − x_o‖) Σ_{y ∈ L} I(y) G(y, x_i) V(y, x_i) F_t(ω) dA(x_i)
//! ```
//!
//! is split into triplets (light cluster, irradiance cluster, shading cluster), each estimated
//! with two samples (Eq. 5–8), and refined where the error bound e_j is largest until the
//! Student-t interval ΔI (Eq. 9) falls below ε·I.
//!
//! * [`vpl`]: VPLs and the binary light tree (MDLC).
//! * [`irradiance_cluster`]: the triangle BVH, uniform area sampling (Eq. 7) and
//!   longest-edge halving of single-triangle clusters in a per-pixel arena.
//! * [`shading_cluster`]: the tree over a pixel's shading points.
//! * [`bounds`]: R_d^u, G^u, F_t^u, e_j (Popoviciu) and the cluster selections (Eq. 10–13,
//!   Max-Extent).
//! * [`estimator`]: the per-pixel loop, its stopping rules, hazards and caps.
//! * [`confidence`]: the Student-t quantile table (`statrs`).
//! * [`profile`]: the checked R_d(r) and F_t(cos θ) closures.
//! * [`summary`]: frame-level counts (pixels at each cap or hazard).
//!
//! The two baselines of the paper's §5 share the VPLs and the light tree but work on a FIXED
//! set of N irradiance points per shading point (BSSRDF importance-sampled by the renderer, or
//! uniform by area, [`gather_tree::uniform_points`]):
//!
//! * [`gather_tree`]: gather points (an irradiance point carrying w(x_o) A_k R_d of its shading
//!   point) and the per-pixel gather tree.
//! * [`mdlc`]: Multidimensional Lightcuts (Walter et al. 2006) with BSSRDF importance sampling
//!   (Walter et al. 2012): the representative cut under the Weber criterion.
//! * [`eelc`]: the error estimation for Lightcuts (Sakai et al. 2019): stratified sampling of
//!   the same product graph with the Student-t interval of the estimator.
//!
//! **Units.** One length unit throughout (positions, `g_max` in 1/length², R_d in
//! 1/length², areas in length²); intensities in W/sr; the result is in the units of
//! `w · R_d · I · G · A`, i.e. radiance when the weights carry 1/π and the exit Fresnel factor.
//!
//! **One object at a time.** A [`TriangleClusterTree`] is one translucent mesh; a pixel whose
//! shading points lie on several objects is estimated once per object with that object's
//! points, and the results are added.
//!
//! ## Accuracy, measured against an independent reference
//!
//! An estimator that is only compared with its own ε → 0 render cannot show its bias. The
//! one found that way (measured against the renderer's path tracer and `exact`): the flat
//! triangles' normals were used for cos θ_i where the renderer's other methods use the mesh's
//! interpolated shading normals, which put the image mean 1 % low on a scanned dragon and
//! 7.6 % high on an icosahedron; see [`irradiance_cluster`] for the measurement and the fix.
//! The baselines' irradiance points had the same flaw (their importance-sampled points carried
//! the triangle's flat normal: EELC 7.5 % high on the icosahedron, 0–2.7 % low on the compare
//! scenes below); an [`IrradiancePoint`] now carries both normals, as a [`SurfaceSample`] does.
//! `cargo xtask compare --manylight` now scores the method against a path-traced reference
//! (BSSRDF importance sampling with probe rays and continuous light sampling: no VPLs,
//! clusters or bounds) on seven scenes: the paper's three (a Buddha, two Buddhas, a head;
//! one quad light of 1 024 VPLs, 16 shading points per pixel), each again under one point
//! light with 4 shading points per pixel, and a scanned dragon under a point light.
//! What it finds (40 pixels per scene; a pixel is scored at ε only where the reference's
//! standard error is at most ε/4):
//!
//! * image mean over the reference's: the paper's estimator, which reports the samples its
//!   stopping test saw, is low at loose ε on every scene (about 1 % at ε = 10 %): the
//!   Student-t stop fires early on a run of low triplet values, which makes the value low and
//!   the interval narrow together. The default estimator evaluates the final partition again
//!   with new samples ([`Settings::fresh_final`], see [`estimator`]), which is unbiased: its
//!   image means scatter on both sides of the reference's within their noise;
//! * estimation accuracy (α = 95 %) pooled over the scenes: within about a point of what a
//!   calibrated estimate scores against this reference at ε = 10, 5 and 2 %, and a few points
//!   below it at 1 %, where each scene rests on few estimates.
//!
//! The figures per scene and ε, with the runs' hosts and dates, are in the repository's
//! `results/2026-12-05-manylight.md`; `docs/compare.md` says what the experiment reports.

#![forbid(unsafe_code)]

//! ## Example
//!
//! ```
//! use glam::DVec3;
//! use sss_manylight::*;
//!
//! // A 1 × 1 square (two triangles, normal +z), lit by one point light 1 above its centre.
//! let pos = [DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::Y];
//! let surface = TriangleClusterTree::new(&pos, &[[0, 1, 2], [0, 2, 3]])?;
//! let lights = LightTree::new(vec![Vpl::point(DVec3::new(0.5, 0.5, 1.0), [1.0; 3])])?;
//! // An exponential profile (non-increasing: checked) and F_t = 1.
//! let profile = RadialProfile::new(|r| [(-4.0 * r).exp(); 3], 2.0)?;
//! let ft = Transmittance::one();
//! let t = StudentT::new(0.95)?;
//! let mut settings = Settings::new(100.0);
//! settings.epsilon = 0.05;
//! let est = Estimator::new(&lights, &surface, &profile, &ft, &t, settings)?;
//! // One shading point at the centre, weight 1.
//! let points = vec![ShadingPoint {
//!     position: DVec3::new(0.5, 0.5, 0.0),
//!     normal: DVec3::Z,
//!     weight: 1.0,
//! }];
//! let shading = ShadingTree::new(points)?;
//! let open_sky = |_: DVec3, _: DVec3| true;
//! let px = est.estimate(&shading, &open_sky, pixel_seed(1, 0));
//! assert_eq!(px.status, Status::Converged);
//! assert!(px.delta < 0.05 * px.value);
//! // The refinement did some work, and every channel agrees (grey light, grey profile).
//! assert!(px.triplets > 8);
//! assert!((px.rgb[0] - px.rgb[2]).abs() <= 1e-12 * px.rgb[0]);
//! # Ok::<(), sss_manylight::Error>(())
//! ```

pub mod aabb;
mod binary_tree;
pub mod bounds;
pub mod cone;
pub mod confidence;
pub mod eelc;
pub mod estimator;
pub mod gather_tree;
pub mod irradiance_cluster;
pub mod mdlc;
mod pairs;
pub mod profile;
pub mod shading_cluster;
pub mod summary;
pub mod vpl;

pub use aabb::{Aabb, Sphere};
pub use bounds::{ClusterKind, Selection};
pub use confidence::StudentT;
pub use eelc::{EelcEstimator, EelcSettings};
pub use estimator::{
    Dof, Estimator, Interval, PixelEstimate, Settings, Status, Visibility, effective_dof,
    pixel_seed,
};
pub use gather_tree::{
    GatherNode, GatherPoint, GatherTree, IrradiancePoint, gather_points, uniform_points,
};
pub use irradiance_cluster::{IcId, Refinements, SurfaceSample, Triangle, TriangleClusterTree};
pub use mdlc::{CutPair, MdlcCut, MdlcSettings};
pub use profile::{LUMINANCE, RadialProfile, Transmittance, luminance};
pub use shading_cluster::{ShadingPoint, ShadingTree};
pub use summary::Summary;
pub use vpl::{LightNode, LightTree, NormalCone, Vpl, VplKind};

/// Errors: bad input data or settings, or a model the bounds cannot handle.
#[derive(Clone, Debug, PartialEq)]
pub enum Error {
    /// Input data or settings out of range (the message says which and why).
    InvalidInput(String),
    /// A profile or transmittance that is not finite, not in range, or not monotone.
    InvalidModel(String),
}

impl std::fmt::Display for Error {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Error::InvalidInput(m) => write!(f, "invalid input: {m}"),
            Error::InvalidModel(m) => write!(f, "invalid model: {m}"),
        }
    }
}

impl std::error::Error for Error {}

#[cfg(test)]
mod send_sync {
    fn assert_send_sync<T: Send + Sync>() {}
    #[test]
    fn shared_data_is_send_and_sync() {
        assert_send_sync::<crate::LightTree>();
        assert_send_sync::<crate::TriangleClusterTree>();
        assert_send_sync::<crate::RadialProfile>();
        assert_send_sync::<crate::Transmittance>();
        assert_send_sync::<crate::StudentT>();
        assert_send_sync::<crate::Estimator<'static>>();
        assert_send_sync::<crate::MdlcCut<'static>>();
        assert_send_sync::<crate::EelcEstimator<'static>>();
        assert_send_sync::<crate::GatherTree>();
    }
}
