//! `mc-table`: the radial profile of the crate's own photon random walk ([`crate::monte_carlo`])
//! tabulated once over albedo, optical radius, relative index η and anisotropy g, and
//! evaluated and sampled like the photon beam diffusion table (pbrt 3rd ed. §11.4.2, §15.4.2:
//! Catmull-Rom in albedo and radius, [`SplineRow`] rows pre-blended per channel), so a
//! renderer gets the random walk's profile at the cost of a table lookup.
//!
//! # The table
//! - **Optical units.** Every walk runs in a medium of unit extinction (σ_t = 1, albedo
//!   ρ = σ_s, σ_a = 1 − ρ), g = 0. A medium of extinction σ_t has the profile
//!   R_d(r) = σ_t² R_d¹(σ_t r), R_d¹ the unit-extinction profile (lengths scale by 1/σ_t; the
//!   same scaling as pbrt Eq. 11.10 and [`crate::PhotonBeamDiffusion`]). The table stores
//!   T(ρ, x) = 2πx R_d¹(x), as PBD's table does.
//! - **Anisotropy.** One set of tables per g in [`GS`] (0, 0.2, 0.4, 0.7, 0.9), each in
//!   *reduced* units: row ρ' is the reduced albedo σ'_s/σ'_t (σ'_s = σ_s (1 − g),
//!   σ'_t = σ_a + σ'_s) and radii are in reduced mean free paths 1/σ'_t (for g = 0 these are the
//!   units above). Every g then shares the rows and knots, the similarity relation (Wyman,
//!   Patterson, Wilson, *Similarity relations for the interaction parameters in radiation
//!   transport*, Appl. Opt. 28(24), 1989; Jensen et al. 2001 §2.4) is exact far from the
//!   entry point, and what g changes — the profile near it, where similarity alone was off
//!   by +24–29 % for marble with g = 0.5 and +50–70 % for skin1 with g = 0.8 at 0.25 reduced
//!   mean free paths — is in the tables. The walk for g ≠ 0 still runs at unit extinction: row
//!   ρ' is simulated at its single-scattering albedo ρ = ρ'/(1 − g + gρ')
//!   ([`single_scattering_albedo`]) with the true g, and each escape is binned at σ'_t r =
//!   (1 − ρg) r for that row (the per-row radius scales of the condensed walk, so the rows still
//!   share their photons). Between the tables the knot values are blended linearly in g
//!   (measured before the choice of grid: profiles move by at most a few per cent between
//!   neighbouring g of this grid away from g = 0, where the near field changes fastest and the
//!   0.2 step sits); a medium outside [0, 0.9] reads the nearest end table at its reduced
//!   coefficients ([`McTableModel::g_in_range`] says so). Presets (Jensen et al. 2001 give σ'_s
//!   with g = 0) read the g = 0 tables.
//! - **Albedos.** [`N_RHO`] albedos on the grid of photon beam diffusion,
//!   ρ_i = (1 − e^{−8i/99})/(1 − e^{−8}) (pbrt §15.5.5), dense near 1.
//! - **Radii.** [`radius_knots`]: 0, then from 0.005 mean free paths steps of 20 % (geometric,
//!   as PBD's grid) until the step reaches 0.75, steps of 0.75 up to 16, then growing again by
//!   0.2 per unit beyond, up to ≈ 1000 mean free paths. The linear stretch keeps Catmull-Rom's
//!   error on exponential tails small: a spline through e^{−σx} at spacing h is off by 0.8 %
//!   mid-interval at σh = 0.75 and 2.5 % at σh = 1, and every ρ ≥ 0.5 decays at σ < 1 per mean
//!   free path, while 20 % geometric steps would give σh > 3 at 16 mean free paths.
//! - **η.** One table per η in [`ETAS`] (1.0 to 1.5 in steps of 0.1) and g; between them the
//!   profile is interpolated linearly in η (which keeps it non-negative and keeps ρ_eff
//!   non-decreasing in ρ); the totals' curvature in η makes that < 0.3 % off at 0.1 spacing.
//!   Outside [1.0, 1.5] the nearest end table is used: [`McTableModel::eta_in_range`] says
//!   whether that happened, and the scene loader and `sss profile` refuse such media.
//!
//! # From tallies to a spline
//! The Monte Carlo tallies the escaped weight in bins around the knots (edges at the midpoints
//! between knots, [`tally_edges`]), i.e. bin integrals M_k = ∫ T over bin k, not point values.
//! A spline through bin averages would be biased by the curvature (at 20 % steps on an
//! exponential tail, several per cent). Instead the knot values v are solved so that the
//! spline's integral over every bin equals its tally, ∫_bin_k S(v) = M_k (histopolation: a
//! square linear system, close to the identity in the sense that each bin integral is
//! dominated by its own knot, so the tallies' noise is not amplified much). The spline has one
//! knot more than the tallies have knots, at 0.1 x₁ ([`spline_knots`]), so that the first bin
//! [0, x₁] — where T tends to a positive constant from single scattering but the spline must
//! start at 0 — is fitted like the others. Before the solve, the narrow, noisy bins near the
//! origin and the poorly resolved far tail are pooled into resolved groups ([`inner_masses`],
//! [`tail_masses`]); after it, R_d at the knots is made non-increasing by an isotonic fit
//! ([`row_nodes`]), and the model makes the first interval [0, 0.1 x₁] linear in T
//! ([`SplineRow::with_linear_first_segment`]) and keeps the row it blends for a medium
//! non-increasing in R_d (`monotone_row`). The spline then reproduces every tallied bin
//! integral where the tallies are resolved and ordered, and its total stays within 3 standard
//! errors of the tallied total reflectance for every albedo ≥ 0.5 (tested).
//!
//! # The far tail: a fitted diffusion far field
//! Measured against MCML (Wang, Jacques & Zheng, *MCML — Monte Carlo modeling of light
//! transport in multi-layered tissues*, Comput. Methods Programs Biomed. 47, 1995; 12 media
//! of reduced albedo 0.68–0.9999, `tests/mcml.rs`, its `stages` test prints the figures) on
//! the table's own bins, the tallies, the pooling, the isotonic fit, the histopolation and
//! the albedo blend all agree with MCML within the tallies' noise up to ≈ 10 mean free paths
//! (worst −4.3 % at 8 mean free paths for ketchup, 2.6 of the tallies' standard errors);
//! what departed was the tail beyond: bins were kept as tallied up to a relative standard
//! error of 20 % ([`RESOLVED_REL_SE`]), so at albedos 0.65–0.85 the rows carried their
//! tallies' noise, 5–20 % per bin at 10–16 mean free paths (ketchup +38 % at 14 mean free
//! paths, skin1 −24 % at 15.5), and the spline through them up to 3 times MCML's value in
//! single MCML bins. (Deviations of single MCML bins closer in, quoted at 5–35 %, were
//! MCML's own noise — its bins have heavy-tailed errors estimated from 5 batches — and at
//! η = 1.3 its normalisation per incident rather than per entering photon, 1.7 %.)
//!
//! So beyond the first bins that are resolved to 1 % ([`ASYMPTOTE_SWITCH_REL_SE`]) the
//! tallies are replaced by the far field of one diffusion pole fitted to the resolved bins
//! from 3 mean free paths on ([`asymptotic_tail`]): R_d ∝ e^{−κd}(1 + κd)/d³ with
//! d = √(x² + z²), the shape of each source of the dipole (Farrell, Patterson & Wilson,
//! *A diffusion theory model of spatially resolved, steady-state diffuse reflectance*, Med.
//! Phys. 19(4), 1992, Eq. 7; Jensen et al. 2001 Eq. 5), with the amplitude, κ and z free:
//! κ is then the decay of the transport solution, not diffusion's σ_tr (0.745 fitted at
//! albedo 0.747, where the root of c·artanh(κ)/κ = 1 of one-speed transport theory is 0.78
//! and σ_tr = 0.87; Case & Zweifel, *Linear Transport Theory*, 1967, §4). Its bin integrals
//! are closed-form. The replaced bins keep their tallied light, so every row's total is
//! unchanged. After it, every MCML case is within 3 % + 3 standard errors up to
//! 10 mean free paths and 10 % + 3 standard errors up to 16 (see `tests/mcml.rs` for the
//! margins and how MCML's noise is treated); evaluation is unchanged, and building a table
//! costs one small fit per row.
//!
//! # Generation
//! [`McTableData::generate`] (run by `cargo xtask tables`) simulates every g, η and albedo band
//! with the condensed walk of [`crate::monte_carlo::condensed`] (one walk per band, every
//! albedo row of the band tallied from the same photons) with fixed seeds, so the result is
//! bit-identical for any thread count; [`McTableData::to_bytes`] writes it, and the crate
//! embeds `data/mc_table.bin`. The bin masses and their standard errors are stored as f32
//! (their relative rounding, 6·10⁻⁸, is far below the Monte Carlo noise; rounding keeps the
//! order of values, so the rows stay non-decreasing in ρ).

#![allow(
    clippy::neg_cmp_op_on_partial_ord,
    reason = "`!(x > 0.0)` deliberately treats NaN as failing the guard"
)]

use crate::catmull_rom::{
    apply_weights, catmull_rom_weights, integrate_catmull_rom, interpolate_catmull_rom,
};
use crate::monte_carlo::MAX_SCATTERING_EVENTS;
use crate::monte_carlo::condensed::{CondensedConfig, simulate_albedos};
use crate::quadrature::gauss_legendre;
use crate::spline_row::{KnotIndex, OpticalProfile, SplineRow};
use crate::{Bssrdf, BssrdfError, Medium, ModelKind, Rgb};
use std::collections::HashMap;
use std::f64::consts::PI;
use std::ops::Range;
use std::sync::{Arc, Mutex, OnceLock};

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
const FIRST_KNOT: f64 = 0.005;
/// Relative step of the geometric parts of the radius grid.
const GEOMETRIC_STEP: f64 = 0.2;
/// Step of the linear part of the radius grid (mean free paths).
const LINEAR_STEP: f64 = 0.75;
/// End of the linear part: beyond it the step grows by 0.2 per mean free path.
const LINEAR_END: f64 = 16.0;
/// The grid stops before its step would pass this optical radius.
const LAST_KNOT_LIMIT: f64 = 1100.0;

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

/// The table file embedded in the crate.
const EMBEDDED: &[u8] = include_bytes!(concat!(env!("CARGO_MANIFEST_DIR"), "/data/mc_table.bin"));

/// File magic of the table data (version 2: tables over g and η).
const MAGIC: &[u8; 8] = b"SSSMCT\x02\x00";

/// File magic of version 1 (g = 0 only), read by [`McTableData::from_bytes_v1`].
const MAGIC_V1: &[u8; 8] = b"SSSMCT\x01\x00";

/// FNV-1a 64 (Fowler, Noll, Vo) of `bytes`: the checksum of the table file.
fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ b as u64).wrapping_mul(0x0100_0000_01b3)
    })
}

/// The Monte Carlo tallies behind the table: for every table (g of [`GS`], η of [`ETAS`]) and
/// albedo row, the escaped weight per photon in each bin of [`tally_edges`] (∫ 2πx R_d¹ dx
/// over the bin; unit extinction for g = 0, unit reduced extinction otherwise) with its
/// standard error, and the row's total reflectance.
///
/// The tables are numbered g-major: table `t = g_index × etas().len() + eta_index`
/// ([`McTableData::table_index`]), so for g = 0 the table index is the η index.
#[derive(Clone, Debug, PartialEq)]
pub struct McTableData {
    seed: u64,
    gs: Vec<f64>,
    etas: Vec<f64>,
    rho: Vec<f64>,
    knots: Vec<f64>,
    edges: Vec<f64>,
    /// Per table, the walks.
    walks: Vec<Vec<Walks>>,
    /// Per (table, row, bin), row-major.
    mass: Vec<f64>,
    mass_se: Vec<f64>,
    /// Per (table, row).
    total: Vec<f64>,
    total_se: Vec<f64>,
    capped_weight: Vec<f64>,
}

impl McTableData {
    /// Runs every walk of [`plan`] (photons × `scale`), calling `progress` with a line after
    /// each. Takes ≈ 700 CPU-seconds at `scale` = 1 for the tables of g = 0 (measured on a
    /// shared 2-core machine) and about 4.5 times that for the others (see the README).
    /// Bit-identical for any number of rayon threads.
    pub fn generate(scale: f64, progress: &dyn Fn(&str)) -> Result<McTableData, BssrdfError> {
        McTableData::generate_reusing(scale, None, progress)
    }

