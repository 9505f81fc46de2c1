//! The BSSRDF probe sampler of pbrt 3rd ed. §15.4, shared by the `pathtrace` reference and
//! the gather-point pipeline of `mdlc` and `eelc` (their importance-sampled irradiance points):
//! a radius drawn from one channel's profile, mapped onto the object by a probe chord along
//! one of three axes of the local frame (normal with probability 1/2, each tangent 1/4) inside
//! the sphere that holds a given fraction of that channel's energy, and the combined density
//! of all 3 × 3 axis-channel techniques (multiple importance sampling, the balance heuristic),
//! where a technique whose probe sphere cannot reach a hit contributes nothing. The bias this
//! leaves (the energy beyond the largest sphere) is discussed in
//! [`crate::integrators::pathtrace`].

use crate::gbuffer::GSample;
use crate::geometry::{SceneGeometry, SurfaceHit};
use crate::lights::{Incident, Receiver, gather, tangent_frame};
use crate::shading::TranslucentShading;
use glam::DVec3;
use rand::RngExt;
use rand_pcg::Pcg64Mcg;
use sss_bssrdf::{Rgb, SurfacePoint};
use sss_scene::Light;
use std::f64::consts::PI;

/// The default energy fraction of each channel's profile inside its probe sphere: the
/// declared default of `--probe-energy` ([`crate::integrators::options::PROBE_ENERGY`]).
pub fn default_probe_energy() -> f64 {
    crate::integrators::options::declared(
        &[crate::integrators::options::PROBE_ENERGY],
        "probe-energy",
    )
}

/// Probabilities of the three probe axes: first tangent, second tangent, normal (pbrt).
const AXIS_PROB: [f64; 3] = [0.25, 0.25, 0.5];

/// Per-material data the sampler reuses at every shading point.
pub struct ProbeRadii {
    /// Probe-sphere radius per channel, scene units (0 for a channel that cannot be sampled).
    pub rmax: [f64; 3],
    /// Per channel, the fraction of the profile's energy (of R_d,total) beyond the largest
    /// probe radius: what the estimator never samples (at most 1 − the energy fraction).
    pub missed: [f64; 3],
}

impl ProbeRadii {
    /// The probe radii of a material whose spheres hold `energy` (in (0, 1)) of each channel's
    /// profile.
    pub fn new(shading: &TranslucentShading, energy: f64) -> Self {
        let model = shading.bssrdf();
        let mut rmax = [0.0; 3];
        for (c, r) in rmax.iter_mut().enumerate() {
            let v = model.radius_for_energy(c, energy) * shading.units_per_mm;
            *r = if v.is_finite() && v > 0.0 { v } else { 0.0 };
        }
        let rmax_all_mm = rmax.iter().copied().fold(0.0, f64::max) / shading.units_per_mm;
        let missed = std::array::from_fn(|c| {
            if rmax[c] > 0.0 {
                energy_beyond(model, c, rmax_all_mm)
            } else {
                // A channel that cannot be sampled misses all its energy (if it has any).
                if model.total_diffuse_reflectance(c) > 0.0 {
                    1.0
                } else {
                    0.0
                }
            }
        });
        ProbeRadii { rmax, missed }
    }
}

/// The probe radii of every material in `shading` (a frame's, indexed by material; `None`
/// for the opaque ones) whose spheres hold `energy` of each channel's profile, and the
/// largest energy fraction they never sample ([`ProbeRadii::missed`], over the materials and
/// channels; 0 when there is none).
pub fn probe_radii(
    shading: &[Option<TranslucentShading>],
    energy: f64,
) -> (Vec<Option<ProbeRadii>>, f64) {
    let radii: Vec<Option<ProbeRadii>> = shading
        .iter()
        .map(|s| s.as_ref().map(|s| ProbeRadii::new(s, energy)))
        .collect();
    let missed = radii
        .iter()
        .flatten()
        .flat_map(|r| r.missed)
        .fold(0.0, f64::max);
    (radii, missed)
}

