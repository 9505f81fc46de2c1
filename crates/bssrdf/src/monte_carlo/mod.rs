//! Monte Carlo photon random walk: the reference the diffusion models' profiles are measured
//! against (real light transport, for a flat half-space under a normal beam).
//!
//! A pencil beam enters a semi-infinite homogeneous [`Medium`] (occupying z < 0, under a smooth
//! dielectric boundary z = 0 of relative index η) at normal incidence at the origin; photons
//! random-walk in the medium in the style of MCML (Wang, Jacques, Zheng, *MCML — Monte Carlo
//! modeling of light transport in multi-layered tissues*, Computer Methods and Programs in
//! Biomedicine 47, 1995), and the weight escaping through the boundary is tallied by the radius
//! of its exit point. The result is the radially resolved diffuse reflectance R_d(r) of each
//! channel in linear radial bins, with standard errors.
//!
//! # Normalisation
//! Everything is per unit power *entering* the medium: the beam's entry Fresnel reflection is
//! not simulated and not counted (at normal incidence the transmitted beam keeps its
//! direction, so every photon starts at the origin heading straight down with weight 1). The
//! bin values are therefore directly comparable with the models' [`crate::Bssrdf::rd`] (1/mm²),
//! and [`WalkProfile::total`] with [`crate::Bssrdf::total_diffuse_reflectance`]. Each bin holds the
//! *area average* of R_d over its annulus, tally / (N · π(r₁² − r₀²)).
//!
//! # Physics and estimators
//! - Free paths: optical depth τ = −ln ξ, distance τ/σ_t (MCML, "step size").
//! - Absorption: implicit (MCML's "survival biasing"): at every collision the weight is
//!   multiplied by the single-scattering albedo σ_s/σ_t, and the photon always scatters.
//!   Russian roulette (as in MCML): once the weight falls below [`ROULETTE_THRESHOLD`] the
//!   photon survives with probability [`ROULETTE_SURVIVAL`] and its weight is divided by it;
//!   otherwise it is terminated. Both are unbiased.
//! - Scattering: Henyey-Greenstein with the medium's g, cos θ sampled by the standard inversion
//!   (as in MCML; pbrt 3rd ed. §15.2.3), isotropic for |g| < 1e-6; a uniform azimuth (by
//!   rejection in the unit disk, avoiding trigonometric calls); the new direction is built in
//!   the orthonormal frame of Duff et al., *Building an Orthonormal Basis, Revisited*,
//!   JCGT 6(1), 2017, which is stable for every direction.
//! - Boundary: a step that would cross z = 0 is stopped there (as in MCML, remembering the
//!   unused optical depth). The internal Fresnel reflectance F = `fr_dielectric(cos, 1/η)` is
//!   applied by *deterministic splitting* (MCML's "partial reflection" option): the weight
//!   w(1 − F) escapes and is tallied at the exit radius, the weight wF is mirrored (d_z → −d_z)
//!   and continues with the remaining optical depth. η = 1 gives F = 0 (everything escapes),
//!   η > 1 gives total internal reflection (F = 1) beyond the critical angle, η < 1 has none.
//! - Cap: a photon about to undergo collision [`MAX_SCATTERING_EVENTS`] + 1 is stopped; it is
//!   counted in [`WalkProfile::capped`] and the weight it still carried in
//!   [`WalkProfile::capped_weight`] (it is *not* tallied). This only matters for albedo 1 (or
//!   nearly), where walks have a heavy tail (the fraction of photons surviving n collisions
//!   decays like 1/√n); for albedo 1, `total + capped_weight` is 1 up to the roulette noise.
//!
//! # Standard errors
//! Photons are independent, so for each bin (and for the total) the estimate is the mean of
//! N i.i.d. per-photon contributions X_i, X_i being the sum of all weight photon i deposits in
//! that bin (a split photon can deposit several times). The walk accumulates X_i per photon,
//! then adds X_i and X_i² to the bin's sums; the standard error of the mean is
//! √(s²/N) with the unbiased sample variance s² = (Σ X² − (Σ X)²/N)/(N − 1), and is then
//! scaled like the bin value. With N = 1 it is reported as 0.
//!
//! # Determinism and parallelism
//! Each channel is an independent simulation (its own σ_a, σ_s) with N = `photons` photons,
//! split into chunks of [`CHUNK_PHOTONS`]. Each chunk owns a `Pcg64Mcg` seeded from
//! (seed, channel, chunk index) through splitmix64 mixing, chunks run in parallel with rayon,
//! and their tallies are summed in chunk order, so the result is bit-identical for any number
//! of threads.

use crate::fresnel::fr_dielectric;
use crate::{BssrdfError, DVec3, Medium, Rgb};
use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg64Mcg;
use rayon::prelude::*;
use sss_util::splitmix64;
use std::sync::Mutex;

pub mod condensed;

/// Photons per chunk: the unit of parallel work and of RNG seeding.
pub const CHUNK_PHOTONS: u64 = 4096;

/// Hard cap on the number of scattering events of one photon (see the module documentation).
pub const MAX_SCATTERING_EVENTS: u64 = 1_000_000;

/// Russian roulette starts when a photon's weight falls below this value (MCML's W_th).
pub const ROULETTE_THRESHOLD: f64 = 1e-4;

/// Probability that a photon survives a round of Russian roulette (MCML's 1/m, m = 10).
pub const ROULETTE_SURVIVAL: f64 = 0.1;

/// Largest accepted number of radial bins (keeps the per-chunk tallies bounded in memory).
pub const MAX_BINS: usize = 1 << 20;

/// The estimated peak bytes of a simulation with `bins` radial bins on `threads` worker
/// threads (saturating, never overflowing). It does not depend on the photon count: photons
/// are traced and tallied in batches, so they cost time only.
///
/// Counted from the allocations of [`simulate`]: per chunk a tally of 3 bin arrays, up to
/// 8 × `threads` chunk tallies held per batch, and per running chunk a scratch of 2 bin arrays;
/// the 3 channel tallies (3 arrays each); the result's `rd`, `se`, `rd_single` (3 channels
/// each), bin edges and areas (11 arrays); every array is `bins` f64.
pub fn memory_bytes(bins: usize, threads: usize) -> u64 {
    let threads = threads.max(1) as u64;
    let arrays = (8 * threads)
        .saturating_mul(3)
        .saturating_add(threads.saturating_mul(2))
        .saturating_add(9 + 9 + 2);
    arrays
        .saturating_mul(bins as u64)
        .saturating_mul(std::mem::size_of::<f64>() as u64)
}

/// What to simulate. Plain data; checked by [`simulate`].
#[derive(Clone, Debug, PartialEq)]
pub struct WalkConfig {
    /// Photons per simulated channel (≥ 1).
    pub photons: u64,
    /// Master seed; channels and chunks derive independent streams from it.
    pub seed: u64,
    /// Outer radius of the radial bins (mm, finite, > 0). Weight escaping beyond it still
    /// counts in [`WalkProfile::total`].
    pub r_max: f64,
    /// Number of radial bins over [0, r_max] (1..=[`MAX_BINS`]).
    pub bins: usize,
    /// Which channels (red, green, blue) to simulate; at least one. Skipped channels report 0.
    pub channels: [bool; 3],
    /// How the bins are laid out: equal widths ([`BinSpacing::Linear`]) or given edges
    /// ([`BinSpacing::Edges`], e.g. log-spaced from [`BinSpacing::geometric`]).
    pub spacing: BinSpacing,
}

