//! Virtual point lights (VPLs) from the scene's lights, for the many-light integrators
//! (`manylight`; Keller 1997, "Instant radiosity"; Walter et al. 2005/2006, Lightcuts and
//! Multidimensional Lightcuts).
//!
//! [`scene_vpls`] makes the VPLs of direct light, so that many-light renders are comparable
//! with `exact` and `pathtrace`, which carry direct light only:
//!
//! * a **point light** is one isotropic VPL of its intensity;
//! * a **directional light** (irradiance E along direction d) is one isotropic VPL placed
//!   [`DISTANT_FACTOR`] scene extents up-light, with intensity E·D² so that the irradiance it
//!   gives at the scene is E up to a relative error of about the scene's size over D (≤ 1e-6);
//! * a **sun** (irradiance E, angular radius α) is `budget` such distant VPLs in directions
//!   uniform over its disc (stratified in cos θ, jittered), each carrying E/`budget`: its
//!   penumbrae by Monte Carlo, E exactly where the whole disc is seen head-on;
//! * a **quad light** (radiance L, area A) is `budget` cosine VPLs on a jittered grid over the
//!   quad, each of intensity L·A/`budget` along the quad's normal (Keller 1997: a sample of an
//!   area light carries I = L A/N);
//! * an **environment light** (radiance L) is `budget` distant VPLs in directions stratified
//!   over the sphere (equal-area bands in z, jittered), each carrying the irradiance
//!   L·4π/`budget` of its solid angle, placed like a directional light.
//!
//! Sampling is seeded per light from the render seed (stream [`Stream::Vpl`]), so the VPLs,
//! and every image built from them, are the same for any thread count.
//!
//! **One indirect bounce** ([`bounce_vpls`], off unless asked for): light paths are traced
//! from the lights (Keller 1997's instant radiosity, one bounce), each light getting paths in
//! proportion to its power; where a path first meets an opaque diffuse surface it leaves a
//! cosine VPL facing the side the light came from, of intensity Φ_path ρ / π (a Lambertian
//! reflector of albedo ρ re-emits ρ Φ_path, and a cosine emitter of intensity I along its
//! normal emits π I). A path whose first hit is translucent, or that leaves the scene, leaves
//! nothing (light inside translucent objects is the BSSRDF's business). Renders with it carry
//! more light than `exact` and `pathtrace`, which carry direct light only.

use crate::Error;
use crate::geometry::SceneGeometry;
use crate::rng::{Stream, rng};
use glam::DVec3;
use rand::RngExt;
use sss_manylight::Vpl;
use sss_scene::{Light, MaterialKind, Scene};
use std::f64::consts::PI;

/// Distant lights (directional, environment) are placed this many scene extents away.
pub const DISTANT_FACTOR: f64 = 1e6;

/// The number of VPLs [`scene_vpls`] makes for `lights` with `budget` per area or environment
/// light (for memory estimates before sampling).
pub fn vpl_count(lights: &[Light], budget: u32) -> u64 {
    lights
        .iter()
        .map(|l| match l {
            Light::Point { .. } | Light::Directional { .. } => 1,
            Light::Sun { .. } | Light::Quad { .. } | Light::Environment { .. } => {
                u64::from(budget.max(1))
            }
        })
        .sum()
}

