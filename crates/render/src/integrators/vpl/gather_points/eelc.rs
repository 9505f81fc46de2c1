//! `eelc`: the error estimation for Lightcuts with supersampling and translucency (Sakai et al.
//! 2019), the EELC baseline of Nabata & Iwasaki §5: the Student-t estimator of
//! [`sss_manylight::eelc`] per pixel over the same VPLs and light tree as `manylight`, with N
//! irradiance points drawn per shading point (see [`super`] for the pipeline and what
//! the pixel value is).
//!
//! **Where it differs from `manylight`.** The same stratified sampling with n_j = 2 and the
//! same interval (ν = J, α = `--alpha`), but over the fixed point set: a cluster that is one
//! gather point cannot be refined, and the interval (reported as the per-pixel standard error,
//! ΔI/t_α) measures the error against the point set's value only, not the point set's own
//! noise — at small ε the image is as noisy as N points make it (the paper's Fig. 10). The
//! per-pixel layer `pairs` is the number of strata.
//!
//! **Not supported** (the errors of `manylight`): the directional dipole and pre-scatter
//! textures.

use super::{PixelEstimator, PointOptions, Prepared};
use crate::Error;
use crate::frame::Frame;
use crate::integrators::Converges;
use crate::integrators::options::{
    ALPHA, IRRADIANCE_POINTS, MAX_PAIRS, REL_ERROR, UNIFORM_POINTS, VPLS, alpha_option, eps_option,
};
use crate::integrators::vpl::{MIN_TRIPLETS, PixelResult};
use crate::integrators::{Integrator, Method, MethodOptions, OptionSpec, Shaded, Sweep};
use crate::progress::Progress;
use sss_manylight::{EelcEstimator, EelcSettings, GatherTree, PixelEstimate, StudentT, Visibility};
use sss_scene::Scene;

/// The options of `eelc` (`--rel-error`, `--alpha` and `--vpls` as `manylight`'s).
pub const OPTIONS: [OptionSpec; 6] = [
    REL_ERROR,
    ALPHA,
    IRRADIANCE_POINTS,
    UNIFORM_POINTS,
    VPLS,
    MAX_PAIRS,
];

/// The registry entry.
pub const METHOD: Method = Method {
    name: "eelc",
    about: "Error estimation for Lightcuts: Student-t stratified sampling over N BSSRDF importance-sampled irradiance points per shading point (Sakai et al. 2019; baseline of Nabata & Iwasaki)",
    options: &OPTIONS,
    build: |o| Ok(Box::new(Eelc::from_options(o)?)),
    sweep: Sweep {
        option: "irradiance-points",
        label: "points",
        values: super::sweep_points,
    },
    converges_to: Converges::Model,
};

/// The `eelc` integrator and its settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Eelc {
    /// Relative error threshold ε (≥ 0; 0 refines until exact or the cap).
    pub eps: f64,
    /// Confidence level α in (0, 1).
    pub alpha: f64,
    /// The irradiance points, VPLs and pair cap.
    pub points: PointOptions,
}

impl Default for Eelc {
    /// The settings of the declared defaults of [`OPTIONS`].
    fn default() -> Self {
        crate::integrators::options::from_declared(METHOD.name, Eelc::from_options)
    }
}

impl Eelc {
    /// The settings `options` describe (errors name the flag).
    pub fn from_options(o: &MethodOptions) -> Result<Self, Error> {
        let eps = eps_option(o, &OPTIONS, "rel-error")?;
        let alpha = alpha_option(o, &OPTIONS)?;
        Ok(Eelc {
            eps,
            alpha,
            points: PointOptions::from_options(o, &OPTIONS)?,
        })
    }

    fn settings(&self, g_max: f64) -> EelcSettings {
        let mut s = EelcSettings::new(g_max);
        s.epsilon = self.eps;
        s.max_pairs = self.points.max_pairs;
        // As `manylight`: the stopping tests from 64 pairs on.
        s.min_pairs = MIN_TRIPLETS.min(self.points.max_pairs);
        s
    }

    /// The Student-t quantiles of `--alpha`.
    fn student_t(&self) -> Result<StudentT, Error> {
        StudentT::new(self.alpha).map_err(|e| Error::Input(format!("--alpha: {e}")))
    }

    /// The per-object estimators of a prepared frame.
    fn estimators<'a>(
        &self,
        prepared: &'a Prepared,
        t: &'a StudentT,
    ) -> Result<Vec<Option<EelcEstimator<'a>>>, Error> {
        let settings = self.settings(prepared.g_max);
        super::estimators(prepared, METHOD.name, |lt, d| {
            EelcEstimator::new(lt, &d.ft, t, settings)
        })
    }

    /// The estimates of the pixels `pixels` of `frame` only, in that order (for subset
    /// references and error measurements): each pixel's subsurface value and standard error
    /// (ΔI / t_α, against its own point set's value) equal what a full render gives it with the
    /// same seed (its points and strata depend on its own index only); `triplets` holds its
    /// strata. The frame's set-up (VPLs, triangle BVHs) is done here, as in a render.
    pub fn shade_pixels(
        &self,
        frame: &Frame<'_>,
        pixels: &[usize],
    ) -> Result<Vec<PixelResult>, Error> {
        let prepared = super::prepare(frame, METHOD.name, &self.points)?;
        let t = self.student_t()?;
        let est = self.estimators(&prepared, &t)?;
        super::shade_pixels(frame, METHOD.name, &self.points, &prepared, &est, pixels)
    }
}

impl PixelEstimator for EelcEstimator<'_> {
    const STD_ERROR: bool = true;

    fn estimate(
        &self,
        gather: &GatherTree,
        visibility: &dyn Visibility,
        seed: u64,
    ) -> PixelEstimate {
        EelcEstimator::estimate(self, gather, visibility, seed)
    }

    fn std_error(&self, px: &PixelEstimate) -> Option<f64> {
        Some(px.std_error)
    }
}

impl Integrator for Eelc {
    fn name(&self) -> &'static str {
        METHOD.name
    }

    fn describe(&self) -> String {
        format!(
            "rel-error {}, alpha {}, {}",
            self.eps,
            self.alpha,
            self.points.describe()
        )
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
        let t = self.student_t()?;
        let est = self.estimators(&prepared, &t)?;
        super::run(frame, METHOD.name, &self.points, &prepared, &est, progress)
    }
}
