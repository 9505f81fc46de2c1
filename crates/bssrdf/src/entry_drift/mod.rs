//! Where light entering at an angle comes out: the first azimuthal harmonic of the random
//! walk's exit density, relative to the direction the light was travelling.
//!
//! A radial model sends the light entering at x_i equally in every direction along the
//! surface: S depends on |x_o − x_i| only. Light that enters obliquely does not forget its
//! direction at once: refracted, it goes on along the surface's tangent for about a mean free
//! path before it scatters, and its first collisions are forward of the entry point, so more
//! of it leaves ahead of x_i (along the light's direction) than behind. On a flat half-space
//! under even light this redistribution cancels; on a curved object lit from one side it does
//! not: light entering a sphere's lit cap near its terminator travels on towards the far side,
//! where a radial model sends half of it back towards the light. (The directional dipole of
//! Frisvad et al. 2014 carries the same effect in closed form; here it comes from the walk.)
//!
//! # The factor
//! The walk ([`crate::monte_carlo`]'s, analog absorption, in the half-space or in the ball of
//! [`crate::sphere_profile`]) starts with the beam refracted from an outside angle θ_i, its
//! direction along the surface +x, and tallies each escaping weight w at its exit point by its
//! chord r and the azimuth φ of the exit point about the entry normal (from +x). The exit
//! density ρ(r, φ) is summarised by its first harmonic,
//!
//! ρ(r, φ) ≈ ρ₀(r) (1 + k(r, θ_i) cos φ),  k = 2 ∫ρ cos φ dφ / ∫ρ dφ = 2 Σ w cos φ / Σ w
//!
//! per chord bin. A renderer multiplies the model's S, per incident direction, by
//!
//! 1 + k(r, θ_i) cos φ_i + k(r, θ_o) cos φ_o  ([`EntryDrift::factor`]; both k scaled down to |k_i| + |k_o| ≤ 1),
//!
//! φ_i between the light's direction of travel along the surface at x_i and the direction from
//! x_i towards x_o along it. The exit's term is the entry's by reciprocity (S is unchanged
//! when entry and exit swap and the directions reverse, Helmholtz): φ_o between the view
//! ray's direction of travel along the surface at x_o (−ω_o's) and the direction from x_o
//! towards x_i along it: light seen at a grazing angle comes mostly from ahead of the view
//! ray. Each term averages to 0 over its azimuth, so the walk's marginal (over exit
//! directions) is kept, and whatever the model returns over a whole annulus (its total, its
//! energy radii, its sampling) is unchanged: the factor only moves light around. It is 1 at
//! normal incidence and normal exit. The product (1 + k_i cos φ_i)(1 + k_o cos φ_o), as
//! reciprocal and with the same marginals, darkens light seen from where it came from by
//! k_i k_o: measured on a 10 mm skin1 sphere lit from the camera's side it is 13–24 % dark
//! against the volumetric path tracer where the sum is within 1.5 %.
//!
//! # Error and cost
//! k is estimated in [`BINS`] geometric chord bins (from a twentieth of a reduced mean free
//! path to 16 diffusion lengths, or to the ball's diameter if shorter) at the outside
//! incidence cosines [`COS_NODES`], [`PHOTONS`] photons per node and channel, interpolated
//! linearly in r (between bin centres) and in cos θ_i (to 0 at cos θ_i = 1). Where few photons
//! reach a bin, k is shrunk towards 0 by its standard error s (k(1 − s²/k²) when |k| > s, 0
//! otherwise), so noise does not move light; the estimate is clamped to [−1, 1], which keeps
//! 1 + k cos φ ≥ 0 (a first harmonic cannot hold a density more lopsided than that). One
//! harmonic is a truncation: very close to the entry point of grazing light (r below a mean
//! free path) the true density is more lopsided than the clamp allows. Walked once per
//! medium, ball radius and process ([`EntryDrift::cached`]).
//!
//! ```
//! use sss_bssrdf::{EntryDrift, Medium};
//! let skin1 = Medium::new([0.032, 0.17, 0.48], [0.74, 0.88, 1.01], 0.0, 1.3).unwrap();
//! let drift = EntryDrift::with_photons(&skin1, Some(10.0), 1 << 12).unwrap();
//! // Light entering at 60° leaves mostly ahead of the entry point, a mean free path away.
//! assert!(drift.k(0, 1.0, 0.5) > 0.0);
//! // At normal incidence and normal exit nothing changes.
//! assert_eq!(drift.factor(1.0, 1.0, 1.0, 1.0, 1.0), [1.0; 3]);
//! ```