/// The VPLs of `scene`'s lights (see the module doc): `budget` ≥ 1 per quad or environment
/// light, seeded by `seed`. `center` and `extent` (the geometry's box centre and largest side)
/// place the distant lights. VPLs of zero intensity are left out; the result may be empty
/// (a scene without light).
pub fn scene_vpls(
    scene: &Scene,
    budget: u32,
    seed: u64,
    center: DVec3,
    extent: f64,
) -> Result<Vec<Vpl>, Error> {
    if budget == 0 {
        return Err(Error::Input("--vpls must be at least 1".into()));
    }
    let far = DISTANT_FACTOR * extent.max(1e-30);
    let m = budget as usize;
    let mut out = Vec::new();
    let mut push = |v: Vpl| {
        if v.intensity.iter().any(|c| *c > 0.0) && v.intensity.iter().all(|c| c.is_finite()) {
            out.push(v);
        }
    };
    for (k, light) in scene.lights.iter().enumerate() {
        let mut r = rng(seed, Stream::Vpl, k as u64);
        match light {
            Light::Point {
                position,
                intensity,
            } => push(Vpl::point(*position, *intensity)),
            Light::Directional {
                direction,
                irradiance,
            } => {
                let d = direction.normalize_or_zero();
                if d == DVec3::ZERO {
                    continue;
                }
                push(Vpl::point(
                    center - d * far,
                    irradiance.map(|e| e * far * far),
                ));
            }
            Light::Sun {
                direction,
                irradiance,
                half_angle,
            } => {
                // `budget` directions over the disc, stratified in cos θ, each a distant point
                // light carrying 1/budget of the irradiance: the penumbrae by Monte Carlo.
                let d = direction.normalize_or_zero();
                if d == DVec3::ZERO {
                    continue;
                }
                for k in 0..budget {
                    let (u1, u2) = crate::lights::stratum(k, budget, &mut r);
                    let w = crate::lights::cone_direction(-d, *half_angle, u1, u2);
                    push(Vpl::point(
                        center + w * far,
                        irradiance.map(|e| e * far * far / m as f64),
                    ));
                }
            }
            Light::Quad {
                corner,
                edge_u,
                edge_v,
                radiance,
            } => {
                let Some((area, n)) = crate::lights::quad_area_normal(*edge_u, *edge_v) else {
                    continue;
                };
                // A jittered nu × nv grid with nu·nv = m exactly (nu the largest divisor of m
                // up to √m: 32 × 32 for 1024, 1 × m for a prime), so the points are uniform on
                // the quad and stratified in both directions when m has a good factorisation.
                let nu = (1..=((m as f64).sqrt() as usize).max(1))
                    .rev()
                    .find(|d| m.is_multiple_of(*d))
                    .unwrap_or(1);
                let nv = m / nu;
                let s = area / m as f64;
                for c in 0..m {
                    let (i, j) = (c % nu, c / nu);
                    let u = ((i as f64 + r.random::<f64>()) / nu as f64).min(1.0);
                    let v = ((j as f64 + r.random::<f64>()) / nv as f64).min(1.0);
                    let y = *corner + *edge_u * u + *edge_v * v;
                    push(Vpl::oriented(y, n, radiance.map(|l| l * s)));
                }
            }
            Light::Environment { radiance } => {
                let s = 4.0 * PI / m as f64 * far * far;
                for c in 0..m {
                    // Uniform on the sphere: z uniform in [−1, 1] (Archimedes), stratified.
                    let z = 1.0 - 2.0 * (c as f64 + r.random::<f64>()) / m as f64;
                    let phi = 2.0 * PI * r.random::<f64>();
                    let rho = (1.0 - z * z).max(0.0).sqrt();
                    let dir = DVec3::new(rho * phi.cos(), rho * phi.sin(), z);
                    push(Vpl::point(center + dir * far, radiance.map(|l| l * s)));
                }
            }
        }
    }
    Ok(out)
}

/// The power (W, per channel) a light sends into a scene whose geometry lies in the sphere of
/// radius `radius`: 4πI for a point light, πR²E for a directional one, πLA for a quad,
/// 4π²R²L for an environment (its radiance through the sphere, πL per unit area of 4πR²).
pub fn light_power(light: &Light, radius: f64) -> [f64; 3] {
    let disk = PI * radius * radius;
    match light {
        Light::Point { intensity, .. } => intensity.map(|i| 4.0 * PI * i),
        Light::Directional { irradiance, .. } | Light::Sun { irradiance, .. } => {
            irradiance.map(|e| e * disk)
        }
        Light::Quad {
            edge_u,
            edge_v,
            radiance,
            ..
        } => {
            let a = crate::lights::quad_area_normal(*edge_u, *edge_v).map_or(0.0, |q| q.0);
            radiance.map(|l| PI * l * a)
        }
        Light::Environment { radiance } => radiance.map(|l| 4.0 * PI * disk * l),
    }
}

