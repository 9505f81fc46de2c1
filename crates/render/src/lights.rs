//! Direct light arriving at a surface point, with shadow rays: the irradiance that enters the
//! translucent surfaces (irradiance samples, the path tracer's exit points) and lights the
//! opaque ones.

use crate::geometry::SceneGeometry;
use glam::DVec3;
use rand::RngExt;
use rand_pcg::Pcg64Mcg;
use sss_bssrdf::Rgb;
use sss_scene::Light;
use std::f64::consts::PI;

/// One packet of light reaching a point: the unit direction it comes from and its
/// contribution to the irradiance, `L cos θ dω / pdf` (no Fresnel factor; already shadowed).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Incident {
    /// Unit direction from the point towards the light.
    pub dir: DVec3,
    /// Irradiance contribution per channel (W per unit area), cos θ included.
    pub e_cos: Rgb,
}

/// A point on a surface where light is gathered.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Receiver {
    /// Position.
    pub p: DVec3,
    /// Unit shading normal (cosines are taken against it).
    pub n: DVec3,
    /// Unit geometric normal (rays leave on its side).
    pub ng: DVec3,
}

/// Gathers the direct light at receiver `at` into `out`:
/// one packet per point or directional light that is above the surface and unblocked, and
/// `area_samples` packets (each carrying 1/`area_samples` of the estimate) per sun, quad or
/// environment light (a sun's directions stratified over its disc: penumbrae). Packets with
/// zero contribution are left out.
pub fn gather(
    geom: &SceneGeometry,
    lights: &[Light],
    at: Receiver,
    area_samples: u32,
    rng: &mut Pcg64Mcg,
    out: &mut Vec<Incident>,
) {
    let Receiver { p, n, ng } = at;
    let m = area_samples.max(1);
    for light in lights {
        match light {
            Light::Point {
                position,
                intensity,
            } => {
                let d = *position - p;
                let dist2 = d.length_squared();
                if !(dist2 > 0.0) {
                    continue;
                }
                let dist = dist2.sqrt();
                let wi = d / dist;
                let cos = n.dot(wi);
                if !(cos > 0.0) || ng.dot(wi) <= 0.0 {
                    continue;
                }
                if !unblocked(geom, p, ng, wi, dist) {
                    continue;
                }
                let s = cos / dist2;
                push(out, wi, intensity.map(|v| v * s));
            }
            Light::Directional {
                direction,
                irradiance,
            } => {
                let wi = -*direction;
                let cos = n.dot(wi);
                if !(cos > 0.0) || ng.dot(wi) <= 0.0 {
                    continue;
                }
                if !unblocked(geom, p, ng, wi, f64::INFINITY) {
                    continue;
                }
                push(out, wi, irradiance.map(|v| v * cos));
            }
            Light::Sun {
                direction,
                irradiance,
                half_angle,
            } => {
                let Some((radiance, solid_angle)) = sun_radiance(*irradiance, *half_angle) else {
                    continue;
                };
                for k in 0..m {
                    let (u1, u2) = stratum(k, m, rng);
                    let wi = cone_direction(-*direction, *half_angle, u1, u2);
                    let cos = n.dot(wi);
                    if !(cos > 0.0) || ng.dot(wi) <= 0.0 {
                        continue;
                    }
                    if !unblocked(geom, p, ng, wi, f64::INFINITY) {
                        continue;
                    }
                    // L cos dω / pdf with pdf = 1/Ω over the disc.
                    let s = cos * solid_angle / m as f64;
                    push(out, wi, radiance.map(|v| v * s));
                }
            }
            Light::Quad {
                corner,
                edge_u,
                edge_v,
                radiance,
            } => {
                let Some((area, nl)) = quad_area_normal(*edge_u, *edge_v) else {
                    continue;
                };
                for k in 0..m {
                    let (s, t) = stratum(k, m, rng);
                    let y = *corner + *edge_u * s + *edge_v * t;
                    let d = y - p;
                    let dist2 = d.length_squared();
                    if !(dist2 > 0.0) {
                        continue;
                    }
                    let dist = dist2.sqrt();
                    let wi = d / dist;
                    let cos = n.dot(wi);
                    let cos_l = -nl.dot(wi);
                    if !(cos > 0.0) || !(cos_l > 0.0) || ng.dot(wi) <= 0.0 {
                        continue;
                    }
                    if !unblocked(geom, p, ng, wi, dist) {
                        continue;
                    }
                    // L cos dω / pdf with pdf = 1/area over the quad and dω = cos_l dA / d².
                    let s = cos * cos_l * area / (dist2 * m as f64);
                    push(out, wi, radiance.map(|v| v * s));
                }
            }
            Light::Environment { radiance } => {
                let (t1, t2) = tangent_frame(n);
                for k in 0..m {
                    let (u1, u2) = stratum(k, m, rng);
                    // Cosine-weighted hemisphere (Malley's method): L cos / (cos/π) = π L.
                    let r = u1.sqrt();
                    let phi = 2.0 * PI * u2;
                    let z = (1.0 - u1).max(0.0).sqrt();
                    let wi = (t1 * (r * phi.cos()) + t2 * (r * phi.sin()) + n * z).normalize();
                    if ng.dot(wi) <= 0.0 {
                        continue;
                    }
                    if !unblocked(geom, p, ng, wi, f64::INFINITY) {
                        continue;
                    }
                    let s = PI / m as f64;
                    push(out, wi, radiance.map(|v| v * s));
                }
            }
        }
    }
}

