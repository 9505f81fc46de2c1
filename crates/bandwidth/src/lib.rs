//! # sss-bandwidth: Fourier bandwidths of BSSRDFs and screen-space sampling rates
//!
//! Use this crate to predict how fast the multiply-scattered radiance of a translucent material
//! can vary across the image, before rendering it: the frequency analysis of Milaenen et al.
//! 2019 (§3). It computes, once per material, the spatial bandwidth B_s of the cosine-weighted
//! BSSRDF and the angular bandwidth B_θ(θ_o) of its outgoing Fresnel term from numerical
//! spectra ([`rustfft`]); carries them to the camera with the transport operators of Eq. 3
//! (curvature, foreshortening, travel), giving the angular bandwidth B_a (Eq. 4) and the
//! per-pixel sampling rate s_p (Eq. 5) that the dual-tree traversal turns into a pixel-cluster
//! extent P = ρ/s_p (Eq. 6); and estimates the per-vertex mesh curvature that Eq. 4 needs. It
//! knows nothing of scenes: models come from `sss-bssrdf`, meshes are plain arrays.
//!
//! ```
//! use sss_bandwidth::{MaterialBandwidth, PixelFootprint, ShadeGeometry};
//! use sss_bssrdf::{make_model, Medium, ModelKind};
//!
//! let model = make_model(ModelKind::BetterDipole, &Medium::preset("skin1")?);
//! let material = MaterialBandwidth::new(model.as_ref())?;       // once per material
//! let b_s = material.spatial_cycles_per_mm();                     // B_s per channel
//! assert!(b_s[0] < b_s[2]);                                       // red blurs most
//!
//! // Per pixel: a flat patch (k = 0) facing the camera 1 m away, 1920 × 1080 at 40° × 23.6°.
//! let here = ShadeGeometry { curvature_per_mm: 0.0, distance_mm: 1000.0, cos_theta_o: 1.0 };
//! let image = PixelFootprint {
//!     fov_x_rad: 40f64.to_radians(),
//!     fov_y_rad: 23.6f64.to_radians(),
//!     width_px: 1920,
//!     height_px: 1080,
//! };
//! let s_p = material.sampling_rate_per_pixel(&here, &image)?;    // samples per pixel
//! let extent_px = 0.75 / s_p;                                     // Eq. 6 with ρ = 0.75
//! assert!(s_p > 0.0 && extent_px.is_finite());
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! ## Modules
//! - [`spectrum`]: discrete 2-D power spectra and the energy-fraction bandwidth of any profile;
//! - [`spatial`]: B_s of the models of `sss-bssrdf` (regularisation, grid choice, the
//!   directional dipole's maximum over incidence);
//! - [`angular`]: the windowed transform of the outgoing Fresnel term and its B_θ(θ_o) table;
//! - [`transport`]: C_k, P_x, T_d, B_a and s_p, with their edge cases;
//! - [`material`]: [`MaterialBandwidth`], the per-material cache;
//! - [`curvature`]: per-vertex principal curvatures (Rusinkiewicz 2004).
//!
//! ## Units
//! Lengths in mm, curvature in 1/mm; spatial bandwidths in **cycles per mm**, angular ones in
//! **cycles per radian**; fields of view in radians; s_p in samples per pixel. The Fourier
//! convention is e^{i2πΩx}, so frequencies are in cycles, not radians.
//!
//! ## Papers implemented
//! - D. Milaenen, L. Belcour, J.-P. Guertin, T. Hachisuka, D. Nowrouzezahrai. *A Frequency
//!   Analysis and Dual Hierarchy for Efficient Rendering of Subsurface Scattering.* Graphics
//!   Interface 2019 — §3: the BSSRDF spectra, Eq. 3–5.
//! - F. Durand, N. Holzschuch, C. Soler, E. Chan, F. Sillion. *A Frequency Analysis of Light
//!   Transport.* SIGGRAPH 2005, and M. M. Bagher, C. Soler, K. Subr, L. Belcour,
//!   N. Holzschuch. *Interactive Rendering of Acquired Materials on Dynamic Geometry Using
//!   Bandwidth Prediction.* I3D 2012 — the operators on bandwidth vectors.
//! - S. Rusinkiewicz. *Estimating Curvatures and Their Derivatives on Triangle Meshes.* 3DPVT
//!   2004 — [`curvature`], standing in for the Kalogerakis et al. 2007 estimator the paper uses;
//!   with N. Max, *Weights for Computing Vertex Normals from Facet Normals*, JGT 1999, and the
//!   mixed Voronoi areas of M. Meyer, M. Desbrun, P. Schröder, A. Barr, *Discrete
//!   Differential-Geometry Operators for Triangulated 2-Manifolds*, VisMath 2002.

#![forbid(unsafe_code)]

pub mod angular;
pub mod curvature;
mod error;
pub mod material;
pub mod spatial;
pub mod spectrum;
pub mod transport;

pub use angular::{AngularOptions, AngularTable};
pub use curvature::{VertexCurvature, vertex_curvatures, vertex_max_abs_curvature};
pub use error::BandwidthError;
pub use material::MaterialBandwidth;
pub use spatial::{
    SpatialOptions, profile_spatial_bandwidth_cycles_per_mm, spatial_bandwidth_cycles_per_mm,
    spatial_bandwidths_cycles_per_mm,
};
pub use spectrum::{DEFAULT_ENERGY_FRACTION, SpectrumGrid};
pub use transport::{
    BandwidthVector, MIN_COS_THETA_O, PixelFootprint, ShadeGeometry, sampling_rate_per_pixel,
    screen_angular_bandwidth,
};