    /// [`McTableData::generate`], taking each table whose g, η, seed and walks `reuse` holds
    /// unchanged from it instead of running its walks again (every walk is seeded, so the
    /// result is the same as a full run; `cargo xtask tables --reuse`).
    pub fn generate_reusing(
        scale: f64,
        reuse: Option<&McTableData>,
        progress: &dyn Fn(&str),
    ) -> Result<McTableData, BssrdfError> {
        if !(scale > 0.0 && scale.is_finite()) {
            return Err(BssrdfError::InvalidArgument(format!(
                "mc-table: photon scale {scale} must be finite and > 0"
            )));
        }
        let rho = rho_samples();
        let knots = radius_knots();
        let edges = tally_edges(&knots);
        let bins = edges.len() - 1;
        let tables = GS.len() * ETAS.len();
        let cells = tables * N_RHO * bins;
        let mut data = McTableData {
            seed: SEED,
            gs: GS.to_vec(),
            etas: ETAS.to_vec(),
            rho: rho.clone(),
            knots,
            edges: edges.clone(),
            walks: Vec::new(),
            mass: vec![0.0; cells],
            mass_se: vec![0.0; cells],
            total: vec![0.0; tables * N_RHO],
            total_se: vec![0.0; tables * N_RHO],
            capped_weight: vec![0.0; tables * N_RHO],
        };
        for (gi, &g) in GS.iter().enumerate() {
            for (e, &eta) in ETAS.iter().enumerate() {
                let t = gi * ETAS.len() + e;
                let walks = plan(gi, e, scale);
                let old = reuse.and_then(|r| r.find_table(g, eta, SEED, &walks));
                if let Some((r, rt)) = old {
                    let (cell, row) = (t * N_RHO * bins, t * N_RHO);
                    let (rcell, rrow) = (rt * N_RHO * bins, rt * N_RHO);
                    let n = N_RHO * bins;
                    data.mass[cell..cell + n].copy_from_slice(&r.mass[rcell..rcell + n]);
                    data.mass_se[cell..cell + n].copy_from_slice(&r.mass_se[rcell..rcell + n]);
                    for (dst, src) in [
                        (&mut data.total, &r.total),
                        (&mut data.total_se, &r.total_se),
                        (&mut data.capped_weight, &r.capped_weight),
                    ] {
                        dst[row..row + N_RHO].copy_from_slice(&src[rrow..rrow + N_RHO]);
                    }
                    progress(&format!("g {g}, eta {eta}: reused"));
                } else {
                    data.simulate_table(t, g, eta, &walks, progress)?;
                }
                data.walks.push(walks);
            }
        }
        Ok(data)
    }

    /// Runs the walks of table `t` (anisotropy `g`, index `eta`) into its cells.
    fn simulate_table(
        &mut self,
        t: usize,
        g: f64,
        eta: f64,
        walks: &[Walks],
        progress: &dyn Fn(&str),
    ) -> Result<(), BssrdfError> {
        let bins = self.edges.len() - 1;
        // Strata of one band add up: sums of masses and totals, variances in quadrature.
        let mut var = vec![0.0; N_RHO * bins];
        let mut total_var = vec![0.0; N_RHO];
        for walk in walks {
            let start = std::time::Instant::now();
            let reduced = &self.rho[walk.rows.clone()];
            // The rows are reduced albedos; the walk runs at their single-scattering albedos
            // in a medium of unit extinction and bins row i at σ'_t r, σ'_t = 1 − ρ_i g.
            let albedos: Vec<f64> = reduced
                .iter()
                .map(|&r| single_scattering_albedo(r, g))
                .collect();
            let radius_scales = if g == 0.0 {
                Vec::new()
            } else {
                albedos.iter().map(|&a| 1.0 - a * g).collect()
            };
            let profile = simulate_albedos(&CondensedConfig {
                photons: walk.photons,
                seed: self.seed,
                stream: walk.stream,
                albedos,
                g,
                eta,
                edges: self.edges.clone(),
                min_events: walk.min_events,
                max_events: walk.max_events,
                radius_scales,
            })?;
            for (k, i) in walk.rows.clone().enumerate() {
                let (cell, row) = ((t * N_RHO + i) * bins, t * N_RHO + i);
                for b in 0..bins {
                    self.mass[cell + b] += profile.row_mass(k)[b];
                    var[i * bins + b] += profile.row_mass_se(k)[b].powi(2);
                }
                self.total[row] += profile.total[k];
                total_var[i] += profile.total_se[k].powi(2);
                if walk.max_events == MAX_SCATTERING_EVENTS {
                    self.capped_weight[row] = profile.capped_weight[k];
                }
            }
            let stopped = if walk.max_events == MAX_SCATTERING_EVENTS {
                format!("{} stopped by the collision cap", profile.capped)
            } else {
                format!("{} walk on past the stratum", profile.capped)
            };
            progress(&format!(
                "g {g}, eta {eta}: albedo rows {}..{} (rho' {:.6}..{:.6}), collisions {}..={}, \
                 {} photons, {:.1} s, {stopped}",
                walk.rows.start,
                walk.rows.end,
                self.rho[walk.rows.start],
                self.rho[walk.rows.end - 1],
                walk.min_events,
                walk.max_events,
                walk.photons,
                start.elapsed().as_secs_f64(),
            ));
        }
        // Stored as f32 (see the module documentation).
        let (cells, rows) = (t * N_RHO * bins, t * N_RHO);
        for (k, v) in var.iter().enumerate() {
            let m = &mut self.mass[cells + k];
            *m = *m as f32 as f64;
            self.mass_se[cells + k] = v.sqrt() as f32 as f64;
        }
        for (i, v) in total_var.iter().enumerate() {
            self.total_se[rows + i] = v.sqrt();
        }
        Ok(())
    }

    /// The table of anisotropy `g` and index `eta`, if this data holds it with the same seed
    /// and walks: (self, its table index).
    fn find_table(&self, g: f64, eta: f64, seed: u64, walks: &[Walks]) -> Option<(&Self, usize)> {
        // The rows and knots are this version's: `parse` and `generate` make no others.
        if self.seed != seed {
            return None;
        }
        let gi = self.gs.iter().position(|&x| x.to_bits() == g.to_bits())?;
        let e = self
            .etas
            .iter()
            .position(|&x| x.to_bits() == eta.to_bits())?;
        let t = gi * self.etas.len() + e;
        (self.walks.get(t)?.as_slice() == walks).then_some((self, t))
    }

    /// The binary file (little-endian): magic, seed, sizes (g, η, ρ, knots, walks per table),
    /// the grids (g, η, ρ, knots, edges), per table the walks (rows, stream, collision range,
    /// photons), per (table, row) the total, its standard error and the capped weight as f64,
    /// per (table, row, bin) the masses and then their standard errors as f32, and the FNV-1a
    /// 64 of everything before it.
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut out = Vec::new();
        out.extend_from_slice(MAGIC);
        out.extend_from_slice(&self.seed.to_le_bytes());
        let n_walks = self.walks.first().map_or(0, Vec::len);
        for n in [
            self.gs.len(),
            self.etas.len(),
            self.rho.len(),
            self.knots.len(),
            n_walks,
        ] {
            out.extend_from_slice(&(n as u32).to_le_bytes());
        }
        for v in self
            .gs
            .iter()
            .chain(&self.etas)
            .chain(&self.rho)
            .chain(&self.knots)
            .chain(&self.edges)
        {
            out.extend_from_slice(&v.to_le_bytes());
        }
        for walks in &self.walks {
            for w in walks {
                for v in [w.rows.start, w.rows.end, w.stream] {
                    out.extend_from_slice(&(v as u32).to_le_bytes());
                }
                for v in [w.min_events, w.max_events, w.photons] {
                    out.extend_from_slice(&v.to_le_bytes());
                }
            }
        }
        for k in 0..self.total.len() {
            for v in [self.total[k], self.total_se[k], self.capped_weight[k]] {
                out.extend_from_slice(&v.to_le_bytes());
            }
        }
        for v in self.mass.iter().chain(&self.mass_se) {
            out.extend_from_slice(&(*v as f32).to_le_bytes());
        }
        let sum = fnv1a(&out);
        out.extend_from_slice(&sum.to_le_bytes());
        out
    }

    /// Reads [`McTableData::to_bytes`]'s format. Errors (never panics) on a wrong magic or
    /// checksum, a truncated file, grids other than this version's ([`GS`], [`ETAS`],
    /// [`rho_samples`], [`radius_knots`]) or values that are not finite and ≥ 0.
    pub fn from_bytes(bytes: &[u8]) -> Result<McTableData, BssrdfError> {
        let data = McTableData::parse(bytes, MAGIC)?;
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<u64>>();
        if bits(&data.gs) != bits(&GS) || bits(&data.etas) != bits(&ETAS) {
            return Err(BssrdfError::InvalidArgument(
                "mc-table data: grids differ from this version's (regenerate with `cargo xtask \
                 tables`)"
                    .into(),
            ));
        }
        Ok(data)
    }

    /// Reads a version-1 file (the tables of g = 0 only, before the tables had g), as data
    /// with `gs() == [0.0]`: something to [`McTableData::generate_reusing`] from, not a table
    /// the model reads.
    pub fn from_bytes_v1(bytes: &[u8]) -> Result<McTableData, BssrdfError> {
        McTableData::parse(bytes, MAGIC_V1)
    }

    /// The common reader of both versions (version 1 has no g grid: it is g = 0).
    fn parse(bytes: &[u8], magic: &[u8; 8]) -> Result<McTableData, BssrdfError> {
        let bad = |what: &str| {
            Err(BssrdfError::InvalidArgument(format!(
                "mc-table data: {what}"
            )))
        };
        if bytes.len() < magic.len() + 8 || &bytes[..magic.len()] != magic {
            return bad("not a table file of this version (magic)");
        }
        let (body, sum) = bytes.split_at(bytes.len() - 8);
        if fnv1a(body).to_le_bytes() != sum {
            return bad("checksum mismatch (corrupt or truncated)");
        }
        let mut r = Reader {
            bytes: body,
            at: magic.len(),
        };
        let v1 = magic == MAGIC_V1;
        let seed = r.u64()?;
        let n_g = if v1 { 1 } else { r.u32()? as usize };
        let sizes = [r.u32()?, r.u32()?, r.u32()?, r.u32()?].map(|v| v as usize);
        let [n_eta, n_rho, n_knots, n_walks] = sizes;
        let gs = if v1 { vec![0.0] } else { r.f64s(n_g)? };
        let etas = r.f64s(n_eta)?;
        let rho = r.f64s(n_rho)?;
        let knots = r.f64s(n_knots)?;
        let edges = r.f64s(n_knots.saturating_add(1))?;
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<u64>>();
        let want_knots = radius_knots();
        if bits(&rho) != bits(&rho_samples())
            || bits(&knots) != bits(&want_knots)
            || bits(&edges) != bits(&tally_edges(&want_knots))
            || n_g == 0
            || n_eta == 0
        {
            return bad("grids differ from this version's (regenerate with `cargo xtask tables`)");
        }
        let tables = n_g.saturating_mul(n_eta);
        let mut walks = Vec::with_capacity(tables.min(64));
        for _ in 0..tables {
            let mut row = Vec::with_capacity(n_walks.min(64));
            for _ in 0..n_walks {
                let (start, end, stream) = (r.u32()? as usize, r.u32()? as usize, r.u32()?);
                let (min_events, max_events, photons) = (r.u64()?, r.u64()?, r.u64()?);
                if !(start < end && end <= n_rho && photons > 0 && min_events <= max_events) {
                    return bad("invalid walk");
                }
                row.push(Walks {
                    rows: start..end,
                    min_events,
                    max_events,
                    photons,
                    stream: stream as usize,
                });
            }
            walks.push(row);
        }
        let rows = tables.saturating_mul(n_rho);
        let (mut total, mut total_se, mut capped_weight) = (
            Vec::with_capacity(rows.min(1 << 16)),
            Vec::with_capacity(rows.min(1 << 16)),
            Vec::with_capacity(rows.min(1 << 16)),
        );
        for _ in 0..rows {
            total.push(r.f64()?);
            total_se.push(r.f64()?);
            capped_weight.push(r.f64()?);
        }
        let cells = rows.saturating_mul(n_knots);
        let mass = r.f32s(cells)?;
        let mass_se = r.f32s(cells)?;
        if r.at != body.len() {
            return bad("trailing bytes");
        }
        let valid = |v: &[f64]| v.iter().all(|x| x.is_finite() && *x >= 0.0);
        if !(valid(&mass)
            && valid(&mass_se)
            && valid(&total)
            && valid(&total_se)
            && valid(&capped_weight)
            && gs.iter().all(|g| g.abs() < 1.0))
        {
            return bad("a tallied value is negative or not finite");
        }
        Ok(McTableData {
            seed,
            gs,
            etas,
            rho,
            knots,
            edges,
            walks,
            mass,
            mass_se,
            total,
            total_se,
            capped_weight,
        })
    }

    /// The table embedded in the crate (`data/mc_table.bin`), parsed on first use.
    pub fn embedded() -> Result<&'static McTableData, BssrdfError> {
        static DATA: OnceLock<Result<McTableData, BssrdfError>> = OnceLock::new();
        DATA.get_or_init(|| McTableData::from_bytes(EMBEDDED))
            .as_ref()
            .map_err(Clone::clone)
    }

    /// The master seed of the walks.
    pub fn seed(&self) -> u64 {
        self.seed
    }

    /// The anisotropy of each table ([`GS`]).
    pub fn gs(&self) -> &[f64] {
        &self.gs
    }

    /// The η of each table ([`ETAS`]).
    pub fn etas(&self) -> &[f64] {
        &self.etas
    }

    /// The index of the table of `gs()[g_index]` and `etas()[eta_index]`, the `t` of the
    /// accessors below.
    pub fn table_index(&self, g_index: usize, eta_index: usize) -> usize {
        g_index * self.etas.len() + eta_index
    }

    /// The albedo rows ([`rho_samples`]): single-scattering albedos for g = 0, reduced
    /// albedos otherwise.
    pub fn rho_samples(&self) -> &[f64] {
        &self.rho
    }

    /// The radius knots ([`radius_knots`]).
    pub fn knots(&self) -> &[f64] {
        &self.knots
    }

    /// The tally bin edges ([`tally_edges`]).
    pub fn edges(&self) -> &[f64] {
        &self.edges
    }

    /// The walks of table `t`.
    pub fn walks(&self, t: usize) -> &[Walks] {
        &self.walks[t]
    }

    fn cell(&self, t: usize, i: usize) -> Range<usize> {
        let bins = self.knots.len();
        let start = (t * self.rho.len() + i) * bins;
        start..start + bins
    }

    /// The tallied bin masses ∫ 2πx R_d¹ dx of table `t`, albedo row `i`.
    pub fn mass(&self, t: usize, i: usize) -> &[f64] {
        &self.mass[self.cell(t, i)]
    }

    /// Standard errors of [`McTableData::mass`].
    pub fn mass_se(&self, t: usize, i: usize) -> &[f64] {
        &self.mass_se[self.cell(t, i)]
    }

    /// The tallied total reflectance (all radii) of table `t`, albedo row `i`, and its
    /// standard error.
    pub fn total(&self, t: usize, i: usize) -> (f64, f64) {
        let k = t * self.rho.len() + i;
        (self.total[k], self.total_se[k])
    }

    /// The weight per photon lost to the event cap of the walk (table `t`, row `i`).
    pub fn capped_weight(&self, t: usize, i: usize) -> f64 {
        self.capped_weight[t * self.rho.len() + i]
    }
}

