//! What the two many-light baselines, [`mdlc`] (Multidimensional Lightcuts) and
//! [`eelc`] (the error estimation for Lightcuts), share on the render side: their point
//! options, the per-frame data (the same VPLs, light tree, profile, F_t and G clamp as
//! [`super::manylight`]), and the per-pixel pipeline that draws the fixed irradiance points,
//! builds the gather tree and splits the pixel estimate over the G-buffer samples.
//!
//! # The pixel value, as `manylight`
//!
//! Per pixel and visible translucent object, each of the pixel's G-buffer samples on the
//! object is a shading point x_o of weight w = `exit_weight(n, ω_o)` / pixel_samples (the
//! renderer averages a pixel's samples), exactly as in `manylight`. For each, N irradiance
//! points x_k are drawn (`--irradiance-points`, the paper's 4096 by default):
//!
//! * **BSSRDF importance sampling** (default): the path tracer's probe rays
//!   ([`crate::probe::Sampler::sample_point`]: an axis and a channel, a radius from that
//!   channel's profile, a chord hit on the same object; multiple importance sampling over the
//!   nine techniques), with the area weight A_k = 1/(N p) of the combined density p. A draw
//!   that finds no point still counts (it is a zero term of the average). Unbiased up to the
//!   profile energy beyond the largest probe sphere (stat `probe_missed_energy`, at most
//!   1 − 0.9999), like `pathtrace`.
//! * **Uniform** (`--uniform-points`): uniform by area over the object's triangles, A_k = A/N
//!   ([`sss_manylight::uniform_points`]): unbiased, but few points land where R_d is large.
//!
//! The irradiance at x_k comes from the VPLs through the same H = cos θ_i cos θ_y
//! min(1/d², G_max) V F_t(cos θ_i) as `manylight`: cos θ_i against the mesh's interpolated
//! shading normal, the light above the triangle's own plane, and the same clamp G_max ([`sss_manylight::Settings::g_max_for_scene`]). So Σ_{x_o} w Σ_k A_k R_d
//! Σ_y I H — the point set's value — is an unbiased estimate of the pixel value `manylight`
//! estimates, and EELC estimates the point set's value without bias at a fixed stratum count;
//! MDLC's representatives are biased at a finite cut (see [`sss_manylight::mdlc`]). The pixel
//! estimate is split over the object's samples in proportion to their exit weights, as in
//! `manylight`.
//!
//! # Memory
//!
//! Per thread, one pixel's points: N irradiance points at a time, at most pixel_samples × N
//! gather points and their tree ([`GatherTree::peak_bytes`]), and the pairs of the cut up to
//! `--max-pairs`; counted in [`PointOptions::structure_bytes`] against `--max-memory` before the frame is
//! built.
//!
//! # Stages
//!
//! The points are drawn inside the per-pixel loop (holding every pixel's points at once would
//! take gigabytes); the loop's wall time is split into stages `points` (drawing the points and
//! building the gather trees) and `shading` (the cut or estimator) in proportion to the thread
//! time each took, so the importance sampling's share (88–96 % of EELC's time in the paper's
//! Table 2) can be read off.

pub mod eelc;
pub mod mdlc;

use super::{
    ObjectData, PixelResult, estimate_seed, light_tree_seeded, model_error, object_data,
    pixel_list, pixel_result, scene_box, shadow_test, stream_seed,
};
use crate::Error;
use crate::frame::Frame;
use crate::integrators::options::{IRRADIANCE_POINTS, MAX_PAIRS, UNIFORM_POINTS, VPLS};
use crate::integrators::vpl::vpls::vpl_count;
use crate::integrators::{Layer, MethodOptions, OptionSpec, Shaded, Stat, check_radial};
use crate::probe::{Sampler, Scratch, default_probe_energy, probe_radii};
use crate::progress::Progress;
use crate::rng::{Stream, rng};
use rand::RngExt;
use rayon::prelude::*;
use sss_bssrdf::Rgb;
use sss_manylight::irradiance_cluster::IcNode;
use sss_manylight::{
    GatherPoint, GatherTree, IrradiancePoint, LightNode, LightTree, PixelEstimate, ShadingPoint,
    Summary, Triangle, Visibility, Vpl, gather_points, uniform_points,
};
use sss_scene::Scene;
use std::time::Instant;

/// The most irradiance points per shading point (`--irradiance-points`).
pub const MAX_IRRADIANCE_POINTS: u32 = 1 << 20;