/// The layout of the radial bins of a [`WalkConfig`].
#[derive(Clone, Debug, Default, PartialEq)]
pub enum BinSpacing {
    /// `bins` bins of equal width over [0, r_max].
    #[default]
    Linear,
    /// The `bins + 1` edges of the bins in mm: the first 0, strictly increasing, finite, the
    /// last equal to `r_max`. An exit radius is binned by bisection over them.
    Edges(Vec<f64>),
}

impl BinSpacing {
    /// Log-spaced bins: [0, `first`], then `bins − 1` bins whose edges grow by a constant ratio
    /// from `first` to `r_max` (`bins ≥ 2`, 0 < `first` < `r_max`, both finite).
    pub fn geometric(first: f64, r_max: f64, bins: usize) -> Result<BinSpacing, BssrdfError> {
        if !(first > 0.0 && first < r_max && r_max.is_finite() && (2..=MAX_BINS).contains(&bins)) {
            return Err(BssrdfError::InvalidArgument(format!(
                "Monte Carlo: geometric bins need 0 < first ({first}) < r_max ({r_max}), both \
                 finite, and 2..={MAX_BINS} bins ({bins})"
            )));
        }
        let ratio = (r_max / first).powf(1.0 / (bins - 1) as f64);
        let mut edges = vec![0.0, first];
        for k in 1..bins - 1 {
            edges.push(first * ratio.powi(k as i32));
        }
        edges.push(r_max);
        Ok(BinSpacing::Edges(edges))
    }
}

impl WalkConfig {
    /// Checks the configuration; [`simulate`] calls it first.
    pub fn validate(&self) -> Result<(), BssrdfError> {
        let bad = |msg: String| Err(BssrdfError::InvalidArgument(msg));
        if self.photons == 0 {
            return bad("Monte Carlo: photons must be at least 1".into());
        }
        if self.bins == 0 || self.bins > MAX_BINS {
            return bad(format!(
                "Monte Carlo: bins = {} must lie in 1..={MAX_BINS}",
                self.bins
            ));
        }
        if !(self.r_max.is_finite() && self.r_max > 0.0) {
            return bad(format!(
                "Monte Carlo: r_max = {} mm must be finite and > 0",
                self.r_max
            ));
        }
        if !self.channels.iter().any(|&c| c) {
            return bad("Monte Carlo: no channel selected".into());
        }
        if let BinSpacing::Edges(edges) = &self.spacing {
            let valid = edges.len() == self.bins + 1
                && edges.first() == Some(&0.0)
                && edges.last() == Some(&self.r_max)
                && edges.iter().all(|e| e.is_finite())
                && edges.windows(2).all(|w| w[0] < w[1]);
            if !valid {
                return bad(format!(
                    "Monte Carlo: {} bin edges given for {} bins; they must be bins + 1 strictly \
                     increasing finite values from 0 to r_max = {} mm",
                    edges.len(),
                    self.bins,
                    self.r_max
                ));
            }
        }
        Ok(())
    }
}

/// The tallied radial profile of a simulation. All values are finite.
#[derive(Clone, Debug, PartialEq)]
pub struct WalkProfile {
    /// Bin edges in mm: `bins + 1` values from 0 to `r_max` (linear, or as given by
    /// [`BinSpacing::Edges`]).
    pub bin_edges: Vec<f64>,
    /// Per channel, the area-averaged R_d of each bin in 1/mm²: tally / (N · annulus area), per
    /// unit power entering the medium. All zero for channels not simulated.
    pub rd: [Vec<f64>; 3],
    /// Standard error of each value of `rd` (1/mm²).
    pub se: [Vec<f64>; 3],
    /// Total diffuse reflectance per channel: all escaped weight / N, including weight
    /// escaping beyond `r_max`.
    pub total: Rgb,
    /// Standard error of `total`.
    pub total_se: Rgb,
    /// Photons simulated per channel (N).
    pub photons: u64,
    /// Photons stopped by [`MAX_SCATTERING_EVENTS`], summed over the simulated channels.
    pub capped: u64,
    /// Weight still carried by capped photons / N, per channel (lost to the tally).
    pub capped_weight: Rgb,
    /// The part of `rd` carried by photons that escaped after exactly one collision (single
    /// scattering), per channel and bin (1/mm²). `rd − rd_single` is the multiple-scattering
    /// profile that diffusion models (the dipoles) approximate.
    pub rd_single: [Vec<f64>; 3],
    /// The single-scattering part of `total`.
    pub total_single: Rgb,
}

impl WalkProfile {
    /// Centre of each bin (mm).
    pub fn bin_centers(&self) -> Vec<f64> {
        self.bin_edges
            .windows(2)
            .map(|e| 0.5 * (e[0] + e[1]))
            .collect()
    }

    /// Area π(r₁² − r₀²) of each bin's annulus (mm²).
    pub fn bin_areas(&self) -> Vec<f64> {
        self.bin_edges
            .windows(2)
            .map(|e| annulus_area(e[0], e[1]))
            .collect()
    }
}

fn annulus_area(r0: f64, r1: f64) -> f64 {
    std::f64::consts::PI * (r1 * r1 - r0 * r0)
}

/// Runs the photon random walk for every selected channel of `medium`.
///
/// Errors with [`BssrdfError::InvalidArgument`] on a bad configuration (see
/// [`WalkConfig::validate`]).
pub fn simulate(medium: &Medium, cfg: &WalkConfig) -> Result<WalkProfile, BssrdfError> {
    simulate_with_progress(medium, cfg, &|_| {})
}

/// [`simulate`], calling `progress` with the cumulative number of photons finished (over all
/// selected channels, so it ends at `photons ×` the number of selected channels) after every
/// chunk. Calls may come from worker threads but are serialised and their values increase.
pub fn simulate_with_progress(
    medium: &Medium,
    cfg: &WalkConfig,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<WalkProfile, BssrdfError> {
    simulate_impl(medium, cfg, MAX_SCATTERING_EVENTS, progress)
}

/// Per-channel parameters of the walk.
#[derive(Clone, Copy, Debug)]
struct Walk<'a> {
    sigma_t: f64,
    albedo: f64,
    g: f64,
    /// n_t / n_i for light leaving the medium: 1/η.
    eta_out: f64,
    /// Analog absorption (the photon dies with probability 1 − α at a collision, its weight
    /// unchanged) instead of implicit absorption (its weight times α): walks as long as the
    /// light lives, not until the weight falls to the roulette's threshold (near α = 1
    /// thousands of collisions fewer; noisier per photon).
    analog: bool,
    max_events: u64,
    /// 1 / bin width (linear bins).
    inv_dr: f64,
    r_max: f64,
    bins: usize,
    /// The bin edges when they are not linear ([`BinSpacing::Edges`]).
    edges: Option<&'a [f64]>,
    /// The medium's shape: `None` the half-space z < 0, `Some(R)` the ball of radius R (mm)
    /// under the entry point, centred at (0, 0, −R) ([`simulate_sphere`]).
    sphere: Option<f64>,
}