/// A little-endian reader over a byte slice that reports truncation as an error.
struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl Reader<'_> {
    fn take(&mut self, n: usize) -> Result<&[u8], BssrdfError> {
        let end = self.at.checked_add(n).filter(|&e| e <= self.bytes.len());
        let Some(end) = end else {
            return Err(BssrdfError::InvalidArgument(
                "mc-table data: truncated".into(),
            ));
        };
        let s = &self.bytes[self.at..end];
        self.at = end;
        Ok(s)
    }

    fn u32(&mut self) -> Result<u32, BssrdfError> {
        let b = self.take(4)?;
        Ok(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    }

    fn u64(&mut self) -> Result<u64, BssrdfError> {
        let b = self.take(8)?;
        let mut a = [0u8; 8];
        a.copy_from_slice(b);
        Ok(u64::from_le_bytes(a))
    }

    fn f64(&mut self) -> Result<f64, BssrdfError> {
        Ok(f64::from_bits(self.u64()?))
    }

    fn f64s(&mut self, n: usize) -> Result<Vec<f64>, BssrdfError> {
        let b = self.take(n.saturating_mul(8))?;
        Ok(b.chunks_exact(8)
            .map(|c| {
                let mut a = [0u8; 8];
                a.copy_from_slice(c);
                f64::from_le_bytes(a)
            })
            .collect())
    }

    fn f32s(&mut self, n: usize) -> Result<Vec<f64>, BssrdfError> {
        let b = self.take(n.saturating_mul(4))?;
        Ok(b.chunks_exact(4)
            .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]) as f64)
            .collect())
    }
}

/// Where the extra spline knot of [`spline_knots`] sits in the first tally bin [0, x₁], as a
/// fraction of x₁.
const NEAR_ORIGIN_KNOT: f64 = 0.1;

/// The knots of the table's splines: the tally knots ([`radius_knots`]) with one more at
/// 0.1 x₁. The spline must be 0 at x = 0 (it is 2πx R_d), while the tallied profile T(x) tends
/// to a positive constant there (single scattering makes R_d ∝ 1/r near the entry point), so
/// a spline from 0 straight to x₁ would miss half of the first bin's light (≈ 0.3 % of the
/// total at albedo 0.8); with the extra knot the first bin's tally is fitted like the others.
pub fn spline_knots(knots: &[f64]) -> Vec<f64> {
    let mut x = Vec::with_capacity(knots.len() + 1);
    x.push(0.0);
    if knots.len() >= 2 {
        x.push(NEAR_ORIGIN_KNOT * knots[1]);
        x.extend_from_slice(&knots[1..]);
    }
    x
}

/// The histopolation system of the tally bins of a knot vector ([`tally_edges`]) and the
/// splines on its [`spline_knots`]: the matrix A with A_kj = ∫_{bin k} φ_j, φ_j the Catmull-Rom
/// cardinal function of spline knot j (the spline through the unit vector e_j), for every bin
/// k and every spline knot but the first (fixed at 0) — as many knots as bins —
/// LU-factorised with partial pivoting (Golub & Van Loan, *Matrix Computations*,
/// Algorithm 3.4.1).
#[derive(Clone, Debug)]
pub struct Histopolation {
    n: usize,
    lu: Vec<f64>,
    pivot: Vec<usize>,
}

impl Histopolation {
    /// The system of the tally `knots` (x₀ = 0, increasing). Each bin is split at the spline
    /// knots it contains and integrated with 3-point Gauss-Legendre, exact for the cubic
    /// pieces.
    pub fn new(knots: &[f64]) -> Result<Histopolation, BssrdfError> {
        let n_knots = knots.len();
        if n_knots < 3 || knots[0] != 0.0 || !knots.windows(2).all(|w| w[0] < w[1]) {
            return Err(BssrdfError::InvalidArgument(
                "histopolation: need ≥ 3 increasing knots from 0".into(),
            ));
        }
        let edges = tally_edges(knots);
        let xs = spline_knots(knots);
        let n = n_knots;
        let mut a = vec![0.0; n * n];
        let (gx, gw) = gauss_legendre(3);
        for k in 0..n {
            let (lo, hi) = (edges[k], edges[k + 1]);
            let mut cuts = vec![lo];
            cuts.extend(xs.iter().copied().filter(|&x| x > lo && x < hi));
            cuts.push(hi);
            for w in cuts.windows(2) {
                let (half, mid) = (0.5 * (w[1] - w[0]), 0.5 * (w[1] + w[0]));
                for (xi, wi) in gx.iter().zip(gw) {
                    let Some((offset, cw)) = catmull_rom_weights(&xs, mid + half * xi) else {
                        continue;
                    };
                    for (m, c) in cw.iter().enumerate() {
                        let j = offset + m as isize;
                        if *c != 0.0 && j >= 1 {
                            a[k * n + (j as usize - 1)] += half * wi * c;
                        }
                    }
                }
            }
        }
        // LU with partial pivoting, in place.
        let mut pivot = vec![0; n];
        for col in 0..n {
            let p = (col..n)
                .max_by(|&x, &y| a[x * n + col].abs().total_cmp(&a[y * n + col].abs()))
                .unwrap_or(col);
            if !(a[p * n + col].abs() > 0.0) {
                return Err(BssrdfError::InvalidArgument(
                    "histopolation: singular system".into(),
                ));
            }
            pivot[col] = p;
            if p != col {
                for c in 0..n {
                    a.swap(p * n + c, col * n + c);
                }
            }
            let d = a[col * n + col];
            for row in col + 1..n {
                let f = a[row * n + col] / d;
                a[row * n + col] = f;
                if f != 0.0 {
                    for c in col + 1..n {
                        a[row * n + c] -= f * a[col * n + c];
                    }
                }
            }
        }
        Ok(Histopolation { n, lu: a, pivot })
    }

    /// The values at spline knots 1.. (see [`spline_knots`]; knot 0 is 0) whose spline
    /// integrates to `masses[k]` over tally bin k, for every bin.
    pub fn solve(&self, masses: &[f64]) -> Vec<f64> {
        let n = self.n;
        let mut x: Vec<f64> = (0..n)
            .map(|k| masses.get(k).copied().unwrap_or(0.0))
            .collect();
        for col in 0..n {
            x.swap(col, self.pivot[col]);
        }
        // Forward substitution with the unit lower triangle, then back substitution.
        for row in 0..n {
            let lower = &self.lu[row * n..row * n + row];
            let s: f64 = lower.iter().zip(&x[..row]).map(|(l, v)| l * v).sum();
            x[row] -= s;
        }
        for row in (0..n).rev() {
            let upper = &self.lu[row * n + row + 1..(row + 1) * n];
            let s: f64 = upper.iter().zip(&x[row + 1..]).map(|(u, v)| u * v).sum();
            x[row] = (x[row] - s) / self.lu[row * n + row];
        }
        x
    }
}

/// A tallied bin is resolved when its relative standard error is at most this.
pub const RESOLVED_REL_SE: f64 = 0.2;

/// Resolved bins fitted by the exponential that continues a row's tail.
const TAIL_FIT_BINS: usize = 6;

/// Largest relative standard error of the pooled groups near the origin ([`inner_masses`]).
pub const INNER_REL_SE: f64 = 0.01;