/// The options both baselines take.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PointOptions {
    /// Irradiance points per shading point (1 ..= [`MAX_IRRADIANCE_POINTS`]).
    pub irradiance_points: u32,
    /// Uniform by area instead of BSSRDF importance sampling.
    pub uniform: bool,
    /// VPLs per sun, quad or environment light.
    pub vpls: u32,
    /// Cap on the pairs per pixel and object.
    pub max_pairs: usize,
    /// Seed of the VPL sampling (`None`: the render's seed), as [`ManyLight::vpl_seed`]:
    /// fixing it keeps one VPL set, and so one integral, across renders of different seeds.
    ///
    /// [`ManyLight::vpl_seed`]: super::manylight::ManyLight::vpl_seed
    pub vpl_seed: Option<u64>,
    /// Mixed into the seeds of the irradiance points and of every pixel estimate (0 by
    /// default), as [`ManyLight::stream`]: another stream gives an independent estimate (new
    /// points, new strata samples) over the same G-buffer and VPLs.
    ///
    /// [`ManyLight::stream`]: super::manylight::ManyLight::stream
    pub stream: u64,
}

impl Default for PointOptions {
    /// The declared defaults of the shared options `--irradiance-points`, `--uniform-points`,
    /// `--vpls` and `--max-pairs`.
    fn default() -> Self {
        crate::integrators::options::from_declared("the gather-point options", |o| {
            PointOptions::from_options(o, &[IRRADIANCE_POINTS, UNIFORM_POINTS, VPLS, MAX_PAIRS])
        })
    }
}

impl PointOptions {
    /// The options `o` gives among `specs` (errors name the flag).
    pub fn from_options(o: &MethodOptions, specs: &[OptionSpec]) -> Result<Self, Error> {
        let irradiance_points: u32 = o.get(specs, IRRADIANCE_POINTS.name)?;
        if !(1..=MAX_IRRADIANCE_POINTS).contains(&irradiance_points) {
            return Err(Error::Input(format!(
                "--irradiance-points must be in 1..={MAX_IRRADIANCE_POINTS}, got {irradiance_points}"
            )));
        }
        let vpls: u32 = o.get(specs, "vpls")?;
        if vpls == 0 {
            return Err(Error::Input("--vpls must be at least 1".into()));
        }
        let max_pairs: usize = o.get(specs, MAX_PAIRS.name)?;
        if !(1..=(1 << 30)).contains(&max_pairs) {
            return Err(Error::Input(format!(
                "--max-pairs must be in 1..=2^30, got {max_pairs}"
            )));
        }
        Ok(PointOptions {
            irradiance_points,
            uniform: o.flag(UNIFORM_POINTS.name),
            vpls,
            max_pairs,
            vpl_seed: None,
            stream: 0,
        })
    }

    /// "4096 importance-sampled irradiance points per shading point, 1024 VPLs ..." for
    /// `describe`.
    pub fn describe(&self) -> String {
        format!(
            "{} {} irradiance points per shading point, {} VPLs per area/environment light, \
             direct light only",
            self.irradiance_points,
            if self.uniform {
                "uniform"
            } else {
                "BSSRDF importance-sampled"
            },
            self.vpls
        )
    }

    /// Bytes of the shared structures (VPLs, light tree, triangle BVHs) and, per thread, one
    /// pixel's points and gather tree plus `pair_bytes` (the method's cut at its cap).
    pub fn structure_bytes(&self, scene: &Scene, pair_bytes: u64) -> u64 {
        let n = vpl_count(&scene.lights, self.vpls);
        let lights = n.saturating_mul(size_of::<Vpl>() as u64).saturating_add(
            (2 * n)
                .saturating_sub(1)
                .saturating_mul(size_of::<LightNode>() as u64),
        );
        let triangles: u64 = (0..scene.objects.len())
            .filter(|&o| scene.translucent(o).is_some())
            .map(|o| scene.objects[o].mesh.triangles.len() as u64)
            .sum();
        let meshes = triangles * (size_of::<Triangle>() + 2 * size_of::<IcNode>()) as u64;
        let n_pts = u64::from(self.irradiance_points);
        let gather = n_pts.saturating_mul(u64::from(scene.camera.pixel_samples.max(1)));
        let per_thread = n_pts
            .saturating_mul(size_of::<IrradiancePoint>() as u64)
            .saturating_add(GatherTree::peak_bytes(
                gather.min(usize::MAX as u64) as usize
            ))
            .saturating_add(pair_bytes);
        lights
            .saturating_add(meshes)
            .saturating_add(per_thread.saturating_mul(rayon::current_num_threads() as u64))
    }
}

