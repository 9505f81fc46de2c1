//! The table's grid and its walks: the albedo rows, the radius knots and tally bins, the
//! η and g of the tables, and the plan of condensed walks (albedo bands, collision-count
//! strata, photons and seeds) that fills them.

use crate::monte_carlo::MAX_SCATTERING_EVENTS;
use std::ops::Range;

/// Number of single-scattering albedo rows (the grid of photon beam diffusion, pbrt §15.5.5).
pub const N_RHO: usize = 100;

/// The relative indices of refraction with a table of their own.
pub const ETAS: [f64; 6] = [1.0, 1.1, 1.2, 1.3, 1.4, 1.5];

/// The η of the measured presets (Jensen et al. 2001), simulated with the most photons.
pub const MAIN_ETA: f64 = 1.3;

/// Photons of the other η tables are those of [`MAIN_ETA`] divided by this.
pub const OTHER_ETA_PHOTON_DIVISOR: u64 = 2;

/// The Henyey-Greenstein anisotropies with tables of their own. The tables for g ≠ 0 are in
/// reduced units (rows of reduced albedo ρ', radii in reduced mean free paths 1/σ'_t; see the
/// module documentation), so at g = 0 they are the isotropic table and every g shares its
/// rows and knots.
pub const GS: [f64; 5] = [0.0, 0.2, 0.4, 0.7, 0.9];

/// Photons of the tables for g ≠ 0 are those of g = 0 divided by this (their walks are
/// longer: at the same reduced albedo the single-scattering albedo is closer to 1).
pub const ANISOTROPIC_PHOTON_DIVISOR: u64 = 2;

/// The single-scattering albedo ρ = ρ'/(1 − g + gρ') of a medium with reduced albedo ρ' and
/// anisotropy g (inverting ρ' = ρ(1 − g)/(1 − ρg), the similarity relation of the module
/// documentation); 0 for ρ' ≤ 0, 1 for ρ' ≥ 1.
pub fn single_scattering_albedo(reduced: f64, g: f64) -> f64 {
    if !(reduced > 0.0) {
        return 0.0;
    }
    if reduced >= 1.0 {
        return 1.0;
    }
    // 1 − g + gρ' ≥ min(1, 1 − g + g·0) > 0 for |g| < 1 and ρ' in (0, 1).
    (reduced / (1.0 - g + g * reduced)).clamp(0.0, 1.0)
}

/// Master seed of every table walk.
pub const SEED: u64 = 0x6d63_5f74_6162_6c65;

/// Upper ends of the albedo bands, as 1 − ρ: band b holds the rows with
/// `BAND_BOUNDS[b] ≤ 1 − ρ < BAND_BOUNDS[b − 1]`; the last band reaches ρ = 1.
const BAND_BOUNDS: [f64; 7] = [0.3, 0.1, 0.03, 0.01, 0.003, 0.001, 0.000_3];

/// The walks of each albedo band at [`MAIN_ETA`]: strata by collision count, each (last
/// collision count of the stratum, photons); a stratum starts after the previous one's last
/// count, the first at 1, and the last ends at [`MAX_SCATTERING_EVENTS`]. Bands near ρ = 1
/// split their walks: many short walks for what escapes early (the profile near the entry
/// point) and fewer full walks for the rest.
pub const BAND_STRATA: [&[(u64, u64)]; 8] = [
    &[(MAX_SCATTERING_EVENTS, 24_000_000)],
    &[(MAX_SCATTERING_EVENTS, 10_000_000)],
    &[(MAX_SCATTERING_EVENTS, 5_000_000)],
    &[(64, 2_000_000), (MAX_SCATTERING_EVENTS, 900_000)],
    &[
        (64, 2_000_000),
        (1024, 1_200_000),
        (MAX_SCATTERING_EVENTS, 30_000),
    ],
    &[
        (64, 2_000_000),
        (1024, 1_200_000),
        (MAX_SCATTERING_EVENTS, 30_000),
    ],
    &[
        (64, 2_000_000),
        (1024, 1_200_000),
        (32_768, 50_000),
        (MAX_SCATTERING_EVENTS, 1_000),
    ],
    &[
        (64, 2_000_000),
        (1024, 1_100_000),
        (32_768, 66_000),
        (MAX_SCATTERING_EVENTS, 2_000),
    ],
];

/// First knot after 0 (optical radius).
pub(super) const FIRST_KNOT: f64 = 0.005;
/// Relative step of the geometric parts of the radius grid.
pub(super) const GEOMETRIC_STEP: f64 = 0.2;
/// Step of the linear part of the radius grid (mean free paths).
pub(super) const LINEAR_STEP: f64 = 0.75;
/// End of the linear part: beyond it the step grows by 0.2 per mean free path.
pub(super) const LINEAR_END: f64 = 16.0;
/// The grid stops before its step would pass this optical radius.
pub(super) const LAST_KNOT_LIMIT: f64 = 1100.0;

