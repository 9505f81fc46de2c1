//! Integrators: ways to compute the subsurface term at the G-buffer's points, behind one
//! interface ([`Integrator`]) and listed in one registry ([`METHODS`]).
//!
//! Each computes the same quantity (see [`crate::shading`] and `ARCHITECTURE.md`):
//! L(x_o, ω_o) = F_t(η, cos θ_o)/(cπ) Σ_i R_d(‖x_i − x_o‖) E_i A_i for radial models, the full S
//! of the directional dipole summed over incident packets otherwise, or the integral these sums
//! approximate.
//!
//! # The contract
//! An integrator works on a whole [`Frame`] (the tree, many-light and separable methods shade
//! sets of pixels together). It receives the prepared frame — G-buffer, per-object BVHs, lights,
//! per-material [`TranslucentShading`](crate::shading::TranslucentShading), and irradiance
//! samples built on request ([`Frame::irradiance_samples`]) — and returns a [`Shaded`]: one
//! subsurface value per G-buffer sample (0 for samples not on a visible translucent object;
//! finite and non-negative), an optional per-pixel standard error, its own statistics and any
//! extra per-pixel layers. It times its stages with [`Frame::timed`] and reports progress in
//! G-buffer samples. Same frame seed, same output, for any thread count.
//!
//! # Layout
//! Methods come in families, each with the code its members share in its own `mod.rs`:
//! - [`point_sums`]: sums over irradiance samples — [`exact`], [`single_tree`], [`dual_tree`],
//!   [`dual_tree_fmm`] (the illumination tree, the dual trees' shading points and s_p);
//! - [`vpl`]: many-light methods over virtual point lights — [`manylight`],
//!   [`sparse_manylight`] (its estimates where the screen-space bandwidth asks, the rest
//!   reconstructed with an interval), and under
//!   [`vpl::gather_points`] (the fixed gather-point pipeline) [`mdlc`] and [`eelc`];
//! - [`pathtrace`] (its probe sampler is [`crate::probe`], which the gather-point pipeline
//!   also draws with) and [`separable`] stand alone;
//! - [`volpath`]: volumetric path tracing of the media themselves (its physics is
//!   [`crate::volume`]), the one method bound to no BSSRDF model ([`Converges::Transport`]).
//!
//! Option specs more than one method takes are named constants in [`options`]; a method
//! lists the ones it takes by name. No method file imports from a sibling method file (a
//! tidy test checks it): shared code lives above the methods that use it. The methods'
//! modules are re-exported here (`integrators::exact`, `integrators::manylight`, ...).
//!
//! # Adding a method
//! One new file in its family (or here, if it stands alone) with the settings type
//! (implementing [`Integrator`]) and a [`Method`] entry (name, options, constructor, compare
//! sweep), and one line in [`METHODS`]. The `sss render` flags, the `cargo xtask compare`
//! sweep and the pipeline all read the registry.

pub mod options;
pub mod pathtrace;
pub mod point_sums;
pub mod separable;
pub mod volpath;
pub mod vpl;

pub use options::{MethodOptions, OptionKind, OptionSpec};
pub use point_sums::{dual_tree, dual_tree_fmm, exact, single_tree};
pub use vpl::gather_points::{eelc, mdlc};
pub use vpl::{manylight, sparse_manylight};

use crate::Error;
use crate::frame::Frame;
use crate::gbuffer::GBuffer;
use crate::irradiance::IrradianceSettings;
use crate::progress::Progress;
use sss_bssrdf::Rgb;
use sss_scene::Scene;

/// One method's output on a frame.
#[derive(Clone, Debug, Default)]
pub struct Shaded {
    /// The subsurface value of every G-buffer sample, indexed like `frame.gbuffer.samples`
    /// (0 for samples not on a visible translucent object).
    pub values: Vec<Rgb>,
    /// Per pixel: the standard error of the pixel's subsurface estimate (stochastic methods).
    pub std_error: Option<Vec<Rgb>>,
    /// The method's own counts (nodes visited, BSSRDF evaluations, paths, taps, ...).
    pub stats: Vec<Stat>,
    /// Extra per-pixel images the method produces (e.g. the separable pass's screen-space
    /// inputs), row-major like the output images.
    pub layers: Vec<Layer>,
}

