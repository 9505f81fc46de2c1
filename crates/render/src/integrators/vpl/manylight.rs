//! `manylight`: many-light subsurface scattering with adaptive irradiance sampling and
//! Student-t error control (Nabata & Iwasaki, IEEE TVCG 2021), the estimator of
//! [`sss_manylight`] wired to the frame.
//!
//! Per visible translucent object: the VPLs of the scene's lights ([`super::vpls`], direct light
//! only) in one [`LightTree`](sss_manylight::LightTree), a triangle BVH over the object's mesh ([`TriangleClusterTree`](sss_manylight::TriangleClusterTree)), the
//! radial profile `R_d` in scene units (the material's model, as
//! [`TranslucentShading::rd_scene`](crate::shading::TranslucentShading::rd_scene) evaluates it)
//! and the entry transmittance F_t(η, cos θ_i) (`ft_dielectric`, as
//! [`transmitted_irradiance`](crate::shading::transmitted_irradiance) applies it). Per pixel and
//! object: the pixel's G-buffer samples on that object are the shading points, each weighted
//! `exit_weight(n, ω_o) / pixel_samples`, so the estimate is the object's share of the pixel's
//! subsurface value (the renderer's `assemble` averages the samples of a pixel with weight
//! 1/pixel_samples).
//!
//! **From one value per pixel to one per G-buffer sample.** The contract wants a value per
//! G-buffer sample. The pixel estimate Î of an object is split over that object's samples in
//! proportion to their exit weights: v_k = Î · spp · e_k / Σ_j e_j, so that Σ_k v_k / spp = Î
//! and the assembled pixel equals the estimate (a sample that cannot be seen through the
//! interface, e_k = 0, gets 0).
//!
//! **What differs from `exact`.** `exact` sums point irradiance samples lit by the renderer's
//! light sampling; this integrates the irradiance over the triangles (Eq. 7), under the VPL
//! approximation of area and environment lights. Both take cos θ_i against the mesh's
//! interpolated shading normal, and let light in only above the triangle's own plane too; they
//! are consistent estimators of the same integral, and at small ε and many VPLs they agree.
//! (With the flat triangles' normals instead, the image mean was 1 % below `exact` and a path
//! trace on a scanned 100 000-triangle dragon, 7.6 % above on a 20-face icosahedron:
//! `sss_manylight::irradiance_cluster` has the measurement.)
//!
//! **G clamp.** G = cos θ_i cos θ_y min(1/d², G_max) with
//! [`Settings::g_max_for_scene`] of the geometry's half-diagonal: d² ≥ (0.05 × half-diagonal)²,
//! MDLC's clamp. Reported as the stat `g_max`, with the number of clamped samples.
//!
//! **Dark pixels.** The paper's criterion is relative: ΔI < εÎ at every pixel, however dark.
//! A pixel lit only from far away (deep in a shadow) can run to the triplet cap for it: on
//! the point-lit head of `cargo xtask compare --manylight` at ε = 10 %, 421 of 3 813
//! translucent pixels did, 89 % of the frame's triplets (see `sss_manylight::estimator`,
//! "Dark pixels"). A pilot estimates [`PILOT_PIXELS`] seeded translucent pixels at
//! ε = [`PILOT_EPS`] (stage `floor_pilot`); the 90th percentile of their luminances is the
//! frame's bright level L, and every estimate also stops once ΔI < ε · `dark_floor` · L
//! (default: the declared `--dark-floor`, 10⁻⁶, about 20 stops below L, darker than any display
//! or tone curve shows; stat `pixels_floor`). Where εÎ is above that the floor
//! never binds and the estimate is bit-identical to the one without it.
//!
//! **Indirect light** is off by default (renders stay comparable with `exact` and
//! `pathtrace`); `--bounce-vpls N` adds the VPLs of one bounce off opaque diffuse surfaces
//! ([`super::vpls::bounce_vpls`]).
//!
//! **Not supported** (clear errors): the directional dipole (not radial) and pre-scatter
//! textures (the estimator's irradiance has no texture factor).

pub use super::{
    BRIGHT_QUANTILE, MIN_TRIPLETS, ManyLight, PILOT_EPS, PILOT_MAX_TRIPLETS, PILOT_PIXELS,
    PROFILE_TOLERANCE, PixelEstimate, PixelEstimator, PixelResult, SELECTIONS, bright_level,
    parse_selection,
};

