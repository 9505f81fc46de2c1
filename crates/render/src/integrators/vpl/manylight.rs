//! `manylight`: many-light subsurface scattering with adaptive irradiance sampling and
//! Student-t error control (Nabata & Iwasaki, IEEE TVCG 2021), the estimator of
//! [`sss_manylight`] wired to the frame.
//!
//! Per visible translucent object: the VPLs of the scene's lights ([`crate::vpls`], direct light
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
//! (default [`DEFAULT_DARK_FLOOR`], stat `pixels_floor`). Where εÎ is above that the floor
//! never binds and the estimate is bit-identical to the one without it.
//!
//! **Indirect light** is off by default (renders stay comparable with `exact` and
//! `pathtrace`); `--bounce-vpls N` adds the VPLs of one bounce off opaque diffuse surfaces
//! ([`crate::vpls::bounce_vpls`]).
//!
//! **Not supported** (clear errors): the directional dipole (not radial) and pre-scatter
//! textures (the estimator's irradiance has no texture factor).

pub use super::{MIN_TRIPLETS, PROFILE_TOLERANCE, PixelResult};

use super::{
    estimate_seed, light_tree_seeded, model_error, object_data, pixel_list, pixel_result,
    scene_box, shadow_test,
};
use crate::Error;
use crate::frame::Frame;
use crate::integrators::Converges;
use crate::integrators::options::{ALPHA, RELATIVE_EPS, VPLS, alpha_option, eps_option};
use crate::integrators::{
    Integrator, Layer, Method, MethodOptions, OptionKind, OptionSpec, Shaded, Stat, Sweep,
    check_radial,
};
use crate::progress::Progress;
use crate::vpls::vpl_count;
use rayon::prelude::*;
use sss_bssrdf::Rgb;
use sss_manylight::irradiance_cluster::IcNode;
use sss_manylight::{
    Estimator, LightNode, Refinements, Selection, Settings, ShadingPoint, ShadingTree, StudentT,
    Summary, Triangle, Vpl,
};
use sss_scene::Scene;

/// The options of `manylight`.
pub const OPTIONS: [OptionSpec; 9] = [
    RELATIVE_EPS,
    ALPHA,
    OptionSpec {
        name: "selection",
        value_name: "SELECTION",
        default: "bssrdf",
        help: "Cluster to refine: BSSRDF-aware (Nabata & Iwasaki Eq. 10-13) or the largest box (Max-Extent)",
        kind: OptionKind::Value,
        values: &SELECTIONS,
    },
    VPLS,
    OptionSpec {
        name: "max-triplets",
        value_name: "N",
        default: "200000",
        help: "Cap on the triplets of one pixel and object (pixels at the cap are counted and warned about)",
        kind: OptionKind::Value,
        values: &[],
    },
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
        help: "Report the samples the stopping test saw (the paper's estimator: biased low at loose eps, about 1 % at 0.1) instead of new samples of the final triplets (unbiased, about half again the samples)",
        kind: OptionKind::Flag,
        values: &[],
    },
    OptionSpec {
        name: "dark-floor",
        value_name: "F",
        default: "1e-6",
        help: "Pixels darker than F times the frame's bright level (the 90th percentile of a 32-pixel pilot at eps 0.2) stop at an absolute error of eps * F * that level instead of eps times their own value; 0: the paper's purely relative criterion",
        kind: OptionKind::Value,
        values: &[],
    },
];

/// The registry entry.
pub const METHOD: Method = Method {
    name: "manylight",
    about: "Many-light SSS: VPL x triangle x pixel clusters refined until the Student-t interval is below eps (Nabata & Iwasaki 2021)",
    options: &OPTIONS,
    build: |o| Ok(Box::new(ManyLight::from_options(o)?)),
    sweep: Sweep {
        option: "eps",
        label: "eps",
        // Loosest (cheapest) first.
        values: |quick| {
            // Not the paper's 0.02 in the default run: on the slab (a wall's shadow 2
            // diffusion lengths deep) ε = 0.02 takes 4 minutes of the 20; finer ε goes with
            // `cargo xtask compare --manylight` and `sss render --eps`.
            if quick {
                vec![0.1, 0.05]
            } else {
                vec![0.2, 0.1, 0.05]
            }
        },
    },
    converges_to: Converges::Model,
};