use crate::binned::{between_centres, memoized};
use crate::monte_carlo::{CHUNK_PHOTONS, walk_escapes};
use crate::{BssrdfError, DVec3, Medium, Rgb};
use rand::SeedableRng;
use rand_pcg::Pcg64Mcg;
use rayon::prelude::*;
use sss_util::splitmix64;
use std::collections::HashMap;
use std::sync::{Arc, Mutex, OnceLock};

/// Photons per incidence node and channel.
pub const PHOTONS: u64 = 1 << 16;

/// Chord bins per incidence node and channel.
pub const BINS: usize = 32;

/// The outside incidence cosines cos θ_i at which the walk runs (k = 0 at cos θ_i = 1).
pub const COS_NODES: [f64; 6] = [0.05, 0.2, 0.35, 0.5, 0.65, 0.8];

/// The walks' seed.
const SEED: u64 = 0x0044_5249_4654;

/// k(r) of one channel: its bins' centres (mm), and per incidence node k and its standard
/// error per bin.
#[derive(Clone, Debug, Default)]
struct Channel {
    centres: Vec<f64>,
    k: Vec<Vec<f64>>,
    se: Vec<Vec<f64>>,
}

impl Channel {
    /// k at node `j` and chord `r`: linear between bin centres, the end bins' values beyond.
    fn at(&self, j: usize, r: f64) -> f64 {
        between_centres(&self.centres, &self.k[j], r)
    }
}

/// The first azimuthal harmonic k(r, θ_i) of the walk's exit density for light entering at
/// outside angle θ_i, per channel (see the module documentation).
#[derive(Clone, Debug)]
pub struct EntryDrift {
    radius: Option<f64>,
    /// Per channel (each with a row per node of [`COS_NODES`]).
    channels: [Channel; 3],
}

/// The chord bins' edges of channel `ch` (mm): geometric from a twentieth of a reduced mean
/// free path to `r_max`, 16 diffusion lengths 1/σ_tr (between 10 and 1 000 reduced mean free
/// paths), or the ball's diameter if that is shorter (k is held beyond the last bin).
fn edges(medium: &Medium, ch: usize, radius: Option<f64>) -> Vec<f64> {
    let mfp = medium.reduced_mean_free_path(ch);
    let mfp = if mfp.is_finite() && mfp > 0.0 {
        mfp
    } else {
        1.0
    };
    let tr = medium.sigma_tr(ch);
    let reach = if tr.is_finite() && tr > 0.0 {
        16.0 / tr
    } else {
        f64::INFINITY
    };
    let reach = reach.clamp(10.0 * mfp, 1000.0 * mfp);
    let r_max = match radius {
        Some(r) => (2.0 * r).min(reach),
        None => reach,
    };
    let first = (0.05 * mfp).min(0.01 * r_max);
    let ratio = (r_max / first).powf(1.0 / (BINS - 1) as f64);
    let mut e = Vec::with_capacity(BINS + 1);
    e.push(0.0);
    for i in 0..BINS {
        e.push(first * ratio.powi(i as i32));
    }
    e[BINS] = r_max;
    e
}

/// Per-bin sums of one (channel, node) run: Σ w, Σ X, Σ X² with X one photon's Σ w cos φ.
#[derive(Clone, Debug)]
struct Sums {
    w: Vec<f64>,
    x: Vec<f64>,
    x2: Vec<f64>,
}

impl Sums {
    fn new() -> Self {
        Sums {
            w: vec![0.0; BINS],
            x: vec![0.0; BINS],
            x2: vec![0.0; BINS],
        }
    }

