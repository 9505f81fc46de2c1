//! The VPL methods: many-light subsurface scattering over virtual point lights. `manylight`
//! (Nabata & Iwasaki 2021: triplets, Student-t error control), `sparse-manylight` (its
//! estimates on the pixels the screen-space bandwidth of Milaenen et al. 2019 asks for, the
//! others reconstructed with an interval), and the two baselines of Nabata & Iwasaki, which
//! first draw a fixed set of irradiance points per shading point ([`gather_points`]: `mdlc`,
//! Walter et al.'s multidimensional lightcuts, and `eelc`, the paper's error-estimated
//! lightcuts). This module holds what they share: the light tree of the frame's VPLs, the
//! per-object data (triangle BVH, radial profile, entry transmittance), the shadow test, the
//! seeds of pixel estimates and streams, the assembly of a subset pixel's result, and the
//! many-light estimator of any set of pixels ([`ManyLight::with_estimator`], with its settings
//! and the dark-pixel floor's pilot).

pub mod gather_points;
pub mod manylight;
pub mod sparse_manylight;
pub mod vpls;

use crate::Error;
use crate::frame::Frame;
use crate::integrators::check_radial;
use crate::integrators::options::{alpha_option, eps_option};
use crate::integrators::{MethodOptions, OptionSpec};
use crate::progress::Progress;
use glam::DVec3;
use rayon::prelude::*;
use sss_bssrdf::Rgb;
use sss_bssrdf::fresnel::ft_dielectric;
use sss_manylight::{
    Estimator, LightTree, RadialProfile, Refinements, Selection, Settings, ShadingPoint,
    ShadingTree, StudentT, Summary, Transmittance, TriangleClusterTree, pixel_seed,
};
use sss_scene::Scene;
use vpls::{bounce_vpls, scene_vpls};

/// The relative rise of R_d(r) accepted when the profile is checked (against the running
/// minimum, see `RadialProfile::with_tolerance`); the bounds are inflated by it. The tabulated
/// photon beam diffusion profile (`pbd`) rises by 1.05 % over its running minimum within
/// r < 1.2e-4 mm (picnic's marble, measured: a table artefact at tiny r), the closed-form
/// dipoles not at all; 5 % leaves room for other presets while keeping the bounds within 5 %.
pub const PROFILE_TOLERANCE: f64 = 5e-2;

/// The estimator's stopping tests (ΔI < εI, and "every sample 0 means the pixel is 0") apply
/// from this many triplets on. The crate's default of 8 declared 320 of slab's 5712 pixel
/// estimates 0 in the wall's shadow, where light diffused from the lit part (marble, diffusion
/// length 1.3 units) makes them 6 % of the image's mean: 16 samples all in shadow are likely
/// there. 64 triplets (128 samples over a cluster cut ≥ 64 ways) make that unlikely.
pub const MIN_TRIPLETS: usize = 64;

/// What the estimator needs of one translucent object.
pub(crate) struct ObjectData {
    pub(crate) tree: TriangleClusterTree,
    pub(crate) profile: RadialProfile,
    pub(crate) ft: Transmittance,
}

/// The estimator's error as this crate's input error, naming the object, material and method.
pub(crate) fn model_error(scene: &Scene, o: u32, method: &str, e: sss_manylight::Error) -> Error {
    let obj = &scene.objects[o as usize];
    Error::Input(format!(
        "object `{}` (material `{}`): {method}: {e}",
        obj.name, scene.materials[obj.material].name
    ))
}

/// The geometry's box centre and half-diagonal over every object.
pub(crate) fn scene_box(frame: &Frame<'_>) -> (DVec3, f64) {
    let mut lo = DVec3::splat(f64::INFINITY);
    let mut hi = DVec3::splat(f64::NEG_INFINITY);
    for o in 0..frame.scene.objects.len() as u32 {
        if let Some((a, b)) = frame.geom.bounds(o) {
            lo = lo.min(a);
            hi = hi.max(b);
        }
    }
    if lo.is_finite() && hi.is_finite() {
        (0.5 * (lo + hi), 0.5 * (hi - lo).length())
    } else {
        (DVec3::ZERO, 0.5 * frame.geom.extent())
    }
}