/// The `manylight` integrator and its settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ManyLight {
    /// Relative error threshold ε (≥ 0; 0 refines until a cap).
    pub eps: f64,
    /// Confidence level α in (0, 1).
    pub alpha: f64,
    /// Cluster selection.
    pub selection: Selection,
    /// VPLs per sun, quad or environment light.
    pub vpls: u32,
    /// Cap on the triplets per pixel and object.
    pub max_triplets: usize,
    /// Cap on the triangle splits per pixel and object.
    pub max_splits: usize,
    /// Light paths for one-bounce VPLs ([`crate::vpls::bounce_vpls`]; 0: direct light only).
    pub bounce_paths: u32,
    /// Seed of the VPL sampling (`None`: the render's seed). Fixing it keeps one VPL set, and
    /// so one integral, across renders of different seeds, as the paper's comparisons do.
    pub vpl_seed: Option<u64>,
    /// Mixed into every pixel estimate's seed (0 by default): another stream gives an
    /// independent estimate over the same G-buffer and VPLs (the frame's seed also places the
    /// camera samples, so changing it changes the pixel values being estimated).
    pub stream: u64,
    /// Re-sample the final triplets before reporting (unbiased; `false`: the paper's
    /// estimator, biased low by the sequential stop at loose ε; see `sss_manylight::estimator`).
    pub fresh_final: bool,
    /// The dark-pixel floor F (≥ 0): a pixel also stops once ΔI < ε · F · the frame's bright
    /// level (see [`DEFAULT_DARK_FLOOR`]); 0 keeps the paper's purely relative criterion.
    pub dark_floor: f64,
}

/// The default dark-pixel floor: 10⁻⁶, about 20 stops below the frame's bright level, darker
/// than any display or tone curve shows. Pixels that dark (in a point-lit head's own shadow,
/// 10⁻⁸ of the median) otherwise refine to the triplet cap for a relative error nobody sees:
/// the triplets' bounds ignore visibility, so the refinement splits the shadowed clusters next
/// to the pixel, whose samples are all 0, long before the faint far ones that carry its value.
pub const DEFAULT_DARK_FLOOR: f64 = 1e-6;

impl Default for ManyLight {
    fn default() -> Self {
        ManyLight {
            eps: 0.02,
            alpha: 0.95,
            selection: Selection::BssrdfAware,
            vpls: 1024,
            max_triplets: 200_000,
            max_splits: 200_000,
            bounce_paths: 0,
            vpl_seed: None,
            stream: 0,
            fresh_final: true,
            dark_floor: DEFAULT_DARK_FLOOR,
        }
    }
}

/// The values of `--selection`, as the help and the error list them: `bssrdf` (also spelt
/// `bssrdf-aware`) and `max-extent`.
pub const SELECTIONS: [&str; 2] = ["bssrdf", "max-extent"];

/// Parses `--selection` (one of [`SELECTIONS`]; the error lists them).
pub fn parse_selection(s: &str) -> Result<Selection, Error> {
    match s.trim() {
        "bssrdf" | "bssrdf-aware" => Ok(Selection::BssrdfAware),
        "max-extent" => Ok(Selection::MaxExtent),
        other => Err(Error::Input(format!(
            "--selection: unknown value `{other}` (known: {})",
            SELECTIONS.join(", ")
        ))),
    }
}

impl ManyLight {
    /// The settings `options` describe (errors name the flag).
    pub fn from_options(o: &MethodOptions) -> Result<Self, Error> {
        let eps = eps_option(o, &OPTIONS)?;
        let alpha = alpha_option(o, &OPTIONS)?;
        let selection = parse_selection(&o.get::<String>(&OPTIONS, "selection")?)?;
        let vpls: u32 = o.get(&OPTIONS, "vpls")?;
        if vpls == 0 {
            return Err(Error::Input("--vpls must be at least 1".into()));
        }
        let max_triplets: usize = o.get(&OPTIONS, "max-triplets")?;
        if !(1..=(1 << 30)).contains(&max_triplets) {
            return Err(Error::Input(format!(
                "--max-triplets must be in 1..=2^30, got {max_triplets}"
            )));
        }
        let bounce_paths: u32 = o.get(&OPTIONS, "bounce-vpls")?;
        let max_splits: usize = o.get(&OPTIONS, "max-splits")?;
        if !(1..=(1 << 30)).contains(&max_splits) {
            return Err(Error::Input(format!(
                "--max-splits must be in 1..=2^30, got {max_splits}"
            )));
        }
        let dark_floor: f64 = o.get(&OPTIONS, "dark-floor")?;
        if !(dark_floor.is_finite() && (0.0..1.0).contains(&dark_floor)) {
            return Err(Error::Input(format!(
                "--dark-floor must be in [0, 1), got {dark_floor}"
            )));
        }
        Ok(ManyLight {
            eps,
            alpha,
            selection,
            vpls,
            max_triplets,
            max_splits,
            bounce_paths,
            vpl_seed: None,
            stream: 0,
            fresh_final: !o.flag("paper-estimate"),
            dark_floor,
        })
    }
}