/// The fraction of channel `ch`'s energy beyond radius `r_mm`: 1 − F with F the largest energy
/// fraction whose radius ([`Bssrdf::radius_for_energy`](sss_bssrdf::Bssrdf::radius_for_energy),
/// non-decreasing in F) is at most `r_mm`, found by bisection on F (60 halvings: F to ~1e-18,
/// below the f64 resolution of fractions near 1). An upper bound (never below the true
/// fraction by more than the bisection's resolution); in [0, 1].
fn energy_beyond(model: &dyn sss_bssrdf::Bssrdf, ch: usize, r_mm: f64) -> f64 {
    if !(r_mm > 0.0) {
        return 1.0;
    }
    let (mut lo, mut hi) = (0.0f64, 1.0f64);
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if model.radius_for_energy(ch, mid) <= r_mm {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    (1.0 - lo).clamp(0.0, 1.0)
}

/// Density per unit plane area (scene units²) of channel `ch`'s radial sampling at radius `r`
/// (scene units).
fn plane_pdf(shading: &TranslucentShading, ch: usize, r: f64, rmax: f64) -> f64 {
    let u = shading.units_per_mm;
    let r_mm = (r / u).max(rmax / u * 1e-9).max(1e-300);
    let p = shading.bssrdf().pdf_sr(ch, r_mm) / (2.0 * PI * r_mm) / (u * u);
    if p.is_finite() && p > 0.0 { p } else { 0.0 }
}

/// Hits of `object` along the line `origin + t·dir`, t in [0, len], in order of t.
fn chord_hits(
    geom: &SceneGeometry,
    object: u32,
    origin: DVec3,
    dir: DVec3,
    len: f64,
    out: &mut Vec<(f64, SurfaceHit)>,
) {
    out.clear();
    let eps = geom.epsilon();
    let mut t0 = 0.0;
    while out.len() < 64 {
        match geom.closest_hit_on(object, origin, dir, t0, len) {
            Some(h) => {
                out.push((h.t, h));
                t0 = h.t + eps;
            }
            None => break,
        }
    }
}

/// The three probe axes at a shading normal: two tangents and the normal.
fn axes(n: DVec3) -> [DVec3; 3] {
    let (s, t) = tangent_frame(n);
    [s, t, n]
}

/// Hits along a chord: (distance from the chord's start, hit).
pub type ChordHits = Vec<(f64, SurfaceHit)>;

/// Reusable buffers of one worker, so sampling does not allocate.
#[derive(Default)]
pub struct Scratch {
    hits: ChordHits,
    chord: ChordHits,
    packets: Vec<Incident>,
}

/// The sampled chord, reused for its own axis in [`Sampler::combined_pdf`]: its axis index,
/// its hits and its start point.
struct KnownChord<'h> {
    axis: usize,
    hits: &'h [(f64, SurfaceHit)],
    base: DVec3,
}

/// What the sampler needs of the scene and of one material.
pub struct Sampler<'a> {
    /// Ray casting.
    pub geom: &'a SceneGeometry,
    /// The scene's lights.
    pub lights: &'a [Light],
    /// The material's model and units.
    pub shading: &'a TranslucentShading,
    /// The material's probe radii.
    pub radii: &'a ProbeRadii,
}

