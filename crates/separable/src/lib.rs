//! # sss-separable: separable subsurface-scattering kernels
//!
//! Use this crate to turn a BSSRDF model of `sss-bssrdf` (any [`sss_bssrdf::Bssrdf`] and
//! [`sss_bssrdf::Medium`]) into the small 1D kernels a real-time screen-space
//! subsurface-scattering pass convolves with, to measure how far each kernel is from the true
//! 2D diffusion kernel, and to run that pass on the CPU ([`screen_space`]) next to its exact
//! 2D convolution ([`convolve2d`]). It implements every kernel of Jimenez et al. 2015 and the
//! sum-of-Gaussians baseline they compare against:
//!
//! | kernel | module | passes | paper |
//! |---|---|---|---|
//! | discretised R_d(x, y), the kernels' reference | [`kernel2d`] | (N² taps) | §3, Eq. 1 |
//! | rank-k SVD, k = 1..6, and the spectrum | [`svd`] | 2k | §3, Eq. 2, Fig. 2, 4 |
//! | pre-integrated rank-1 | [`preintegrated`] | 2 | §4, Eq. 4–5 |
//! | artist-friendly two-Gaussian (Table 2 presets, fitter) | [`artist`] | 2 | §5, Eq. 6 |
//! | guided rank-1 optimisation | [`guided`] | 2 | Appendix A, Eq. 7–8 |
//! | sum of N Gaussians, N = 1..6 | [`gaussians`] | 2N | d'Eon et al. 2007, Eq. 3 |
//! | importance-sampled / uniform taps | [`taps`] | | §6 |
//! | a kernel as GLSL / HLSL / WGSL constants | [`shader`] | | |
//! | a kernel as a JSON file (`sss kernel --format json`), written and read back | [`kernel_json`] | | |
//!
//! Every kernel ends up as the same plain data, a [`SeparableKernel`]: a list of
//! (horizontal, vertical) [`Kernel1d`] pairs of [`Tap`]s (offset in mm, RGB weights), applied
//! as one two-pass convolution per pair and summed. Its weights sum in 2D to the model's total
//! diffuse reflectance per channel ([`Energy::TotalReflectance`], so the filter outputs the
//! exitance E ∗ R_d) or to 1 ([`Energy::Unit`]). All fitting is in f64, and no function
//! returns NaN or infinity: bad input is an [`SeparableError`], a fit that did not converge
//! says so in its result.
//!
//! ```
//! use sss_bssrdf::{make_model, Medium, ModelKind};
//! use sss_separable::{
//!     preintegrated, screen_space, FilterOptions, Kernel2d, Kernel2dSpec, ScreenInput,
//!     TapPlacement,
//! };
//!
//! let model = make_model(ModelKind::BetterDipole, &Medium::preset("skin1")?);
//! let k2 = Kernel2d::from_model(model.as_ref(), &Kernel2dSpec { cells: 63, ..Default::default() })?;
//! // The paper's pass: the pre-integrated kernel (Eq. 5), 7 importance-sampled taps.
//! let kernel = preintegrated::kernel(&k2, TapPlacement::Importance(7))?;
//! let total = kernel.total_weight();
//! assert!((total[0] - model.total_diffuse_reflectance(0)).abs() < 1e-12);
//!
//! // Filter a 32 × 32 image: left half lit, one object, 0.5 mm per pixel.
//! let (w, h) = (32, 32);
//! let irradiance: Vec<[f32; 3]> =
//!     (0..w * h).map(|i| if i % w < w / 2 { [1.0; 3] } else { [0.0; 3] }).collect();
//! let input = ScreenInput {
//!     width: w,
//!     height: h,
//!     irradiance: &irradiance,
//!     depth: &vec![1000.0; w * h],
//!     mask: &vec![0; w * h],
//!     mm_per_pixel: &vec![0.5; w * h],
//! };
//! let out = screen_space::filter(&input, &kernel, &FilterOptions::default())?;
//! assert!(out[16 * w + w / 2 + 1][0] > 0.0); // light bleeds into the shadow
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! ## Conventions
//! - Lengths in mm; R_d in 1/mm² as in `sss-bssrdf`; tap weights are dimensionless masses.
//! - Kernel grids are odd-sized and centred on 0; matrices are row-major with rows along y.
//! - Jimenez's public separable-SSS shader code (2012) stores a 1D kernel as `float4`s
//!   `(r, g, b, offset)` with the centre tap first: [`Kernel1d::to_float4`] exports that
//!   layout (offsets in mm; the shader scales them by its `sssWidth`), and [`shader`] writes
//!   it as GLSL, HLSL or WGSL constant arrays (`examples/separable_sss.wgsl` is a WGSL
//!   two-pass filter that uses them).
//!
//! ## Papers implemented
//! - J. Jimenez, K. Zsolnai, A. Jarabo, C. Freude, T. Auzinger, X.-C. Wu, J. von der Pahlen,
//!   M. Wimmer, D. Gutierrez. *Separable Subsurface Scattering.* Computer Graphics Forum
//!   34(6), 2015 — SVD, pre-integrated, artist-friendly and guided kernels, importance
//!   sampling and jittering.
//! - E. d'Eon, D. Luebke, E. Enderton. *Efficient Rendering of Human Skin.* EGSR 2007 — the
//!   sum-of-Gaussians fit ([`gaussians`]).
//! - J. Jimenez, V. Sundstedt, D. Gutierrez. *Screen-Space Perceptual Rendering of Human
//!   Skin.* ACM TAP 6(4), 2009 — the screen-space formulation (kernel width from the
//!   projected pixel size, depth-aware taps).

#![warn(missing_docs)]
// The crate's only `unsafe` is the screen-space pass's AVX2 form: every block states the
// invariant it relies on, which the differential tests and Miri check (`docs/testing.md`).
#![deny(clippy::undocumented_unsafe_blocks)]

pub mod artist;
pub mod convolve2d;
mod error;
pub mod gaussians;
pub mod guided;
mod kernel;
pub mod kernel2d;
pub mod kernel_json;
mod optimize;
pub mod preintegrated;
pub mod screen_space;
pub mod shader;
mod special;
pub mod svd;
pub mod taps;

pub use error::SeparableError;
pub use kernel::{Energy, Kernel1d, Profile1d, SeparableKernel, SeparableTerm, Tap};
pub use kernel2d::{Kernel2d, Kernel2dSpec};
pub use screen_space::{FilterOptions, FilterScratch, NO_OBJECT, ScreenInput};
pub use special::{erf, erfc, gaussian_mass};
pub use taps::TapPlacement;

/// Three linear colour channels (red, green, blue): `sss-util`'s, the one colour type of the
/// toolkit.
pub use sss_util::Rgb;
