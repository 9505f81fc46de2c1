//! The light a path sees when it leaves the translucent objects: quad lights hit by the ray
//! (one-sided, no geometry: quads block nothing in this renderer, as in its shadow rays) and
//! the environment and the suns' discs where the ray leaves the scene.

use crate::lights::{background, quad_area_normal, sun_radiance};
use glam::DVec3;
use sss_bssrdf::Rgb;
use sss_scene::Light;

/// One quad light, ready for ray tests.
#[derive(Clone, Debug)]
struct Quad {
    corner: DVec3,
    edge_u: DVec3,
    edge_v: DVec3,
    /// edge_u × edge_v (not normalised) and its squared length.
    cross: DVec3,
    cross2: f64,
    /// Unit normal: the side it emits towards.
    normal: DVec3,
    radiance: Rgb,
}

/// The lights a path can hit.
#[derive(Clone, Debug)]
pub struct Emitters {
    quads: Vec<Quad>,
    /// The environment lights' summed radiance.
    environment: Rgb,
    /// The suns: (unit direction towards the disc's centre, cosine of its angular radius,
    /// radiance).
    suns: Vec<(DVec3, f64, Rgb)>,
}

impl Emitters {
    /// The quad, sun and environment lights of `lights` (point and directional lights cannot
    /// be hit by a ray).
    pub fn new(lights: &[Light]) -> Self {
        let suns = lights
            .iter()
            .filter_map(|l| match l {
                Light::Sun {
                    direction,
                    irradiance,
                    half_angle,
                } => {
                    let (radiance, _) = sun_radiance(*irradiance, *half_angle)?;
                    Some((-*direction, half_angle.cos(), radiance))
                }
                _ => None,
            })
            .collect();
        let quads = lights
            .iter()
            .filter_map(|l| match l {
                Light::Quad {
                    corner,
                    edge_u,
                    edge_v,
                    radiance,
                } => {
                    let (_, normal) = quad_area_normal(*edge_u, *edge_v)?;
                    let cross = edge_u.cross(*edge_v);
                    Some(Quad {
                        corner: *corner,
                        edge_u: *edge_u,
                        edge_v: *edge_v,
                        cross,
                        cross2: cross.length_squared(),
                        normal,
                        radiance: *radiance,
                    })
                }
                _ => None,
            })
            .collect();
        Emitters {
            quads,
            environment: background(lights),
            suns,
        }
    }

    /// The radiance arriving along the ray `origin + t·dir` (unit `dir`) from the quad lights
    /// it crosses on their emitting side at t in (0, `t_max`), summed.
    pub fn quads_hit(&self, origin: DVec3, dir: DVec3, t_max: f64) -> Rgb {
        let mut l = [0.0; 3];
        for q in &self.quads {
            let cos = dir.dot(q.normal);
            // Only the emitting side (the ray travels against the normal).
            if !(cos < 0.0) {
                continue;
            }
            let t = (q.corner - origin).dot(q.normal) / cos;
            if !(t > 0.0 && t < t_max) {
                continue;
            }
            // w = s·edge_u + t·edge_v: s = (w × edge_v)·N/|N|², t = (edge_u × w)·N/|N|².
            let w = origin + dir * t - q.corner;
            let s = w.cross(q.edge_v).dot(q.cross) / q.cross2;
            let r = q.edge_u.cross(w).dot(q.cross) / q.cross2;
            if (0.0..=1.0).contains(&s) && (0.0..=1.0).contains(&r) {
                for c in 0..3 {
                    l[c] += q.radiance[c];
                }
            }
        }
        l
    }

    /// The radiance of a ray that leaves the scene along the unit `dir`: the environment, and
    /// every sun whose disc `dir` points into.
    pub fn escaped(&self, dir: DVec3) -> Rgb {
        let mut l = self.environment;
        for (axis, cos_max, radiance) in &self.suns {
            if dir.dot(*axis) >= *cos_max {
                for c in 0..3 {
                    l[c] += radiance[c];
                }
            }
        }
        l
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_quad_is_hit_inside_on_its_emitting_side_only() {
        // A 2 × 1 quad in z = 5 emitting down (edge_u × edge_v = −z).
        let e = Emitters::new(&[Light::Quad {
            corner: DVec3::new(-1.0, 0.0, 5.0),
            edge_u: DVec3::new(0.0, 1.0, 0.0),
            edge_v: DVec3::new(2.0, 0.0, 0.0),
            radiance: [1.0, 2.0, 3.0],
        }]);
        let up = DVec3::Z;
        assert_eq!(
            e.quads_hit(DVec3::new(0.5, 0.5, 0.0), up, f64::INFINITY),
            [1.0, 2.0, 3.0]
        );
        // Outside the edges, beyond t_max, from behind.
        assert_eq!(
            e.quads_hit(DVec3::new(1.5, 0.5, 0.0), up, f64::INFINITY),
            [0.0; 3]
        );
        assert_eq!(
            e.quads_hit(DVec3::new(0.5, 1.5, 0.0), up, f64::INFINITY),
            [0.0; 3]
        );
        assert_eq!(e.quads_hit(DVec3::new(0.5, 0.5, 0.0), up, 4.0), [0.0; 3]);
        assert_eq!(
            e.quads_hit(DVec3::new(0.5, 0.5, 9.0), -up, f64::INFINITY),
            [0.0; 3]
        );
        assert_eq!(e.escaped(DVec3::Z), [0.0; 3]);
    }

    /// A ray leaving the scene sees the environment, plus a sun's radiance
    /// E / (π sin² α) inside its disc (angular radius α about the direction it comes from)
    /// and nothing of it outside.
    #[test]
    fn escaping_rays_see_the_suns_disc() {
        let alpha = 0.1f64;
        let e = Emitters::new(&[
            Light::Sun {
                direction: DVec3::new(0.0, 0.0, -1.0),
                irradiance: [1.0, 2.0, 4.0],
                half_angle: alpha,
            },
            Light::Environment { radiance: [0.5; 3] },
        ]);
        let l = 1.0 / (std::f64::consts::PI * alpha.sin().powi(2));
        let inside = DVec3::new((0.99 * alpha).sin(), 0.0, (0.99 * alpha).cos());
        let outside = DVec3::new((1.01 * alpha).sin(), 0.0, (1.01 * alpha).cos());
        let got = e.escaped(inside);
        for (c, k) in [1.0, 2.0, 4.0].iter().enumerate() {
            assert!((got[c] - (0.5 + k * l)).abs() < 1e-12 * k * l, "{got:?}");
        }
        assert_eq!(e.escaped(outside), [0.5; 3]);
        assert_eq!(e.escaped(-DVec3::Z), [0.5; 3]);
    }
}