    fn add(&mut self, o: &Sums) {
        for b in 0..BINS {
            self.w[b] += o.w[b];
            self.x[b] += o.x[b];
            self.x2[b] += o.x2[b];
        }
    }
}

/// The start direction of light refracted from outside cosine `cos_i` through index `eta`:
/// along +x on the surface, into the medium (d_z < 0). Snell: sin θ_t = sin θ_i / η. `None`
/// beyond the critical angle of a medium less dense than outside (η < 1): no light enters.
fn refracted(cos_i: f64, eta: f64) -> Option<DVec3> {
    let sin_i = (1.0 - cos_i * cos_i).max(0.0).sqrt();
    let sin_t = sin_i / eta;
    if !(sin_t < 1.0 - 1e-9) {
        return None;
    }
    let cos_t = (1.0 - sin_t * sin_t).max(0.0).sqrt();
    Some(DVec3::new(sin_t, 0.0, -cos_t))
}

/// The sums of `photons` walks from `start` in channel `ch`, tallied in the bins `edges`;
/// with `single` only the light leaving after one collision.
#[allow(clippy::too_many_arguments)]
fn run_chunk(
    medium: &Medium,
    ch: usize,
    radius: Option<f64>,
    start: DVec3,
    edges: &[f64],
    photons: u64,
    seed: u64,
    single: bool,
) -> Sums {
    let mut rng = Pcg64Mcg::seed_from_u64(seed);
    let mut sums = Sums::new();
    let mut photon = vec![0.0; BINS];
    let mut touched: Vec<usize> = Vec::new();
    let r_max = edges[BINS];
    for _ in 0..photons {
        walk_escapes(medium, ch, radius, start, &mut rng, &mut |p, w, n| {
            let r = p.length();
            if !(r < r_max) || (single && n > 1) {
                return;
            }
            let b = edges.partition_point(|&e| e <= r).clamp(1, BINS) - 1;
            let rho = p.x.hypot(p.y);
            let cos_phi = if rho > 0.0 { p.x / rho } else { 0.0 };
            sums.w[b] += w;
            if photon[b] == 0.0 {
                touched.push(b);
            }
            photon[b] += w * cos_phi;
        });
        for &b in &touched {
            sums.x[b] += photon[b];
            sums.x2[b] += photon[b] * photon[b];
            photon[b] = 0.0;
        }
        touched.clear();
    }
    sums
}

/// Per bin, the raw estimate k = 2 Σ X / Σ w of `photons` walks' sums and its standard
/// error (from the per-photon spread of X; Σ w's own spread left out), both 0 where no light
/// arrived.
fn raw_k(s: &Sums, photons: u64) -> (Vec<f64>, Vec<f64>) {
    let n = photons as f64;
    let mut k = vec![0.0; BINS];
    let mut se = vec![0.0; BINS];
    for b in 0..BINS {
        if !(s.w[b] > 0.0) {
            continue;
        }
        let var = if n > 1.0 {
            ((s.x2[b] - s.x[b] * s.x[b] / n) / (n - 1.0)).max(0.0)
        } else {
            0.0
        };
        let wbar = s.w[b] / n;
        let raw = 2.0 * (s.x[b] / n) / wbar;
        let err = 2.0 * (var / n).sqrt() / wbar;
        k[b] = if raw.is_finite() { raw } else { 0.0 };
        se[b] = if err.is_finite() { err } else { 0.0 };
    }
    (k, se)
}

/// k shrunk towards 0 by its standard error `err` (k(1 − err²/k²) where |k| > err, else 0)
/// and clamped to [−1, 1].
fn shrink(k: f64, err: f64) -> f64 {
    let shrunk = if k.abs() > err {
        k * (1.0 - (err * err) / (k * k))
    } else {
        0.0
    };
    if shrunk.is_finite() {
        shrunk.clamp(-1.0, 1.0)
    } else {
        0.0
    }
}

impl EntryDrift {
    /// Runs the walks for every channel of `medium` in the half-space (`radius` `None`) or in
    /// the ball of radius `radius` (mm, finite, > 0).
    pub fn new(medium: &Medium, radius: Option<f64>) -> Result<EntryDrift, BssrdfError> {
        Self::with_photons(medium, radius, PHOTONS)
    }

