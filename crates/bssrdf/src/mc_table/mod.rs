//! `mc-table`: the radial profile of the crate's own photon random walk ([`crate::monte_carlo`])
//! tabulated once over albedo, optical radius, relative index η and anisotropy g, and
//! evaluated and sampled like the photon beam diffusion table (pbrt 3rd ed. §11.4.2, §15.4.2:
//! Catmull-Rom in albedo and radius, [`SplineRow`](crate::spline_row::SplineRow) rows pre-blended per channel), so a
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
//! ([`SplineRow::with_linear_first_segment`](crate::spline_row::SplineRow::with_linear_first_segment)) and keeps the row it blends for a medium
//! non-increasing in R_d (`monotone_row`). The spline then reproduces every tallied bin
//! integral where the tallies are resolved and ordered, and its total stays within 3 standard
//! errors of the tallied total reflectance for every albedo ≥ 0.5 (tested).
//!
//! # The far tail: a fitted diffusion far field
//! Measured against MCML (Wang, Jacques & Zheng, *MCML — Monte Carlo modeling of light
//! transport in multi-layered tissues*, Comput. Methods Programs Biomed. 47, 1995; 12 media
//! of reduced albedo 0.68–0.9999, `tests/integration/mcml.rs`, whose `stages` test prints
//! the figures) on the table's own bins, the tallies, the pooling, the isotonic fit, the
//! histopolation and the albedo blend all agree with MCML within the tallies' noise up to ≈ 10
//! mean free paths (worst −4.3 % at 8 mean free paths for ketchup, 2.6 of the tallies'
//! standard errors); what departed was the tail beyond: bins were kept as tallied up to a
//! relative standard error of 20 % ([`RESOLVED_REL_SE`]), so at albedos 0.65–0.85 the rows
//! carried their tallies' noise, 5–20 % per bin at 10–16 mean free paths (ketchup +38 % at
//! 14 mean free paths, skin1 −24 % at 15.5), and the spline through them up to 3 times MCML's
//! value in single MCML bins. (Deviations of single MCML bins closer in, quoted at 5–35 %, were
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
//! 10 mean free paths and 10 % + 3 standard errors up to 16 (see `tests/integration/mcml.rs`
//! for the margins and how MCML's noise is treated); evaluation is unchanged, and building a table
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

mod data;
mod fit;
mod grid;
mod histopolation;
mod model;
mod table;
#[cfg(test)]
mod tests;

pub use data::*;
pub use fit::*;
pub use grid::*;
pub use histopolation::*;
pub use model::*;
pub use table::*;