/// A named count or measure of a method's work.
#[derive(Clone, Debug, PartialEq)]
pub struct Stat {
    /// Name (snake_case).
    pub name: &'static str,
    /// Value.
    pub value: f64,
}

/// A named per-pixel RGB image.
#[derive(Clone, Debug, PartialEq)]
pub struct Layer {
    /// Layer name (as written to EXR).
    pub name: &'static str,
    /// Pixels, row-major from the top-left.
    pub pixels: Vec<Rgb>,
}

/// A way to compute the subsurface term of a whole frame.
pub trait Integrator: Send + Sync {
    /// The registry name (`exact`, `pathtrace`, ...).
    fn name(&self) -> &'static str;
    /// One line describing the settings, for summaries.
    fn describe(&self) -> String;
    /// Names of the extra layers [`Shaded::layers`] will hold (empty for most methods).
    fn layer_names(&self) -> &'static [&'static str] {
        &[]
    }
    /// The irradiance-sample settings the method will ask the frame for, if any: their memory
    /// is estimated before the render ([`crate::budget::check_irradiance`]).
    fn irradiance_settings(&self) -> Option<IrradianceSettings> {
        None
    }
    /// Bytes of the method's own structures (trees over irradiance samples or pixels), from
    /// the scene and the per-object irradiance-sample estimates of
    /// [`crate::budget::irradiance_estimate`] (object, count, bytes): counted with the samples
    /// against `--max-memory` before the frame is built.
    fn structure_bytes(&self, scene: &Scene, samples: &[(usize, u64, u64)]) -> u64 {
        let _ = (scene, samples);
        0
    }
    /// Whether the method follows light through the media themselves (`volpath`), so that its
    /// image already holds the light refracted through the objects without a collision: the
    /// pipeline adds that light ([`crate::unscattered`], the scene key `unscattered`) to every
    /// other method's image.
    fn follows_media(&self) -> bool {
        false
    }
    /// Shades every G-buffer sample on a visible translucent object of `frame`.
    fn integrate(&self, frame: &Frame<'_>, progress: &dyn Progress) -> Result<Shaded, Error>;
}

/// How `cargo xtask compare` sweeps a method: one option over values, cheapest first.
#[derive(Clone, Copy, Debug)]
pub struct Sweep {
    /// The option swept (a name from [`Method::options`]).
    pub option: &'static str,
    /// The parameter's name in reports (`results.csv`'s `param` column).
    pub label: &'static str,
    /// Values, cheapest first; the argument is `--quick`.
    pub values: fn(bool) -> Vec<f64>,
}

/// What a method's image converges to as its parameters are refined.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Converges {
    /// The sum or integral of the material's BSSRDF model (every model-based method): scored
    /// against `exact` with the same model.
    Model,
    /// Light transport itself in the scene's geometry (`volpath`): no model; scored against
    /// itself at many samples, and the models against it (`cargo xtask compare --truth`).
    Transport,
}

/// A registry entry: everything the CLI, `compare` and the pipeline need to know of a method.
#[derive(Clone, Copy, Debug)]
pub struct Method {
    /// Name on the command line and in reports.
    pub name: &'static str,
    /// One line for `--help`.
    pub about: &'static str,
    /// Its options (`sss render --<name> <value>`), with defaults.
    pub options: &'static [OptionSpec],
    /// Builds the integrator from option values (defaults for the ones not given); errors
    /// name the offending flag.
    pub build: fn(&MethodOptions) -> Result<Box<dyn Integrator>, Error>,
    /// Its sweep in `cargo xtask compare`.
    pub sweep: Sweep,
    /// What its image converges to: the model's sum (scored against `exact` by the default
    /// comparison) or light transport (scored by `compare --truth`).
    pub converges_to: Converges,
}

