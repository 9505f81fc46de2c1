//! The VPL methods: many-light subsurface scattering over virtual point lights. `manylight`
//! (Nabata & Iwasaki 2021: triplets, Student-t error control) and the two baselines of that
//! paper, which first draw a fixed set of irradiance points per shading point
//! ([`gather_points`]: `mdlc`, Walter et al.'s multidimensional lightcuts, and `eelc`, the
//! paper's error-estimated lightcuts). This module holds what all three share: the light
//! tree of the frame's VPLs, the per-object data (triangle BVH, radial profile, entry
//! transmittance), the shadow test, the seeds of pixel estimates and streams, and the
//! assembly of a subset pixel's result.

pub mod gather_points;
pub mod manylight;

use crate::Error;
use crate::frame::Frame;
use crate::vpls::{bounce_vpls, scene_vpls};
use glam::DVec3;
use sss_bssrdf::fresnel::ft_dielectric;
use sss_bssrdf::{Rgb, make_model};
use sss_manylight::{
    LightTree, RadialProfile, Summary, Transmittance, TriangleClusterTree, pixel_seed,
};
use sss_scene::Scene;

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