/// Pixels of the pilot that measures the frame's bright level for the dark-pixel floor.
pub const PILOT_PIXELS: usize = 32;
/// ε of the pilot's estimates.
pub const PILOT_EPS: f64 = 0.2;
/// Triplet cap of the pilot's estimates.
pub const PILOT_MAX_TRIPLETS: usize = 4096;
/// Seed salt of the pilot: its pixels and its estimator stream.
const PILOT_SEED: u64 = 0x5049_4c4f_5421;
/// The quantile of the pilot's pixel luminances taken as the frame's bright level.
pub const BRIGHT_QUANTILE: f64 = 0.9;

/// The bright level of a frame from its pilot pixels' luminances: their
/// [`BRIGHT_QUANTILE`] quantile (the nearest rank; 0 without pilot pixels), robust to a few
/// outliers and still set by the lit part where most of the object is in shadow.
pub fn bright_level(mut lum: Vec<f64>) -> f64 {
    lum.retain(|v| v.is_finite());
    if lum.is_empty() {
        return 0.0;
    }
    lum.sort_by(f64::total_cmp);
    let k = ((BRIGHT_QUANTILE * lum.len() as f64).ceil() as usize).clamp(1, lum.len());
    lum[k - 1].max(0.0)
}

/// One pixel's output.
#[derive(Default)]
struct PixelOut {
    values: Vec<Rgb>,
    triplets: f64,
    std_error: Rgb,
    summary: Summary,
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
    ) -> Result<(Vec<PixelOut>, Settings, usize, f64), Error> {
        check_radial(frame, METHOD.name)?;
        let scene = frame.scene;
        let objects = frame.timed("irradiance_tree", || object_data(frame, METHOD.name))?;
        let vpl_seed = self.vpl_seed.unwrap_or(frame.seed);
        let lights = frame.timed("light_tree", || {
            light_tree_seeded(frame, self.vpls, self.bounce_paths, vpl_seed)
        })?;
        let (_, half_diag) = scene_box(frame);
        let g_max = Settings::g_max_for_scene(half_diag);
        let mut settings = Settings::new(g_max);
        settings.epsilon = self.eps;
        settings.selection = self.selection;
        settings.max_triplets = self.max_triplets;
        settings.max_splits = self.max_splits;
        settings.min_triplets = MIN_TRIPLETS.min(self.max_triplets);
        settings.fresh_final = self.fresh_final;
        let t = StudentT::new(self.alpha).map_err(|e| Error::Input(format!("--alpha: {e}")))?;
        let estimators = |settings: Settings| -> Result<Vec<Option<Estimator<'_>>>, Error> {
            Ok(match &lights {
                None => objects.iter().map(|_| None).collect(),
                Some(lt) => objects
                    .iter()
                    .enumerate()
                    .map(|(o, d)| {
                        d.as_ref()
                            .map(|d| {
                                Estimator::new(lt, &d.tree, &d.profile, &d.ft, &t, settings)
                                    .map_err(|e| model_error(scene, o as u32, METHOD.name, e))
                            })
                            .transpose()
                    })
                    .collect::<Result<_, _>>()?,
            })
        };
        let visibility = shadow_test(frame);
        let gb = &frame.gbuffer;
        let list = pixel_list(frame, only, METHOD.name)?;
        let spp = gb.samples_per_pixel as f64;
        let max_splits = settings.max_splits;
        let shade = |estimators: &[Option<Estimator<'_>>],
                     stream: u64,
                     refs: &mut Refinements,
                     i: usize|
         -> Result<PixelOut, Error> {
            let samples = gb.pixel(i);
            let mut out = PixelOut {
                values: vec![[0.0; 3]; samples.len()],
                ..PixelOut::default()
            };
            let mut var = [0.0; 3];
            let mut done: Vec<u32> = Vec::new();
            for g in samples {
                let o = g.object;
                if done.contains(&o) {
                    continue;
                }
                done.push(o);
                let (Some(sh), Some(Some(est))) = (frame.shading_of(o), estimators.get(o as usize))
                else {
                    continue;
                };
                let mut points = Vec::new();
                let mut members = Vec::new();
                for (k, s) in samples.iter().enumerate() {
                    if s.object == o {
                        let e = sh.exit_weight(s.n, s.wo);
                        points.push(ShadingPoint {
                            position: s.p,
                            normal: s.n,
                            weight: e / spp,
                        });
                        members.push((k, e));
                    }
                }
                let e_sum: f64 = members.iter().map(|m| m.1).sum();
                if !(e_sum > 0.0) {
                    continue;
                }
                let tree =
                    ShadingTree::new(points).map_err(|e| model_error(scene, o, METHOD.name, e))?;
                let seed = estimate_seed(frame.seed, o, stream, i);
                let px = est.estimate_with(&tree, &visibility, seed, refs);
                out.summary.add(&px);
                out.triplets += px.triplets as f64;
                for (k, e) in members {
                    for c in 0..3 {
                        out.values[k][c] = px.rgb[c].max(0.0) * spp * e / e_sum;
                    }
                }
                // The standard error of the luminance, ΔI / t_α(ν), given to each
                // channel in proportion to its value.
                if px.std_error > 0.0 && px.value > 0.0 {
                    let se = px.std_error;
                    for c in 0..3 {
                        let s = px.rgb[c].max(0.0) * se / px.value;
                        var[c] += s * s;
                    }
                }
            }
            out.std_error = var.map(f64::sqrt);
            Ok(out)
        };
        // The dark-pixel floor: ε · `dark_floor` · the frame's bright level, measured by a
        // pilot on a seeded subset of the translucent pixels (the same for a full render and
        // for any subset of it, on every thread count).
        if self.dark_floor > 0.0 && settings.epsilon > 0.0 {
            let level = frame.timed("floor_pilot", || -> Result<f64, Error> {
                let mut pilot = settings;
                pilot.epsilon = PILOT_EPS;
                pilot.max_triplets = PILOT_MAX_TRIPLETS.min(settings.max_triplets);
                pilot.min_triplets = pilot.min_triplets.min(pilot.max_triplets);
                let est = estimators(pilot)?;
                let chosen = crate::metrics::subset_pixels(
                    &frame.translucent_pixels(),
                    PILOT_PIXELS,
                    frame.seed ^ PILOT_SEED,
                );
                let lum: Vec<f64> = chosen
                    .par_iter()
                    .map_init(
                        || Refinements::new(max_splits),
                        |refs, &i| {
                            shade(&est, PILOT_SEED, refs, i).map(|o| {
                                let px = pixel_result(
                                    frame,
                                    i,
                                    &o.values,
                                    o.std_error,
                                    o.triplets,
                                    o.summary,
                                );
                                sss_manylight::luminance(px.subsurface)
                            })
                        },
                    )
                    .collect::<Result<_, _>>()?;
                Ok(bright_level(lum))
            })?;
            settings.floor = settings.epsilon * self.dark_floor * level;
        }
        let estimators = estimators(settings)?;
        let pixels: Vec<PixelOut> = frame.timed("shading", || {
            list.par_iter()
                .with_min_len(8)
                .map_init(
                    || Refinements::new(max_splits),
                    |refs, &i| {
                        progress.advance(gb.pixel(i).len() as u64);
                        shade(&estimators, self.stream, refs, i)
                    },
                )
                .collect::<Result<Vec<PixelOut>, Error>>()
        })?;
        let n_vpls = lights.as_ref().map_or(0, |l| l.vpls().len());
        Ok((pixels, settings, n_vpls, g_max))
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
            "eps {}, alpha {}, {} selection, {} VPLs per area/environment light, {}",
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
