//! Each surface point's own ball (`sphere_radius = "local"`): the radius of the medium around
//! a point, from the chords the object's mesh cuts into it.
//!
//! `sphere_radius = "auto"` gives a material one ball, of radius 3 V/A, and a shape of many
//! sizes cannot hold one radius: a thin ear takes the body's ball and comes out dark, a small
//! ball's gain lands on a thick body. Here each point x gets
//!
//! R(x) = 3/4 · E[t(x, ω)], ω cosine-distributed about the inward normal,
//!
//! t the distance from x along ω to the object's surface. By Cauchy's mean chord formula the
//! cosine-weighted (μ-random) chords of a convex body have mean 4V/A (Santaló, *Integral
//! Geometry and Geometric Probability*, 1976, §I.4), so on a ball R(x) is its radius at every
//! point (chord 2R cos θ, mean 4R/3), averaged over any convex body's surface it is 3 V/A, the
//! value of `"auto"`, and on a slab of thickness d it is 3d/2 (chord d/cos θ, mean 2d): a slab
//! of thickness d holds about as much medium within reach as a ball of radius 3d/2, not d/2
//! (the one-chord radius along the normal, measured too bright on thin parts). A pair
//! (x_i, x_o) takes the ball of radius √(R(x_i) R(x_o)) ([`sss_bssrdf::BallFamily`]), the
//! same for both orders.
//!
//! The chords are [`CHORD_RAYS`] rays per point on a fixed Hammersley pattern (deterministic,
//! whatever the thread count). A ray that leaves the mesh without a hit (an open mesh) is left
//! out; a point with fewer than half its rays hitting has no radius and keeps the half-space's
//! profile.

use crate::Error;
use crate::frame::Frame;
use crate::geometry::SceneGeometry;
use crate::irradiance::ObjectSamples;
use glam::DVec3;
use rayon::prelude::*;
use sss_bssrdf::BallFamily;

/// Rays per point.
pub const CHORD_RAYS: u32 = 64;

/// The radius (scene units) of the ball around the point `p` (unit outward normal `n`) of
/// object `object`: 3/4 of its mean cosine-weighted chord, or `None` when fewer than half the
/// rays meet the object again (see the module documentation).
pub fn local_radius(geom: &SceneGeometry, object: u32, p: DVec3, n: DVec3) -> Option<f64> {
    let inward = -n;
    if !(inward.is_finite() && inward.length_squared() > 0.5) {
        return None;
    }
    let (a, b) = inward.any_orthonormal_pair();
    let origin = geom.offset(p, n, inward);
    let (mut sum, mut hits) = (0.0, 0u32);
    for i in 0..CHORD_RAYS {
        // Hammersley point (i + 1/2)/N, radical inverse of i; cosine-distributed (Malley).
        let u1 = (f64::from(i) + 0.5) / f64::from(CHORD_RAYS);
        let u2 = f64::from(i.reverse_bits()) / 4_294_967_296.0;
        let (s, phi) = (u1.sqrt(), std::f64::consts::TAU * u2);
        let dir = a * (s * phi.cos()) + b * (s * phi.sin()) + inward * (1.0 - u1).sqrt();
        if let Some(h) = geom.closest_hit_on(object, origin, dir, 0.0, f64::INFINITY) {
            sum += h.t;
            hits += 1;
        }
    }
    (2 * hits >= CHORD_RAYS && sum > 0.0).then(|| 0.75 * sum / f64::from(hits))
}

/// One object's balls: its family of deltas and each of its irradiance samples' radius.
pub struct LocalBalls {
    /// The deltas over the radii of the object's samples and shaded points.
    pub family: BallFamily,
    /// Per irradiance sample (in the object's order) its radius in mm; NaN without one.
    pub samples: Vec<f64>,
}

/// The balls of a frame: per G-buffer sample its radius in mm (NaN off `"local"`
/// materials or without one), and per object (indexed by object) its [`LocalBalls`] where its
/// material asks for them. Timed as stage `local_radius`; errors only if a walk does.
pub struct FrameBalls {
    /// Per G-buffer sample, its radius (mm) or NaN.
    pub points: Vec<f64>,
    /// Per object, its balls or `None`.
    pub objects: Vec<Option<LocalBalls>>,
}

impl FrameBalls {
    /// Whether any object of the frame has its balls.
    pub fn any(&self) -> bool {
        self.objects.iter().any(Option::is_some)
    }