impl Walk<'_> {
    /// A walk with analog absorption and the event cap whose caller tallies escapes itself
    /// (no bins): extinction `sigma_t`, albedo `albedo` (clamped to [0, 1]), anisotropy `g`,
    /// relative index `eta`, in the half-space or the ball of radius `sphere`.
    fn unbinned(sigma_t: f64, albedo: f64, g: f64, eta: f64, sphere: Option<f64>) -> Self {
        Walk {
            sigma_t,
            albedo: albedo.clamp(0.0, 1.0),
            g,
            eta_out: 1.0 / eta,
            analog: true,
            max_events: MAX_SCATTERING_EVENTS,
            inv_dr: 0.0,
            r_max: 0.0,
            bins: 1,
            edges: None,
            sphere,
        }
    }

    /// The radial bin holding exit radius `r`, or `None` beyond `r_max`.
    fn bin(&self, r: f64) -> Option<usize> {
        match self.edges {
            None => (r < self.r_max).then(|| ((r * self.inv_dr) as usize).min(self.bins - 1)),
            Some(edges) => {
                (r < self.r_max).then(|| edges.partition_point(|&e| e <= r).clamp(1, self.bins) - 1)
            }
        }
    }
}

/// Sums of one channel over a set of photons.
#[derive(Clone, Debug)]
struct Tally {
    sum: Vec<f64>,
    single: Vec<f64>,
    single_total: f64,
    sum_sq: Vec<f64>,
    total: f64,
    total_sq: f64,
    capped: u64,
    capped_weight: f64,
}

impl Tally {
    fn new(bins: usize) -> Self {
        Tally {
            sum: vec![0.0; bins],
            single: vec![0.0; bins],
            single_total: 0.0,
            sum_sq: vec![0.0; bins],
            total: 0.0,
            total_sq: 0.0,
            capped: 0,
            capped_weight: 0.0,
        }
    }

    fn add(&mut self, other: &Tally) {
        for (a, b) in self.sum.iter_mut().zip(&other.sum) {
            *a += b;
        }
        for (a, b) in self.sum_sq.iter_mut().zip(&other.sum_sq) {
            *a += b;
        }
        for (a, b) in self.single.iter_mut().zip(&other.single) {
            *a += b;
        }
        self.single_total += other.single_total;
        self.total += other.total;
        self.total_sq += other.total_sq;
        self.capped += other.capped;
        self.capped_weight += other.capped_weight;
    }
}

/// One photon's deposits, accumulated before they are squared.
struct PhotonScratch {
    bin_weight: Vec<f64>,
    /// Single-scattering deposits go straight to the tally (means only, no variance).
    single: Vec<f64>,
    single_total: f64,
    touched: Vec<usize>,
    total: f64,
}

impl PhotonScratch {
    fn deposit(&mut self, walk: &Walk, r: f64, w: f64) {
        self.total += w;
        if let Some(b) = walk.bin(r) {
            if self.bin_weight[b] == 0.0 {
                self.touched.push(b);
            }
            self.bin_weight[b] += w;
        }
    }

    fn deposit_single(&mut self, walk: &Walk, r: f64, w: f64) {
        self.single_total += w;
        if let Some(b) = walk.bin(r) {
            self.single[b] += w;
        }
    }

    fn flush(&mut self, tally: &mut Tally) {
        for &b in &self.touched {
            let x = self.bin_weight[b];
            tally.sum[b] += x;
            tally.sum_sq[b] += x * x;
            self.bin_weight[b] = 0.0;
        }
        self.touched.clear();
        tally.total += self.total;
        tally.total_sq += self.total * self.total;
        self.total = 0.0;
    }
}

/// The seed of one chunk of one channel: (seed, channel, chunk) hashed through
/// [`splitmix64`] (Steele, Lea, Flood, *Fast splittable pseudorandom number generators*,
/// OOPSLA 2014), a bijective mixer with full avalanche.
fn chunk_seed(seed: u64, channel: usize, chunk: u64) -> u64 {
    let h = splitmix64(seed);
    let h = splitmix64(h ^ (channel as u64 + 1).wrapping_mul(0xD6E8_FEB8_6659_FD93));
    splitmix64(h ^ chunk.wrapping_mul(0xA076_1D64_78BD_642F))
}

/// Uniform in [0, 1).
fn uniform(rng: &mut Pcg64Mcg) -> f64 {
    rng.random::<f64>()
}

/// Samples cos θ between the old and new propagation directions from the Henyey-Greenstein
/// phase function with anisotropy `g` (g > 0 forward), from a uniform `xi` in [0, 1):
/// cos θ = (1 + g² − ((1 − g²)/(1 − g + 2gξ))²)/(2g) (Wang et al. 1995; pbrt 3rd ed. §15.2.3),
/// and cos θ = 1 − 2ξ for |g| < 1e-6. The denominator 1 − g + 2gξ ≥ 1 − |g| > 0 for |g| < 1.
fn sample_hg_cos(g: f64, xi: f64) -> f64 {
    if g.abs() < 1e-6 {
        return (1.0 - 2.0 * xi).clamp(-1.0, 1.0);
    }
    let t = (1.0 - g * g) / (1.0 - g + 2.0 * g * xi);
    ((1.0 + g * g - t * t) / (2.0 * g)).clamp(-1.0, 1.0)
}

/// (cos φ, sin φ) of a uniform azimuth φ, without trigonometric calls: for a uniform point
/// (a, b) in the unit disk (by rejection from the square, acceptance π/4; von Neumann 1951),
/// ((a² − b²)/r², 2ab/r²) is (cos 2ψ, sin 2ψ) with ψ = atan2(b, a) uniform.
fn sample_azimuth(rng: &mut Pcg64Mcg) -> (f64, f64) {
    loop {
        let a = 2.0 * uniform(rng) - 1.0;
        let b = 2.0 * uniform(rng) - 1.0;
        let r2 = a * a + b * b;
        if r2 <= 1.0 && r2 > 1e-200 {
            let inv = 1.0 / r2;
            return ((a * a - b * b) * inv, 2.0 * a * b * inv);
        }
    }
}

/// New unit direction at angle acos(`cos_theta`) from the unit vector `d`, at the azimuth
/// given by (`cos_phi`, `sin_phi`) in the frame of Duff et al. 2017 (glam's
/// `any_orthonormal_pair`).
fn scatter_direction(d: DVec3, cos_theta: f64, cos_phi: f64, sin_phi: f64) -> DVec3 {
    let (t, b) = d.any_orthonormal_pair();
    let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
    let n = (t * cos_phi + b * sin_phi) * sin_theta + d * cos_theta;
    // Renormalise against drift; n has length 1 up to rounding, never near 0.
    n * n.length_squared().sqrt().recip()
}