/// Builds the light tree of the frame's VPLs, drawn from `seed` (the frame's seed unless a
/// run fixes another): `budget` per area or environment light, plus the one-bounce VPLs of
/// `bounce_paths` light paths; `None` without light.
pub(crate) fn light_tree_seeded(
    frame: &Frame<'_>,
    budget: u32,
    bounce_paths: u32,
    seed: u64,
) -> Result<Option<LightTree>, Error> {
    let (center, half_diag) = scene_box(frame);
    let mut vpls = scene_vpls(frame.scene, budget, seed, center, frame.geom.extent())?;
    vpls.extend(bounce_vpls(
        frame.scene,
        &frame.geom,
        bounce_paths,
        seed,
        center,
        half_diag,
    ));
    if vpls.is_empty() {
        return Ok(None);
    }
    LightTree::new(vpls)
        .map(Some)
        .map_err(|e| Error::Input(format!("manylight VPLs: {e}")))
}

/// The per-object data of every visible translucent object (indexed by object).
pub(crate) fn object_data(
    frame: &Frame<'_>,
    method: &str,
) -> Result<Vec<Option<ObjectData>>, Error> {
    let scene = frame.scene;
    let mut out: Vec<Option<ObjectData>> = (0..scene.objects.len()).map(|_| None).collect();
    for &o in &frame.visible {
        let Some(sh) = frame.shading_of(o) else {
            continue;
        };
        sh.radial(method)?;
        sh.scalar_weights(method)?;
        if sh.collision.is_some() {
            return Err(Error::Unsupported(format!(
                "material `{}`: method {method} does not take `unscattered = true` (its \
                 estimator lights its points without the ray through the object that splits \
                 off the light going straight through); use exact, the trees, pathtrace or \
                 separable",
                sh.name
            )));
        }
        if sh.texture.is_some() {
            return Err(Error::Input(format!(
                "material `{}`: method {method} does not support pre-scatter textures (the \
                 estimator's irradiance has no texture factor); use exact or pathtrace, or \
                 remove the texture",
                sh.name
            )));
        }
        let Some(t) = scene.translucent(o as usize) else {
            continue;
        };
        let mesh = &scene.objects[o as usize].mesh;
        // The mesh's shading normals, as `exact` and `pathtrace` use them (see
        // `sss_manylight::irradiance_cluster`).
        let tree =
            TriangleClusterTree::with_normals(&mesh.positions, &mesh.normals, &mesh.triangles)
                .map_err(|e| model_error(scene, o, method, e))?;
        // R_d in scene units as `rd_scene` computes it: R_d(r/u)/u², u = units per mm. The
        // profile must own its model, so the material's model is built again here.
        let model: std::sync::Arc<dyn sss_bssrdf::Bssrdf> =
            crate::shading::material_model(t).into();
        let u = sh.units_per_mm;
        let [inv_u2, _, _] = crate::shading::scene_unit_factors(u);
        let diag = frame
            .geom
            .bounds(o)
            .map_or(frame.geom.extent(), |(a, b)| (b - a).length());
        let rd = move |r: f64| {
            let v = model.rd_rgb(r / u);
            [v[0] * inv_u2, v[1] * inv_u2, v[2] * inv_u2]
        };
        let r_scale = diag.max(1e-30);
        // Strictly checked (exact bounds) when the profile is monotone, as the closed-form
        // dipoles are; with the documented tolerance otherwise (tabulated PBD).
        let profile = match RadialProfile::new(rd.clone(), r_scale) {
            Ok(p) => p,
            Err(_) => RadialProfile::with_tolerance(rd, r_scale, PROFILE_TOLERANCE)
                .map_err(|e| model_error(scene, o, method, e))?,
        };
        let eta = sh.eta;
        let ft = Transmittance::new(move |c| ft_dielectric(c, eta))
            .map_err(|e| model_error(scene, o, method, e))?;
        out[o as usize] = Some(ObjectData { tree, profile, ft });
    }
    Ok(out)
}