/// Every rendering method, in report order.
pub const METHODS: &[Method] = &[
    exact::METHOD,
    pathtrace::METHOD,
    separable::METHOD,
    single_tree::METHOD,
    dual_tree::METHOD,
    dual_tree_fmm::METHOD,
    manylight::METHOD,
    sparse_manylight::METHOD,
    mdlc::METHOD,
    eelc::METHOD,
    volpath::METHOD,
];

/// The registry entry named `name`.
pub fn method(name: &str) -> Result<&'static Method, Error> {
    METHODS.iter().find(|m| m.name == name).ok_or_else(|| {
        let names: Vec<&str> = METHODS.iter().map(|m| m.name).collect();
        Error::Input(format!(
            "unknown method `{name}` (known: {})",
            names.join(", ")
        ))
    })
}

/// Builds the method `name` with `options` (the other options at their defaults).
pub fn build(name: &str, options: &MethodOptions) -> Result<Box<dyn Integrator>, Error> {
    let m = method(name)?;
    options.check_known(m)?;
    (m.build)(options)
}

/// Adds `s·v` to `acc`.
#[inline]
pub(crate) fn add_scaled(acc: &mut Rgb, v: Rgb, s: f64) {
    for c in 0..3 {
        acc[c] += v[c] * s;
    }
}

/// acc += v · w, channel by channel.
#[inline]
pub(crate) fn add_weighted(acc: &mut Rgb, v: Rgb, w: Rgb) {
    for c in 0..3 {
        acc[c] += v[c] * w[c];
    }
}

/// The mean of `k` estimates from their sum and sum of squares, and the variance of that mean
/// (the unbiased sample variance over k; 0 for k = 1).
pub(crate) fn mean_and_variance(sum: Rgb, sum2: Rgb, k: u32) -> (Rgb, Rgb) {
    let k = k.max(1) as f64;
    let mean = sum.map(|s| s / k);
    let var = [0, 1, 2].map(|c| {
        if k > 1.0 {
            ((sum2[c] - k * mean[c] * mean[c]) / (k - 1.0)).max(0.0) / k
        } else {
            0.0
        }
    });
    (mean, var)
}

/// Per pixel, the standard error of its value from the variances of its G-buffer samples'
/// values (indexed like `gb.samples`): the pixel averages its camera samples, each with weight
/// 1/(camera samples per pixel), and they are independent.
pub(crate) fn pixel_std_error(gb: &GBuffer, variances: &[Rgb]) -> Vec<Rgb> {
    let cs = gb.samples_per_pixel as f64;
    (0..gb.pixels())
        .map(|i| {
            let mut v = [0.0; 3];
            for k in gb.offsets[i] as usize..gb.offsets[i + 1] as usize {
                for c in 0..3 {
                    v[c] += variances[k][c] / (cs * cs);
                }
            }
            v.map(|x| x.sqrt())
        })
        .collect()
}

/// Errors when a visible translucent material drifts (`drift = true`), for methods that sum
/// one irradiance per point.
pub(crate) fn check_no_drift(frame: &Frame<'_>, method: &str) -> Result<(), Error> {
    for &o in &frame.visible {
        if let Some(sh) = frame.shading_of(o) {
            sh.no_drift(method)?;
        }
    }
    Ok(())
}

/// Errors unless every visible translucent material is radial and does not drift.
pub(crate) fn check_radial(frame: &Frame<'_>, method: &str) -> Result<(), Error> {
    for &o in &frame.visible {
        if let Some(sh) = frame.shading_of(o) {
            sh.radial(method)?;
        }
    }
    check_no_drift(frame, method)
}

/// [`check_radial`] for the methods that take each point's own ball
/// (`sphere_radius = "local"`): errors unless every visible translucent material is radial and
/// does not drift.
pub(crate) fn check_radial_balls(frame: &Frame<'_>, method: &str) -> Result<(), Error> {
    for &o in &frame.visible {
        if let Some(sh) = frame.shading_of(o) {
            sh.radial(method)?;
            sh.one_irradiance(method)?;
        }
    }
    Ok(())
}