/// The bin masses of one row with the narrow bins near the origin pooled (see
/// [`row_nodes`]).
///
/// The first bins are narrow (5·10⁻⁴ mean free paths at x₁) and their tallies noisy (several
/// % at albedos near 1, whose bands have fewer photons), and the histopolation system, whose
/// first bin is 10 times wider than its second, turns that noise into oscillations of the knot
/// values of 20 % and more. So from bin 0 outward, consecutive bins are pooled into groups
/// whose relative standard error is at most [`INNER_REL_SE`], until a bin is that precise on
/// its own (or the bin of largest mass is reached); each group keeps its tallied mass, spread
/// over its bins by the density interpolated log-linearly between the groups' mean densities.
/// Near the origin 2πx R_d is smooth (single scattering makes it tend to a constant), so this
/// changes the profile only within the noise, below 0.1 mean free paths.
pub fn inner_masses(edges: &[f64], mass: &[f64], se: &[f64]) -> Vec<f64> {
    let bins = mass.len();
    let precise = |m: f64, s2: f64| m > 0.0 && s2.sqrt() <= INNER_REL_SE * m;
    let peak = (0..bins)
        .max_by(|&a, &b| mass[a].total_cmp(&mass[b]))
        .unwrap_or(0);
    let mut groups: Vec<Range<usize>> = Vec::new();
    let mut k = 0;
    while k < peak {
        let (mut m, mut v, mut j) = (0.0, 0.0, k);
        while j < bins && !precise(m, v) {
            m += mass[j];
            v += se[j].powi(2);
            j += 1;
        }
        if !precise(m, v) || j - k == 1 {
            break;
        }
        groups.push(k..j);
        k = j;
    }
    let mut out = mass.to_vec();
    if groups.is_empty() {
        return out;
    }
    // Mean densities at the groups' centres and at the two bins after them (if any).
    let end = groups[groups.len() - 1].end;
    let mut points: Vec<(f64, f64)> = groups
        .iter()
        .map(|g| {
            let (lo, hi) = (edges[g.start], edges[g.end]);
            (
                0.5 * (lo + hi),
                mass[g.clone()].iter().sum::<f64>() / (hi - lo),
            )
        })
        .collect();
    for k in end..(end + 2).min(bins) {
        if mass[k] > 0.0 {
            points.push((
                0.5 * (edges[k] + edges[k + 1]),
                mass[k] / (edges[k + 1] - edges[k]),
            ));
        }
    }
    let log_density_at = |x: f64| -> f64 {
        if points.len() < 2 {
            return points[0].1.ln();
        }
        let j = points
            .partition_point(|p| p.0 <= x)
            .clamp(1, points.len() - 1);
        let ((c0, d0), (c1, d1)) = (points[j - 1], points[j]);
        let t = (x - c0) / (c1 - c0);
        (1.0 - t) * d0.ln() + t * d1.ln()
    };
    for g in &groups {
        let target: f64 = mass[g.clone()].iter().sum();
        let shape: Vec<f64> = g
            .clone()
            .map(|k| {
                let c = 0.5 * (edges[k] + edges[k + 1]);
                log_density_at(c).exp() * (edges[k + 1] - edges[k])
            })
            .collect();
        let total: f64 = shape.iter().sum();
        for (k, v) in g.clone().zip(&shape) {
            let m = target * v / total;
            out[k] = if m.is_finite() { m.max(0.0) } else { mass[k] };
        }
    }
    out
}

/// The bin masses of one row with its tail beyond the resolved bins regularised (see
/// [`row_nodes`]); also returns the last resolved bin K.
///
/// - K: outward from the bin of largest mass, the last bin before the first one whose
///   relative standard error exceeds [`RESOLVED_REL_SE`] (the small bins near the origin may
///   be noisier than the tail's start, and are kept as tallied).
/// - Beyond K, consecutive bins are pooled into groups just large enough to be resolved; each
///   group keeps its tallied mass, spread over its bins by the density interpolated
///   log-linearly between the groups' (and the last resolved bins') mean densities.
/// - What cannot be pooled into a resolved group (the last bins, reached by too few photons)
///   keeps its total tallied mass, spread over its bins like the exponential e^{−κx} fitted
///   to the last resolved bins and groups (weights (mass/se)², the bin averages'
///   sinh(κw/2)/(κw/2) factor accounted for), or like 1/x² if that fit does not decay.
pub fn tail_masses(edges: &[f64], mass: &[f64], se: &[f64]) -> (Vec<f64>, usize) {
    let bins = mass.len();
    let resolved = |m: f64, s2: f64| m > 0.0 && s2.sqrt() <= RESOLVED_REL_SE * m;
    let peak = (1..bins)
        .max_by(|&a, &b| mass[a].total_cmp(&mass[b]))
        .unwrap_or(0);
    let last = if peak >= 1 && resolved(mass[peak], se[peak].powi(2)) {
        (peak..bins)
            .take_while(|&k| resolved(mass[k], se[k].powi(2)))
            .last()
            .unwrap_or(peak)
    } else {
        0
    };
    let mut out = mass.to_vec();
    // Nothing resolved (an empty row), or nothing beyond K: the tally as it is.
    if last == 0 || last + 1 >= bins {
        return (out, last);
    }
    // Pool the bins beyond K into resolved groups.
    let mut groups: Vec<Range<usize>> = Vec::new();
    let mut k = last + 1;
    let mut rest = bins;
    while k < bins {
        let (mut m, mut v, mut j) = (0.0, 0.0, k);
        while j < bins && !resolved(m, v) {
            m += mass[j];
            v += se[j].powi(2);
            j += 1;
        }
        if resolved(m, v) {
            groups.push(k..j);
            k = j;
        } else {
            rest = k;
            break;
        }
    }
    // Points (centre, mean density, weight, lo, hi): the last resolved bins, then the groups.
    struct Point {
        lo: f64,
        hi: f64,
        density: f64,
        weight: f64,
    }
    let first = last.saturating_sub(TAIL_FIT_BINS - 1).max(1);
    let mut points: Vec<Point> = (first..=last)
        .map(|k| Point {
            lo: edges[k],
            hi: edges[k + 1],
            density: mass[k] / (edges[k + 1] - edges[k]),
            weight: if se[k] > 0.0 {
                (mass[k] / se[k]).powi(2)
            } else {
                1.0
            },
        })
        .collect();
    for g in &groups {
        let m: f64 = mass[g.clone()].iter().sum();
        let v: f64 = se[g.clone()].iter().map(|s| s * s).sum();
        let (lo, hi) = (edges[g.start], edges[g.end]);
        points.push(Point {
            lo,
            hi,
            density: m / (hi - lo),
            weight: if v > 0.0 { m * m / v } else { 1.0 },
        });
    }
    // Groups: log-linear density between neighbouring points' centres, rescaled to the
    // group's tallied mass.
    let centre = |p: &Point| 0.5 * (p.lo + p.hi);
    let log_density_at = |x: f64| -> f64 {
        if points.len() < 2 {
            return points.first().map_or(0.0, |p| p.density.ln());
        }
        let j = points
            .partition_point(|p| centre(p) <= x)
            .clamp(1, points.len() - 1);
        let (a, b) = (&points[j - 1], &points[j]);
        let slope = (b.density.ln() - a.density.ln()) / (centre(b) - centre(a));
        if x > centre(b) {
            // Beyond the last point the density may only fall (a noisy last group must not
            // pile its mass up at its far end).
            return b.density.ln() + slope.min(0.0) * (x - centre(b));
        }
        a.density.ln() + slope * (x - centre(a))
    };
    for g in &groups {
        let target: f64 = mass[g.clone()].iter().sum();
        let shape: Vec<f64> = g
            .clone()
            .map(|k| {
                let c = 0.5 * (edges[k] + edges[k + 1]);
                log_density_at(c).exp() * (edges[k + 1] - edges[k])
            })
            .collect();
        let total: f64 = shape.iter().sum();
        for (k, v) in g.clone().zip(&shape) {
            out[k] = if total > 0.0 && total.is_finite() {
                target * v / total
            } else {
                target / g.len() as f64
            };
        }
    }
    if rest >= bins {
        return (out, last);
    }
    // The unresolved rest keeps its tallied mass (noisy, but without the bias of dropping
    // it: at albedo 1 it is ≈ 1 % of the light), spread like the exponential fitted to the
    // last points, or like 1/x² (the albedo-1 tail of 2πx R_d) if that fit does not decay.
    let rest_mass: f64 = mass[rest..].iter().sum();
    let fit_from = points.len().saturating_sub(TAIL_FIT_BINS);
    let fit = &points[fit_from..];
    let (kappa, _) = fit_exponential(fit.iter().map(|p| (p.lo, p.hi, p.density, p.weight)));
    let x0 = edges[rest];
    let shape: Vec<f64> = (rest..bins)
        .map(|k| {
            let (lo, hi) = (edges[k], edges[k + 1]);
            if kappa > 1e-3 {
                // ∫ e^{−κ(x − x₀)} dx over the bin.
                (-kappa * (lo - x0)).exp() * (-(-kappa * (hi - lo)).exp_m1()) / kappa
            } else {
                1.0 / lo - 1.0 / hi
            }
        })
        .collect();
    let total: f64 = shape.iter().sum();
    for (k, v) in (rest..bins).zip(&shape) {
        let m = rest_mass * v / total;
        out[k] = if m.is_finite() { m.max(0.0) } else { 0.0 };
    }
    (out, last)
}

/// Weighted least squares of ln(mean density) = a − κc + ln(sinh(κw/2)/(κw/2)) over intervals
/// (lo, hi, mean density, weight) of width w and centre c: the exponential e^{a − κx} whose
/// interval means match. Returns (κ, a); κ is NaN when fewer than two intervals are given.
fn fit_exponential(points: impl Iterator<Item = (f64, f64, f64, f64)> + Clone) -> (f64, f64) {
    let solve = |kappa: f64| -> Option<(f64, f64)> {
        let (mut sw, mut sx, mut sy, mut sxx, mut sxy, mut n) = (0.0, 0.0, 0.0, 0.0, 0.0, 0);
        for (lo, hi, d, w) in points.clone() {
            let c = 0.5 * (lo + hi);
            let h = 0.5 * kappa * (hi - lo);
            let factor = if h > 1e-12 { (h.sinh() / h).ln() } else { 0.0 };
            let y = d.ln() - factor;
            if !(y.is_finite() && w > 0.0) {
                continue;
            }
            sw += w;
            sx += w * c;
            sy += w * y;
            sxx += w * c * c;
            sxy += w * c * y;
            n += 1;
        }
        let det = sw * sxx - sx * sx;
        if n < 2 || !(det > 0.0) {
            return None;
        }
        let k = -(sw * sxy - sx * sy) / det;
        Some((k, (sy + k * sx) / sw))
    };
    let Some((mut kappa, mut a)) = solve(0.0) else {
        return (f64::NAN, f64::NAN);
    };
    // Fixed-point rounds for the sinh factor (exact at once for equal widths).
    for _ in 0..6 {
        if !(kappa > 1e-3) {
            break;
        }
        match solve(kappa) {
            Some((k, b)) => (kappa, a) = (k, b),
            None => break,
        }
    }
    (kappa, a)
}

/// Past the start of the far-field fit, the tallies give way to the fit from the first bin
/// whose relative standard error exceeds this ([`asymptotic_tail`]).
pub const ASYMPTOTE_SWITCH_REL_SE: f64 = 0.01;

/// ∫ 2πx R dx over [lo, hi] for R(x) = e^{−κd}(1 + κd)/d³, d = √(x² + z²): the far field of
/// one diffusion pole at depth z (a point source's flux gradient through the surface), whose
/// integral is closed: d(−e^{−κd}/d)/dd = e^{−κd}(1 + κd)/d² and x dx = d dd.
fn pole_mass(kappa: f64, z: f64, lo: f64, hi: f64) -> f64 {
    let e = |x: f64| {
        let d = (x * x + z * z).sqrt();
        if d > 0.0 { (-kappa * d).exp() / d } else { 0.0 }
    };
    2.0 * PI * (e(lo) - e(hi))
}

/// The amplitude a and χ² of the weighted least-squares fit of a·pole_mass(κ, z) to the bins
/// (lo, hi, mass, 1/se²).
fn pole_fit(kappa: f64, z: f64, bins: &[(f64, f64, f64, f64)]) -> (f64, f64) {
    let (mut sff, mut sfm) = (0.0, 0.0);
    let shapes: Vec<f64> = bins
        .iter()
        .map(|&(lo, hi, m, w)| {
            let f = pole_mass(kappa, z, lo, hi);
            sff += w * f * f;
            sfm += w * f * m;
            f
        })
        .collect();
    if !(sff > 0.0) {
        return (0.0, f64::INFINITY);
    }
    let a = sfm / sff;
    let chi2 = bins
        .iter()
        .zip(&shapes)
        .map(|(&(_, _, m, w), f)| w * (a * f - m).powi(2))
        .sum();
    (a, chi2)
}

/// Where the far-field fit may start (optical radii, mean free paths): the first at which
/// the fit is consistent with the tallies (see [`asymptotic_tail`]).
pub const ASYMPTOTE_STARTS: [f64; 5] = [3.0, 4.5, 6.0, 8.0, 10.0];

/// Optical radii at which the far-field fit may stop replacing the tallies
/// ([`asymptotic_tail`]), tried from the farthest.
pub const ASYMPTOTE_ENDS: [f64; 4] = [64.0, 32.0, 20.0, 16.0];

/// A far-field fit is accepted when its χ² per degree of freedom is at most this. The
/// tallies' errors far out are heavier-tailed than normal (few photons of large weight), so
/// good fits run at 1–3 (ketchup's rows near albedo 0.75: 1.9 from 3 mean free paths,
/// κ = 0.745 against the transport value 0.78); a wrong shape gives far more.
pub const ASYMPTOTE_MAX_CHI2: f64 = 4.0;