/// What a VPL method's `shade_pixels` ([`ManyLight::shade_pixels`](manylight::ManyLight::shade_pixels),
/// [`Mdlc::shade_pixels`](gather_points::mdlc::Mdlc::shade_pixels),
/// [`Eelc::shade_pixels`](gather_points::eelc::Eelc::shade_pixels)) gives one pixel.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PixelResult {
    /// The pixel's subsurface value, assembled as the renderer assembles it.
    pub subsurface: Rgb,
    /// The standard error of each channel (from ΔI of each object's estimate; EELC's against
    /// its own point set's value; 0 for MDLC, which has no interval).
    pub std_error: Rgb,
    /// Triplets over the pixel's objects; for the baselines the cluster pairs (MDLC's cut
    /// size, EELC's strata).
    pub triplets: f64,
    /// The counters of the pixel's estimates (for the baselines, pairs in place of triplets
    /// and the pair cap in place of the triplet cap).
    pub summary: Summary,
}

/// A subset pixel's result from its G-buffer samples' values, assembled exactly as the
/// renderer assembles a full frame.
pub(crate) fn pixel_result(
    frame: &Frame<'_>,
    i: usize,
    values: &[Rgb],
    std_error: Rgb,
    triplets: f64,
    summary: Summary,
) -> PixelResult {
    let gb = &frame.gbuffer;
    let vals: Vec<Option<Rgb>> = gb
        .pixel(i)
        .iter()
        .zip(values)
        .map(|(g, v)| frame.shading_of(g.object).map(|_| *v))
        .collect();
    PixelResult {
        subsurface: crate::frame::assembled_subsurface(&vals, gb.samples_per_pixel),
        std_error,
        triplets,
        summary,
    }
}

/// The visibility of the many-light methods: a shadow ray from
/// the irradiance point (on a flat triangle, so the ray leaves it on the lit side; the origin
/// is moved off the surface by starting the ray at 16 × the geometry's epsilon) to the VPL,
/// stopping as far short of it.
pub(crate) fn shadow_test<'a>(frame: &'a Frame<'_>) -> impl Fn(DVec3, DVec3) -> bool + Sync + 'a {
    let geom = &frame.geom;
    let eps_ray = 16.0 * geom.epsilon();
    move |x: DVec3, y: DVec3| {
        let d = y - x;
        let dist = d.length();
        if !(dist > 2.0 * eps_ray) {
            return false;
        }
        !geom.occluded(x, d / dist, eps_ray, dist - eps_ray)
    }
}

/// The pixels to shade: `only`, in its order, or every pixel of the frame; a pixel past the
/// image is an input error naming `method`.
pub(crate) fn pixel_list(
    frame: &Frame<'_>,
    only: Option<&[usize]>,
    method: &str,
) -> Result<Vec<usize>, Error> {
    let n = frame.gbuffer.pixels();
    if let Some(&bad) = only.and_then(|p| p.iter().find(|&&i| i >= n)) {
        return Err(Error::Input(format!(
            "{method}: pixel {bad} is past the image's {n} pixels"
        )));
    }
    Ok(only.map_or_else(|| (0..n).collect(), <[usize]>::to_vec))
}

/// `seed` with the random stream `stream` mixed in (`seed` itself for stream 0, so the default
/// stream keeps a render's bits).
pub(crate) fn stream_seed(seed: u64, stream: u64) -> u64 {
    if stream == 0 {
        seed
    } else {
        seed ^ sss_util::splitmix64(stream ^ 0x5354_5245_414d)
    }
}