    /// Per pixel of `frame`, the mean radius (mm) of its G-buffer samples that have one, 0
    /// where none has (the same value in the three channels): the layer `local_radius`.
    pub fn pixel_radii(&self, frame: &Frame<'_>) -> Vec<sss_bssrdf::Rgb> {
        let gb = &frame.gbuffer;
        (0..gb.pixels())
            .map(|i| {
                let range = gb.offsets[i] as usize..gb.offsets[i + 1] as usize;
                let (sum, n) = self
                    .points
                    .get(range)
                    .unwrap_or(&[])
                    .iter()
                    .filter(|r| r.is_finite())
                    .fold((0.0, 0u32), |(s, n), r| (s + r, n + 1));
                let mean = if n > 0 { sum / f64::from(n) } else { 0.0 };
                [mean; 3]
            })
            .collect()
    }

    /// The number of ball radii walked for the frame, over its objects.
    pub fn nodes(&self) -> usize {
        self.objects
            .iter()
            .flatten()
            .map(|b| b.family.radii().len())
            .sum()
    }
}

/// The [`FrameBalls`] of `frame` with its irradiance samples `by_object` (indexed by object).
pub fn frame_balls(
    frame: &Frame<'_>,
    by_object: &[Option<&ObjectSamples>],
) -> Result<FrameBalls, Error> {
    let local = |o: u32| frame.shading_of(o).is_some_and(|sh| sh.local_radius);
    let n = frame.scene.objects.len();
    if !frame.visible.iter().any(|&o| local(o)) {
        return Ok(FrameBalls {
            points: Vec::new(),
            objects: (0..n).map(|_| None).collect(),
        });
    }
    frame.timed("local_radius", || {
        let mm = |o: u32, r: Option<f64>| {
            let u = frame.shading_of(o).map_or(1.0, |sh| sh.units_per_mm);
            r.map_or(f64::NAN, |r| r / u)
        };
        let points: Vec<f64> = frame
            .gbuffer
            .samples
            .par_iter()
            .map(|g| {
                if local(g.object) {
                    mm(g.object, local_radius(&frame.geom, g.object, g.p, g.n))
                } else {
                    f64::NAN
                }
            })
            .collect();
        let mut objects: Vec<Option<LocalBalls>> = (0..n).map(|_| None).collect();
        for (o, slot) in objects.iter_mut().enumerate() {
            let o = o as u32;
            let (Some(sh), Some(s)) = (frame.shading_of(o), by_object[o as usize]) else {
                continue;
            };
            if !sh.local_radius {
                continue;
            }
            let samples: Vec<f64> = s
                .samples
                .par_iter()
                .map(|p| mm(o, local_radius(&frame.geom, o, p.position, p.normal)))
                .collect();
            let own = points
                .iter()
                .zip(&frame.gbuffer.samples)
                .filter(|(_, g)| g.object == o)
                .map(|(r, _)| *r);
            let (lo, hi) = samples
                .iter()
                .copied()
                .chain(own)
                .filter(|r| r.is_finite() && *r > 0.0)
                .fold((f64::INFINITY, 0.0f64), |(lo, hi), r| {
                    (lo.min(r), hi.max(r))
                });
            if !(lo <= hi) {
                continue;
            }
            // Radii under a quarter of the smallest reduced mean free path read the smallest
            // node there: the walk's bins start at a tenth of it.
            let medium = sh.bssrdf().medium();
            let floor = (0..3)
                .map(|c| medium.reduced_mean_free_path(c))
                .filter(|v| v.is_finite() && *v > 0.0)
                .fold(f64::INFINITY, f64::min)
                * 0.25;
            let lo = if floor.is_finite() { lo.max(floor) } else { lo };
            let family = if sh.local_drift {
                BallFamily::with_drift(medium, lo, hi.max(lo))?
            } else {
                BallFamily::new(medium, lo, hi.max(lo))?
            };
            *slot = Some(LocalBalls { family, samples });
        }
        Ok(FrameBalls { points, objects })
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use sss_scene::{LoadOptions, load_str};

    fn geometry(objects: &str) -> SceneGeometry {
        let text = format!(
            "[camera]\nposition = [0.0, 0.0, 50.0]\ntarget = [0.0, 0.0, 0.0]\nfov = 30.0\n\
             resolution = [8, 8]\n\n[[lights]]\ntype = \"environment\"\nradiance = 1.0\n\n\
             [materials.skin]\ntype = \"translucent\"\nmodel = \"mc-table\"\npreset = \"skin1\"\n\
             units_per_mm = 1.0\n\n{objects}"
        );
        let scene = load_str(&text, "local.toml", None, &LoadOptions::default()).unwrap();
        SceneGeometry::new(&scene)
    }

    #[test]
    fn a_ball_has_its_own_radius_at_every_point() {
        // Cauchy: the cosine-weighted chords of a ball of radius R have mean 4R/3.
        let g = geometry(
            "[[objects]]\nmaterial = \"skin\"\nshape = \"sphere\"\nradius = 5.0\n\
             subdivisions = 6\n",
        );
        for d in [
            DVec3::X,
            DVec3::new(1.0, 2.0, -0.5),
            DVec3::new(-0.3, -1.0, 0.2),
        ] {
            let n = d.normalize();
            // The tessellated sphere's surface lies within 5 · 10⁻³ of the radius here.
            let r = local_radius(&g, 0, 5.0 * n * 0.9995, n).unwrap();
            assert!((r / 5.0 - 1.0).abs() < 0.01, "{n}: {r}");
        }
    }

    #[test]
    fn a_slab_reads_three_halves_of_its_thickness() {
        // Chord d/cos θ, cosine-weighted mean 2d: R = 3d/2. The fixed pattern's midpoint rule
        // misses part of the integrable 1/cos θ near grazing, about 3.7 % of it at 64 rays
        // (the last cell's ∫(1 − u)^(−1/2) is 0.25/64 against its midpoint's 0.177/64).
        let g = geometry(
            "[[objects]]\nmaterial = \"skin\"\nshape = \"box\"\nsize = [400.0, 2.0, 400.0]\n",
        );
        let r = local_radius(&g, 0, DVec3::new(3.0, 1.0, -7.0), DVec3::Y).unwrap();
        // The pattern's own sum of d/cos θ: cos θ = √(1 − u₁), u₁ = (i + 1/2)/N.
        let n = f64::from(CHORD_RAYS);
        let pattern = (0..CHORD_RAYS)
            .map(|i| 2.0 / (1.0 - (f64::from(i) + 0.5) / n).sqrt())
            .sum::<f64>()
            / n;
        // The rays start 4 · 10⁻⁶ of the scene's extent (1.6 · 10⁻³ here) inside the
        // surface, which shortens each chord by that over its cos θ: 0.08 % of the mean.
        let want = 0.75 * pattern;
        assert!((r / want - 1.0).abs() < 2e-3, "{r} vs {want}");
        assert!((r / 3.0 - 1.0).abs() < 0.05, "{r}");
        assert!(r < 3.0);
    }

    /// A radius needs at least half the rays to meet the object: from 3 radii off a unit ball,
    /// facing it, a ninth of the cosine-weighted rays do (sin² 19.5°); on the ball with the
    /// normal tilted 60° off the true one, more than half do (the half-space
    /// cos 60° √(1 − ρ²) + sin 60° x > 0 of the projected unit disk).
    #[test]
    fn half_the_rays_decide() {
        let g = geometry(
            "[[objects]]\nmaterial = \"skin\"\nshape = \"sphere\"\nradius = 1.0\n\
             subdivisions = 5\n",
        );
        assert_eq!(
            local_radius(&g, 0, DVec3::new(0.0, 0.0, 3.0), DVec3::Z),
            None
        );
        let tilted = DVec3::new(0.5, 0.75f64.sqrt(), 0.0);
        // Just outside the tessellated ball (its surface lies within the sphere), so the
        // rays leaving away from it miss.
        assert!(local_radius(&g, 0, DVec3::X * 1.001, tilted).is_some());
    }

    #[test]
    fn an_open_surface_has_no_radius() {
        let g =
            geometry("[[objects]]\nmaterial = \"skin\"\nshape = \"plane\"\nsize = [10.0, 10.0]\n");
        assert_eq!(local_radius(&g, 0, DVec3::ZERO, DVec3::Y), None);
        // A normal that is no direction neither.
        let g = geometry("[[objects]]\nmaterial = \"skin\"\nshape = \"sphere\"\nradius = 1.0\n");
        assert_eq!(local_radius(&g, 0, DVec3::X, DVec3::ZERO), None);
        // From the centre, where every ray in any direction would meet the ball.
        assert_eq!(local_radius(&g, 0, DVec3::ZERO, DVec3::ZERO), None);
        assert_eq!(local_radius(&g, 0, DVec3::X, DVec3::splat(f64::NAN)), None);
    }
}