    /// [`EntryDrift::new`] with `photons` per node and channel.
    pub fn with_photons(
        medium: &Medium,
        radius: Option<f64>,
        photons: u64,
    ) -> Result<EntryDrift, BssrdfError> {
        if let Some(r) = radius
            && !(r.is_finite() && r > 0.0)
        {
            return Err(BssrdfError::InvalidArgument(format!(
                "entry drift: the ball's radius must be finite and > 0, got {r} mm"
            )));
        }
        let photons = photons.max(1);
        let chunks = photons.div_ceil(CHUNK_PHOTONS);
        let nodes = COS_NODES.len();
        let all_edges: [Vec<f64>; 3] = std::array::from_fn(|ch| edges(medium, ch, radius));
        let items: Vec<(usize, usize, u64)> = (0..3)
            .flat_map(|ch| (0..nodes).flat_map(move |j| (0..chunks).map(move |k| (ch, j, k))))
            .collect();
        let results: Vec<Sums> = items
            .par_iter()
            .map(|&(ch, j, k)| {
                let n = CHUNK_PHOTONS.min(photons - k * CHUNK_PHOTONS);
                let seed = splitmix64(
                    SEED ^ splitmix64(((ch * nodes + j) as u64) << 32 | k).wrapping_add(ch as u64),
                );
                match refracted(COS_NODES[j], medium.eta()) {
                    Some(start) => {
                        run_chunk(medium, ch, radius, start, &all_edges[ch], n, seed, false)
                    }
                    None => Sums::new(),
                }
            })
            .collect();
        let mut totals: Vec<Sums> = (0..3 * nodes).map(|_| Sums::new()).collect();
        for (&(ch, j, _), s) in items.iter().zip(&results) {
            totals[ch * nodes + j].add(s);
        }
        let channels: [Channel; 3] = std::array::from_fn(|ch| {
            let mut channel = Channel {
                centres: all_edges[ch]
                    .windows(2)
                    .map(|w| 0.5 * (w[0] + w[1]))
                    .collect(),
                ..Channel::default()
            };
            for j in 0..nodes {
                let (raw, se) = raw_k(&totals[ch * nodes + j], photons);
                channel
                    .k
                    .push(raw.iter().zip(&se).map(|(&k, &e)| shrink(k, e)).collect());
                channel.se.push(se);
            }
            channel
        });
        Ok(EntryDrift { radius, channels })
    }

    /// The factors of one medium and ball radius (`None`: the half-space), walked once per
    /// process and shared.
    pub fn cached(medium: &Medium, radius: Option<f64>) -> Result<Arc<EntryDrift>, BssrdfError> {
        Self::cached_with(medium, radius, PHOTONS)
    }

    /// [`EntryDrift::cached`] with `photons` per node and channel (kept apart per count).
    pub fn cached_with(
        medium: &Medium,
        radius: Option<f64>,
        photons: u64,
    ) -> Result<Arc<EntryDrift>, BssrdfError> {
        type Cache = Mutex<HashMap<([u64; 8], Option<u64>, u64), Arc<EntryDrift>>>;
        static CACHE: OnceLock<Cache> = OnceLock::new();
        memoized(
            &CACHE,
            (medium.bits(), radius.map(f64::to_bits), photons),
            || EntryDrift::with_photons(medium, radius, photons),
        )
    }

    /// The ball's radius (mm), `None` for the half-space.
    pub fn radius(&self) -> Option<f64> {
        self.radius
    }

    /// k(r, θ_i) of channel `ch` at chord `r` (mm) for light entering at outside incidence
    /// cosine `cos_i`: in [−1, 1], 0 at normal incidence; linear in cos θ_i between
    /// [`COS_NODES`] (the first node's value below it). [`EntryDrift::at`] then
    /// [`DriftAt::ks`] reads many incidences at one chord faster.
    pub fn k(&self, ch: usize, r: f64, cos_i: f64) -> f64 {
        self.at(r).ks(cos_i)[ch]
    }