/// Traces one photon that starts at the origin heading along `start` (a unit vector into the
/// medium, d_z < 0), calling `escape(p, r, weight, collisions)` for every weight that leaves
/// through the boundary at the point `p` (radius, or chord in a ball, `r`) after `collisions`
/// collisions. Returns `Some(weight)` if it hit the event cap still carrying `weight`.
fn trace_photon(
    walk: &Walk,
    start: DVec3,
    rng: &mut Pcg64Mcg,
    escape: &mut impl FnMut(DVec3, f64, f64, u64),
) -> Option<f64> {
    let mut p = DVec3::ZERO;
    let mut d = start;
    let mut w = 1.0_f64;
    let mut events = 0_u64;
    loop {
        // Optical depth to the next collision: −ln ξ with ξ in (0, 1].
        let mut tau = -(1.0 - uniform(rng)).ln();
        loop {
            let s = tau / walk.sigma_t;
            if let Some(radius) = walk.sphere {
                match sphere_boundary(walk, radius, s, tau, &mut p, &mut d, &mut w, events, escape)
                {
                    SphereStep::Inside => {}
                    SphereStep::Reflected(left) => {
                        tau = left;
                        continue;
                    }
                    SphereStep::Spent => return None,
                }
            } else if d.z > 0.0 {
                // p.z <= 0 always, so the distance to the boundary is >= 0.
                let s_b = -p.z / d.z;
                if s >= s_b {
                    p += d * s_b;
                    p.z = 0.0;
                    tau = (tau - s_b * walk.sigma_t).max(0.0);
                    let f = fr_dielectric(d.z, walk.eta_out);
                    let escaped = w * (1.0 - f);
                    if escaped > 0.0 {
                        escape(p, p.x.hypot(p.y), escaped, events);
                    }
                    w *= f;
                    if w <= 0.0 {
                        return None;
                    }
                    d.z = -d.z;
                    continue;
                }
            }
            p += d * s;
            break;
        }
        // Collision.
        events += 1;
        if events > walk.max_events {
            return Some(w);
        }
        if walk.analog {
            // Analog absorption: the photon survives the collision with probability α.
            if uniform(rng) >= walk.albedo {
                return None;
            }
        } else {
            w *= walk.albedo;
        }
        if w < ROULETTE_THRESHOLD {
            if w <= 0.0 || uniform(rng) >= ROULETTE_SURVIVAL {
                return None;
            }
            w /= ROULETTE_SURVIVAL;
        }
        let cos_theta = sample_hg_cos(walk.g, uniform(rng));
        let (cos_phi, sin_phi) = sample_azimuth(rng);
        d = scatter_direction(d, cos_theta, cos_phi, sin_phi);
    }
}

/// The boundary step of a walk in a ball of radius `radius` centred at (0, 0, −radius): when
/// the free path `s` (optical depth `tau`) from `p` along `d` reaches the sphere, moves the
/// photon onto it, lets w(1 − F) escape (tallied at the chord distance |p| from the entry
/// point, unless the photon has not collided yet: light crossing the ball without a collision
/// is not diffuse and belongs to no profile) and reflects the rest about the sphere's normal.
/// The distance to the sphere from inside is the larger root of
/// |q + s d|² = R² (q = p − centre): s = −q·d + √((q·d)² − (|q|² − R²)).
#[allow(clippy::too_many_arguments)]
fn sphere_boundary(
    walk: &Walk,
    radius: f64,
    s: f64,
    tau: f64,
    p: &mut DVec3,
    d: &mut DVec3,
    w: &mut f64,
    events: u64,
    escape: &mut impl FnMut(DVec3, f64, f64, u64),
) -> SphereStep {
    let centre = DVec3::new(0.0, 0.0, -radius);
    let q = *p - centre;
    let b = q.dot(*d);
    let c = q.length_squared() - radius * radius;
    let s_b = (-b + (b * b - c).max(0.0).sqrt()).max(0.0);
    if s < s_b {
        return SphereStep::Inside;
    }
    let q = *p + *d * s_b - centre;
    let len = q.length();
    let n = if len > 0.0 { q / len } else { DVec3::Z };
    *p = centre + n * radius;
    let left = (tau - s_b * walk.sigma_t).max(0.0);
    let cos = d.dot(n).clamp(0.0, 1.0);
    let f = fr_dielectric(cos, walk.eta_out);
    let escaped = *w * (1.0 - f);
    if escaped > 0.0 && events > 0 {
        escape(*p, p.length(), escaped, events);
    }
    *w *= f;
    if *w <= 0.0 {
        return SphereStep::Spent;
    }
    let r = *d - n * (2.0 * d.dot(n));
    *d = r * r.length_squared().sqrt().recip();
    SphereStep::Reflected(left)
}

/// What [`sphere_boundary`] did.
enum SphereStep {
    /// The collision comes before the sphere: the photon stays inside.
    Inside,
    /// It reached the sphere and the reflected weight goes on with this optical depth left.
    Reflected(f64),
    /// It reached the sphere and no weight is left.
    Spent,
}

fn run_chunk(walk: &Walk, photons: u64, seed: u64) -> Tally {
    let mut rng = Pcg64Mcg::seed_from_u64(seed);
    let mut tally = Tally::new(walk.bins);
    let mut scratch = PhotonScratch {
        bin_weight: vec![0.0; walk.bins],
        single: vec![0.0; walk.bins],
        single_total: 0.0,
        touched: Vec::new(),
        total: 0.0,
    };
    for _ in 0..photons {
        let traced = trace_photon(walk, DVec3::NEG_Z, &mut rng, &mut |_, r, w, events| {
            scratch.deposit(walk, r, w);
            if events == 1 {
                scratch.deposit_single(walk, r, w);
            }
        });
        if let Some(w) = traced {
            tally.capped += 1;
            tally.capped_weight += w;
        }
        scratch.flush(&mut tally);
    }
    tally.single = std::mem::take(&mut scratch.single);
    tally.single_total = scratch.single_total;
    tally
}

/// One photon's walk in a half-space of single-scattering albedo `albedo`, in units of the
/// mean free path (σ_t = 1), with Henyey–Greenstein `g` under a boundary of relative index
/// `eta`, starting at the boundary heading along `start` (unit, d_z < 0) with weight 1: the
/// walk of [`simulate`] (Fresnel splitting at the boundary, the event cap) with analog
/// absorption. Calls `escape(collisions, weight)` for each weight leaving. A half-space has
/// no length of its own, so a medium of albedo α ≤ `albedo` returns Σ weight · (α/albedo)ⁿ
/// over the same walks (n collisions): one walk at the largest albedo serves every channel
/// (the condensed Monte Carlo of Graaff et al. 1993). Used by
/// [`crate::angular::DirectionalAlbedo`].
pub(crate) fn condensed_escapes(
    albedo: f64,
    g: f64,
    eta: f64,
    start: DVec3,
    rng: &mut Pcg64Mcg,
    escape: &mut impl FnMut(u64, f64),
) {
    let walk = Walk::unbinned(1.0, albedo, g, eta, None);
    trace_photon(&walk, start, rng, &mut |_, _, w, n| escape(n, w));
}