/// The (κ, z, a) of the far field a·pole_mass(κ, z) fitted to `fit` (lo, hi, mass, 1/se²)
/// by weighted least squares (a in closed form; κ in [0, 2], z in [0, 8] on a grid, then
/// boxes shrinking around the best), and its χ².
fn fit_pole(fit: &[(f64, f64, f64, f64)]) -> (f64, f64, f64, f64) {
    let (mut kappa, mut z, mut step_k, mut step_z) = (1.0, 4.0, 0.1, 0.4);
    let mut best = (f64::INFINITY, kappa, z);
    for round in 0..6 {
        let n: i32 = if round == 0 { 10 } else { 4 };
        for i in -n..=n {
            for j in -n..=n {
                let (k, zz) = (kappa + i as f64 * step_k, z + j as f64 * step_z);
                if !(0.0..=2.0).contains(&k) || !(0.0..=8.0).contains(&zz) {
                    continue;
                }
                let (_, chi2) = pole_fit(k, zz, fit);
                if chi2 < best.0 {
                    best = (chi2, k, zz);
                }
            }
        }
        (kappa, z) = (best.1, best.2);
        step_k *= 0.3;
        step_z *= 0.3;
    }
    let (a, chi2) = pole_fit(kappa, z, fit);
    (kappa, z, a, chi2)
}

/// The masses of one row with its noisy far tail replaced by the fitted diffusion far field
/// (see [`row_nodes`]); `last` is the last resolved bin of [`tail_masses`].
///
/// - The fit: a·pole_mass(κ, z) (R_d ∝ e^{−κd}(1 + κd)/d³, d = √(x² + z²)) by weighted
///   least squares over the resolved bins from the first start of [`ASYMPTOTE_STARTS`] at
///   which χ²/(n − 3) ≤ [`ASYMPTOTE_MAX_CHI2`] (at least 4 bins); no such start: the row is
///   kept as it is.
/// - The tallies give way to the fit from the first bin past that start whose relative
///   standard error exceeds [`ASYMPTOTE_SWITCH_REL_SE`], up to the table's end, or, when the
///   fit's light over the replaced bins would differ from the tallied light by more than 3
///   standard errors, up to the last resolved bin `last` or the first of the radii
///   [`ASYMPTOTE_ENDS`] at which it agrees (near albedo 1 a per cent of the light escapes
///   beyond 16 mean free paths, and a fitted κ slightly above 0 would lose it); none: the
///   row is kept as it is. The replaced bins are rescaled to their tallied light (a change
///   within 3 standard errors of it), so the row's total stays the tallied one.
pub fn asymptotic_tail(edges: &[f64], mass: &[f64], se: &[f64], last: usize) -> Vec<f64> {
    let mut out = mass.to_vec();
    let bins = mass.len();
    let last = last.min(bins.saturating_sub(1));
    let mut accepted = None;
    for start in ASYMPTOTE_STARTS {
        let fit: Vec<(f64, f64, f64, f64)> = (0..=last)
            .filter(|&k| edges[k] >= start && mass[k] > 0.0 && se[k] > 0.0)
            .map(|k| (edges[k], edges[k + 1], mass[k], se[k].powi(-2)))
            .collect();
        if fit.len() < 4 {
            break;
        }
        let (kappa, z, a, chi2) = fit_pole(&fit);
        if a > 0.0 && a.is_finite() && chi2 <= ASYMPTOTE_MAX_CHI2 * (fit.len() - 3) as f64 {
            accepted = Some((start, kappa, z, a));
            break;
        }
    }
    let Some((start, kappa, z, a)) = accepted else {
        return out;
    };
    let fitted = |k: usize| {
        let m = a * pole_mass(kappa, z, edges[k], edges[k + 1]);
        if m.is_finite() { m.max(0.0) } else { 0.0 }
    };
    let Some(switch) = (0..bins).find(|&k| {
        edges[k] >= start && !(mass[k] > 0.0 && se[k] <= ASYMPTOTE_SWITCH_REL_SE * mass[k])
    }) else {
        return out;
    };
    // The replaced bins [switch, end): the farthest end among the table's end, the last
    // resolved bin and the radii of ASYMPTOTE_ENDS at which the fit's light over the replaced
    // bins agrees with the tallied light within 3 standard errors.
    let ends = std::iter::once(bins)
        .chain(std::iter::once(last + 1))
        .chain(
            ASYMPTOTE_ENDS
                .iter()
                .map(|&x| edges.partition_point(|&e| e < x).min(bins)),
        );
    for end in ends {
        if end <= switch {
            continue;
        }
        let tallied: f64 = mass[switch..end].iter().sum();
        let var: f64 = se[switch..end].iter().map(|s| s * s).sum();
        let replaced: Vec<f64> = (switch..end).map(fitted).collect();
        let light: f64 = replaced.iter().sum();
        if light > 0.0 && (light - tallied).abs() <= 3.0 * var.sqrt() {
            // Rescaled to the tallied light of the replaced bins: no light gained or lost.
            let scale = tallied / light;
            for (o, v) in out[switch..end].iter_mut().zip(&replaced) {
                let m = v * scale;
                *o = if m.is_finite() { m.max(0.0) } else { 0.0 };
            }
            break;
        }
    }
    out
}

/// Weighted isotonic regression: the non-increasing sequence closest to `y` in the weighted
/// least-squares sense, by pooling adjacent violators (Ayer, Brunk, Ewing, Reid, Silverman,
/// *An empirical distribution function for sampling with incomplete information*, Ann. Math.
/// Statist. 26(4), 1955; Barlow et al., *Statistical Inference under Order Restrictions*,
/// 1972).
pub fn non_increasing_fit(y: &[f64], w: &[f64]) -> Vec<f64> {
    // Blocks of (mean, weight, count).
    let mut blocks: Vec<(f64, f64, usize)> = Vec::with_capacity(y.len());
    for (&v, &wt) in y.iter().zip(w) {
        let wt = if wt > 0.0 && wt.is_finite() {
            wt
        } else {
            1e-300
        };
        blocks.push((v, wt, 1));
        while blocks.len() >= 2 {
            let (m1, w1, c1) = blocks[blocks.len() - 1];
            let (m0, w0, c0) = blocks[blocks.len() - 2];
            if m1 <= m0 {
                break;
            }
            blocks.pop();
            let wsum = w0 + w1;
            let last = blocks.len() - 1;
            blocks[last] = ((w0 * m0 + w1 * m1) / wsum, wsum, c0 + c1);
        }
    }
    blocks
        .into_iter()
        .flat_map(|(m, _, c)| std::iter::repeat_n(m, c))
        .collect()
}

/// The bin masses of one row that [`row_nodes`] fits its spline to (steps 1 and 2 there).
pub fn row_masses(knots: &[f64], mass: &[f64], se: &[f64]) -> Vec<f64> {
    let edges = tally_edges(knots);
    let inner = inner_masses(&edges, mass, se);
    let (pooled, last) = tail_masses(&edges, &inner, se);
    let tail = asymptotic_tail(&edges, &pooled, se, last);
    // R_d averaged over each bin's annulus, made non-increasing with the annuli's areas as
    // weights: pooled bins share their total mass, so no light is gained or lost.
    let areas: Vec<f64> = edges
        .windows(2)
        .map(|e| PI * (e[1] * e[1] - e[0] * e[0]))
        .collect();
    let averages: Vec<f64> = tail.iter().zip(&areas).map(|(m, a)| m / a).collect();
    non_increasing_fit(&averages, &areas)
        .iter()
        .zip(&areas)
        .map(|(d, a)| d * a)
        .collect()
}

/// The values of one row's spline at its [`spline_knots`] from the row's tallies (bins of
/// [`tally_edges`]):
/// 1. the narrow bins near the origin are pooled by [`inner_masses`], the tail beyond the
///    resolved bins is regularised by [`tail_masses`] (pooled groups, the unresolved rest
///    spread like the fitted exponential), and the noisy far tail is replaced by the fitted
///    diffusion far field of [`asymptotic_tail`];
/// 2. the bins' R_d averages over their annuli are made non-increasing by isotonic regression
///    with the annuli's areas as weights (mass-conserving: pooled bins share their tallied
///    light), which changes nothing where the tallies are ordered and pools neighbours where
///    noise reverses them;
/// 3. the histopolation system gives the knot values whose spline integrates to every bin;
/// 4. negative values are set to 0, and R_d = T/(2πx) at the knots is made non-increasing by
///    isotonic regression weighted by the light each knot carries (a knot value can overshoot
///    its neighbour a little even when the bin averages are ordered).
pub fn row_nodes(system: &Histopolation, knots: &[f64], mass: &[f64], se: &[f64]) -> Vec<f64> {
    let xs = spline_knots(knots);
    let n = xs.len();
    let edges = tally_edges(knots);
    let masses = row_masses(knots, mass, se);
    let v = system.solve(&masses);
    // The spline's own R_d at the knots, made non-increasing too (the bin averages are, but a
    // knot value can still overshoot its neighbour by a little), weighted by the mass each
    // knot carries (x times the width of its bin), which keeps the total.
    let mut u = Vec::with_capacity(n - 1);
    let mut w = Vec::with_capacity(n - 1);
    for j in 1..n {
        let value = v[j - 1];
        let value = if value.is_finite() {
            value.max(0.0)
        } else {
            0.0
        };
        u.push(value / xs[j]);
        w.push(xs[j] * (edges[j] - edges[j - 1]));
    }
    let fitted = non_increasing_fit(&u, &w);
    let mut out = vec![0.0; n];
    for j in 1..n {
        let v = fitted[j - 1] * xs[j];
        out[j] = if v.is_finite() { v.max(0.0) } else { 0.0 };
    }
    out
}

/// The knot values of every albedo row of table `e` ([`row_nodes`]). Row-major [`N_RHO`] ×
/// knots.
fn node_values(data: &McTableData, e: usize) -> Vec<f64> {
    let knots = data.knots();
    let n = knots.len() + 1;
    let rows = data.rho_samples().len();
    let mut out = vec![0.0; rows * n];
    let Ok(system) = Histopolation::new(knots) else {
        return out;
    };
    for i in 0..rows {
        let v = row_nodes(&system, knots, data.mass(e, i), data.mass_se(e, i));
        out[i * n..(i + 1) * n].copy_from_slice(&v);
    }
    out
}

/// Per table of the embedded data (g-major over [`GS`] × [`ETAS`]), its knot values, each
/// computed on first use (a medium with g = 0 never solves the tables of g ≠ 0).
fn embedded_nodes(t: usize) -> Option<&'static [f64]> {
    const TABLES: usize = GS.len() * ETAS.len();
    static NODES: [OnceLock<Option<Vec<f64>>>; TABLES] = [const { OnceLock::new() }; TABLES];
    NODES
        .get(t)?
        .get_or_init(|| Some(node_values(McTableData::embedded().ok()?, t)))
        .as_deref()
}

/// `(1 − t) a + t b` per value, exactly `a` at t = 0 and `b` at t = 1 (empty unless both have
/// `len` values).
fn blend_nodes(a: &[f64], b: &[f64], t: f64, len: usize) -> Vec<f64> {
    if a.len() != len || b.len() != len {
        return Vec::new();
    }
    a.iter()
        .zip(b)
        .map(|(a, b)| {
            if t == 0.0 {
                *a
            } else if t == 1.0 {
                *b
            } else {
                (1.0 - t) * a + t * b
            }
        })
        .collect()
}

/// The knot values at (`eta`, `g`), both already clamped: the four tables around them blended
/// bilinearly (linear in η, then in g), through `nodes(t)` for table t.
fn blended_nodes<'a>(eta: f64, g: f64, nodes: impl Fn(usize) -> Option<&'a [f64]>) -> Vec<f64> {
    let len = N_RHO * (radius_knots().len() + 1);
    let (e0, e1, te) = eta_bracket(eta);
    let (g0, g1, tg) = g_bracket(g);
    let at = |gi: usize| {
        let (a, b) = (nodes(gi * ETAS.len() + e0), nodes(gi * ETAS.len() + e1));
        blend_nodes(a.unwrap_or(&[]), b.unwrap_or(&[]), te, len)
    };
    if tg == 0.0 {
        at(g0)
    } else {
        blend_nodes(&at(g0), &at(g1), tg, len)
    }
}