/// A uniformly distributed unit vector from two uniforms (Archimedes: z uniform).
fn uniform_sphere(u1: f64, u2: f64) -> DVec3 {
    let z = 1.0 - 2.0 * u1;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * PI * u2;
    DVec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// A point of the disk of radius `r` about `c` perpendicular to the unit `d`, uniform by area.
fn disk_point(c: DVec3, d: DVec3, r: f64, u1: f64, u2: f64) -> DVec3 {
    let (a, b) = crate::lights::tangent_frame(d);
    let rho = r * u1.sqrt();
    let phi = 2.0 * PI * u2;
    c + a * (rho * phi.cos()) + b * (rho * phi.sin())
}

/// One-bounce VPLs (see the module doc): `paths` light paths in all, split over the lights in
/// proportion to their power (luminance), each light's paths carrying its power equally,
/// traced against `geom`, seeded by `seed` (stream [`Stream::Bounce`], per light). `center`
/// and `radius` bound the geometry (distant lights enter through that sphere). `paths` = 0
/// gives none.
pub fn bounce_vpls(
    scene: &Scene,
    geom: &SceneGeometry,
    paths: u32,
    seed: u64,
    center: DVec3,
    radius: f64,
) -> Vec<Vpl> {
    let lum = |c: [f64; 3]| sss_manylight::luminance(c);
    let radius = radius.max(1e-30);
    let powers: Vec<[f64; 3]> = scene
        .lights
        .iter()
        .map(|l| light_power(l, radius))
        .collect();
    let total: f64 = powers.iter().map(|p| lum(*p).max(0.0)).sum();
    let mut out = Vec::new();
    if paths == 0 || !(total > 0.0 && total.is_finite()) {
        return out;
    }
    let eps = 16.0 * geom.epsilon();
    for (k, light) in scene.lights.iter().enumerate() {
        let share = lum(powers[k]).max(0.0) / total;
        let n = (f64::from(paths) * share).round() as u64;
        if n == 0 {
            continue;
        }
        let phi = powers[k].map(|p| p / n as f64);
        let mut r = rng(seed, Stream::Bounce, k as u64);
        for _ in 0..n {
            let (u1, u2, u3, u4) = (
                r.random::<f64>(),
                r.random::<f64>(),
                r.random::<f64>(),
                r.random::<f64>(),
            );
            let (origin, dir) = match light {
                Light::Point { position, .. } => (*position, uniform_sphere(u1, u2)),
                Light::Directional { direction, .. } => {
                    let d = direction.normalize_or_zero();
                    if d == DVec3::ZERO {
                        break;
                    }
                    (disk_point(center - 2.0 * radius * d, d, radius, u1, u2), d)
                }
                Light::Sun {
                    direction,
                    half_angle,
                    ..
                } => {
                    let axis = direction.normalize_or_zero();
                    if axis == DVec3::ZERO {
                        break;
                    }
                    let d = -crate::lights::cone_direction(-axis, *half_angle, u3, u4);
                    (disk_point(center - 2.0 * radius * d, d, radius, u1, u2), d)
                }
                Light::Quad {
                    corner,
                    edge_u,
                    edge_v,
                    ..
                } => {
                    let Some((_, nl)) = crate::lights::quad_area_normal(*edge_u, *edge_v) else {
                        break;
                    };
                    // Cosine-weighted about the normal (Malley's method).
                    let (a, b) = crate::lights::tangent_frame(nl);
                    let (rr, ph) = (u3.sqrt(), 2.0 * PI * u4);
                    let z = (1.0 - u3).max(0.0).sqrt();
                    let d = (a * (rr * ph.cos()) + b * (rr * ph.sin()) + nl * z).normalize();
                    (*corner + *edge_u * u1 + *edge_v * u2, d)
                }
                Light::Environment { .. } => {
                    let d = uniform_sphere(u3, u4);
                    (disk_point(center - 2.0 * radius * d, d, radius, u1, u2), d)
                }
            };
            let Some(hit) = geom.closest_hit(origin, dir, eps, f64::INFINITY) else {
                continue;
            };
            let material = &scene.materials[scene.objects[hit.object as usize].material];
            let MaterialKind::Diffuse { albedo, texture } = &material.kind else {
                continue;
            };
            let tex = texture.as_ref().map_or([1.0; 3], |t| t.eval(hit.p));
            let facing = if hit.ng.dot(dir) < 0.0 {
                hit.ng
            } else {
                -hit.ng
            };
            let intensity: [f64; 3] = std::array::from_fn(|c| phi[c] * albedo[c] * tex[c] / PI);
            if intensity.iter().all(|v| v.is_finite() && *v >= 0.0)
                && intensity.iter().any(|v| *v > 0.0)
            {
                out.push(Vpl::oriented(
                    geom.offset(hit.p, hit.ng, -dir),
                    facing,
                    intensity,
                ));
            }
        }
    }
    out
}