/// One photon's walk in channel `ch` of `medium` (lengths in mm) with analog absorption,
/// in the half-space (`sphere` `None`) or in the ball of radius `sphere` under the entry point
/// (centred at (0, 0, −R)), starting at the origin heading along `start` (unit, d_z < 0) with
/// weight 1. Calls `escape(p, weight, collisions)` for each weight leaving at the point `p`
/// after `collisions` ≥ 1 collisions (the beam starts into the medium, and the ball's boundary
/// step tallies nothing before the first collision: light crossing without one is not
/// diffuse). Used by
/// [`crate::entry_drift::EntryDrift`].
pub(crate) fn walk_escapes(
    medium: &Medium,
    ch: usize,
    sphere: Option<f64>,
    start: DVec3,
    rng: &mut Pcg64Mcg,
    escape: &mut impl FnMut(DVec3, f64, u64),
) {
    let walk = Walk::unbinned(
        medium.sigma_t(ch),
        medium.albedo(ch),
        medium.g(),
        medium.eta(),
        sphere,
    );
    trace_photon(&walk, start, rng, &mut |p, _, w, n| escape(p, w, n));
}

/// Standard error of the mean of N samples with sums `s`, `s2`.
fn standard_error(s: f64, s2: f64, n: f64) -> f64 {
    if n < 2.0 {
        return 0.0;
    }
    let var = ((s2 - s * s / n) / (n - 1.0)).max(0.0);
    let se = (var / n).sqrt();
    if se.is_finite() { se } else { 0.0 }
}

