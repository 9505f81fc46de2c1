//! The boundary of a translucent object: a smooth dielectric (Fresnel reflection and
//! refraction, total internal reflection), or the diffuse boundary of Cycles' random walk
//! (Lambertian transmission in and out, no internal reflection).

use crate::lights::tangent_frame;
use glam::DVec3;
use sss_bssrdf::fresnel::fr_dielectric;
use std::f64::consts::PI;

/// How light crosses the boundary of a translucent object.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Boundary {
    /// A smooth dielectric at the material's η: Fresnel reflection and refraction, total
    /// internal reflection (the physics of Mitsuba 3's `dielectric` and pbrt's
    /// `DielectricBxDF`).
    Dielectric,
    /// Lambertian transmission in and out with no reflection, and next-event estimation at the
    /// exit (Blender Cycles' random-walk subsurface boundary): point and directional lights
    /// reach the medium, and comparisons with Cycles are like for like.
    Lambertian,
}

impl Boundary {
    /// The option value naming it.
    pub fn name(self) -> &'static str {
        match self {
            Boundary::Dielectric => "dielectric",
            Boundary::Lambertian => "lambertian",
        }
    }
}

/// A direction leaving a smooth dielectric interface.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Crossing {
    /// The new unit propagation direction.
    pub dir: DVec3,
    /// True when the light went through the interface (refraction), false when reflected.
    pub refracted: bool,
}

/// The Fresnel reflectance and the refracted direction (None under total internal reflection)
/// of light travelling along unit `d` onto an interface with unit shading normal `n` (either
/// orientation) between the outside (index 1) and an inside of relative index `eta`. The side
/// it comes from is read off the shading normal, as Mitsuba 3's `dielectric` does: `n` points
/// outside.
pub fn fresnel(d: DVec3, n: DVec3, eta: f64) -> (f64, Option<DVec3>) {
    // cos_i > 0: the light arrives from the outside (against n).
    let cos_i = -d.dot(n);
    let (eta_rel, nf) = if cos_i >= 0.0 {
        (eta, n)
    } else {
        (1.0 / eta, -n)
    };
    let c = cos_i.abs().min(1.0);
    let f = fr_dielectric(c, eta_rel);
    // Snell's law: sin²θ_t = sin²θ_i / η_rel².
    let sin2_t = (1.0 - c * c).max(0.0) / (eta_rel * eta_rel);
    if f >= 1.0 || sin2_t >= 1.0 {
        return (1.0, None);
    }
    let cos_t = (1.0 - sin2_t).max(0.0).sqrt();
    // d = −c·nf + tangential; the refracted ray keeps tangential/η_rel and goes −cos_t·nf.
    let t = d / eta_rel + nf * (c / eta_rel - cos_t);
    (f, Some(t.normalize_or(-nf)))
}

/// The mirror direction of unit `d` about the plane of normal `n`.
pub fn reflect(d: DVec3, n: DVec3) -> DVec3 {
    (d - n * (2.0 * d.dot(n))).normalize_or(-d)
}

/// Light along `d` meets a smooth dielectric of relative index `eta` with shading normal `n`:
/// it is reflected with the Fresnel probability F (chosen with the uniform `u`) and refracted
/// otherwise, so the path weight is unchanged (F/F and (1 − F)/(1 − F)). The factors η² of
/// radiance across the interface cancel between a path's entry and exit, so they are left out.
pub fn cross_dielectric(d: DVec3, n: DVec3, eta: f64, u: f64) -> Crossing {
    let (f, t) = fresnel(d, n, eta);
    match t {
        Some(t) if u >= f => Crossing {
            dir: t,
            refracted: true,
        },
        _ => Crossing {
            dir: reflect(d, n),
            refracted: false,
        },
    }
}

/// A direction about unit normal `n` with density cos θ/π (Malley's method), from two uniform
/// numbers: the Lambertian transmission's sample, whose weight (1/π · cos/pdf) is 1.
pub fn cosine_direction(n: DVec3, u1: f64, u2: f64) -> DVec3 {
    let (t1, t2) = tangent_frame(n);
    let r = u1.sqrt();
    let phi = 2.0 * PI * u2;
    let z = (1.0 - u1).max(0.0).sqrt();
    (t1 * (r * phi.cos()) + t2 * (r * phi.sin()) + n * z).normalize_or(n)
}

#[cfg(test)]
mod tests {
    use super::*;
    use sss_bssrdf::fresnel::ft_dielectric;

    /// Snell's law (η_i sin θ_i = η_t sin θ_t), the plane of incidence, and the Fresnel value of
    /// the bssrdf crate, both ways across the interface.
    #[test]
    fn refraction_obeys_snell_both_ways() {
        let n = DVec3::Z;
        let eta = 1.3;
        for deg in [0.0f64, 10.0, 35.0, 50.0, 75.0, 89.0] {
            let th = deg.to_radians();
            // From outside, travelling down.
            let d = DVec3::new(th.sin(), 0.0, -th.cos());
            let (f, t) = fresnel(d, n, eta);
            let t = t.unwrap();
            assert!((f - 1.0 + ft_dielectric(th.cos(), eta)).abs() < 1e-12);
            assert!(t.z < 0.0 && t.y.abs() < 1e-12);
            assert!((th.sin() - eta * t.x).abs() < 1e-12, "{deg}");
            // And back out along the reversed refracted ray: the original direction reversed.
            let (f2, back) = fresnel(-t, n, eta);
            let back = back.unwrap();
            assert!((back + d).length() < 1e-12, "{deg}: {back}");
            assert!((f2 - f).abs() < 1e-12, "reciprocal Fresnel");
        }
        // Beyond the critical angle from inside: total internal reflection.
        let crit = (1.0f64 / eta).asin();
        let th = crit + 0.01;
        let d = DVec3::new(th.sin(), 0.0, th.cos());
        assert_eq!(fresnel(d, n, eta), (1.0, None));
        let c = cross_dielectric(d, n, eta, 0.999);
        assert!(!c.refracted && (c.dir - DVec3::new(th.sin(), 0.0, -th.cos())).length() < 1e-12);
    }

    #[test]
    fn the_fresnel_choice_splits_by_u() {
        let d = DVec3::new(0.6, 0.0, -0.8);
        let (f, _) = fresnel(d, DVec3::Z, 1.5);
        assert!(!cross_dielectric(d, DVec3::Z, 1.5, f * 0.99).refracted);
        assert!(cross_dielectric(d, DVec3::Z, 1.5, f * 1.01).refracted);
    }

    /// Cosine-weighted directions: ⟨cos⟩ = 2/3 and ⟨cos²⟩ = 1/2.
    #[test]
    fn cosine_directions_have_the_lambertian_moments() {
        let n = DVec3::new(1.0, 2.0, -2.0).normalize();
        let k = 300;
        let (mut m1, mut m2) = (0.0, 0.0);
        for i in 0..k {
            for j in 0..k {
                let w =
                    cosine_direction(n, (i as f64 + 0.5) / k as f64, (j as f64 + 0.5) / k as f64);
                let c = w.dot(n);
                assert!(c >= 0.0);
                m1 += c;
                m2 += c * c;
            }
        }
        let m = (k * k) as f64;
        assert!((m1 / m - 2.0 / 3.0).abs() < 1e-4 && (m2 / m - 0.5).abs() < 1e-4);
    }
}
