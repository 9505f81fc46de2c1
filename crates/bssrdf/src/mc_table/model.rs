//! The `mc-table` model of one medium ([`McTableModel`]): the table's row blended at the
//! medium's reduced albedo, made monotone, and evaluated and sampled through
//! [`OpticalProfile`].

use super::*;
use crate::catmull_rom::{apply_weights, catmull_rom_weights};
use crate::spline_row::{OpticalProfile, SplineRow, optical_profile_bssrdf};
use crate::{Medium, ModelKind, Rgb};
use std::sync::Arc;

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
///
/// [`Bssrdf::rd`]: crate::Bssrdf::rd
/// [`Bssrdf::total_diffuse_reflectance`]: crate::Bssrdf::total_diffuse_reflectance
/// [`Bssrdf::sample_sr`]: crate::Bssrdf::sample_sr
/// [`Bssrdf::pdf_sr`]: crate::Bssrdf::pdf_sr
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
    let (offset, w) = catmull_rom_weights(table.rho_samples(), rho)?;
    let xs = table.radius_samples();
    let n = xs.len();
    let mut values: Vec<f64> = (0..n)
        .map(|k| apply_weights(offset, &w, |i| table.profile(i, k)).max(0.0))
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
    Some(SplineRow::new(table.index(), &values).monotone_over_x())
}

optical_profile_bssrdf!(McTableModel, ModelKind::McTable);
