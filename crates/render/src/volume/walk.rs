//! One path of the volumetric path tracer, from a camera hit on a translucent object back to
//! the lights (pbrt 3rd ed. §15.3; pbrt-v4's `VolPathIntegrator` for the chromatic media).
//!
//! - **Camera vertex.** The light leaving the G-buffer point towards the camera that crossed
//!   the boundary there: with the dielectric boundary the path refracts in and its result is
//!   multiplied by 1 − F(η, cos θ_o) (the specular reflection at that point is not part of the
//!   subsurface term, like every model's); with the Lambertian boundary it enters in a
//!   cosine-weighted direction with weight 1.
//! - **Inside** a homogeneous medium (the object's closed mesh): free flights sampled in the
//!   hero channel ([`super::spectral`]), collisions scattered by Henyey–Greenstein, Russian
//!   roulette on the path weight (the camera vertex's transmittance left out) once it falls
//!   below 1. No cap on the number of collisions
//!   unless `--max-events` sets one. With `--scattering single` or `multiple`, light reaching
//!   the path counts only if the path's collisions so far are of those orders ([`Scattering`];
//!   a single-scattering path ends at its second collision).
//! - **At the boundary from inside**, dielectric: reflected with probability F (total
//!   internal reflection included), refracted out otherwise; the pre-scatter texture is
//!   applied where the light leaves (where, following the light, it entered). Lambertian: the
//!   path leaves and gathers the direct light there (shadow rays to every light, delta lights
//!   included) with the Lambertian transmittance 1/π, and ends.
//! - **Outside** (dielectric only): the ray collects the quad lights it crosses and the
//!   environment where it leaves the scene; a translucent object it meets is entered (or
//!   reflects it) through its own boundary; an opaque surface ends the path: opaque surfaces
//!   reflect no light onto translucent objects here, as in every other method of the toolkit,
//!   which light translucent surfaces with direct light only.
//!
//! The walk inside object `o` sees only `o`'s mesh: objects must not intersect.

use super::boundary::{Boundary, cosine_direction, cross_dielectric, fresnel};
use super::emitters::Emitters;
use super::interior::Interior;
use super::spectral::SpectralWeight;
use crate::gbuffer::GSample;
use crate::geometry::SceneGeometry;
use crate::lights::{Incident, Receiver, gather};
use glam::DVec3;
use rand::RngExt;
use rand_pcg::Pcg64Mcg;
use sss_bssrdf::Rgb;
use sss_scene::Scene;
use std::f64::consts::PI;

/// What a path did, summed over paths.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct WalkCounts {
    /// Paths traced.
    pub paths: u64,
    /// Collisions (scattering events) in the media.
    pub collisions: u64,
    /// Boundary crossings and reflections, camera vertex excluded.
    pub interfaces: u64,
    /// Paths lost: a walk that found no surface of its own object ahead (an open mesh or a
    /// ray slipping between triangles).
    pub lost: u64,
    /// Paths stopped by `--max-events`.
    pub capped: u64,
}

impl WalkCounts {
    /// Adds `o`'s counts.
    pub fn add(&mut self, o: &WalkCounts) {
        self.paths += o.paths;
        self.collisions += o.collisions;
        self.interfaces += o.interfaces;
        self.lost += o.lost;
        self.capped += o.capped;
    }
}

/// Which light a path's estimate keeps, by its collisions in the media (the classic split of
/// subsurface light into single and multiple scattering, Hanrahan & Krueger 1993; Jensen et
/// al. 2001 §3): the part of the image each order carries, in real transport.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Scattering {
    /// Every path (the image).
    #[default]
    All,
    /// Paths with exactly one collision.
    Single,
    /// Paths with two collisions or more.
    Multiple,
    /// Paths with no collision: light refracted through the media and out again, attenuated
    /// but never scattered (a path ends at its first collision).
    Unscattered,
}

impl Scattering {
    /// The option's value naming it.
    pub fn name(self) -> &'static str {
        match self {
            Scattering::All => "all",
            Scattering::Single => "single",
            Scattering::Multiple => "multiple",
            Scattering::Unscattered => "unscattered",
        }
    }

    /// Whether light that reached the camera after `collisions` collisions counts.
    pub fn keeps(self, collisions: u64) -> bool {
        match self {
            Scattering::All => true,
            Scattering::Single => collisions == 1,
            Scattering::Multiple => collisions >= 2,
            Scattering::Unscattered => collisions == 0,
        }
    }
}