/// The tabulated Monte Carlo profile for one η and g (the counterpart of
/// [`crate::photon_beam_diffusion::PbdTable`]): [`N_RHO`] albedo rows × [`radius_knots`] of
/// T(ρ', x') = 2πx' R_d¹(x') (reduced albedo and radius in reduced mean free paths; for g = 0
/// these are ρ and σ_t r), their running integrals and totals.
#[derive(Clone, Debug)]
pub struct McTable {
    eta: f64,
    g: f64,
    rho_samples: Vec<f64>,
    radius_samples: Vec<f64>,
    /// Row-major N_RHO × knots values of T.
    profile: Vec<f64>,
    /// Row-major running integrals of the profile splines.
    profile_cdf: Vec<f64>,
    /// ρ_eff per albedo row: the integral of the row's spline.
    rho_eff: Vec<f64>,
    index: KnotIndex,
}

impl McTable {
    /// The isotropic (g = 0) table for `eta`: [`McTable::anisotropic`] at g = 0.
    pub fn new(eta: f64) -> McTable {
        McTable::anisotropic(eta, 0.0)
    }

    /// The table for `eta` and `g` from the embedded data: η clamped to [1.0, 1.5] and g to
    /// [0, 0.9] ([`GS`]), then the knot values of the four neighbouring tables blended
    /// bilinearly (linear in η, then in g). If the embedded data could not be read (see
    /// [`McTableData::embedded`]) the table is all zeros.
    pub fn anisotropic(eta: f64, g: f64) -> McTable {
        let (eta, g) = (clamp_eta(eta), clamp_g(g));
        McTable::from_nodes(eta, g, &blended_nodes(eta, g, embedded_nodes))
    }

    /// The isotropic table from `data` without any cache: the spline knot values of the two η
    /// tables are solved from the tallies here (what the first model of a process pays).
    pub fn from_data(data: &McTableData, eta: f64) -> McTable {
        McTable::from_data_anisotropic(data, eta, 0.0)
    }

    /// [`McTable::anisotropic`] from `data` (which must hold the tables of [`GS`] × [`ETAS`];
    /// all zeros otherwise), without any cache.
    pub fn from_data_anisotropic(data: &McTableData, eta: f64, g: f64) -> McTable {
        let (eta, g) = (clamp_eta(eta), clamp_g(g));
        let full = data.gs().len() == GS.len() && data.etas().len() == ETAS.len();
        let ((e0, e1, _), (g0, g1, _)) = (eta_bracket(eta), g_bracket(g));
        let needed = |t: usize| {
            let (gi, e) = (t / ETAS.len(), t % ETAS.len());
            (gi == g0 || gi == g1) && (e == e0 || e == e1)
        };
        let solved: Vec<Option<Vec<f64>>> = (0..GS.len() * ETAS.len())
            .map(|t| (full && needed(t)).then(|| node_values(data, t)))
            .collect();
        McTable::from_nodes(
            eta,
            g,
            &blended_nodes(eta, g, |t| solved.get(t)?.as_deref()),
        )
    }

    /// [`McTable::from_data`] of the embedded file, parsed again (a cold start: what the first
    /// `mc-table` model of a process costs, for timing); all zeros if it cannot be read.
    pub fn from_embedded_uncached(eta: f64) -> McTable {
        match McTableData::from_bytes(EMBEDDED) {
            Ok(data) => McTable::from_data(&data, eta),
            Err(_) => McTable::from_nodes(clamp_eta(eta), 0.0, &[]),
        }
    }

    /// The table through the knot values `nodes` (all zeros when it is not a full table).
    fn from_nodes(eta: f64, g: f64, nodes: &[f64]) -> McTable {
        let rho_samples = rho_samples();
        let radius_samples = spline_knots(&radius_knots());
        let n = radius_samples.len();
        let mut profile = vec![0.0; N_RHO * n];
        if nodes.len() == profile.len() {
            profile.copy_from_slice(nodes);
        }
        let mut profile_cdf = Vec::with_capacity(profile.len());
        let mut rho_eff = Vec::with_capacity(N_RHO);
        for row in profile.chunks_exact(n) {
            let (total, cdf) = integrate_catmull_rom(&radius_samples, row);
            profile_cdf.extend(cdf);
            rho_eff.push(total);
        }
        let index = KnotIndex::new(&radius_samples).expect("the radius knots are increasing");
        McTable {
            eta,
            g,
            rho_samples,
            radius_samples,
            profile,
            profile_cdf,
            rho_eff,
            index,
        }
    }

    /// The table for `eta` and `g` from a process-wide cache keyed by the clamped values'
    /// bits, built on first use. Every call with the same η and g returns the same `Arc`.
    pub fn shared(eta: f64, g: f64) -> Arc<McTable> {
        type Cache = Mutex<HashMap<(u64, u64), Arc<McTable>>>;
        static CACHE: OnceLock<Cache> = OnceLock::new();
        let cache = CACHE.get_or_init(|| Mutex::new(HashMap::new()));
        let key = (clamp_eta(eta).to_bits(), clamp_g(g).to_bits());
        if let Some(t) = cache.lock().unwrap_or_else(|e| e.into_inner()).get(&key) {
            return Arc::clone(t);
        }
        let table = Arc::new(McTable::anisotropic(eta, g));
        let mut map = cache.lock().unwrap_or_else(|e| e.into_inner());
        Arc::clone(map.entry(key).or_insert(table))
    }

    /// The η of the table (clamped to [`ETAS`]' range).
    pub fn eta(&self) -> f64 {
        self.eta
    }

    /// The g of the table (clamped to [`GS`]' range).
    pub fn g(&self) -> f64 {
        self.g
    }

    /// The albedo rows ρ_i.
    pub fn rho_samples(&self) -> &[f64] {
        &self.rho_samples
    }

    /// The optical radius knots of the splines (mean free paths 1/σ_t; [`spline_knots`]).
    pub fn radius_samples(&self) -> &[f64] {
        &self.radius_samples
    }

    /// Largest tabulated optical radius; the profile is 0 beyond it.
    pub fn max_optical_radius(&self) -> f64 {
        self.radius_samples[self.radius_samples.len() - 1]
    }

    /// The value T = 2πx R_d¹(x) at albedo row `i`, knot `j`.
    pub fn profile(&self, i: usize, j: usize) -> f64 {
        self.profile[i * self.radius_samples.len() + j]
    }

    /// Row-major [`N_RHO`] × knots array of all profile values.
    pub fn profile_values(&self) -> &[f64] {
        &self.profile
    }

    /// Row-major running integrals of the profile splines.
    pub fn profile_cdf_values(&self) -> &[f64] {
        &self.profile_cdf
    }

    /// The effective albedo ρ_eff (integral of the spline) of every albedo row.
    pub fn rho_eff_samples(&self) -> &[f64] {
        &self.rho_eff
    }

    /// Spline-interpolated effective albedo, unclamped; 0 outside [0, 1].
    fn effective_albedo_raw(&self, rho: f64) -> f64 {
        match catmull_rom_weights(&self.rho_samples, rho) {
            Some((offset, w)) => apply_weights(offset, &w, |i| self.rho_eff[i]),
            None => 0.0,
        }
    }

    /// The total diffuse reflectance of albedo `rho` (Catmull-Rom over the rows' ρ_eff),
    /// clamped to [0, 1]; 0 outside [0, 1].
    pub fn effective_albedo(&self, rho: f64) -> f64 {
        let v = self.effective_albedo_raw(rho);
        if v.is_finite() {
            v.clamp(0.0, 1.0)
        } else {
            0.0
        }
    }

    /// Tensor-product spline interpolation of T at albedo `rho` and optical radius
    /// `r_optical`, or `None` outside the table.
    pub fn interpolate_profile(&self, rho: f64, r_optical: f64) -> Option<f64> {
        let (ro, rw) = catmull_rom_weights(&self.rho_samples, rho)?;
        let n = self.radius_samples.len();
        let (co, cw) = catmull_rom_weights(&self.radius_samples, r_optical)?;
        Some(apply_weights(ro, &rw, |i| {
            apply_weights(co, &cw, |j| self.profile[i * n + j])
        }))
    }

    /// The spline of albedo row `i` at optical radius `x` (`None` outside the knots).
    pub fn row_spline(&self, i: usize, x: f64) -> Option<f64> {
        let n = self.radius_samples.len();
        interpolate_catmull_rom(&self.radius_samples, &self.profile[i * n..(i + 1) * n], x)
    }
}

/// The two entries of the increasing `grid` (≥ 2 values) around `v` (already clamped to it)
/// and the weight of the upper one.
fn bracket(grid: &[f64], v: f64) -> (usize, usize, f64) {
    let hi = grid.partition_point(|&x| x <= v).clamp(1, grid.len() - 1);
    let (a, b) = (grid[hi - 1], grid[hi]);
    (hi - 1, hi, ((v - a) / (b - a)).clamp(0.0, 1.0))
}

/// `v` clamped to the range of the increasing `grid`, NaN to `nan`.
fn clamp_to(grid: &[f64], v: f64, nan: f64) -> f64 {
    if v.is_nan() {
        nan
    } else {
        v.clamp(grid[0], grid[grid.len() - 1])
    }
}

/// The two tables of [`ETAS`] around `eta` (already clamped) and the weight of the upper one.
fn eta_bracket(eta: f64) -> (usize, usize, f64) {
    bracket(&ETAS, eta)
}

/// η clamped to the range of [`ETAS`] (NaN to [`MAIN_ETA`]).
fn clamp_eta(eta: f64) -> f64 {
    clamp_to(&ETAS, eta, MAIN_ETA)
}

/// True when `eta` lies in the range of [`ETAS`], where the tables are interpolated rather
/// than clamped.
pub fn eta_in_range(eta: f64) -> bool {
    (ETAS[0]..=ETAS[ETAS.len() - 1]).contains(&eta)
}

/// The two tables of [`GS`] around `g` (already clamped) and the weight of the upper one.
fn g_bracket(g: f64) -> (usize, usize, f64) {
    bracket(&GS, g)
}

/// g clamped to the range of [`GS`] (NaN to 0).
fn clamp_g(g: f64) -> f64 {
    clamp_to(&GS, g, 0.0)
}

/// True when `g` lies in the range of [`GS`], where the tables are interpolated; a medium
/// outside it (g < 0, or g > 0.9) reads the nearest end table at its reduced albedo and radius
/// (the similarity relation: an approximation near the entry point, see the module
/// documentation).
pub fn g_in_range(g: f64) -> bool {
    (GS[0]..=GS[GS.len() - 1]).contains(&g)
}

/// The `mc-table` model for one [`Medium`]: the random walk's profile from the shared
/// [`McTable`] of its η and g, scaled to its reduced extinction.
///
/// - With σ'_t = σ_a + σ_s(1 − g) and ρ' = σ_s(1 − g)/σ'_t (the tables' reduced units, see
///   the module documentation), [`Bssrdf::rd`] is σ'_t² times the table row blended at ρ',
///   evaluated at x = rσ'_t and divided by 2πx, clamped to ≥ 0, and 0 beyond the table's
///   last knot. The row's first interval [0, 0.0005] is linear in 2πx R_d
///   ([`SplineRow::with_linear_first_segment`]): R_d is constant there instead of bumping.
/// - [`Bssrdf::total_diffuse_reflectance`] is the row's integral (the interpolated effective
///   albedo up to that first interval, ≈ 10⁻⁵ of it), clamped to [0, 1].
/// - [`Bssrdf::sample_sr`] inverts the CDF of the non-negative row
///   ([`SplineRow::non_negative`]) and [`Bssrdf::pdf_sr`] is its exact density, as for
///   [`crate::PhotonBeamDiffusion`]; a channel without tabulated mass (ρ' = 0) samples
///   σ'_t e^{−σ'_t r}.
#[derive(Clone, Debug)]
pub struct McTableModel {
    medium: Medium,
    table: Arc<McTable>,
    rho: Rgb,
    profile: OpticalProfile,
}