/// The albedo rows ρ_i = (1 − e^{−8i/99})/(1 − e^{−8}), i = 0..[`N_RHO`] (pbrt §15.5.5).
pub fn rho_samples() -> Vec<f64> {
    let denom = 1.0 - (-8.0f64).exp();
    (0..N_RHO)
        .map(|i| (1.0 - (-8.0 * i as f64 / (N_RHO - 1) as f64).exp()) / denom)
        .collect()
}

/// The optical radius knots: 0, 0.005, then x_{k+1} = x_k + min(0.2 x_k, 0.75 + 0.2 max(0,
/// x_k − 16)) up to ≈ 1000 (see the module documentation).
pub fn radius_knots() -> Vec<f64> {
    let mut x = vec![0.0, FIRST_KNOT];
    loop {
        let last = x[x.len() - 1];
        let step = (GEOMETRIC_STEP * last)
            .min(LINEAR_STEP + GEOMETRIC_STEP * (last - LINEAR_END).max(0.0));
        let next = last + step;
        if next > LAST_KNOT_LIMIT {
            return x;
        }
        x.push(next);
    }
}

/// The tally bins of `knots` (n knots → n bins, n + 1 edges): bin 0 is [0, x₁]; bin k
/// (1 ≤ k ≤ n − 1) holds knot k and reaches to the midpoints between it and its neighbours,
/// except that bin 1 starts at x₁ and bin n − 1 ends at x_{n−1}.
pub fn tally_edges(knots: &[f64]) -> Vec<f64> {
    let n = knots.len();
    let mut edges = Vec::with_capacity(n + 1);
    edges.push(0.0);
    if n >= 2 {
        edges.push(knots[1]);
        for k in 2..n {
            edges.push(0.5 * (knots[k - 1] + knots[k]));
        }
        edges.push(knots[n - 1]);
    }
    edges
}

/// One walk of the table of one η: a stratum of collision counts of one albedo band.
#[derive(Clone, Debug, PartialEq)]
pub struct Walks {
    /// The albedo rows of the band.
    pub rows: Range<usize>,
    /// Weight escaping after `min_events..=max_events` collisions is tallied.
    pub min_events: u64,
    /// See `min_events`.
    pub max_events: u64,
    /// Photons of the walk.
    pub photons: u64,
    /// The walk's stream (distinct for every walk of every η).
    pub stream: usize,
}

/// The rows of each albedo band (by [`BAND_BOUNDS`] on 1 − ρ).
fn band_rows(rho: &[f64]) -> Vec<Range<usize>> {
    let mut bands = Vec::new();
    let mut start = 0;
    for bound in BAND_BOUNDS {
        let end = start
            + rho[start..]
                .iter()
                .take_while(|&&r| 1.0 - r >= bound)
                .count();
        bands.push(start..end);
        start = end;
    }
    bands.push(start..rho.len());
    bands
}

/// The walks of the table of `GS[g_index]` and `ETAS[eta_index]`, with photon counts
/// multiplied by `scale` (1 for the table in the repository; at least one photon per walk).
/// The streams of the table of g = 0 and η index e start at e × (walks per table), as they
/// did before the tables had g; table (g, e) starts at (g × [`ETAS`]`.len()` + e) × that.
pub fn plan(g_index: usize, eta_index: usize, scale: f64) -> Vec<Walks> {
    let rho = rho_samples();
    let mut divisor = if ETAS.get(eta_index) == Some(&MAIN_ETA) {
        1
    } else {
        OTHER_ETA_PHOTON_DIVISOR
    };
    if g_index > 0 {
        divisor *= ANISOTROPIC_PHOTON_DIVISOR;
    }
    let per_eta: usize = BAND_STRATA.iter().map(|s| s.len()).sum();
    let mut stream = (g_index * ETAS.len() + eta_index) * per_eta;
    let mut walks = Vec::with_capacity(per_eta);
    for (rows, strata) in band_rows(&rho).into_iter().zip(BAND_STRATA) {
        let mut min_events = 1;
        for &(max_events, photons) in strata {
            walks.push(Walks {
                rows: rows.clone(),
                min_events,
                max_events,
                photons: (((photons / divisor) as f64 * scale).round() as u64).max(1),
                stream,
            });
            stream += 1;
            min_events = max_events + 1;
        }
    }
    walks
}
