//! # sss-render: the subsurface-scattering toolkit's front end
//!
//! Today this crate holds the `sss` command-line tool and the pieces around it that other
//! tools reuse: PNG/SVG line plots ([`plot`]), radial-profile tables of any model or of the
//! Monte Carlo reference ([`profile`]), the measured-material table ([`presets_table`]) and
//! progress bars ([`progress`]). Scenes, ray casting and the subsurface integrators will live
//! here later.
//!
//! ```
//! use sss_render::profile::{compute, MediumSpec, ProfileModel, ProfileRequest};
//!
//! // Rd(r) of the directional dipole for skim milk at 8 radii up to 10 mm.
//! let req = ProfileRequest {
//!     steps: 8,
//!     ..ProfileRequest::new(ProfileModel::DirectionalDipole, MediumSpec::Preset("skimmilk".into()), 10.0)
//! };
//! let table = compute(&req, &|_| {})?;
//! assert_eq!(table.rows.len(), 8);
//! assert!(table.rows.iter().all(|row| row.rd.iter().all(|v| v.is_finite() && *v >= 0.0)));
//! # Ok::<(), sss_render::Error>(())
//! ```
//!
//! ## Papers
//! None of its own yet: it composes the models of `sss-bssrdf` (Jensen et al. 2001, d'Eon
//! 2012, Frisvad et al. 2014, Habel et al. 2013) and its Monte Carlo reference (MCML, Wang et
//! al. 1995).

// `!(x > 0.0)` is the NaN-rejecting comparison used throughout the numerical code.
#![allow(clippy::neg_cmp_op_on_partial_ord)]
// Colour loops index several [f64; 3] arrays in step (`for c in 0..3`).
#![allow(clippy::needless_range_loop)]

pub mod camera;
pub mod cli;
mod error;
pub mod filter_cli;
pub mod gbuffer;
pub mod geometry;
pub mod image;
pub mod integrators;
pub mod irradiance;
pub mod kernel_cli;
pub mod lights;
pub mod plot;
pub mod presets_table;
pub mod profile;
pub mod progress;
pub mod render;
pub mod render_cli;
pub mod rng;

pub use error::Error;
/// The scene format (re-exported from `sss-scene`).
pub use sss_scene as scene;
