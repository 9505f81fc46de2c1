//! Virtual point lights (VPLs) from the scene's lights, for the many-light integrators
//! (`manylight`; Keller 1997, "Instant radiosity"; Walter et al. 2005/2006, Lightcuts and
//! Multidimensional Lightcuts).
//!
//! Direct light only (no indirect bounce), so that many-light renders are comparable with
//! `exact` and `pathtrace`, which carry direct light only:
//!
//! * a **point light** is one isotropic VPL of its intensity;
//! * a **directional light** (irradiance E along direction d) is one isotropic VPL placed
//!   [`DISTANT_FACTOR`] scene extents up-light, with intensity E·D² so that the irradiance it
//!   gives at the scene is E up to a relative error of about the scene's size over D (≤ 1e-6);
//! * a **quad light** (radiance L, area A) is `budget` cosine VPLs on a jittered grid over the
//!   quad, each of intensity L·A/`budget` along the quad's normal (Keller 1997: a sample of an
//!   area light carries I = L A/N);
//! * an **environment light** (radiance L) is `budget` distant VPLs in directions stratified
//!   over the sphere (equal-area bands in z, jittered), each carrying the irradiance
//!   L·4π/`budget` of its solid angle, placed like a directional light.
//!
//! Sampling is seeded per light from the render seed (stream [`Stream::Vpl`]), so the VPLs,
//! and every image built from them, are the same for any thread count.

use crate::Error;
use crate::rng::{Stream, rng};
use glam::DVec3;
use rand::RngExt;
use sss_manylight::Vpl;
use sss_scene::{Light, Scene};
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
            Light::Quad { .. } | Light::Environment { .. } => u64::from(budget.max(1)),
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
