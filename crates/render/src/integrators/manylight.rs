//! `manylight`: many-light subsurface scattering with adaptive irradiance sampling and
//! Student-t error control (Nabata & Iwasaki, IEEE TVCG 2021), the estimator of
//! [`sss_manylight`] wired to the frame.
//!
//! Per visible translucent object: the VPLs of the scene's lights ([`crate::vpls`], direct light
//! only) in one [`LightTree`], a triangle BVH over the object's mesh ([`IrradianceTree`]), the
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

use super::single_tree::{check_radial, eps_option};
use super::{
    Integrator, Layer, Method, MethodOptions, OptionKind, OptionSpec, Shaded, Stat, Sweep,
};
use crate::Error;
use crate::frame::Frame;
use crate::progress::Progress;
use crate::vpls::{bounce_vpls, scene_vpls, vpl_count};
use glam::DVec3;
use rayon::prelude::*;
use sss_bssrdf::fresnel::ft_dielectric;
use sss_bssrdf::{Rgb, make_model};
use sss_manylight::irradiance_cluster::IcNode;
use sss_manylight::{
    Estimator, IrradianceTree, LightNode, LightTree, RadialProfile, Refinements, Selection,
    Settings, ShadingPoint, ShadingTree, StudentT, Summary, Transmittance, Triangle, Vpl,
    pixel_seed,
};
use sss_scene::Scene;

/// The options of `manylight`.
pub const OPTIONS: [OptionSpec; 9] = [
    OptionSpec {
        name: "eps",
        value_name: "E",
        default: "0.02",
        help: "Relative error threshold: refine each pixel until its Student-t interval is below E times its value (the paper uses 0.02)",
        kind: OptionKind::Value,
        values: &[],
    },
    OptionSpec {
        name: "alpha",
        value_name: "A",
        default: "0.95",
        help: "Confidence level of the interval, in (0, 1)",
        kind: OptionKind::Value,
        values: &[],
    },
    OptionSpec {
        name: "selection",
        value_name: "SELECTION",
        default: "bssrdf",
        help: "Cluster to refine: BSSRDF-aware (Nabata & Iwasaki Eq. 10-13) or the largest box (Max-Extent)",
        kind: OptionKind::Value,
        values: &SELECTIONS,
    },
    OptionSpec {
        name: "vpls",
        value_name: "N",
        default: "1024",
        help: "VPLs per quad or environment light (a point or directional light is one VPL)",
        kind: OptionKind::Value,
        values: &[],
    },
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
    /// VPLs per quad or environment light.
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

/// Reads and checks the confidence level α (in (0, 1)); shared with `eelc`.
pub(crate) fn alpha_option(o: &MethodOptions, options: &[OptionSpec]) -> Result<f64, Error> {
    let alpha: f64 = o.get(options, "alpha")?;
    if !(alpha > 0.0 && alpha < 1.0) {
        return Err(Error::Input(format!(
            "--alpha must be in (0, 1), got {alpha}"
        )));
    }
    Ok(alpha)
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

/// What the estimator needs of one translucent object (shared with the baselines).
pub(crate) struct ObjectData {
    pub(crate) tree: IrradianceTree,
    pub(crate) profile: RadialProfile,
    pub(crate) ft: Transmittance,
}

/// One pixel's output.
#[derive(Default)]
struct PixelOut {
    values: Vec<Rgb>,
    triplets: f64,
    std_error: Rgb,
    summary: Summary,
}

/// The estimator's error as this crate's input error, naming the object, material and method.
pub(crate) fn model_error(scene: &Scene, o: u32, method: &str, e: sss_manylight::Error) -> Error {
    let obj = &scene.objects[o as usize];
    Error::Input(format!(
        "object `{}` (material `{}`): {method}: {e}",
        obj.name, scene.materials[obj.material].name
    ))
}

/// The geometry's box centre and half-diagonal over every object (shared with the baselines).
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
/// `bounce_paths` light paths; `None` without light. Shared with the baselines.
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

/// The per-object data of every visible translucent object (indexed by object; shared with
/// the baselines).
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
        let tree = IrradianceTree::with_normals(&mesh.positions, &mesh.normals, &mesh.triangles)
            .map_err(|e| model_error(scene, o, method, e))?;
        // R_d in scene units as `rd_scene` computes it: R_d(r/u)/u², u = units per mm. The
        // profile must own its model, so the material's model is built again here.
        let model: std::sync::Arc<dyn sss_bssrdf::Bssrdf> = make_model(t.model, &t.medium).into();
        let u = sh.units_per_mm;
        let inv_u2 = 1.0 / (u * u);
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

/// What [`ManyLight::shade_pixels`] (and the baselines' `shade_pixels`,
/// [`Mdlc::shade_pixels`](super::mdlc::Mdlc::shade_pixels) and
/// [`Eelc::shade_pixels`](super::eelc::Eelc::shade_pixels)) gives one pixel.
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
/// renderer assembles a full frame (shared with the baselines).
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
        subsurface: crate::render::assembled_subsurface(&vals, gb.samples_per_pixel),
        std_error,
        triplets,
        summary,
    }
}

/// The visibility of the many-light methods (shared with the baselines): a shadow ray from
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
/// image is an input error naming `method` (shared with the baselines).
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
/// stream keeps a render's bits); shared with the baselines.
pub(crate) fn stream_seed(seed: u64, stream: u64) -> u64 {
    if stream == 0 {
        seed
    } else {
        seed ^ sss_util::splitmix64(stream ^ 0x5354_5245_414d)
    }
}

/// The seed of pixel `i`'s estimate on object `o` under the frame's seed and the estimator
/// stream `stream` (shared with the baselines): a pixel's estimate depends on its own index,
/// never on which other pixels are shaded or on the thread.
pub(crate) fn estimate_seed(frame_seed: u64, o: u32, stream: u64, i: usize) -> u64 {
    let object_seed = stream_seed(frame_seed ^ sss_util::splitmix64(u64::from(o)), stream);
    pixel_seed(sss_util::splitmix64(object_seed), i as u64)
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
                        let out = shade(&estimators, self.stream, refs, i);
                        progress.advance(gb.pixel(i).len() as u64);
                        out
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