/// One baseline's per-pixel estimate on one object, as the pipeline calls it.
pub(crate) trait PixelEstimator: Sync {
    /// Whether [`PixelEstimator::std_error`] gives a value (the method has an interval).
    const STD_ERROR: bool;
    /// Estimates one pixel from its gather tree.
    fn estimate(
        &self,
        gather: &GatherTree,
        visibility: &dyn Visibility,
        seed: u64,
    ) -> PixelEstimate;
    /// The standard error of the estimate's luminance, if the method has one.
    fn std_error(&self, px: &PixelEstimate) -> Option<f64>;
}

/// The per-frame data: per object (indexed by object) the triangle BVH, profile and F_t; the
/// light tree (`None` without light); the G clamp.
pub(crate) struct Prepared {
    pub(crate) objects: Vec<Option<ObjectData>>,
    pub(crate) lights: Option<LightTree>,
    pub(crate) g_max: f64,
}

/// Builds the per-frame data (the VPLs from `opts.vpl_seed`, else the frame's seed), refusing
/// the directional dipole and pre-scatter textures with the errors of `manylight`.
pub(crate) fn prepare(
    frame: &Frame<'_>,
    method: &str,
    opts: &PointOptions,
) -> Result<Prepared, Error> {
    check_radial(frame, method)?;
    let objects = frame.timed("irradiance_tree", || object_data(frame, method))?;
    let vpl_seed = opts.vpl_seed.unwrap_or(frame.seed);
    let lights = frame.timed("light_tree", || {
        light_tree_seeded(frame, opts.vpls, 0, vpl_seed)
    })?;
    let (_, half_diag) = scene_box(frame);
    Ok(Prepared {
        objects,
        lights,
        g_max: sss_manylight::Settings::g_max_for_scene(half_diag),
    })
}

/// The per-object estimators (indexed by object; `None` for an object without data, and for
/// every object when the frame has no light), each made by `make` from the light tree and the
/// object's data; its errors name `method`.
pub(crate) fn estimators<'a, E>(
    prepared: &'a Prepared,
    method: &str,
    make: impl Fn(&'a LightTree, &'a ObjectData) -> Result<E, sss_manylight::Error>,
) -> Result<Vec<Option<E>>, Error> {
    let Some(lt) = &prepared.lights else {
        return Ok(prepared.objects.iter().map(|_| None).collect());
    };
    prepared
        .objects
        .iter()
        .map(|d| {
            d.as_ref()
                .map(|d| make(lt, d).map_err(|e| Error::Input(format!("{method}: {e}"))))
                .transpose()
        })
        .collect()
}

/// One pixel's output.
#[derive(Default)]
struct PixelOut {
    values: Vec<Rgb>,
    pairs: f64,
    var: Rgb,
    gather_points: u64,
    summary: Summary,
    seconds_points: f64,
    seconds_estimate: f64,
}

