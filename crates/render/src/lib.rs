//! # sss-render: render the subsurface term of a scene with any integrator
//!
//! A thin library composing the toolkit's crates behind one integrator interface: ray casting
//! (one exact BVH per object, `sss-hierarchy`), the G-buffer, direct lighting with shadow rays,
//! irradiance samples, the [`integrators`] and their registry, image output (EXR, PNG) and
//! image [`metrics`]. The eleven methods come in families (`integrators/`): the point sums
//! `exact`, `single-tree`, `dual-tree` and `dual-tree-fmm` (sums over irradiance samples,
//! exactly or through trees); the VPL methods `manylight`, `sparse-manylight`, `mdlc` and
//! `eelc` (many-light estimators over virtual point lights; `sparse-manylight` estimates only
//! where the screen-space sampling rate of [`sampling_rate`] asks and reconstructs the rest); the `pathtrace` reference of each model; the
//! screen-space `separable` pass; and `volpath`, volumetric path tracing of the media in the
//! meshes, the reference of real light transport that no model is bound to. Use it to render a scene from code ([`render`]) or to add a method; the
//! `sss` binary (crate `sss-cli`) and `cargo xtask compare` are thin layers over it. It pulls in
//! no CLI, progress-bar or plotting crate: progress reaches the caller through
//! [`progress::Progress`].
//!
//! ```
//! use sss_render::integrators::{self, MethodOptions};
//! use sss_render::progress::NoProgress;
//! use sss_render::{RenderSettings, render};
//! use sss_render::scene::{LoadOptions, load_str};
//!
//! let text = r#"
//! [camera]
//! position = [0.0, 0.0, 4.0]
//! target = [0.0, 0.0, 0.0]
//! up = [0.0, 1.0, 0.0]
//! fov = 30.0
//! resolution = [16, 12]
//!
//! [[lights]]
//! type = "directional"
//! direction = [0.0, 0.0, -1.0]
//! irradiance = 1.0
//!
//! [materials.skin]
//! type = "translucent"
//! model = "better-dipole"
//! preset = "skin1"
//! units_per_mm = 0.1
//!
//! [[objects]]
//! material = "skin"
//! shape = "sphere"
//! radius = 1.0
//! "#;
//! let scene = load_str(text, "doc.toml", None, &LoadOptions::default())?;
//! let method = integrators::build("pathtrace", &MethodOptions::new().with("spp", 4))?;
//! let out = render(&scene, method.as_ref(), &RenderSettings::default(), &NoProgress)?;
//! assert_eq!(out.subsurface.len(), 16 * 12);
//! assert!(out.subsurface.iter().flatten().all(|v| v.is_finite() && *v >= 0.0));
//! assert!(out.translucent_pixels().len() > 0);
//! # Ok::<(), sss_render::Error>(())
//! ```
//!
//! ## Papers
//! - Jensen & Buhler 2002, *A rapid hierarchical rendering technique for translucent
//!   materials*: irradiance samples, the point-based sum and the single tree ([`irradiance`],
//!   `exact`, `single-tree`).
//! - Milaenen et al. 2019, *Frequency analysis and dual hierarchy for efficient rendering of
//!   subsurface scattering*: the dual tree with per-pixel sampling rates (`dual-tree`; the
//!   local-expansion variant `dual-tree-fmm` is this crate's own).
//! - Nabata & Iwasaki 2021, *Many-light rendering of subsurface scattering with adaptive
//!   irradiance sampling and error control*: `manylight` (and, with Milaenen et al.'s sampling
//!   rates, this crate's own `sparse-manylight`), and its baselines Walter et al. 2006
//!   (multidimensional lightcuts, `mdlc`) and Sakai et al. 2019 (error estimation for
//!   lightcuts, `eelc`).
//! - Pharr, Jakob & Humphreys, *Physically Based Rendering* 3rd ed., §11.4 and §15.4: the
//!   separable BSSRDF S_ω normalisation and BSSRDF importance sampling with probe rays
//!   (`pathtrace`, [`probe`]); §15.3, volumetric path tracing (`volpath`), with pbrt-v4's
//!   spectral multiple importance sampling of chromatic media.
//! - Jimenez et al. 2015, *Separable Subsurface Scattering*: the screen-space pass
//!   (`separable`, kernels from `sss-separable`).
//! - The models of `sss-bssrdf` (Jensen et al. 2001, d'Eon 2012, Frisvad et al. 2014, Habel et
//!   al. 2013).

#![forbid(unsafe_code)]

pub mod budget;
pub mod camera;
mod error;
pub mod flip;
pub mod frame;
pub mod gbuffer;
pub mod geometry;
pub mod image;
pub mod integrators;
pub mod irradiance;
pub mod kernel_choice;
pub mod kernel_export;
pub mod lights;
pub mod local_radius;
pub mod metrics;
pub mod pipeline;
pub mod probe;
pub mod progress;
pub mod rng;
pub mod sampling_rate;
pub mod shading;
pub mod unscattered;
pub mod volume;

pub use error::Error;
/// The scene format (re-exported from `sss-scene`).
pub use sss_scene as scene;

pub use pipeline::{
    RenderOutput, RenderSettings, Stage, assembled_subsurface, check_scene, render,
};