/// Whether nothing blocks the way from `p` (leaving on `ng`'s side of the surface towards
/// `wi`) to a light at distance `dist` (infinite for distant lights and the environment).
fn unblocked(geom: &SceneGeometry, p: DVec3, ng: DVec3, wi: DVec3, dist: f64) -> bool {
    let o = geom.offset(p, ng, wi);
    let t_max = if dist.is_finite() {
        (dist - 4.0 * geom.epsilon()).max(0.0)
    } else {
        f64::INFINITY
    };
    !geom.occluded(o, wi, 0.0, t_max)
}

fn push(out: &mut Vec<Incident>, dir: DVec3, e_cos: Rgb) {
    if e_cos.iter().all(|v| v.is_finite() && *v >= 0.0) && e_cos.iter().any(|v| *v > 0.0) {
        out.push(Incident { dir, e_cos });
    }
}

/// The area and unit normal (edge_u × edge_v, normalised) of a quad light, `None` for a
/// degenerate or non-finite one (which emits nothing).
pub(crate) fn quad_area_normal(edge_u: DVec3, edge_v: DVec3) -> Option<(f64, DVec3)> {
    let cross = edge_u.cross(edge_v);
    let area = cross.length();
    (area > 0.0 && area.is_finite()).then(|| (area, cross / area))
}

/// A sun's radiance L = E / (π sin² α) and its solid angle Ω = 2π(1 − cos α) = 4π sin²(α/2),
/// for irradiance `irradiance` at normal incidence and angular radius `half_angle` = α (the
/// integral of L cos θ over the disc seen head-on is L π sin² α). None for an angle outside
/// (0, π/2] or a degenerate one.
pub fn sun_radiance(irradiance: Rgb, half_angle: f64) -> Option<(Rgb, f64)> {
    if !(half_angle > 0.0 && half_angle <= 0.5 * PI) {
        return None;
    }
    let s = half_angle.sin();
    let projected = PI * s * s;
    let solid_angle = 4.0 * PI * (0.5 * half_angle).sin().powi(2);
    if !(projected > 0.0 && solid_angle > 0.0) {
        return None;
    }
    Some((irradiance.map(|e| e / projected), solid_angle))
}

/// A direction uniform in solid angle over the cone of half-angle `half_angle` about the unit
/// `axis`, from uniform numbers `u1`, `u2` in [0, 1): cos θ = 1 − u1 (1 − cos α), the
/// azimuth 2π u2 (1 − cos α written 2 sin²(α/2), exact for tiny cones).
pub fn cone_direction(axis: DVec3, half_angle: f64, u1: f64, u2: f64) -> DVec3 {
    let one_minus_cos = u1 * 2.0 * (0.5 * half_angle).sin().powi(2);
    let cos_t = 1.0 - one_minus_cos;
    let sin_t = (one_minus_cos * (2.0 - one_minus_cos)).max(0.0).sqrt();
    let phi = 2.0 * PI * u2;
    let (a, b) = tangent_frame(axis);
    (a * (sin_t * phi.cos()) + b * (sin_t * phi.sin()) + axis * cos_t).normalize_or(axis)
}

/// A point of the unit square in stratum `k` of `m` equal strips along the first axis (uniform
/// overall, with less variance than independent points).
pub(crate) fn stratum(k: u32, m: u32, rng: &mut Pcg64Mcg) -> (f64, f64) {
    let u = ((k as f64 + rng.random::<f64>()) / m as f64).min(1.0 - f64::EPSILON / 2.0);
    (u, rng.random::<f64>())
}

/// Two unit tangents completing `n` to an orthonormal frame (Duff et al. 2017).
pub fn tangent_frame(n: DVec3) -> (DVec3, DVec3) {
    let sign = 1f64.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    (
        DVec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
        DVec3::new(b, sign + n.y * n.y * a, -n.y),
    )
}

/// The radiance seen along a ray that leaves the scene: the environment lights' sum.
pub fn background(lights: &[Light]) -> Rgb {
    let mut l = [0.0; 3];
    for light in lights {
        if let Light::Environment { radiance } = light {
            for c in 0..3 {
                l[c] += radiance[c];
            }
        }
    }
    l
}