use super::vpls::vpl_count;
use super::{eps_sweep, estimator_options, pixel_list, pixel_result};
use crate::Error;
use crate::frame::Frame;
use crate::integrators::Converges;
use crate::integrators::options::{
    ALPHA, DARK_FLOOR, MAX_TRIPLETS, REL_ERROR, SELECTION, VPLS, declared,
};
use crate::integrators::{
    Integrator, Layer, Method, MethodOptions, OptionKind, OptionSpec, Shaded, Stat, Sweep,
};
use crate::progress::Progress;
use sss_manylight::irradiance_cluster::IcNode;
use sss_manylight::{LightNode, Selection, Settings, Summary, Triangle, Vpl};
use sss_scene::Scene;

/// The options of `manylight`.
pub const OPTIONS: [OptionSpec; 9] = [
    REL_ERROR,
    ALPHA,
    SELECTION,
    VPLS,
    MAX_TRIPLETS,
    OptionSpec {
        name: "bounce-vpls",
        value_name: "N",
        default: "0",
        help: "Light paths traced for one indirect bounce off opaque diffuse surfaces, each leaving a VPL where it lands (0: direct light only, comparable with exact and pathtrace)",
        kind: OptionKind::Value,
        values: &[],
    },
    OptionSpec {
        name: "max-splits",
        value_name: "N",
        default: "200000",
        help: "Cap on the triangle splits of one pixel and object, about 400 bytes each, allocated as needed (pixels at the cap are counted and warned about)",
        kind: OptionKind::Value,
        values: &[],
    },
    OptionSpec {
        name: "paper-estimate",
        value_name: "",
        default: "",
        help: "Report the samples the stopping test saw (the paper's estimator: biased low at loose rel-error, about 1 % at 0.1) instead of new samples of the final triplets (unbiased, about half again the samples)",
        kind: OptionKind::Flag,
        values: &[],
    },
    DARK_FLOOR,
];

/// The registry entry.
pub const METHOD: Method = Method {
    name: "manylight",
    about: "Many-light SSS: VPL x triangle x pixel clusters refined until the Student-t interval is below rel-error (Nabata & Iwasaki 2021)",
    options: &OPTIONS,
    build: |o| Ok(Box::new(ManyLight::from_options(o)?)),
    sweep: Sweep {
        option: "rel-error",
        label: "rel_error",
        values: eps_sweep,
    },
    converges_to: Converges::Model,
};

impl Default for ManyLight {
    /// The declared defaults of [`OPTIONS`] (`--paper-estimate` off: a fresh final
    /// estimate), the frame's own VPL seed and the first estimator stream.
    fn default() -> Self {
        let selection: String = declared(&OPTIONS, "selection");
        ManyLight {
            eps: declared(&OPTIONS, "rel-error"),
            alpha: declared(&OPTIONS, "alpha"),
            selection: match parse_selection(&selection) {
                Ok(s) => s,
                Err(e) => panic!("the declared default of --selection: {e}"),
            },
            vpls: declared(&OPTIONS, "vpls"),
            max_triplets: declared(&OPTIONS, "max-triplets"),
            max_splits: declared(&OPTIONS, "max-splits"),
            bounce_paths: declared(&OPTIONS, "bounce-vpls"),
            vpl_seed: None,
            stream: 0,
            fresh_final: true,
            dark_floor: declared(&OPTIONS, "dark-floor"),
        }
    }
}

impl ManyLight {
    /// The settings `options` describe (errors name the flag).
    pub fn from_options(o: &MethodOptions) -> Result<Self, Error> {
        let max_splits: usize = o.get(&OPTIONS, "max-splits")?;
        if !(1..=(1 << 30)).contains(&max_splits) {
            return Err(Error::Input(format!(
                "--max-splits must be in 1..=2^30, got {max_splits}"
            )));
        }
        Ok(ManyLight {
            max_splits,
            bounce_paths: o.get(&OPTIONS, "bounce-vpls")?,
            fresh_final: !o.flag("paper-estimate"),
            ..estimator_options(o, &OPTIONS)?
        })
    }
}

impl ManyLight {
    /// The estimates of the pixels `only` of `frame` (all pixels when `None`), in that order,
    /// with the settings used, the VPL count and the G clamp. Shared by the integrator and by
    /// [`ManyLight::shade_pixels`].
    fn estimate_pixels(
        &self,
        frame: &Frame<'_>,
        only: Option<&[usize]>,
        progress: &dyn Progress,
    ) -> Result<(Vec<PixelEstimate>, Settings, usize, f64), Error> {
        self.with_estimator(frame, METHOD.name, |e| {
            let list = pixel_list(frame, only, METHOD.name)?;
            let pixels = frame.timed("shading", || e.estimate(&list, progress))?;
            Ok((pixels, e.settings, e.vpls, e.g_max))
        })
    }