/// The seed of pixel `i`'s estimate on object `o` under the frame's seed and the estimator
/// stream `stream`: a pixel's estimate depends on its own index,
/// never on which other pixels are shaded or on the thread.
pub(crate) fn estimate_seed(frame_seed: u64, o: u32, stream: u64, i: usize) -> u64 {
    let object_seed = stream_seed(frame_seed ^ sss_util::splitmix64(u64::from(o)), stream);
    pixel_seed(sss_util::splitmix64(object_seed), i as u64)
}

/// The settings of the many-light estimator of Nabata & Iwasaki 2021: the `manylight` method
/// itself (its registry entry and [`Integrator`](crate::integrators::Integrator) are in
/// [`manylight`]), and the estimator of the methods built on it.
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
    /// Light paths for one-bounce VPLs ([`vpls::bounce_vpls`]; 0: direct light only).
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
    /// level (`--dark-floor`, see [`crate::integrators::options::DARK_FLOOR`]); 0 keeps the paper's purely relative criterion.
    pub dark_floor: f64,
}

pub use crate::integrators::options::SELECTIONS;

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

/// The ε values `cargo xtask compare` sweeps for the many-light estimator's methods, loosest
/// (cheapest) first. Not the paper's 0.02 in the default run: on the slab (a wall's shadow 2
/// diffusion lengths deep) ε = 0.02 takes 4 minutes of the 20; finer ε goes with
/// `cargo xtask compare --manylight` and `sss render --rel-error`.
pub fn eps_sweep(quick: bool) -> Vec<f64> {
    if quick {
        vec![0.1, 0.05]
    } else {
        vec![0.2, 0.1, 0.05]
    }
}

/// The many-light estimator's settings every method built on it reads from its options (`eps`,
/// `alpha`, `selection`, `vpls`, `max-triplets`, `dark-floor`; errors name the flag), the
/// others at their defaults.
pub(crate) fn estimator_options(
    o: &MethodOptions,
    options: &[OptionSpec],
) -> Result<ManyLight, Error> {
    let vpls: u32 = o.get(options, "vpls")?;
    if vpls == 0 {
        return Err(Error::Input("--vpls must be at least 1".into()));
    }
    let max_triplets: usize = o.get(options, "max-triplets")?;
    if !(1..=(1 << 30)).contains(&max_triplets) {
        return Err(Error::Input(format!(
            "--max-triplets must be in 1..=2^30, got {max_triplets}"
        )));
    }
    let dark_floor: f64 = o.get(options, "dark-floor")?;
    if !(dark_floor.is_finite() && (0.0..1.0).contains(&dark_floor)) {
        return Err(Error::Input(format!(
            "--dark-floor must be in [0, 1), got {dark_floor}"
        )));
    }
    Ok(ManyLight {
        eps: eps_option(o, options, "rel-error")?,
        alpha: alpha_option(o, options)?,
        selection: parse_selection(&o.get::<String>(options, "selection")?)?,
        vpls,
        max_triplets,
        dark_floor,
        ..ManyLight::default()
    })
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

/// One pixel's many-light estimate.
#[derive(Clone, Debug, Default)]
pub struct PixelEstimate {
    /// The value of each of the pixel's G-buffer samples (the estimate of each object split
    /// over its samples by exit weight; 0 off translucent objects).
    pub values: Vec<Rgb>,
    /// The triplets of the pixel's estimates, summed over its objects.
    pub triplets: f64,
    /// The standard error of each channel of the pixel's assembled value (ΔI / t_α(ν) of each
    /// object's estimate, given to the channels in proportion to their values).
    pub std_error: Rgb,
    /// The counters of the pixel's estimates.
    pub summary: Summary,
}

/// The estimates of a list of pixels, in its order.
type ShadeFn<'e> =
    dyn Fn(&[usize], f64, &dyn Progress) -> Result<Vec<PixelEstimate>, Error> + Sync + 'e;

/// Many-light estimates of any pixels of one frame, with what every estimate shares built once
/// (the light tree, each object's triangle tree, profile and transmittance, the dark-pixel
/// floor): what [`ManyLight::with_estimator`] hands its closure. A pixel's estimate depends on
/// its own index and the settings only, never on the other pixels of a call or on the thread
/// count, so estimating pixels in several calls gives the values of one call.
pub struct PixelEstimator<'e> {
    shade: &'e ShadeFn<'e>,
    /// The estimator's settings, the dark-pixel floor's absolute error included
    /// ([`Settings::floor`]).
    pub settings: Settings,
    /// The VPLs of the light tree.
    pub vpls: usize,
    /// The G clamp.
    pub g_max: f64,
}