impl McTableModel {
    /// The model for `medium`, sharing the table of its η with every other medium.
    pub fn new(medium: Medium) -> Self {
        let table = McTable::shared(medium.eta(), medium.g());
        let sigma_t: Rgb = std::array::from_fn(|ch| medium.sigma_t_reduced(ch));
        let rho: Rgb = std::array::from_fn(|ch| {
            let st = sigma_t[ch];
            let v = medium.sigma_s_reduced(ch) / st;
            if v.is_finite() {
                v.clamp(0.0, 1.0)
            } else {
                0.0
            }
        });
        let rows = std::array::from_fn(|ch| {
            monotone_row(&table, rho[ch]).map(|row| row.with_linear_first_segment())
        });
        McTableModel {
            medium,
            table,
            rho,
            profile: OpticalProfile::new(sigma_t, rows),
        }
    }

    /// The shared table behind this model.
    pub fn table(&self) -> &McTable {
        &self.table
    }

    /// The reduced albedo ρ' of channel `ch` at which the table is read.
    pub fn reduced_albedo(&self, ch: usize) -> f64 {
        self.rho[ch]
    }

    /// The effective albedo (total diffuse reflectance) of channel `ch`: the integral of the
    /// channel's row (the table's ρ_eff interpolated at ρ', with the first interval linear),
    /// clamped to [0, 1].
    pub fn effective_albedo(&self, ch: usize) -> f64 {
        let v = self.profile.rows[ch].as_ref().map_or(0.0, SplineRow::total);
        if v.is_finite() {
            v.clamp(0.0, 1.0)
        } else {
            0.0
        }
    }

    /// True when the medium's η lies in [1.0, 1.5], the range of [`ETAS`]; otherwise the
    /// nearest end table was used.
    pub fn eta_in_range(&self) -> bool {
        eta_in_range(self.medium.eta())
    }

    /// True when the medium's g lies in [0, 0.9], the range of [`GS`]; otherwise the nearest
    /// end table was read at the reduced albedo (see [`g_in_range`]).
    pub fn g_in_range(&self) -> bool {
        g_in_range(self.medium.g())
    }
}

/// The table's row at reduced albedo `rho`, with R_d non-increasing: the knot values blended
/// with the Catmull-Rom weights of `rho` over the albedo rows (as [`SplineRow::blend`]),
/// clamped to ≥ 0 and made non-increasing in R_d ∝ T/x at the knots by a running minimum,
/// then every segment on which R_d would still rise made straight
/// ([`SplineRow::monotone_over_x`]). Every row is non-increasing at its knots on its own
/// ([`row_nodes`]), but the Catmull-Rom weights go negative and its segments overshoot after
/// flat stretches: where neighbouring rows' far tails differ (poorly resolved tails near
/// ρ' → 1, mostly in the tables of g ≠ 0) R_d rose by up to 30 % at 10⁻⁸ of its peak, more
/// than the many-light profile check accepts. `None` outside the rows.
fn monotone_row(table: &McTable, rho: f64) -> Option<SplineRow> {
    let (offset, w) = catmull_rom_weights(&table.rho_samples, rho)?;
    let xs = &table.radius_samples;
    let n = xs.len();
    let mut values: Vec<f64> = (0..n)
        .map(|k| apply_weights(offset, &w, |i| table.profile[i * n + k]).max(0.0))
        .collect();
    let mut least = f64::INFINITY;
    for (v, &x) in values.iter_mut().zip(xs).skip(1) {
        // x > 0 past the first knot (the knots increase from 0).
        let r = *v / x;
        if r > least {
            *v = least * x;
        } else {
            least = r;
        }
    }
    Some(SplineRow::new(&table.index, &values).monotone_over_x())
}

impl Bssrdf for McTableModel {
    fn kind(&self) -> ModelKind {
        ModelKind::McTable
    }

    fn medium(&self) -> &Medium {
        &self.medium
    }

    fn rd(&self, ch: usize, r: f64) -> f64 {
        self.profile.rd(ch, r)
    }

    fn rd_rgb(&self, r: f64) -> Rgb {
        self.profile.rd_rgb(r)
    }

    /// The derivatives of the blended Catmull-Rom spline
    /// ([`OpticalProfile::rd_derivatives`]).
    fn rd_derivatives(&self, ch: usize, r: f64) -> (f64, f64, f64) {
        self.profile.rd_derivatives(ch, r.abs())
    }

    fn total_diffuse_reflectance(&self, ch: usize) -> f64 {
        self.effective_albedo(ch)
    }

    fn sample_sr(&self, ch: usize, u: f64) -> f64 {
        self.profile.sample_sr(ch, u)
    }

    fn pdf_sr(&self, ch: usize, r: f64) -> f64 {
        self.profile.pdf_sr(ch, r)
    }