impl Sampler<'_> {
    /// Combined density (per unit area, scene units²) of sampling `pi` from `po` over all nine
    /// techniques, counting for each technique the hits on its chord through `pi`.
    fn combined_pdf(
        &self,
        object: u32,
        po: DVec3,
        axes: &[DVec3; 3],
        pi: &SurfaceHit,
        known: KnownChord<'_>,
        scratch: &mut ChordHits,
    ) -> f64 {
        let (geom, shading, radii) = (self.geom, self.shading, self.radii);
        let d = pi.p - po;
        let dist2 = d.length_squared();
        let rmax_all = radii.rmax.iter().copied().fold(0.0, f64::max);
        let mut pdf = 0.0;
        for (a, v) in axes.iter().enumerate() {
            let along = d.dot(*v);
            let rproj2 = (dist2 - along * along).max(0.0);
            let rproj = rproj2.sqrt();
            let cos = pi.ng.dot(*v).abs();
            if !(cos > 0.0) || rproj > rmax_all {
                continue;
            }
            // Hits along the line through pi parallel to v, as signed offsets from the point of
            // the line closest to po (where the chords are centred).
            let centre = po + (d - *v * along);
            let offsets: Vec<f64> = if known.axis == a {
                let base = known.base;
                known
                    .hits
                    .iter()
                    .map(|(_, h)| (h.p - base).dot(*v) - (centre - base).dot(*v))
                    .collect()
            } else {
                let half = (rmax_all * rmax_all - rproj2).max(0.0).sqrt();
                let base = centre - *v * half;
                chord_hits(geom, object, base, *v, 2.0 * half, scratch);
                scratch.iter().map(|(t, _)| t - half).collect()
            };
            for ch in 0..3 {
                let rmax = radii.rmax[ch];
                if !(rmax > 0.0) || dist2 > rmax * rmax || rproj > rmax {
                    continue;
                }
                let half2 = rmax * rmax - rproj2;
                let n = offsets.iter().filter(|o| **o * **o <= half2).count().max(1);
                pdf += AXIS_PROB[a] / 3.0 * plane_pdf(shading, ch, rproj, rmax) * cos / n as f64;
            }
        }
        pdf
    }

    /// One BSSRDF importance-sampled point on `g`'s object around `g` (King et al. 2013, pbrt
    /// 3rd ed. §15.4: an axis and a channel, a radius from that channel's profile, one of the
    /// probe chord's hits chosen uniformly) and its combined density per unit area over the
    /// nine axis-channel techniques (finite, > 0); `None` when the probe finds no point (such
    /// draws still count in an average). The irradiance points of the `mdlc` and `eelc`
    /// baselines are drawn here.
    pub fn sample_point(
        &self,
        g: &GSample,
        rng: &mut Pcg64Mcg,
        scratch: &mut Scratch,
    ) -> Option<(SurfaceHit, f64)> {
        let (geom, shading, radii) = (self.geom, self.shading, self.radii);
        let Scratch { hits, chord, .. } = scratch;
        let ax = axes(g.n);
        // Choose axis and channel.
        let u1: f64 = rng.random();
        let (a, vx, vy) = if u1 < 0.5 {
            (2, ax[0], ax[1])
        } else if u1 < 0.75 {
            (0, ax[1], ax[2])
        } else {
            (1, ax[2], ax[0])
        };
        let vz = ax[a];
        let ch = rng.random_range(0..3usize);
        let rmax = radii.rmax[ch];
        if !(rmax > 0.0) {
            return None;
        }
        let u = shading.units_per_mm;
        let r = shading.bssrdf().sample_sr(ch, rng.random::<f64>()) * u;
        if !(r.is_finite() && r >= 0.0) || r > rmax {
            return None;
        }
        let phi = 2.0 * PI * rng.random::<f64>();
        let rmax_all = radii.rmax.iter().copied().fold(0.0, f64::max);
        let half_all = (rmax_all * rmax_all - r * r).max(0.0).sqrt();
        let centre = g.p + (vx * phi.cos() + vy * phi.sin()) * r;
        let base = centre - vz * half_all;
        chord_hits(geom, g.object, base, vz, 2.0 * half_all, hits);
        // This technique's chord is the part inside its own channel's sphere.
        let half = (rmax * rmax - r * r).max(0.0).sqrt();
        let mine: Vec<usize> = (0..hits.len())
            .filter(|&k| (hits[k].0 - half_all).abs() <= half)
            .collect();
        if mine.is_empty() {
            return None;
        }
        let pick = mine[rng.random_range(0..mine.len())];
        let pi = hits[pick].1;
        let known = KnownChord {
            axis: a,
            hits: hits.as_slice(),
            base,
        };
        let pdf = self.combined_pdf(g.object, g.p, &ax, &pi, known, chord);
        if !(pdf > 0.0) || !pdf.is_finite() {
            return None;
        }
        Some((pi, pdf))
    }

    /// One path-traced estimate of the subsurface radiance leaving `g` (0 when the probe finds no
    /// point; such samples still count).
    pub fn sample(&self, g: &GSample, rng: &mut Pcg64Mcg, scratch: &mut Scratch) -> Rgb {
        let (geom, lights, shading) = (self.geom, self.lights, self.shading);
        let Some((pi, pdf)) = self.sample_point(g, rng, scratch) else {
            return [0.0; 3];
        };
        let packets = &mut scratch.packets;
        let u = shading.units_per_mm;
        // Direct light at the exit point.
        packets.clear();
        let at = Receiver {
            p: pi.p,
            n: pi.n,
            ng: pi.ng,
        };
        gather(geom, lights, at, 1, rng, packets);
        if packets.is_empty() {
            return [0.0; 3];
        }
        if let Some(c) = &shading.collision {
            c.scale_entering(geom, pi.object, (pi.p, pi.n, pi.ng), packets);
        }
        let tex = shading.texture_at(pi.p);
        let mut out = [0.0; 3];
        if shading.directional() {
            let xo = SurfacePoint { p: g.p / u, n: g.n };
            let xi = SurfacePoint {
                p: pi.p / u,
                n: pi.n,
            };
            let s_area = 1.0 / (u * u * pdf);
            let model = shading.bssrdf();
            for packet in packets.iter() {
                let sv = model.s(&xi, packet.dir, &xo, g.wo);
                for c in 0..3 {
                    out[c] += sv[c] * packet.e_cos[c] * tex[c] * s_area;
                }
            }
        } else {
            let e = if shading.drift.is_some() {
                // Each packet moved by the drift ([`TranslucentShading::entering_towards`]).
                for packet in packets.iter_mut() {
                    for c in 0..3 {
                        packet.e_cos[c] *= tex[c];
                    }
                }
                shading.entering_towards(packets, (pi.p, pi.n), (g.p, g.n, g.wo))
            } else {
                shading.weights.entering(packets, pi.n, tex)
            };
            let rd = shading.rd_scene((pi.p - g.p).length());
            let w = shading.exit_weights(g.n, g.wo);
            for c in 0..3 {
                out[c] = rd[c] * e[c] * (w[c] / pdf);
            }
        }
        if out.iter().all(|v| v.is_finite()) {
            out
        } else {
            [0.0; 3]
        }
    }
}