impl PixelEstimator<'_> {
    /// The estimates of `pixels`, in that order (in parallel; `progress` advances by each
    /// pixel's G-buffer samples).
    pub fn estimate(
        &self,
        pixels: &[usize],
        progress: &dyn Progress,
    ) -> Result<Vec<PixelEstimate>, Error> {
        (self.shade)(pixels, self.settings.epsilon, progress)
    }

    /// The estimates of `pixels` at the relative error threshold `eps` instead of the
    /// settings' (the dark-pixel floor scaled with it), otherwise as [`Self::estimate`]: the
    /// same seeds, so at the settings' ε the same values.
    pub fn estimate_at(
        &self,
        pixels: &[usize],
        eps: f64,
        progress: &dyn Progress,
    ) -> Result<Vec<PixelEstimate>, Error> {
        (self.shade)(pixels, eps, progress)
    }
}

impl ManyLight {
    /// Builds what the estimates of `frame` share (light tree, triangle trees, profiles, the
    /// dark-pixel floor's pilot) and calls `f` with an estimator of any pixels: for `manylight`
    /// itself and for methods that choose which pixels to estimate as they go. Errors name
    /// `method`.
    pub fn with_estimator<R>(
        &self,
        frame: &Frame<'_>,
        method: &str,
        f: impl FnOnce(&PixelEstimator<'_>) -> Result<R, Error>,
    ) -> Result<R, Error> {
        check_radial(frame, method)?;
        let scene = frame.scene;
        let objects = frame.timed("irradiance_tree", || object_data(frame, method))?;
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
                                    .map_err(|e| model_error(scene, o as u32, method, e))
                            })
                            .transpose()
                    })
                    .collect::<Result<_, _>>()?,
            })
        };
        let visibility = shadow_test(frame);
        let gb = &frame.gbuffer;
        let spp = gb.samples_per_pixel as f64;
        let max_splits = settings.max_splits;
        let shade = |estimators: &[Option<Estimator<'_>>],
                     stream: u64,
                     refs: &mut Refinements,
                     i: usize|
         -> Result<PixelEstimate, Error> {
            let samples = gb.pixel(i);
            let mut out = PixelEstimate {
                values: vec![[0.0; 3]; samples.len()],
                ..PixelEstimate::default()
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
                    ShadingTree::new(points).map_err(|e| model_error(scene, o, method, e))?;
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
        let at_settings = estimators(settings)?;
        let run = |list: &[usize], eps: f64, progress: &dyn Progress| {
            // Another ε: the same trees, estimators with that threshold and the floor scaled
            // with it (ε · F · the bright level).
            let other;
            let est = if eps == settings.epsilon {
                &at_settings
            } else {
                let mut s = settings;
                s.epsilon = eps;
                if settings.epsilon > 0.0 {
                    s.floor = settings.floor * eps / settings.epsilon;
                }
                other = estimators(s)?;
                &other
            };
            list.par_iter()
                .with_min_len(8)
                .map_init(
                    || Refinements::new(max_splits),
                    |refs, &i| {
                        progress.advance(gb.pixel(i).len() as u64);
                        shade(est, self.stream, refs, i)
                    },
                )
                .collect::<Result<Vec<PixelEstimate>, Error>>()
        };
        f(&PixelEstimator {
            shade: &run,
            settings,
            vpls: lights.as_ref().map_or(0, |l| l.vpls().len()),
            g_max,
        })
    }
}