/// Everything a path reads.
pub struct Walker<'a> {
    /// The scene (objects' materials).
    pub scene: &'a Scene,
    /// Per-object BVHs.
    pub geom: &'a SceneGeometry,
    /// Per material, its interior (None for opaque materials).
    pub interiors: &'a [Option<Interior>],
    /// The lights a ray can hit.
    pub emitters: &'a Emitters,
    /// How light crosses the boundaries.
    pub boundary: Boundary,
    /// Collisions and interface events per path before it is stopped (None: no cap).
    pub max_events: Option<u64>,
    /// Which scattering orders the estimate keeps.
    pub scattering: Scattering,
    /// Whether a path that left a medium goes on into a translucent surface it meets (false:
    /// it ends there, so no light traded between translucent surfaces counts).
    pub reentry: bool,
}

/// Hits closer than this to a surface point `p` a ray leaves from are the surface itself:
/// 10⁻⁹ of the point's largest coordinate plus 10⁻¹² of the scene's extent.
pub fn surface_tolerance(geom: &SceneGeometry, p: DVec3) -> f64 {
    1e-9 * p.abs().max_element() + 1e-12 * geom.extent()
}

/// Where the path is.
enum Place {
    /// Inside object `o`'s medium.
    Inside(u32),
    /// Outside every translucent object.
    Outside,
}