/// The estimates of the pixels `only` of `frame` (all pixels when `None`), in that order, with
/// the largest probe-missed energy; records the stages `points` and `shading`. Shared by
/// [`run`] and [`shade_pixels`]: every pixel's points and estimate are seeded by its own index,
/// so a pixel gets the same bits either way.
fn estimate_pixels<E: PixelEstimator>(
    frame: &Frame<'_>,
    method: &'static str,
    opts: &PointOptions,
    prepared: &Prepared,
    estimators: &[Option<E>],
    only: Option<&[usize]>,
    progress: &dyn Progress,
) -> Result<(Vec<PixelOut>, f64), Error> {
    let scene = frame.scene;
    let geom = &frame.geom;
    let gb = &frame.gbuffer;
    let list = pixel_list(frame, only, method)?;
    // Uniform points need no probe spheres.
    let (radii, missed) = if opts.uniform {
        (frame.shading.iter().map(|_| None).collect(), 0.0)
    } else {
        probe_radii(&frame.shading, default_probe_energy())
    };
    // Shadow rays from the gather point to the VPL, as `manylight`'s.
    let visibility = shadow_test(frame);
    let spp = gb.samples_per_pixel as f64;
    let gspp = gb.samples_per_pixel as u64;
    let n = opts.irradiance_points as usize;
    let points_seed = stream_seed(frame.seed, opts.stream);
    let wall = Instant::now();
    let pixels: Vec<PixelOut> = list
        .par_iter()
        .with_min_len(4)
        .map_init(
            || (Scratch::default(), Vec::new(), Vec::new()),
            |(scratch, points, gathered), &i| {
                let samples = gb.pixel(i);
                progress.advance(samples.len() as u64);
                let mut out = PixelOut {
                    values: vec![[0.0; 3]; samples.len()],
                    ..PixelOut::default()
                };
                let mut done: Vec<u32> = Vec::new();
                for g in samples {
                    let o = g.object;
                    if done.contains(&o) {
                        continue;
                    }
                    done.push(o);
                    let (Some(sh), Some(Some(data)), Some(Some(est))) = (
                        frame.shading_of(o),
                        prepared.objects.get(o as usize),
                        estimators.get(o as usize),
                    ) else {
                        continue;
                    };
                    let t0 = Instant::now();
                    let mut members = Vec::new();
                    gathered.clear();
                    for (k, s) in samples.iter().enumerate() {
                        if s.object != o {
                            continue;
                        }
                        let e = sh.exit_weight(s.n, s.wo);
                        members.push((k, e));
                        if !(e > 0.0) {
                            continue;
                        }
                        let x_o = ShadingPoint {
                            position: s.p,
                            normal: s.n,
                            weight: e / spp,
                        };
                        let mut r = rng(
                            points_seed,
                            Stream::IrradiancePoints,
                            s.pixel as u64 * gspp + s.index as u64,
                        );
                        points.clear();
                        match radii[scene.objects[o as usize].material].as_ref() {
                            Some(rad) if !opts.uniform => {
                                let sampler = Sampler {
                                    geom,
                                    lights: &scene.lights,
                                    shading: sh,
                                    radii: rad,
                                };
                                let a = 1.0 / n as f64;
                                for _ in 0..n {
                                    if let Some((hit, pdf)) =
                                        sampler.sample_point(s, &mut r, scratch)
                                    {
                                        points.push(IrradiancePoint {
                                            position: hit.p,
                                            normal: hit.n,
                                            geometric: hit.ng,
                                            area: a / pdf,
                                        });
                                    }
                                }
                            }
                            _ => {
                                let mut next = || r.random::<f64>();
                                uniform_points(&data.tree, n, &mut next, points);
                            }
                        }
                        gather_points(&x_o, points, &data.profile, gathered);
                    }
                    let e_sum: f64 = members.iter().map(|m| m.1).sum();
                    if !(e_sum > 0.0) {
                        continue;
                    }
                    out.gather_points += gathered.len() as u64;
                    let seed = estimate_seed(frame.seed, o, opts.stream, i);
                    let tree = if gathered.is_empty() {
                        None
                    } else {
                        let pts: Vec<GatherPoint> = std::mem::take(gathered);
                        Some(
                            GatherTree::new(pts, seed)
                                .map_err(|e| model_error(scene, o, method, e))?,
                        )
                    };
                    let t1 = Instant::now();
                    let px = match &tree {
                        Some(t) => est.estimate(t, &visibility, seed),
                        None => PixelEstimate::zero(),
                    };
                    out.seconds_points += (t1 - t0).as_secs_f64();
                    out.seconds_estimate += t1.elapsed().as_secs_f64();
                    out.summary.add(&px);
                    out.pairs += px.triplets as f64;
                    for (k, e) in members {
                        for c in 0..3 {
                            out.values[k][c] = px.rgb[c].max(0.0) * spp * e / e_sum;
                        }
                    }
                    if let Some(se) = est.std_error(&px)
                        && px.value > 0.0
                    {
                        for c in 0..3 {
                            let s = px.rgb[c].max(0.0) * se / px.value;
                            out.var[c] += s * s;
                        }
                    }
                }
                Ok(out)
            },
        )
        .collect::<Result<Vec<PixelOut>, Error>>()?;
    // Split the loop's wall time by the thread time of its two parts.
    let wall = wall.elapsed().as_secs_f64();
    let (tp, te) = pixels.iter().fold((0.0, 0.0), |(a, b), p| {
        (a + p.seconds_points, b + p.seconds_estimate)
    });
    let share = if tp + te > 0.0 { tp / (tp + te) } else { 0.0 };
    frame.record("points", wall * share);
    frame.record("shading", wall * (1.0 - share));
    Ok((pixels, missed))
}