pub(crate) fn simulate_impl(
    medium: &Medium,
    cfg: &WalkConfig,
    max_events: u64,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<WalkProfile, BssrdfError> {
    simulate_in(medium, cfg, max_events, None, false, progress)
}

/// [`simulate`] in a ball of radius `radius` (mm, finite, > 0) instead of the half-space: the
/// beam enters at the top of the sphere (the origin, heading down its diameter; the ball is
/// centred at (0, 0, −radius)), the internal Fresnel splitting uses the sphere's normal, and
/// the escaping weight is tallied by the *chord* distance between entry and exit point, which
/// on a sphere says everything (the exit point's position up to the rotation about the
/// diameter). The area of a sphere within chord distance r of a point is exactly πr² (for
/// r ≤ 2R, Archimedes' hat-box theorem), so the bins' area normalisation — and with it every
/// radial model's 2πr R_d(r) — applies unchanged: the result is a radial profile over
/// [0, 2R] whose integral is the ball's total diffuse reflectance. Light that crosses the ball
/// without a collision is not tallied (nor counted in `total`). With the same seed, chunk for
/// chunk, the walks share their random numbers with [`simulate`]'s (common random numbers:
/// a photon that never reaches where the shapes differ walks the same path).
pub fn simulate_sphere(
    medium: &Medium,
    radius: f64,
    cfg: &WalkConfig,
) -> Result<WalkProfile, BssrdfError> {
    if !(radius.is_finite() && radius > 0.0) {
        return Err(BssrdfError::InvalidArgument(format!(
            "Monte Carlo: the sphere's radius must be finite and > 0, got {radius} mm"
        )));
    }
    simulate_in(
        medium,
        cfg,
        MAX_SCATTERING_EVENTS,
        Some(radius),
        false,
        &|_| {},
    )
}

/// [`simulate`] (`sphere` `None`) or [`simulate_sphere`] with analog absorption (a photon
/// dies at a collision with probability 1 − α instead of losing weight): walks end when the
/// light is absorbed, not when its weight falls to the roulette's threshold — near albedo 1
/// thousands of collisions sooner, at more noise per photon.
pub(crate) fn simulate_analog(
    medium: &Medium,
    cfg: &WalkConfig,
    sphere: Option<f64>,
) -> Result<WalkProfile, BssrdfError> {
    simulate_in(medium, cfg, MAX_SCATTERING_EVENTS, sphere, true, &|_| {})
}

fn simulate_in(
    medium: &Medium,
    cfg: &WalkConfig,
    max_events: u64,
    sphere: Option<f64>,
    analog: bool,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<WalkProfile, BssrdfError> {
    cfg.validate()?;
    let bins = cfg.bins;
    let dr = cfg.r_max / bins as f64;
    let bin_edges: Vec<f64> = match &cfg.spacing {
        BinSpacing::Linear => {
            let mut edges: Vec<f64> = (0..=bins).map(|i| i as f64 * dr).collect();
            edges[bins] = cfg.r_max;
            edges
        }
        BinSpacing::Edges(edges) => edges.clone(),
    };
    let given_edges = match &cfg.spacing {
        BinSpacing::Linear => None,
        BinSpacing::Edges(_) => Some(bin_edges.as_slice()),
    };

    let walks: [Walk; 3] = std::array::from_fn(|ch| Walk {
        sigma_t: medium.sigma_t(ch),
        albedo: medium.albedo(ch).clamp(0.0, 1.0),
        g: medium.g(),
        eta_out: 1.0 / medium.eta(),
        analog,
        max_events,
        inv_dr: 1.0 / dr,
        r_max: cfg.r_max,
        bins,
        edges: given_edges,
        sphere,
    });

    let n_chunks = cfg.photons.div_ceil(CHUNK_PHOTONS);
    // The (channel, chunk) work items are generated one batch at a time, never all at once:
    // memory does not grow with the photon count, only time does.
    let active: Vec<usize> = (0..3).filter(|&ch| cfg.channels[ch]).collect();
    let n_items = active.len() as u64 * n_chunks;

    let mut tallies: [Tally; 3] = std::array::from_fn(|_| Tally::new(bins));
    let done = Mutex::new(0_u64);
    // Batches bound the memory held in per-chunk tallies; their size does not affect the
    // result because tallies are always summed in chunk order.
    let batch = 8 * rayon::current_num_threads().max(1) as u64;
    let mut start = 0_u64;
    while start < n_items {
        let end = start.saturating_add(batch).min(n_items);
        let group: Vec<(usize, u64)> = (start..end)
            .map(|i| (active[(i / n_chunks) as usize], i % n_chunks))
            .collect();
        start = end;
        let results: Vec<Tally> = group
            .par_iter()
            .map(|&(ch, k)| {
                let n = CHUNK_PHOTONS.min(cfg.photons - k * CHUNK_PHOTONS);
                let t = run_chunk(&walks[ch], n, chunk_seed(cfg.seed, ch, k));
                let mut guard = done.lock().unwrap_or_else(|e| e.into_inner());
                *guard += n;
                progress(*guard);
                t
            })
            .collect();
        for (&(ch, _), t) in group.iter().zip(&results) {
            tallies[ch].add(t);
        }
    }

    let n = cfg.photons as f64;
    let areas: Vec<f64> = bin_edges
        .windows(2)
        .map(|e| annulus_area(e[0], e[1]))
        .collect();
    let mut rd: [Vec<f64>; 3] = std::array::from_fn(|_| vec![0.0; bins]);
    let mut se: [Vec<f64>; 3] = std::array::from_fn(|_| vec![0.0; bins]);
    let mut total = [0.0; 3];
    let mut total_se = [0.0; 3];
    let mut capped_weight = [0.0; 3];
    let mut capped = 0;
    let mut rd_single: [Vec<f64>; 3] = std::array::from_fn(|_| vec![0.0; bins]);
    let mut total_single = [0.0; 3];
    for ch in (0..3).filter(|&ch| cfg.channels[ch]) {
        let t = &tallies[ch];
        for b in 0..bins {
            let area = areas[b];
            if area > 0.0 {
                rd[ch][b] = t.sum[b] / (n * area);
                rd_single[ch][b] = t.single[b] / (n * area);
                se[ch][b] = standard_error(t.sum[b], t.sum_sq[b], n) / area;
            }
        }
        total[ch] = t.total / n;
        total_single[ch] = t.single_total / n;
        total_se[ch] = standard_error(t.total, t.total_sq, n);
        capped_weight[ch] = t.capped_weight / n;
        capped += t.capped;
    }
    Ok(WalkProfile {
        bin_edges,
        rd,
        se,
        total,
        total_se,
        photons: cfg.photons,
        capped,
        capped_weight,
        rd_single,
        total_single,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn memory_estimate_covers_the_tallies_and_saturates() {
        // The result alone holds rd, se, rd_single for 3 channels (9 arrays of bins f64) and
        // each of the 8 chunk tallies per thread 3 more arrays.
        let bins = 1000;
        for threads in [1, 2, 16] {
            let b = memory_bytes(bins, threads);
            assert!(b >= (9 + 24 * threads as u64) * 8 * bins as u64, "{b}");
            // Linear in bins.
            assert_eq!(memory_bytes(2 * bins, threads), 2 * b);
        }
        // 0 threads counts as 1; absurd sizes saturate instead of overflowing.
        assert_eq!(memory_bytes(bins, 0), memory_bytes(bins, 1));
        assert_eq!(memory_bytes(usize::MAX, 64), u64::MAX);
    }
    use crate::quadrature::{gauss_legendre, integrate};

    /// Event cap of the albedo-1 tests: P(a walk survives n collisions) ~ 1.7/√n, so this
    /// caps ~1 % of the photons while bounding the cost per photon to ~500 collisions.
    const TEST_CAP: u64 = 20_000;

    fn cfg(photons: u64, seed: u64, r_max: f64, bins: usize) -> WalkConfig {
        WalkConfig {
            photons,
            seed,
            r_max,
            bins,
            channels: [true, false, false],
            spacing: BinSpacing::Linear,
        }
    }

    fn medium(albedo: f64, g: f64, eta: f64) -> Medium {
        Medium::from_extinction_albedo([1.0; 3], [albedo; 3], g, eta).unwrap()
    }

    /// Chandrasekhar's H-function for isotropic scattering with albedo `omega`,
    /// H(μ) = 1 + (ω/2) μ H(μ) ∫₀¹ H(μ')/(μ + μ') dμ' (Radiative Transfer, 1960, Ch. V),
    /// solved by fixed-point iteration on a composite Gauss-Legendre rule graded towards μ = 0
    /// (Nyström). Returns H(1) from the original equation, H(1) from the iterated form, and
    /// ∫₀¹ H dμ.
    fn chandrasekhar_h1(omega: f64) -> (f64, f64, f64) {
        let (x, w) = gauss_legendre(24);
        let panels = 12;
        let mut mu = Vec::new();
        let mut wt = Vec::new();
        for p in 0..panels {
            let a = (p as f64 / panels as f64).powi(2);
            let b = ((p + 1) as f64 / panels as f64).powi(2);
            for (xi, wi) in x.iter().zip(w) {
                mu.push(0.5 * (a + b) + 0.5 * (b - a) * xi);
                wt.push(0.5 * (b - a) * wi);
            }
        }
        let integral = |h: &[f64], m: f64| -> f64 {
            mu.iter()
                .zip(&wt)
                .zip(h)
                .map(|((mj, wj), hj)| wj * hj / (m + mj))
                .sum::<f64>()
        };
        // Iterate the equivalent form 1/H(μ) = √(1 − ω) + (ω/2) ∫₀¹ μ' H(μ')/(μ + μ') dμ'
        // (obtained with μ/(μ+μ') = 1 − μ'/(μ+μ') and (ω/2)∫H = 1 − √(1 − ω)), which
        // converges much faster than the original near ω = 1 once damped (undamped it can
        // alternate between two states); the original equation and the moment identity are
        // then checked on the result.
        let root = (1.0 - omega).sqrt();
        let mut h = vec![1.0; mu.len()];
        for _ in 0..20_000 {
            let mh: Vec<f64> = mu.iter().zip(&h).map(|(m, h)| m * h).collect();
            let next: Vec<f64> = mu
                .iter()
                .zip(&h)
                .map(|(&m, &old)| 0.5 * (old + 1.0 / (root + 0.5 * omega * integral(&mh, m))))
                .collect();
            let change = next
                .iter()
                .zip(&h)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max);
            h = next;
            if change < 1e-14 {
                break;
            }
        }
        let h1 = 1.0 / (1.0 - 0.5 * omega * integral(&h, 1.0));
        let mh: Vec<f64> = mu.iter().zip(&h).map(|(m, h)| m * h).collect();
        let h1_alt = 1.0 / (root + 0.5 * omega * integral(&mh, 1.0));
        let mean = wt.iter().zip(&h).map(|(a, b)| a * b).sum::<f64>();
        (h1, h1_alt, mean)
    }

    #[test]
    fn h_function_solver_matches_known_values() {
        // Chandrasekhar 1960, Table V (isotropic, conservative): H(1) = 2.9078.
        let (h1, h1_alt, m0) = chandrasekhar_h1(1.0);
        assert!((h1 - 2.9078).abs() < 1e-4, "H(1) = {h1}");
        assert!((h1_alt - 2.9078).abs() < 1e-4, "H(1) = {h1_alt}");
        assert!((m0 - 2.0).abs() < 1e-6, "conservative zeroth moment {m0}");
        for omega in [0.5, 0.9, 0.99] {
            let (h1, h1_alt, m0) = chandrasekhar_h1(omega);
            // Both forms of the equation agree on the solution...
            assert!(
                (h1 - h1_alt).abs() < 1e-6,
                "omega {omega}: {h1} vs {h1_alt}"
            );
            // ...and it has the zeroth moment ∫₀¹ H dμ = (2/ω)(1 − √(1 − ω)).
            let exact = 2.0 / omega * (1.0 - (1.0 - omega).sqrt());
            assert!((m0 - exact).abs() < 1e-6, "omega {omega}: {m0} vs {exact}");
        }
    }

    #[test]
    fn total_reflectance_matches_chandrasekhar_h_function() {
        // Plane albedo of a semi-infinite isotropically scattering half-space at normal
        // incidence: R(μ₀ = 1) = 1 − H(1)√(1 − ω) (Chandrasekhar 1960, §V). The pencil beam
        // integrated over all r is the same quantity.
        for (omega, photons) in [(0.5, 400_000), (0.9, 200_000), (0.99, 100_000)] {
            let (h1, _, _) = chandrasekhar_h1(omega);
            let exact = 1.0 - h1 * (1.0 - omega).sqrt();
            let m = medium(omega, 0.0, 1.0);
            let prof = simulate(&m, &cfg(photons, 17, 10.0, 10)).unwrap();
            let (r, se) = (prof.total[0], prof.total_se[0]);
            assert_eq!(prof.capped, 0);
            assert!(se > 0.0 && se < 0.01);
            assert!(
                (r - exact).abs() < 4.0 * se,
                "omega {omega}: MC {r} ± {se}, H-function {exact}"
            );
        }
    }

    #[test]
    fn single_scattering_profile_matches_closed_form() {
        // With one collision allowed (the cap stops the photon at the second), the tally is
        // exactly single scattering. A photon scattered at depth z towards the exit point at
        // radius r (path length ℓ, exit cosine μ = z/ℓ) contributes
        // R₁(r) = ∫ σ_s e^{−σ_t z} p(−μ) e^{−σ_t ℓ} μ/ℓ² T(μ) dz; with z = r tan α,
        // 2πr R₁(r) = 2π σ_s ∫₀^{π/2} e^{−σ_t r (tan α + sec α)} p(−sin α) T(sin α) sin α dα.
        for (g, eta) in [(0.0, 1.0), (0.6, 1.4), (-0.4, 0.8)] {
            let sigma_s = 0.8;
            let sigma_t = 2.0;
            let m = Medium::new([sigma_t - sigma_s; 3], [sigma_s; 3], g, eta).unwrap();
            let hg = |c: f64| {
                (1.0 - g * g) / (4.0 * std::f64::consts::PI * (1.0 + g * g - 2.0 * g * c).powf(1.5))
            };
            let two_pi_r_r1 = |r: f64| {
                let f = |a: f64| {
                    let (s, c) = a.sin_cos();
                    let e = (-sigma_t * r * (s + 1.0) / c.max(1e-300)).exp();
                    e * hg(-s) * (1.0 - fr_dielectric(s, 1.0 / eta)) * s
                };
                let half_pi = std::f64::consts::FRAC_PI_2;
                (0..8)
                    .map(|k| {
                        integrate(
                            &f,
                            half_pi * k as f64 / 8.0,
                            half_pi * (k + 1) as f64 / 8.0,
                            32,
                        )
                    })
                    .sum::<f64>()
                    * 2.0
                    * std::f64::consts::PI
                    * sigma_s
            };
            let c = WalkConfig {
                channels: [false, true, false],
                ..cfg(200_000, 5, 1.0, 10)
            };
            let prof = simulate_impl(&m, &c, 1, &|_| {}).unwrap();
            assert!(prof.capped > 0);
            let mut chi2 = 0.0;
            for b in 0..c.bins {
                let (r0, r1) = (prof.bin_edges[b], prof.bin_edges[b + 1]);
                let area = std::f64::consts::PI * (r1 * r1 - r0 * r0);
                let exact = integrate(&two_pi_r_r1, r0, r1, 32) / area;
                let (mc, se) = (prof.rd[1][b], prof.se[1][b]);
                assert!(se > 0.0, "g {g} eta {eta} bin {b}: {mc} {se}");
                let z = (mc - exact) / se;
                chi2 += z * z;
                assert!(
                    z.abs() < 4.5,
                    "g {g} eta {eta} bin {b}: {mc} ± {se} vs {exact}"
                );
            }
            // 10 bins: χ² has mean 10 and standard deviation √20.
            assert!(
                chi2 < 10.0 + 4.0 * 20f64.sqrt(),
                "g {g} eta {eta}: chi2 {chi2}"
            );
            assert_eq!(prof.rd[0], vec![0.0; c.bins]);
            assert_eq!(prof.total[2], 0.0);
        }
    }

    #[test]
    fn energy_is_conserved_without_absorption_index_matched() {
        for g in [0.0, 0.5] {
            let m = medium(1.0, g, 1.0);
            // A lower event cap than the public one keeps the heavy-tailed walks of albedo 1
            // cheap; the capped weight is accounted for.
            let prof = simulate_impl(&m, &cfg(8192, 3, 5.0, 5), TEST_CAP, &|_| {}).unwrap();
            assert!(
                prof.capped > 0 && prof.capped < 8192 / 20,
                "capped {}",
                prof.capped
            );
            // No Fresnel splitting and no roulette at albedo 1: weight is exactly conserved.
            let sum = prof.total[0] + prof.capped_weight[0];
            assert!((sum - 1.0).abs() < 1e-12, "g {g}: total + capped = {sum}");
            assert!(prof.total[0] > 0.97, "g {g}: total {}", prof.total[0]);
            assert!(prof.rd[0].iter().all(|v| v.is_finite() && *v > 0.0));
        }
    }

    #[test]
    fn energy_is_conserved_without_absorption_with_fresnel() {
        for eta in [1.33, 0.75] {
            let m = medium(1.0, 0.0, eta);
            let prof = simulate_impl(&m, &cfg(8192, 4, 5.0, 5), TEST_CAP, &|_| {}).unwrap();
            let sum = prof.total[0] + prof.capped_weight[0];
            let se = prof.total_se[0];
            assert!(
                se > 0.0,
                "eta {eta}: roulette of split weight gives some noise"
            );
            assert!(
                (sum - 1.0).abs() < 4.0 * se + 1e-12,
                "eta {eta}: total + capped = {sum} ± {se}"
            );
            assert!(prof.total[0] > 0.98, "eta {eta}: total {}", prof.total[0]);
        }
    }

    #[test]
    fn single_scattering_tally_is_the_one_collision_part() {
        // With the cap at one collision every escaping photon is singly scattered, so the
        // split must equal the whole; without the cap it is a strict part of it.
        let m = medium(0.9, 0.3, 1.3);
        let c = cfg(20_000, 5, 4.0, 16);
        let one = simulate_impl(&m, &c, 1, &|_| {}).unwrap();
        assert_eq!(one.total_single[0], one.total[0]);
        assert_eq!(one.rd_single[0], one.rd[0]);
        let all = simulate(&m, &c).unwrap();
        assert!(all.total_single[0] < all.total[0]);
        assert!(all.rd_single[0].iter().zip(&all.rd[0]).all(|(s, t)| s <= t));
    }

    #[test]
    fn pure_absorber_reflects_nothing() {
        let m = medium(0.0, 0.0, 1.3);
        let prof = simulate(&m, &cfg(5000, 1, 1.0, 4)).unwrap();
        assert_eq!(prof.total[0], 0.0);
        assert_eq!(prof.total_se[0], 0.0);
    }

    #[test]
    fn bins_sum_to_total_inside_r_max() {
        let m = Medium::preset("skin1").unwrap();
        let prof = simulate(&m, &cfg(20_000, 9, 1000.0, 7)).unwrap();
        let binned: f64 = prof.rd[0]
            .iter()
            .zip(prof.bin_areas())
            .map(|(v, a)| v * a)
            .sum();
        assert!((binned - prof.total[0]).abs() < 1e-12 * prof.total[0].max(1.0));
        let centers = prof.bin_centers();
        assert_eq!(centers.len(), 7);
        assert!((centers[0] - 1000.0 / 14.0).abs() < 1e-9);
        assert_eq!(*prof.bin_edges.last().unwrap(), 1000.0);
    }

    #[test]
    fn direction_samplers_have_the_right_moments() {
        // For Henyey-Greenstein ⟨cos θ⟩ = g and ⟨P₂(cos θ)⟩ = g².
        let mut rng = Pcg64Mcg::seed_from_u64(11);
        for g in [-0.7, 0.0, 0.3, 0.9, 0.999] {
            let n = 400_000;
            let (mut m1, mut m2) = (0.0, 0.0);
            for _ in 0..n {
                let c = sample_hg_cos(g, uniform(&mut rng));
                assert!((-1.0..=1.0).contains(&c));
                m1 += c;
                m2 += 1.5 * c * c - 0.5;
            }
            m1 /= n as f64;
            m2 /= n as f64;
            assert!((m1 - g).abs() < 0.005, "g {g}: <cos> = {m1}");
            assert!((m2 - g * g).abs() < 0.005, "g {g}: <P2> = {m2}");
        }
        // Azimuths are uniform: ⟨cos φ⟩ = ⟨sin φ⟩ = ⟨cos 2φ⟩ = 0, ⟨cos² φ⟩ = 1/2.
        let n = 400_000;
        let (mut c1, mut s1, mut c2, mut cc) = (0.0, 0.0, 0.0, 0.0);
        for _ in 0..n {
            let (c, s) = sample_azimuth(&mut rng);
            assert!((c * c + s * s - 1.0).abs() < 1e-12);
            c1 += c;
            s1 += s;
            c2 += c * c - s * s;
            cc += c * c;
        }
        let n = n as f64;
        for (name, v, want) in [
            ("cos", c1, 0.0),
            ("sin", s1, 0.0),
            ("cos2", c2, 0.0),
            ("cc", cc, 0.5),
        ] {
            assert!((v / n - want).abs() < 0.005, "{name}: {}", v / n);
        }
        for d in [
            DVec3::new(0.3, -0.4, 0.5).normalize(),
            DVec3::Z,
            DVec3::NEG_Z,
        ] {
            for (ct, phi) in [(0.2f64, 0.1f64), (-0.9, 2.7), (1.0, 4.0), (-1.0, 1.0)] {
                let n = scatter_direction(d, ct, phi.cos(), phi.sin());
                assert!((n.length() - 1.0).abs() < 1e-14);
                assert!((n.dot(d) - ct).abs() < 1e-12);
            }
        }
    }

    #[test]
    fn results_are_bit_identical_across_thread_counts() {
        let m = Medium::preset("skin1").unwrap();
        let c = WalkConfig {
            channels: [true, true, true],
            ..cfg(3 * CHUNK_PHOTONS + 123, 42, 20.0, 16)
        };
        let run = |threads: usize, cfg: &WalkConfig| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| simulate(&m, cfg).unwrap())
        };
        let one = run(1, &c);
        let two = run(2, &c);
        let bits = |p: &WalkProfile| -> Vec<u64> {
            (0..3)
                .flat_map(|ch| p.rd[ch].iter().chain(&p.se[ch]).map(|v| v.to_bits()))
                .chain(p.total.iter().map(|v| v.to_bits()))
                .collect()
        };
        assert_eq!(bits(&one), bits(&two));
        assert_eq!(one, two);
        let other = run(
            2,
            &WalkConfig {
                seed: 43,
                ..c.clone()
            },
        );
        assert_ne!(bits(&one), bits(&other));
        // Channels use independent streams: identical media give different tallies.
        let grey = medium(0.9, 0.0, 1.3);
        let g = simulate(
            &grey,
            &WalkConfig {
                channels: [true; 3],
                ..c
            },
        )
        .unwrap();
        assert_ne!(g.total[0].to_bits(), g.total[1].to_bits());
    }

    #[test]
    fn progress_reports_every_photon() {
        let m = medium(0.5, 0.0, 1.0);
        let c = WalkConfig {
            channels: [true, false, true],
            ..cfg(2 * CHUNK_PHOTONS + 7, 1, 1.0, 3)
        };
        let seen = Mutex::new(Vec::new());
        simulate_with_progress(&m, &c, &|n| seen.lock().unwrap().push(n)).unwrap();
        let seen = seen.into_inner().unwrap();
        assert_eq!(seen.len(), 6);
        assert!(seen.windows(2).all(|w| w[0] < w[1]));
        assert_eq!(*seen.last().unwrap(), 2 * c.photons);
    }

    #[test]
    fn bad_config_is_rejected() {
        let m = medium(0.5, 0.0, 1.0);
        let good = cfg(10, 0, 1.0, 4);
        assert!(simulate(&m, &good).is_ok());
        let bad = [
            WalkConfig {
                photons: 0,
                ..good.clone()
            },
            WalkConfig {
                bins: 0,
                ..good.clone()
            },
            WalkConfig {
                bins: MAX_BINS + 1,
                ..good.clone()
            },
            WalkConfig {
                r_max: 0.0,
                ..good.clone()
            },
            WalkConfig {
                r_max: -1.0,
                ..good.clone()
            },
            WalkConfig {
                r_max: f64::NAN,
                ..good.clone()
            },
            WalkConfig {
                r_max: f64::INFINITY,
                ..good.clone()
            },
            WalkConfig {
                channels: [false; 3],
                ..good.clone()
            },
        ];
        for c in bad {
            assert!(
                matches!(simulate(&m, &c), Err(BssrdfError::InvalidArgument(_))),
                "{c:?}"
            );
        }
        // A single photon is valid; its standard errors are reported as 0.
        let one = simulate(&m, &WalkConfig { photons: 1, ..good }).unwrap();
        assert!(one.se[0].iter().all(|&s| s == 0.0) && one.total_se[0] == 0.0);
    }

    #[test]
    fn standard_errors_are_honest() {
        // K independent runs: the spread of their estimates must match the standard error
        // each run reports. η = 1.3 makes photons deposit weight several times (Fresnel
        // splitting), so squaring per deposit instead of per photon would underestimate it.
        // With K = 60 the sample standard deviation is good to ~9 %.
        let m = medium(0.9, 0.3, 1.3);
        let k = 60;
        let runs: Vec<WalkProfile> = (0..k)
            .map(|seed| simulate(&m, &cfg(4000, 1000 + seed, 2.0, 4)).unwrap())
            .collect();
        let spread = |v: &[f64]| {
            let mean = v.iter().sum::<f64>() / v.len() as f64;
            (v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (v.len() - 1) as f64).sqrt()
        };
        let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
        let pick = |f: &dyn Fn(&WalkProfile) -> f64| runs.iter().map(f).collect::<Vec<f64>>();
        let cases = [
            ("bin 0", pick(&|p| p.rd[0][0]), pick(&|p| p.se[0][0])),
            ("bin 2", pick(&|p| p.rd[0][2]), pick(&|p| p.se[0][2])),
            ("total", pick(&|p| p.total[0]), pick(&|p| p.total_se[0])),
        ];
        for (name, v, s) in cases {
            let ratio = spread(&v) / mean(&s);
            assert!(
                (0.75..=1.33).contains(&ratio),
                "{name}: spread / SE = {ratio}"
            );
        }
    }
}