    /// Inverts the row's CDF, as [`Bssrdf::sample_sr`].
    fn radius_for_energy(&self, ch: usize, fraction: f64) -> f64 {
        self.sample_sr(ch, fraction)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::quadrature::integrate;

    /// ∫ x e^{−ax} dx from 0 to x.
    fn xexp_integral(a: f64, x: f64) -> f64 {
        (1.0 - (-a * x).exp() * (a * x + 1.0)) / (a * a)
    }

    /// A smooth test profile T(x) = x e^{−0.7x} + 0.3 x e^{−3x} and its bin integrals.
    fn synthetic(x: f64) -> f64 {
        x * (-0.7 * x).exp() + 0.3 * x * (-3.0 * x).exp()
    }

    fn synthetic_bin(lo: f64, hi: f64) -> f64 {
        let f = |x| xexp_integral(0.7, x) + 0.3 * xexp_integral(3.0, x);
        f(hi) - f(lo)
    }

    /// ∫ of the spline through `values` over [lo, hi] (exact: Gauss-Legendre per knot piece).
    fn spline_integral(knots: &[f64], values: &[f64], lo: f64, hi: f64) -> f64 {
        let mut cuts = vec![lo];
        cuts.extend(knots.iter().copied().filter(|&x| x > lo && x < hi));
        cuts.push(hi);
        cuts.windows(2)
            .map(|w| {
                integrate(
                    &|x| interpolate_catmull_rom(knots, values, x).unwrap(),
                    w[0],
                    w[1],
                    4,
                )
            })
            .sum()
    }

    #[test]
    fn grids_are_as_documented() {
        let rho = rho_samples();
        assert_eq!((rho.len(), rho[0], rho[N_RHO - 1]), (N_RHO, 0.0, 1.0));
        let x = radius_knots();
        assert_eq!((x[0], x[1]), (0.0, FIRST_KNOT));
        assert!(x.len() >= 80 && x.len() <= 90, "{}", x.len());
        let last = x[x.len() - 1];
        assert!(last > 900.0 && last <= LAST_KNOT_LIMIT, "{last}");
        for w in x[1..].windows(2) {
            let step = w[1] - w[0];
            // Geometric (20 %) near 0, never more than 0.75 on [4, 16], geometric again
            // beyond.
            assert!(step <= 0.2 * w[0] * (1.0 + 1e-12), "{w:?}");
            if w[0] >= 4.0 && w[0] < LINEAR_END {
                assert!((step - LINEAR_STEP).abs() < 1e-12, "{w:?}");
            }
        }
        let edges = tally_edges(&x);
        assert_eq!(edges.len(), x.len() + 1);
        assert_eq!((edges[1], edges[edges.len() - 1]), (x[1], last));
        for k in 2..x.len() {
            assert!(edges[k] < x[k] && x[k] < edges[k + 1] || k == x.len() - 1);
        }
        // Bands cover every row once; each η has its own streams.
        let p13 = plan(0, 3, 1.0);
        let p10 = plan(0, 0, 1.0);
        let mut covered = vec![0; N_RHO];
        for w in p13.iter().filter(|w| w.min_events == 1) {
            for i in w.rows.clone() {
                covered[i] += 1;
            }
        }
        assert!(covered.iter().all(|&c| c == 1), "{covered:?}");
        assert!(p13.iter().zip(&p10).all(|(a, b)| a.stream != b.stream));
        assert!(
            p13.iter()
                .zip(&p10)
                .all(|(a, b)| a.photons == OTHER_ETA_PHOTON_DIVISOR * b.photons)
        );
        // Every table of every g has its own streams; g ≠ 0 has half the photons.
        let mut streams: Vec<usize> = (0..GS.len())
            .flat_map(|g| (0..ETAS.len()).flat_map(move |e| plan(g, e, 1.0)))
            .map(|w| w.stream)
            .collect();
        let n = streams.len();
        streams.sort_unstable();
        streams.dedup();
        assert_eq!(streams.len(), n);
        for g in 1..GS.len() {
            let pg = plan(g, 3, 1.0);
            assert!(pg.iter().zip(&p13).all(|(a, b)| {
                a.rows == b.rows && ANISOTROPIC_PHOTON_DIVISOR * a.photons == b.photons
            }));
        }
        // ρ' ↦ ρ inverts the similarity relation ρ' = ρ(1 − g)/(1 − ρg).
        for g in [-0.5, 0.0, 0.4, 0.9] {
            for rp in [0.0, 0.1, 0.5, 0.9, 0.999, 1.0] {
                let rho = single_scattering_albedo(rp, g);
                let back = rho * (1.0 - g) / (1.0 - rho * g);
                assert!(
                    (back - rp).abs() < 1e-14,
                    "g {g} rho' {rp}: {rho} -> {back}"
                );
            }
        }
    }

    #[test]
    fn histopolation_reproduces_bin_integrals_and_point_values() {
        let knots = radius_knots();
        let xs = spline_knots(&knots);
        assert_eq!(xs.len(), knots.len() + 1);
        let edges = tally_edges(&knots);
        let system = Histopolation::new(&knots).unwrap();
        let masses: Vec<f64> = edges
            .windows(2)
            .map(|e| synthetic_bin(e[0], e[1]))
            .collect();
        let v = system.solve(&masses);
        let mut values = vec![0.0];
        values.extend(&v);
        // Every bin integrates to its mass.
        for k in 0..knots.len() {
            let got = spline_integral(&xs, &values, edges[k], edges[k + 1]);
            assert!(
                // (The masses far out are differences of O(1) values: 10⁻¹⁵ absolute.)
                (got - masses[k]).abs() <= 1e-10 * masses[k] + 1e-14,
                "bin {k}: {got} vs {}",
                masses[k]
            );
        }
        // The knot values are the point values of the profile (not its bin averages, which
        // are several % off where the bins are wide), over the accuracy range (up to 16 mean
        // free paths; beyond, the steps grow and this profile's decay of 0.7 per unit makes the
        // spline a few % off between knots).
        let mut worst_avg: f64 = 0.0;
        for j in 1..xs.len() {
            let want = synthetic(xs[j]);
            // (2 % at the extra knot, whose first interval must start at 0.)
            let tol = if j == 1 { 0.02 } else { 0.01 };
            if xs[j] <= 16.0 {
                assert!(
                    (values[j] - want).abs() < tol * want,
                    "x {}: {} vs {want}",
                    xs[j],
                    values[j]
                );
            }
            if j >= 2 && xs[j] <= 16.0 {
                let k = j - 1;
                let avg = masses[k] / (edges[k + 1] - edges[k]);
                worst_avg = worst_avg.max((avg / want - 1.0).abs());
            }
        }
        assert!(
            worst_avg > 0.03,
            "bin averages happen to be point values: {worst_avg}"
        );
    }

    #[test]
    fn isotonic_fit_pools_adjacent_violators() {
        assert_eq!(
            non_increasing_fit(&[5.0, 3.0, 4.0, 1.0], &[1.0; 4]),
            vec![5.0, 3.5, 3.5, 1.0]
        );
        assert_eq!(
            non_increasing_fit(&[1.0, 2.0], &[3.0, 1.0]),
            vec![1.25, 1.25]
        );
        // Already ordered: unchanged; a long violation pools across blocks.
        let y = [9.0, 7.0, 7.0, 2.0];
        assert_eq!(non_increasing_fit(&y, &[1.0; 4]), y.to_vec());
        assert_eq!(
            non_increasing_fit(&[3.0, 1.0, 2.0, 6.0], &[1.0; 4]),
            vec![3.0, 3.0, 3.0, 3.0]
        );
    }

    #[test]
    fn unresolved_tail_keeps_its_mass_in_the_fitted_shape() {
        let knots = radius_knots();
        let edges = tally_edges(&knots);
        let exact: Vec<f64> = edges
            .windows(2)
            .map(|e| ((-0.5 * e[0]).exp() - (-0.5 * e[1]).exp()) / 0.5)
            .collect();
        let se: Vec<f64> = exact.iter().map(|m| 0.01 * m).collect();
        // The tally beyond r = 10 is noise: zeros and single hits (relative standard error
        // 1), too few to pool into resolved groups. Their total is kept, spread like the
        // exponential of the resolved bins (κ = 0.5 recovered exactly).
        let mut noisy = exact.clone();
        let mut noisy_se = se.clone();
        let first_bad = edges.partition_point(|&e| e < 10.0);
        for k in first_bad..noisy.len() {
            noisy[k] = if k % 3 == 0 { 5.0 * exact[k] } else { 0.0 };
            noisy_se[k] = noisy[k];
        }
        let (tail, last) = tail_masses(&edges, &noisy, &noisy_se);
        assert_eq!(last, first_bad - 1);
        assert_eq!(tail[..first_bad], exact[..first_bad]);
        let ratio = noisy[first_bad..].iter().sum::<f64>() / exact[first_bad..].iter().sum::<f64>();
        assert!(ratio > 1.0);
        for k in first_bad..exact.len() {
            assert!(
                (tail[k] - ratio * exact[k]).abs() <= 1e-9 * ratio * exact[k] + 1e-300,
                "bin {k}: {} vs {}",
                tail[k],
                ratio * exact[k]
            );
        }
        // A tail that does not decay where it is resolved (here it rises slowly from x = 6 to
        // the last resolved bin) is spread like 1/x² instead.
        let rising: Vec<f64> = edges
            .windows(2)
            .map(|e| {
                let c = 0.5 * (e[0] + e[1]);
                let d = if c < 6.0 {
                    (-0.5 * c).exp()
                } else if c < 12.0 {
                    (-3.0f64).exp() * (1.0 + 0.01 * (c - 6.0))
                } else {
                    (-3.0 - (c - 12.0)).exp()
                };
                d * (e[1] - e[0])
            })
            .collect();
        let rising_se: Vec<f64> = rising
            .iter()
            .zip(&edges)
            .map(|(m, &lo)| if lo < 10.0 { 0.01 * m } else { *m })
            .collect();
        let (spread, last) = tail_masses(&edges, &rising, &rising_se);
        assert_eq!(last, first_bad - 1);
        assert_eq!(spread[..first_bad], rising[..first_bad]);
        let rest: f64 = rising[first_bad..].iter().sum();
        let x0 = edges[first_bad];
        let end = edges[edges.len() - 1];
        for k in first_bad..rising.len() {
            let want = rest * (1.0 / edges[k] - 1.0 / edges[k + 1]) / (1.0 / x0 - 1.0 / end);
            assert!((spread[k] - want).abs() <= 1e-9 * want, "bin {k}");
        }
    }

    #[test]
    fn poorly_resolved_tail_bins_are_pooled_keeping_their_mass() {
        // A power-law tail (as at albedo 1) whose bins beyond x = 20 each have a relative
        // standard error of 30 %, with ±30 % noise: pooled in resolved groups, each group keeps
        // its tallied mass and the density becomes smooth (non-increasing) inside it.
        let knots = radius_knots();
        let edges = tally_edges(&knots);
        let density = |x: f64| 1.0 / (1.0 + x * x);
        let exact: Vec<f64> = edges
            .windows(2)
            .map(|e| (e[1].atan() - e[0].atan()) / 1.0)
            .collect();
        let first_bad = edges.partition_point(|&e| e < 20.0);
        let mut mass = exact.clone();
        let mut se: Vec<f64> = exact.iter().map(|m| 0.01 * m).collect();
        for k in first_bad..mass.len() - 3 {
            mass[k] = exact[k] * if k % 2 == 0 { 1.3 } else { 0.7 };
            se[k] = 0.3 * mass[k];
        }
        let n = mass.len();
        for k in n - 3..n {
            mass[k] = 0.0;
            se[k] = 0.0;
        }
        let (out, last) = tail_masses(&edges, &mass, &se);
        assert_eq!(last, first_bad - 1);
        // Groups are runs of two or three bins (0.3/√2 > 0.2 ≥ 0.3/√3); their sums are kept.
        let mut k = first_bad;
        let mut groups = 0;
        while k + 3 <= n - 3 {
            let kept: f64 = out[k..k + 3].iter().sum();
            let tallied: f64 = mass[k..k + 3].iter().sum();
            assert!((kept - tallied).abs() <= 1e-12 * tallied, "group at {k}");
            groups += 1;
            k += 3;
        }
        assert!(groups >= 3, "{groups}");
        // Within the pooled region the density falls from bin to bin, and stays within 30 %
        // of the exact one (the groups' own noise is ±10 %; the shape extrapolated at the
        // end of the last group adds the rest).
        for k in first_bad..k {
            let d = out[k] / (edges[k + 1] - edges[k]);
            let c = 0.5 * (edges[k] + edges[k + 1]);
            assert!(
                (d / density(c) - 1.0).abs() < 0.3,
                "bin {k}: {d} vs {}",
                density(c)
            );
            if k > first_bad {
                let prev = out[k - 1] / (edges[k] - edges[k - 1]);
                assert!(d <= prev * (1.0 + 1e-12), "bin {k} rises");
            }
        }
        assert!(out.iter().all(|v| v.is_finite() && *v >= 0.0));
    }

    #[test]
    fn table_file_round_trips_and_rejects_damage() {
        let quiet = |_: &str| {};
        let run = |threads: usize| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| McTableData::generate(2e-5, &quiet).unwrap())
        };
        let data = run(2);
        let bytes = data.to_bytes();
        // The same bytes for any thread count, and a faithful round trip.
        assert_eq!(run(1).to_bytes(), bytes);
        let back = McTableData::from_bytes(&bytes).unwrap();
        assert_eq!(back, data);
        assert_eq!(back.to_bytes(), bytes);
        assert_eq!(data.gs(), GS);
        // Reusing a run's tables gives its bytes; tables whose walks differ (another scale)
        // are run again, as without reuse.
        let reused = McTableData::generate_reusing(2e-5, Some(&data), &quiet).unwrap();
        assert_eq!(reused.to_bytes(), bytes);
        let other_scale = McTableData::generate_reusing(3e-5, Some(&data), &quiet).unwrap();
        assert_eq!(
            other_scale.to_bytes(),
            McTableData::generate(3e-5, &quiet).unwrap().to_bytes()
        );
        assert!(McTableData::from_bytes_v1(&bytes).is_err());
        // Every table's rows hold their own walks: the total (all escaped weight) is at least
        // the binned weight, and the tables differ.
        for t in 0..GS.len() * ETAS.len() {
            for i in 0..N_RHO {
                let binned: f64 = data.mass(t, i).iter().sum();
                let (total, _) = data.total(t, i);
                assert!(
                    total >= binned * (1.0 - 1e-6),
                    "table {t} row {i}: {total} < {binned}"
                );
            }
        }
        assert!((0..N_RHO).any(|i| data.total(0, i) != data.total(GS.len() * ETAS.len() - 1, i)));
        // Any damage is an error, never a panic.
        for at in [0, 9, 40, bytes.len() / 2, bytes.len() - 1] {
            let mut bad = bytes.clone();
            bad[at] ^= 0x10;
            assert!(McTableData::from_bytes(&bad).is_err(), "flip at {at}");
        }
        for len in [0, 7, 16, 100, bytes.len() - 8, bytes.len() - 1] {
            assert!(
                McTableData::from_bytes(&bytes[..len]).is_err(),
                "length {len}"
            );
        }
        // A well-formed file of other grids is refused.
        let mut other = data.clone();
        other.knots[5] *= 1.0 + 1e-12;
        let err = McTableData::from_bytes(&other.to_bytes()).unwrap_err();
        assert!(err.to_string().contains("grids differ"), "{err}");
        assert!(McTableData::generate(0.0, &quiet).is_err());
    }

    #[test]
    fn embedded_table_is_read() {
        let data = McTableData::embedded().unwrap();
        assert_eq!(data.etas(), ETAS);
        assert_eq!(data.gs(), GS);
        assert_eq!(data.seed(), SEED);
        for g in 0..GS.len() {
            for e in 0..ETAS.len() {
                let t = data.table_index(g, e);
                assert_eq!(data.walks(t), plan(g, e, 1.0).as_slice(), "g {g}, eta {e}");
            }
        }
    }

    #[test]
    fn eta_between_tables_is_linear_and_clamped_outside() {
        let (a, b, mid) = (McTable::new(1.3), McTable::new(1.4), McTable::new(1.35));
        for ((p, q), m) in a
            .profile_values()
            .iter()
            .zip(b.profile_values())
            .zip(mid.profile_values())
        {
            assert!((m - 0.5 * (p + q)).abs() <= 1e-14 * (p + q) + 1e-300);
        }
        assert_eq!(
            McTable::new(2.5).profile_values(),
            McTable::new(1.5).profile_values()
        );
        assert_eq!(
            McTable::new(0.7).profile_values(),
            McTable::new(1.0).profile_values()
        );
        for (eta, inside) in [
            (1.0, true),
            (1.5, true),
            (1.33, true),
            (0.99, false),
            (1.51, false),
        ] {
            assert_eq!(eta_in_range(eta), inside, "{eta}");
        }
        assert!(!eta_in_range(f64::NAN));
        // The uncached build is the cached one.
        assert_eq!(
            McTable::from_embedded_uncached(1.35).profile_values(),
            mid.profile_values()
        );
    }

    #[test]
    fn anisotropic_media_read_the_tables_of_their_g_at_their_reduced_coefficients() {
        // g = 0.5 lies a third of the way from the 0.4 table to the 0.7 one.
        let (lo, hi, mid) = (
            McTable::anisotropic(1.3, 0.4),
            McTable::anisotropic(1.3, 0.7),
            McTable::anisotropic(1.3, 0.5),
        );
        assert_eq!(mid.g(), 0.5);
        let mut differ = 0;
        for ((p, q), m) in lo
            .profile_values()
            .iter()
            .zip(hi.profile_values())
            .zip(mid.profile_values())
        {
            let want = (2.0 * p + q) / 3.0;
            assert!((m - want).abs() <= 1e-13 * (p + q) + 1e-300);
            differ += usize::from(p != q);
        }
        assert!(differ > N_RHO, "the tables of g = 0.4 and 0.7 differ");
        assert_ne!(
            McTable::anisotropic(1.3, 0.4).profile_values(),
            McTable::new(1.3).profile_values()
        );
        // Outside [0, 0.9]: the end table at the reduced coefficients. σ_s = 2, g = −1/2 has
        // σ'_s = 3, the same model as σ_s = 3, g = 0; σ_s = 20, g = 0.95 has σ'_s = 1, as
        // σ_s = 10, g = 0.9.
        for ((sa, ga), (sb, gb)) in [((2.0, -0.5), (3.0, 0.0)), ((20.0, 0.95), (10.0, 0.9))] {
            let a = Medium::new([0.1, 0.3, 0.0], [sa, 2.0 * sa, 3.0 * sa], ga, 1.3).unwrap();
            let b = Medium::new([0.1, 0.3, 0.0], [sb, 2.0 * sb, 3.0 * sb], gb, 1.3).unwrap();
            let (ma, mb) = (McTableModel::new(a), McTableModel::new(b));
            assert!(!ma.g_in_range() && mb.g_in_range());
            for ch in 0..3 {
                let (x, y) = (ma.reduced_albedo(ch), mb.reduced_albedo(ch));
                assert!((x - y).abs() < 1e-15, "{x} vs {y}");
                for r in [0.0, 0.01, 0.3, 2.0, 40.0] {
                    let (x, y) = (ma.rd(ch, r), mb.rd(ch, r));
                    assert!(
                        (x - y).abs() <= 1e-12 * y,
                        "g {ga} ch {ch} r {r}: {x} vs {y}"
                    );
                }
            }
        }
        assert!(g_in_range(0.0) && g_in_range(0.9) && g_in_range(0.55));
        assert!(!g_in_range(-0.01) && !g_in_range(0.91) && !g_in_range(f64::NAN));
        let a = Medium::new([0.1; 3], [1.0; 3], 0.5, 1.3).unwrap();
        assert!(McTableModel::new(a).eta_in_range());
        let out = Medium::new([0.1; 3], [1.0; 3], 0.0, 1.7).unwrap();
        assert!(!McTableModel::new(out).eta_in_range());
    }
}