    /// The estimates of the pixels `pixels` of `frame` only (for subset references and
    /// accuracy measurements): each pixel's subsurface value equals what a full render gives
    /// it with the same seed, since every pixel's estimate is seeded by its own index.
    pub fn shade_pixels(
        &self,
        frame: &Frame<'_>,
        pixels: &[usize],
    ) -> Result<Vec<PixelResult>, Error> {
        let (outs, _, _, _) =
            self.estimate_pixels(frame, Some(pixels), &crate::progress::NoProgress)?;
        Ok(outs
            .into_iter()
            .zip(pixels)
            .map(|(o, &i)| pixel_result(frame, i, &o.values, o.std_error, o.triplets, o.summary))
            .collect())
    }
}

impl Integrator for ManyLight {
    fn name(&self) -> &'static str {
        METHOD.name
    }

    fn describe(&self) -> String {
        format!(
            "rel-error {}, alpha {}, {} selection, {} VPLs per area/environment light, {}",
            self.eps,
            self.alpha,
            match self.selection {
                Selection::BssrdfAware => "BSSRDF-aware",
                Selection::MaxExtent => "Max-Extent",
            },
            self.vpls,
            if self.bounce_paths == 0 {
                "direct light only".to_string()
            } else {
                format!("one bounce from {} light paths", self.bounce_paths)
            }
        )
    }

    fn layer_names(&self) -> &'static [&'static str] {
        &["triplets"]
    }

    fn structure_bytes(&self, scene: &Scene, _samples: &[(usize, u64, u64)]) -> u64 {
        let n = vpl_count(&scene.lights, self.vpls) + u64::from(self.bounce_paths);
        let lights =
            n * size_of::<Vpl>() as u64 + (2 * n).saturating_sub(1) * size_of::<LightNode>() as u64;
        let triangles: u64 = (0..scene.objects.len())
            .filter(|&o| scene.translucent(o).is_some())
            .map(|o| scene.objects[o].mesh.triangles.len() as u64)
            .sum();
        let meshes = triangles * (size_of::<Triangle>() + 2 * size_of::<IcNode>()) as u64;
        // One pixel's triplets, queue and split arena per thread, at the caps.
        let mut settings = Settings::new(1.0);
        settings.max_triplets = self.max_triplets;
        settings.max_splits = self.max_splits;
        lights + meshes + settings.peak_pixel_bytes() * rayon::current_num_threads() as u64
    }

    fn integrate(&self, frame: &Frame<'_>, progress: &dyn Progress) -> Result<Shaded, Error> {
        let gb = &frame.gbuffer;
        let (pixels, settings, n_vpls, g_max) = self.estimate_pixels(frame, None, progress)?;
        let mut summary = Summary::default();
        let mut values = Vec::with_capacity(gb.samples.len());
        let mut std_error = Vec::with_capacity(pixels.len());
        let mut triplets = Vec::with_capacity(pixels.len());
        for p in &pixels {
            summary.merge(&p.summary);
            values.extend_from_slice(&p.values);
            std_error.push(p.std_error);
            triplets.push([p.triplets; 3]);
        }
        if summary.triplet_cap + summary.split_cap + summary.exhausted > 0 {
            frame.warn(format!(
                "manylight: {} pixel estimates stopped at the triplet cap ({}), {} hit the split \
                 cap ({}), {} ran out of clusters to refine, before reaching eps = {}",
                summary.triplet_cap,
                settings.max_triplets,
                summary.split_cap,
                settings.max_splits,
                summary.exhausted,
                self.eps
            ));
        }
        let stat = |name, value: f64| Stat { name, value };
        Ok(Shaded {
            values,
            std_error: Some(std_error),
            stats: vec![
                stat("vpls", n_vpls as f64),
                stat("g_max", g_max),
                stat("pixel_estimates", summary.pixels as f64),
                stat("triplets", summary.triplets as f64),
                stat("mean_triplets", summary.mean_triplets()),
                stat("splits", summary.splits as f64),
                stat("samples", summary.samples as f64),
                stat("g_clamped", summary.g_clamped as f64),
                stat("zero_variance_triplets", summary.zero_variance as f64),
                stat("pixels_converged", summary.converged as f64),
                stat("pixels_floor", summary.floor as f64),
                stat("pixels_triplet_cap", summary.triplet_cap as f64),
                stat("pixels_split_cap", summary.split_cap as f64),
                stat("pixels_exhausted", summary.exhausted as f64),
                stat("pixels_zero", summary.zero as f64),
                stat("pixels_exact", summary.exact as f64),
            ],
            layers: vec![Layer {
                name: "triplets",
                pixels: triplets,
            }],
        })
    }
}
