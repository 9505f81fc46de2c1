//! `mdlc`: Multidimensional Lightcuts (Walter et al. 2006) with BSSRDF importance sampling of
//! the irradiance points (Walter et al. 2012), the MDLC baseline of Nabata & Iwasaki §5: the
//! cut of [`sss_manylight::mdlc`] per pixel over the same VPLs and light tree as `manylight`,
//! with N irradiance points drawn per shading point (see [`super`] for the pipeline
//! and what the pixel value is).
//!
//! **Where it differs from `manylight`.** The irradiance points are fixed before the pixel is
//! estimated, so the point set's own noise stays in the image whatever ε; each pair of the cut
//! is estimated from its representatives (one shadow ray), biased at a finite cut, and every
//! pair's error bound is below ε·Î — no bound on the pixel's total error. Deterministic given
//! the points: no standard error is reported. The per-pixel layer `pairs` is the cut size.
//!
//! **Not supported** (the errors of `manylight`): the directional dipole and pre-scatter
//! textures.

use super::{PixelEstimator, PointOptions, Prepared};
use crate::Error;
use crate::frame::Frame;
use crate::integrators::Converges;
use crate::integrators::options::{IRRADIANCE_POINTS, MAX_PAIRS, UNIFORM_POINTS, VPLS, eps_option};
use crate::integrators::vpl::PixelResult;
use crate::integrators::{
    Integrator, Method, MethodOptions, OptionKind, OptionSpec, Shaded, Sweep,
};
use crate::progress::Progress;
use sss_manylight::{GatherTree, MdlcCut, MdlcSettings, PixelEstimate, Visibility};
use sss_scene::Scene;

/// The options of `mdlc`.
pub const OPTIONS: [OptionSpec; 5] = [
    OptionSpec {
        name: "rel-error",
        value_name: "E",
        default: "0.02",
        help: "Lightcuts' relative threshold: refine the cut until every cluster pair's error bound is below E times the pixel's estimate (Weber's law; the paper uses 0.02)",
        kind: OptionKind::Value,
        values: &[],
    },
    IRRADIANCE_POINTS,
    UNIFORM_POINTS,
    VPLS,
    MAX_PAIRS,
];

/// The registry entry.
pub const METHOD: Method = Method {
    name: "mdlc",
    about: "Multidimensional Lightcuts over N BSSRDF importance-sampled irradiance points per shading point (Walter et al. 2006/2012; baseline of Nabata & Iwasaki)",
    options: &OPTIONS,
    build: |o| Ok(Box::new(Mdlc::from_options(o)?)),
    sweep: Sweep {
        option: "irradiance-points",
        label: "points",
        // Cheapest first, at ε = 0.02. Importance sampling dominates the cost (a few probe rays
        // per point, about 2 µs each on one core: 256 points over the sphere's 6456 pixels take
        // ~5 s on 2 cores), and the sweep runs on every radial scene with all threads and one,
        // so it stays at the cheap end; the paper's 4096 per shading point is for `sss render`
        // (measured times: `docs/compare.md`).
        values: super::sweep_points,
    },
    converges_to: Converges::Model,
};

/// The `mdlc` integrator and its settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Mdlc {
    /// Relative threshold ε of the Weber criterion (≥ 0; 0 refines until exact or the cap).
    pub eps: f64,
    /// The irradiance points, VPLs and pair cap.
    pub points: PointOptions,
}

impl Default for Mdlc {
    /// The settings of the declared defaults of [`OPTIONS`].
    fn default() -> Self {
        crate::integrators::options::from_declared(METHOD.name, Mdlc::from_options)
    }
}

impl Mdlc {
    /// The settings `options` describe (errors name the flag).
    pub fn from_options(o: &MethodOptions) -> Result<Self, Error> {
        let eps = eps_option(o, &OPTIONS, "rel-error")?;
        Ok(Mdlc {
            eps,
            points: PointOptions::from_options(o, &OPTIONS)?,
        })
    }

    fn settings(&self, g_max: f64) -> MdlcSettings {
        let mut s = MdlcSettings::new(g_max);
        s.epsilon = self.eps;
        s.max_pairs = self.points.max_pairs;
        s
    }

    /// The per-object cuts of a prepared frame.
    fn cuts<'a>(&self, prepared: &'a Prepared) -> Result<Vec<Option<MdlcCut<'a>>>, Error> {
        let settings = self.settings(prepared.g_max);
        super::estimators(prepared, METHOD.name, |lt, d| {
            MdlcCut::new(lt, &d.ft, settings)
        })
    }

    /// The estimates of the pixels `pixels` of `frame` only, in that order (for subset
    /// references and error measurements): each pixel's subsurface value equals what a full
    /// render gives it with the same seed (its points and cut depend on its own index only);
    /// `triplets` holds its cut size and `std_error` is 0 (MDLC has no interval). The frame's
    /// set-up (VPLs, triangle BVHs) is done here, as in a render.
    pub fn shade_pixels(
        &self,
        frame: &Frame<'_>,
        pixels: &[usize],
    ) -> Result<Vec<PixelResult>, Error> {
        let prepared = super::prepare(frame, METHOD.name, &self.points)?;
        let cuts = self.cuts(&prepared)?;
        super::shade_pixels(frame, METHOD.name, &self.points, &prepared, &cuts, pixels)
    }
}

impl PixelEstimator for MdlcCut<'_> {
    const STD_ERROR: bool = false;

    fn estimate(
        &self,
        gather: &GatherTree,
        visibility: &dyn Visibility,
        _seed: u64,
    ) -> PixelEstimate {
        MdlcCut::estimate(self, gather, visibility)
    }

    fn std_error(&self, _px: &PixelEstimate) -> Option<f64> {
        None
    }
}

impl Integrator for Mdlc {
    fn name(&self) -> &'static str {
        METHOD.name
    }

    fn describe(&self) -> String {
        format!("rel-error {}, {}", self.eps, self.points.describe())
    }

    fn layer_names(&self) -> &'static [&'static str] {
        &["pairs"]
    }

    fn structure_bytes(&self, scene: &Scene, _samples: &[(usize, u64, u64)]) -> u64 {
        self.points
            .structure_bytes(scene, self.settings(1.0).peak_pixel_bytes())
    }

    fn integrate(&self, frame: &Frame<'_>, progress: &dyn Progress) -> Result<Shaded, Error> {
        let prepared = super::prepare(frame, METHOD.name, &self.points)?;
        let cuts = self.cuts(&prepared)?;
        super::run(frame, METHOD.name, &self.points, &prepared, &cuts, progress)
    }
}