    /// Every channel's k at every incidence node at chord `r` (mm), read once for the many
    /// incidences of one pair of points.
    pub fn at(&self, r: f64) -> DriftAt {
        DriftAt {
            nodes: std::array::from_fn(|ch| std::array::from_fn(|j| self.channels[ch].at(j, r))),
        }
    }

    /// The standard error of channel `ch`'s k in bin `bin` at node `node` (before shrinking).
    pub fn k_se(&self, ch: usize, node: usize, bin: usize) -> f64 {
        self.channels[ch].se[node][bin]
    }

    /// The bins' centres of channel `ch` (mm).
    pub fn centres(&self, ch: usize) -> &[f64] {
        &self.channels[ch].centres
    }

    /// 1 + k(r, θ_i) cos φ_i + k(r, θ_o) cos φ_o per channel (both k divided by
    /// |k_i| + |k_o| where that exceeds 1, so the factor is ≥ 0): the factor on S for
    /// light entering at outside incidence cosine `cos_i` and leaving at outside cosine
    /// `cos_o`, with `cos_phi_i` the cosine between the light's direction of travel along the
    /// surface at entry and the direction from the entry towards the exit point, and
    /// `cos_phi_o` the cosine between the view ray's direction of travel along the surface at
    /// the exit (−ω_o's) and the direction from the exit towards the entry point (see the
    /// module documentation: the entry's term is the walk's, the exit's its reciprocal).
    pub fn factor(&self, r: f64, cos_i: f64, cos_phi_i: f64, cos_o: f64, cos_phi_o: f64) -> Rgb {
        let at = self.at(r);
        DriftAt::combine(at.ks(cos_i), cos_phi_i, at.ks(cos_o), cos_phi_o)
    }
}

/// [`EntryDrift`] read at one chord: k per channel at each incidence node.
#[derive(Clone, Copy, Debug)]
pub struct DriftAt {
    nodes: [[f64; COS_NODES.len()]; 3],
}

impl DriftAt {
    /// k per channel for light entering (or, by reciprocity, leaving) at outside cosine
    /// `cos`: linear between [`COS_NODES`], the first node's value below it, to 0 at 1; in
    /// [−1, 1].
    pub fn ks(&self, cos: f64) -> Rgb {
        let c = if cos.is_finite() {
            cos.clamp(0.0, 1.0)
        } else {
            1.0
        };
        let last = COS_NODES.len() - 1;
        let (j, wj, wn) = if c <= COS_NODES[0] {
            (0, 1.0, 0.0)
        } else if c >= COS_NODES[last] {
            (last, (1.0 - c) / (1.0 - COS_NODES[last]), 0.0)
        } else {
            let j = COS_NODES.partition_point(|&x| x <= c) - 1;
            let t = (c - COS_NODES[j]) / (COS_NODES[j + 1] - COS_NODES[j]);
            (j, 1.0 - t, t)
        };
        std::array::from_fn(|ch| {
            let row = &self.nodes[ch];
            let next = row.get(j + 1).copied().unwrap_or(0.0);
            let value = wj * row[j] + wn * next;
            if value.is_finite() {
                value.clamp(-1.0, 1.0)
            } else {
                0.0
            }
        })
    }

    /// The factor 1 + k_i cos φ_i + k_o cos φ_o per channel from the entry's and the exit's k
    /// ([`DriftAt::ks`]) and the two azimuth cosines (see [`EntryDrift::factor`]).
    pub fn combine(ki: Rgb, cos_phi_i: f64, ko: Rgb, cos_phi_o: f64) -> Rgb {
        let clean = |x: f64| {
            if x.is_finite() {
                x.clamp(-1.0, 1.0)
            } else {
                0.0
            }
        };
        let (pi, po) = (clean(cos_phi_i), clean(cos_phi_o));
        std::array::from_fn(|ch| {
            // |k_i| + |k_o| ≤ 1 keeps the factor ≥ 0 without a clamp, which would add light
            // (the factor's mean over either azimuth stays 1).
            let s = (ki[ch].abs() + ko[ch].abs()).max(1.0);
            (1.0 + (ki[ch] * pi + ko[ch] * po) / s).max(0.0)
        })
    }
}

#[cfg(test)]
mod tests;