impl Walker<'_> {
    fn tolerance(&self, p: DVec3) -> f64 {
        surface_tolerance(self.geom, p)
    }

    fn interior_of(&self, object: u32) -> Option<&Interior> {
        let m = self.scene.objects[object as usize].material;
        self.interiors.get(m).and_then(Option::as_ref)
    }

    /// One path's estimate of the radiance leaving `g` towards the camera through the
    /// boundary of `g`'s translucent object (0 for an opaque object).
    pub fn radiance(
        &self,
        g: &GSample,
        rng: &mut Pcg64Mcg,
        counts: &mut WalkCounts,
        packets: &mut Vec<Incident>,
    ) -> Rgb {
        counts.paths += 1;
        let Some(interior) = self.interior_of(g.object) else {
            return [0.0; 3];
        };
        let w = SpectralWeight::new(rng.random_range(0..3usize));
        // The camera vertex: the ray arrives along −wo. Its transmittance multiplies the
        // result instead of the path weight, so that the roulette answers to what the medium
        // absorbs only (a medium that absorbs nothing never plays it).
        let d0 = -g.wo;
        let (dir, entry) = match self.boundary {
            Boundary::Dielectric => {
                let (f, t) = fresnel(d0, g.n, interior.eta);
                let Some(t) = t else { return [0.0; 3] };
                (t, 1.0 - f)
            }
            Boundary::Lambertian => {
                // Into the side away from the camera.
                let n_in = if g.n.dot(g.wo) >= 0.0 { -g.n } else { g.n };
                (cosine_direction(n_in, rng.random(), rng.random()), 1.0)
            }
        };
        // Refracted or scattered about the shading normal to the outside of the geometric
        // surface (at grazing angles on a coarse mesh): mirrored through the geometric plane,
        // so the light still enters.
        let dir = if dir.dot(g.ng) >= 0.0 {
            (dir - g.ng * (2.0 * dir.dot(g.ng))).normalize_or(-g.ng)
        } else {
            dir
        };
        self.trace(
            Place::Inside(g.object),
            g.p,
            Some(g.ng),
            dir,
            w,
            rng,
            counts,
            packets,
        )
        .map(|v| v * entry)
    }

    /// Follows the path from `p` (on a surface of geometric normal `ng`, or inside a medium
    /// when `ng` is None) along `dir` until it ends; returns its contribution.
    #[allow(clippy::too_many_arguments)]
    fn trace(
        &self,
        mut place: Place,
        mut p: DVec3,
        mut ng: Option<DVec3>,
        mut dir: DVec3,
        mut w: SpectralWeight,
        rng: &mut Pcg64Mcg,
        counts: &mut WalkCounts,
        packets: &mut Vec<Incident>,
    ) -> Rgb {
        let mut acc = [0.0; 3];
        let mut events = 0u64;
        // Collisions so far, for `scattering`: light is kept where it reaches the path only if
        // the path's collisions up to there are of the orders asked for.
        let mut collisions = 0u64;
        let kept = |collisions: u64| {
            if self.scattering.keeps(collisions) {
                1.0
            } else {
                0.0
            }
        };
        loop {
            if let Some(cap) = self.max_events
                && events >= cap
            {
                counts.capped += 1;
                return acc;
            }
            // Rays leave surfaces from the hit point itself and ignore hits closer than a
            // tolerance far above the f64 hit's rounding and far below any mean free path
            // (the geometry's own offset, 4·10⁻⁶ of the scene's extent, would start every
            // walk that deep inside: measurably darker media in large scenes).
            let (origin, t_min) = match ng {
                Some(_) => (p, self.tolerance(p)),
                None => (p, 0.0),
            };
            match place {
                Place::Inside(o) => {
                    let Some(med) = self.interior_of(o) else {
                        return acc;
                    };
                    // Free flight in the hero channel: t = −ln(1 − ξ)/σ_t,h.
                    let xi: f64 = rng.random();
                    let t = -(1.0 - xi).ln() / med.sigma_t[w.hero];
                    // Only surfaces closer than the collision matter.
                    match self.geom.closest_hit_on(o, origin, dir, t_min, t) {
                        None => {
                            if !t.is_finite() {
                                counts.lost += 1;
                                return acc;
                            }
                            events += 1;
                            counts.collisions += 1;
                            collisions += 1;
                            // Single scattering needs nothing past the first collision, the
                            // unscattered light nothing past none.
                            if (self.scattering == Scattering::Single && collisions > 1)
                                || self.scattering == Scattering::Unscattered
                            {
                                return acc;
                            }
                            w.scatter(med.sigma_s, med.sigma_t, t);
                            p = origin + dir * t;
                            ng = None;
                            // Russian roulette once the weight falls below 1.
                            let q = w.weight().into_iter().fold(0.0, f64::max);
                            if q < 1.0 {
                                if !(rng.random::<f64>() < q) {
                                    return acc;
                                }
                                w.scale([1.0 / q; 3]);
                            }
                            dir = med.scatter(dir, rng.random(), rng.random());
                        }
                        Some(hit) => {
                            events += 1;
                            counts.interfaces += 1;
                            w.pass(med.sigma_t, hit.t);
                            p = hit.p;
                            ng = Some(hit.ng);
                            match self.boundary {
                                Boundary::Dielectric => {
                                    let c = cross_dielectric(dir, hit.n, med.eta, rng.random());
                                    dir = c.dir;
                                    if dir.dot(hit.ng) > 0.0 {
                                        // Out: the light entered here (followed forwards).
                                        w.scale(med.texture_at(p));
                                        place = Place::Outside;
                                    }
                                }
                                Boundary::Lambertian => {
                                    let e = self.exit_light(p, hit.n, hit.ng, rng, packets);
                                    let tex = med.texture_at(p);
                                    let wt = w.weight();
                                    let k = kept(collisions);
                                    for c in 0..3 {
                                        acc[c] += k * wt[c] * tex[c] * e[c];
                                    }
                                    return acc;
                                }
                            }
                        }
                    }
                }
                Place::Outside => {
                    let hit = self.geom.closest_hit(origin, dir, t_min, f64::INFINITY);
                    let t_obj = hit.map_or(f64::INFINITY, |h| h.t);
                    let mut le = self.emitters.quads_hit(origin, dir, t_obj);
                    let Some(hit) = hit else {
                        let env = self.emitters.escaped(dir);
                        for c in 0..3 {
                            le[c] += env[c];
                        }
                        let wt = w.weight();
                        let k = kept(collisions);
                        for c in 0..3 {
                            acc[c] += k * wt[c] * le[c];
                        }
                        return acc;
                    };
                    let wt = w.weight();
                    let k = kept(collisions);
                    for c in 0..3 {
                        acc[c] += k * wt[c] * le[c];
                    }
                    // An opaque surface ends the path (and the Lambertian boundary never
                    // leaves a path outside).
                    let Some(med) = self.interior_of(hit.object) else {
                        return acc;
                    };
                    if self.boundary == Boundary::Lambertian || !self.reentry {
                        return acc;
                    }
                    events += 1;
                    counts.interfaces += 1;
                    let c = cross_dielectric(dir, hit.n, med.eta, rng.random());
                    dir = c.dir;
                    p = hit.p;
                    ng = Some(hit.ng);
                    if dir.dot(hit.ng) < 0.0 {
                        place = Place::Inside(hit.object);
                    }
                }
            }
        }
    }

    /// The radiance leaving a Lambertian boundary inwards at `p` per unit path weight: the
    /// direct irradiance there (one light sample per area light) over π.
    fn exit_light(
        &self,
        p: DVec3,
        n: DVec3,
        ng: DVec3,
        rng: &mut Pcg64Mcg,
        packets: &mut Vec<Incident>,
    ) -> Rgb {
        packets.clear();
        gather(
            self.geom,
            &self.scene.lights,
            Receiver { p, n, ng },
            1,
            rng,
            packets,
        );
        let mut e = [0.0; 3];
        for k in packets.iter() {
            for c in 0..3 {
                e[c] += k.e_cos[c] / PI;
            }
        }
        e
    }
}