/// Runs the per-pixel pipeline over the whole frame with the per-object estimators
/// `estimators` (indexed by object) and assembles the method's output.
pub(crate) fn run<E: PixelEstimator>(
    frame: &Frame<'_>,
    method: &'static str,
    opts: &PointOptions,
    prepared: &Prepared,
    estimators: &[Option<E>],
    progress: &dyn Progress,
) -> Result<Shaded, Error> {
    let (pixels, missed) =
        estimate_pixels(frame, method, opts, prepared, estimators, None, progress)?;
    let gb = &frame.gbuffer;
    let mut summary = Summary::default();
    let mut values = Vec::with_capacity(gb.samples.len());
    let mut std_error = Vec::with_capacity(pixels.len());
    let mut pairs = Vec::with_capacity(pixels.len());
    let mut n_gather = 0u64;
    for p in &pixels {
        summary.merge(&p.summary);
        values.extend_from_slice(&p.values);
        std_error.push(p.var.map(f64::sqrt));
        pairs.push([p.pairs; 3]);
        n_gather += p.gather_points;
    }
    let has_se = E::STD_ERROR;
    if summary.triplet_cap > 0 {
        frame.warn(format!(
            "{method}: {} pixel estimates stopped at the pair cap ({}) before reaching their \
             threshold; raise --max-pairs",
            summary.triplet_cap, opts.max_pairs
        ));
    }
    let n_vpls = prepared.lights.as_ref().map_or(0, |l| l.vpls().len());
    let stat = |name, value: f64| Stat { name, value };
    let mut stats = vec![
        stat("vpls", n_vpls as f64),
        stat("g_max", prepared.g_max),
        stat("irradiance_points", f64::from(opts.irradiance_points)),
        stat("gather_points", n_gather as f64),
        stat("pixel_estimates", summary.pixels as f64),
        stat("pairs", summary.triplets as f64),
        stat("mean_pairs", summary.mean_triplets()),
        stat("evaluations", summary.samples as f64),
        stat("g_clamped", summary.g_clamped as f64),
        stat("pixels_converged", summary.converged as f64),
        stat("pixels_pair_cap", summary.triplet_cap as f64),
        stat("pixels_exact", summary.exact as f64),
    ];
    if has_se {
        stats.push(stat("pixels_zero", summary.zero as f64));
        stats.push(stat("zero_variance_pairs", summary.zero_variance as f64));
    }
    if !opts.uniform {
        stats.push(stat("probe_missed_energy", missed));
    }
    Ok(Shaded {
        values,
        std_error: has_se.then_some(std_error),
        stats,
        layers: vec![Layer {
            name: "pairs",
            pixels: pairs,
        }],
    })
}

/// The estimates of the pixels `pixels` of `frame` only, in that order (the baselines'
/// `shade_pixels`): each pixel's subsurface value and standard error equal what a full render
/// gives it ([`run`]), since its points and estimate are seeded by its own index. `triplets`
/// holds the pixel's pairs (MDLC's cut, EELC's strata); `std_error` is 0 without an interval
/// (MDLC).
pub(crate) fn shade_pixels<E: PixelEstimator>(
    frame: &Frame<'_>,
    method: &'static str,
    opts: &PointOptions,
    prepared: &Prepared,
    estimators: &[Option<E>],
    pixels: &[usize],
) -> Result<Vec<PixelResult>, Error> {
    let (outs, _) = estimate_pixels(
        frame,
        method,
        opts,
        prepared,
        estimators,
        Some(pixels),
        &crate::progress::NoProgress,
    )?;
    Ok(outs
        .into_iter()
        .zip(pixels)
        .map(|(o, &i)| {
            pixel_result(
                frame,
                i,
                &o.values,
                o.var.map(f64::sqrt),
                o.pairs,
                o.summary,
            )
        })
        .collect())
}

/// The irradiance-point counts `mdlc` and `eelc` sweep in `cargo xtask compare` (cheapest
/// first, at ε = 0.02): 64 with `--quick`, else 64 and 256 (the reasons are at `mdlc`'s
/// registry entry).
pub(super) fn sweep_points(quick: bool) -> Vec<f64> {
    if quick { vec![64.0] } else { vec![64.0, 256.0] }
}
